// Two identical rectangular blocks pressed together along a long planar interface y = 0
// (the rupture scene of docs/dynamics.md). Lower block x in [-L/2, L/2], y in [-H, 0];
// upper block the same above. Each block has its own interface line (the contact pair:
// "lower_face" slave, "upper_face" master); lateral sides named for the side tractions.
// Sizes: h_i along the interface over |x| <= x_f, growing at rate k_grow away from it,
// capped at h_far.
Geometry.AutoCoherence = 0;
DefineConstant[
  L      = {500.0, Name "L"},
  H      = {125.0, Name "H"},
  h_i    = {1.0, Name "h_i"},
  x_f    = {250.0, Name "x_f"},
  k_grow = {0.15, Name "k_grow"},
  h_far  = {20.0, Name "h_far"}
];
W = L / 2;

Point(1) = {-W, -H, 0};
Point(2) = { W, -H, 0};
Point(3) = { W,  0, 0};
Point(4) = {-W,  0, 0};
Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // lower right side
Line(3) = {3, 4};   // lower face (interface), from +W to -W
Line(4) = {4, 1};   // lower left side
Curve Loop(1) = {1, 2, 3, 4};
Plane Surface(1) = {1};

Point(5) = {-W, 0, 0};
Point(6) = { W, 0, 0};
Point(7) = { W, H, 0};
Point(8) = {-W, H, 0};
Line(5) = {5, 6};   // upper face (interface), from -W to +W
Line(6) = {6, 7};   // upper right side
Line(7) = {7, 8};   // top
Line(8) = {8, 5};   // upper left side
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(2) = {2};

Physical Surface("lower_block", 1) = {1};
Physical Surface("upper_block", 2) = {2};
Physical Curve("bottom", 3)      = {1};
Physical Curve("top", 4)         = {7};
Physical Curve("lower_face", 5)  = {3};
Physical Curve("upper_face", 6)  = {5};
Physical Curve("lower_left", 7)  = {4};
Physical Curve("lower_right", 8) = {2};
Physical Curve("upper_left", 9)  = {8};
Physical Curve("upper_right", 10) = {6};

// h_i within the band |y| <= h_i of the interface over |x| <= x_f, growing away from it
Field[1] = Box;
Field[1].VIn  = h_i;
Field[1].VOut = h_far;
Field[1].XMin = -x_f;
Field[1].XMax =  x_f;
Field[1].YMin = -h_i;
Field[1].YMax =  h_i;
Field[1].ZMin = -1;
Field[1].ZMax = 1;
Field[1].Thickness = (h_far - h_i) / k_grow;
Background Field = 1;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeMax = h_far;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
General.NumThreads = 1;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = 0;
Mesh.HighOrderOptimize = 0;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 1;
Mesh.SaveAll = 0;
