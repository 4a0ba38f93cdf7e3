// Laboratory line contact for the material-pair cases (docs/material_pairs.md):
// a cylindrical pad of radius R pressed on a flat specimen (plane strain). Units: mm.
//   lower body : the flat specimen, rectangle [-W/2, W/2] x [0, H]; its top face y = H is the
//                contact face (named `lower_arc` like the VM272 meshes, although it is straight)
//   upper body : the pad, lower half of the disc of radius R centred at (0, H + R); flat face
//                y = H + R (`top`, where the rigid pilot acts)
// The bodies touch at (0, H). They share NO point, curve or node.
//
// Parameters (override with  gmsh -setnumber NAME VALUE  or gmsh.onelab.setNumber):
//   h_c    : element size along both contact faces for |x| <= x_f
//   x_f    : half-width of the fine zone on the contact faces
//   k_grow : size growth rate with distance from the fine zone (h = h_c + k_grow * d)
//   h_far  : cap on the element size far from the contact
//
// Each contact face is split at |x| = x_f and at x = 0, so it consists of 4 pieces; the two
// central ones (|x| <= x_f) get size h_c.

Geometry.AutoCoherence = 0;   // never merge the coincident contact points

DefineConstant[
  h_c    = {0.0005, Name "h_c"},
  x_f    = {0.1, Name "x_f"},
  k_grow = {0.1, Name "k_grow"},
  h_far  = {2.5, Name "h_far"},
  order  = {2, Name "order"}
];

R  = 25.0;            // pad radius
W  = 50.0;            // width of the flat specimen
H  = 10.0;            // thickness of the flat specimen
ys = R - Sqrt(R*R - x_f*x_f);   // height of the pad arc above y = H at |x| = x_f

// ---------------- lower body: the flat (rectangle) ----------------
Point(1) = {-W/2, 0, 0};
Point(2) = { W/2, 0, 0};
Point(3) = { W/2, H, 0};
Point(4) = { x_f, H, 0};
Point(5) = { 0,   H, 0};         // contact point, lower copy
Point(6) = {-x_f, H, 0};
Point(7) = {-W/2, H, 0};

Line(1) = {1, 2};                // bottom, y = 0
Line(2) = {2, 3};                // right side (free)
Line(3) = {3, 4};                // outer right piece of the top face
Line(4) = {4, 5};                // central right piece
Line(5) = {5, 6};                // central left piece
Line(6) = {6, 7};                // outer left piece
Line(7) = {7, 1};                // left side (free)
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7};   // counter-clockwise
Plane Surface(1) = {1};

// ---------------- upper body: the pad (centre (0, H + R)) ----------------
Point(11) = {0, H + R, 0};       // centre (not meshed)
Point(12) = {-R, H + R, 0};
Point(13) = { R, H + R, 0};
Point(14) = {-x_f, H + ys, 0};
Point(15) = { 0, H, 0};          // contact point, upper copy
Point(16) = { x_f, H + ys, 0};

Circle(11) = {12, 11, 14};       // outer left arc
Circle(12) = {14, 11, 15};       // central left arc
Circle(13) = {15, 11, 16};       // central right arc
Circle(14) = {16, 11, 13};       // outer right arc
Line(15)   = {13, 12};           // top, y = H + R
Curve Loop(2) = {11, 12, 13, 14, 15};   // counter-clockwise
Plane Surface(2) = {2};

// ---------------- physical groups (names as in vm272.geo) ----------------
Physical Surface("lower_body", 1) = {1};
Physical Surface("upper_body", 2) = {2};
Physical Curve("bottom", 3)    = {1};
Physical Curve("top", 4)       = {15};
Physical Curve("lower_arc", 5) = {3, 4, 5, 6};
Physical Curve("upper_arc", 6) = {11, 12, 13, 14};

// ---------------- mesh size: h = min(h_far, h_c + k_grow * dist(fine zone)) ----------------
Field[1] = Distance;
Field[1].CurvesList = {4, 5, 12, 13};
Field[1].Sampling = 2000;

Field[2] = Threshold;
Field[2].InField = 1;
Field[2].SizeMin = h_c;
Field[2].SizeMax = h_far;
Field[2].DistMin = 0;
Field[2].DistMax = (h_far - h_c) / k_grow;

Background Field = 2;

Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeMax = h_far;
Mesh.Algorithm = 6;              // Frontal-Delaunay
Mesh.RandomSeed = 1;
General.NumThreads = 1;

Mesh.ElementOrder = order;
Mesh.SecondOrderLinear = 0;      // mid-edge nodes on the true arc
Mesh.HighOrderOptimize = 0;

Mesh.MshFileVersion = 4.1;
Mesh.Binary = 1;
Mesh.SaveAll = 0;                // only elements in physical groups
