// VM272 extension: two elastic half-discs (plane strain) in frictional contact.
// Units: mm.
//   lower body : upper half of the disc of radius R centred at (0, 0)  (flat face y = 0)
//   upper body : lower half of the disc of radius R centred at (0, 2R) (flat face y = 2R)
// The bodies touch at (0, R). They are separate surfaces and share NO point,
// curve or node (each body has its own copy of the contact point (0, R)).
//
// Parameters (override with  gmsh -setnumber NAME VALUE  or gmsh.parser.setNumber):
//   h_c    : element size along both arcs for |x| <= 1.5 a
//   k_grow : size growth rate with distance from the central arcs (h = h_c + k_grow * d)
//   h_far  : cap on the element size far from the contact
//   order  : element order (2 = 6-node triangles, 1 = 3-node triangles)
//
// Each arc is split at the points with |x| = 1.5 a and at the contact point (0, R),
// so it consists of 4 circle arcs; the two central ones (|x| <= 1.5 a) get size h_c.

Geometry.AutoCoherence = 0;   // never merge the coincident contact points

DefineConstant[
  h_c    = {0.21275, Name "h_c"},
  k_grow = {0.05, Name "k_grow"},
  h_far  = {1.0, Name "h_far"},
  order  = {2, Name "order"}
];

R  = 8.0;
a  = 0.6808;          // Hertz contact semi-width for P = 10 N/mm
xs = 1.5 * a;         // split abscissa
ys = Sqrt(R*R - xs*xs);

// ---------------- lower body (centre (0,0)) ----------------
Point(1) = {0, 0, 0};            // centre (not meshed)
Point(2) = {-R, 0, 0};
Point(3) = { R, 0, 0};
Point(4) = { xs, ys, 0};
Point(5) = { 0,  R, 0};          // contact point, lower copy
Point(6) = {-xs, ys, 0};

Line(1)   = {2, 3};              // bottom, y = 0
Circle(2) = {3, 1, 4};           // outer right arc
Circle(3) = {4, 1, 5};           // central right arc
Circle(4) = {5, 1, 6};           // central left arc
Circle(5) = {6, 1, 2};           // outer left arc
Curve Loop(1) = {1, 2, 3, 4, 5}; // counter-clockwise
Plane Surface(1) = {1};

// ---------------- upper body (centre (0,2R)) ----------------
Point(11) = {0, 2*R, 0};         // centre (not meshed)
Point(12) = {-R, 2*R, 0};
Point(13) = { R, 2*R, 0};
Point(14) = {-xs, 2*R - ys, 0};
Point(15) = { 0, R, 0};          // contact point, upper copy
Point(16) = { xs, 2*R - ys, 0};

Circle(11) = {12, 11, 14};       // outer left arc
Circle(12) = {14, 11, 15};       // central left arc
Circle(13) = {15, 11, 16};       // central right arc
Circle(14) = {16, 11, 13};       // outer right arc
Line(15)   = {13, 12};           // top, y = 2R
Curve Loop(2) = {11, 12, 13, 14, 15}; // counter-clockwise
Plane Surface(2) = {2};

// ---------------- physical groups (tags fixed, names are the contract) ----------------
Physical Surface("lower_body", 1) = {1};
Physical Surface("upper_body", 2) = {2};
Physical Curve("bottom", 3)    = {1};
Physical Curve("top", 4)       = {15};
Physical Curve("lower_arc", 5) = {2, 3, 4, 5};
Physical Curve("upper_arc", 6) = {11, 12, 13, 14};

// ---------------- mesh size: h = min(h_far, h_c + k_grow * dist(central arcs)) ----------------
Field[1] = Distance;
Field[1].CurvesList = {3, 4, 12, 13};
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
Mesh.SecondOrderLinear = 0;      // mid-edge nodes on the true arcs
Mesh.HighOrderOptimize = 0;
Mesh.SecondOrderIncomplete = 0;  // (6-node triangles are complete anyway)

Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;                 // generate.py switches to binary for the fine levels
Mesh.SaveAll = 0;                // only elements in physical groups
