// Rectangular block (elastic half-space surrogate) for the Hertz / McEwen check.
// x in [-W, W], y in [-D, 0], W = D = 60 a, a = 0.6808 mm. Loaded on y = 0.
// The top edge is split at x = -1.2a, -a, 0, a, 1.2a so that the nodes x = +-a
// (kink of the Hertz pressure) and x = 0 exist exactly.
// Sizes: ~a/40 on the top edge for |x| <= 1.2a, ~a/20 along x = 0 down to y = -3.5a,
// growing linearly (rate k_grow) to h_far elsewhere.
Geometry.AutoCoherence = 0;
DefineConstant[
  k_grow = {0.06, Name "k_grow"},
  h_far  = {4.0, Name "h_far"}
];
a  = 0.6808;
W  = 60 * a;
D  = 60 * a;
h_top  = a / 40;
h_axis = a / 20;

Point(1) = {-W, -D, 0};
Point(2) = { W, -D, 0};
Point(3) = { W,  0, 0};
Point(4) = { 1.2*a, 0, 0};
Point(5) = { a, 0, 0};
Point(6) = { 0, 0, 0};
Point(7) = {-a, 0, 0};
Point(8) = {-1.2*a, 0, 0};
Point(9) = {-W,  0, 0};

Line(1) = {1, 2};   // bottom
Line(2) = {2, 3};   // right
Line(3) = {3, 4};   // top, x in [1.2a, W]
Line(4) = {4, 5};   // top, x in [a, 1.2a]
Line(5) = {5, 6};   // top, x in [0, a]
Line(6) = {6, 7};   // top, x in [-a, 0]
Line(7) = {7, 8};   // top, x in [-1.2a, -a]
Line(8) = {8, 9};   // top, x in [-W, -1.2a]
Line(9) = {9, 1};   // left
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8, 9};   // counter-clockwise
Plane Surface(1) = {1};

Physical Surface("block", 1) = {1};
Physical Curve("top", 2)    = {3, 4, 5, 6, 7, 8};
Physical Curve("bottom", 3) = {1};
Physical Curve("left", 4)   = {9};
Physical Curve("right", 5)  = {2};

// fine along the loaded part of the top edge
Field[1] = Distance;
Field[1].CurvesList = {4, 5, 6, 7};
Field[1].Sampling = 1000;
Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_top;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = (h_far - h_top) / k_grow;
// fine along the symmetry axis x = 0, y in [-3.5a, 0]
Field[3] = Box;
Field[3].VIn  = h_axis;
Field[3].VOut = h_far;
Field[3].XMin = -0.5 * h_axis;
Field[3].XMax =  0.5 * h_axis;
Field[3].YMin = -3.5 * a;
Field[3].YMax = 0;
Field[3].ZMin = -1;
Field[3].ZMax = 1;
Field[3].Thickness = (h_far - h_axis) / k_grow;
Field[4] = Min;
Field[4].FieldsList = {2, 3};
Background Field = 4;

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
