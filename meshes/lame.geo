// Lame problem: quarter of a thick-walled cylinder, inner radius 1, outer radius 2.
// Parameters:  h      : uniform target element size
//              linear : 0 -> mid-edge nodes on the true arcs (curved, isoparametric)
//                       1 -> mid-edge nodes at the chord midpoints (straight-edged)
Geometry.AutoCoherence = 0;
DefineConstant[
  h      = {0.4, Name "h"},
  linear = {0, Name "linear"}
];
ri = 1.0;
ro = 2.0;
Point(1) = {0, 0, 0};      // centre (not meshed)
Point(2) = {ri, 0, 0};
Point(3) = {ro, 0, 0};
Point(4) = {0, ro, 0};
Point(5) = {0, ri, 0};
Line(1)   = {2, 3};        // y = 0, x in [1,2]
Circle(2) = {3, 1, 4};     // r = 2
Line(3)   = {4, 5};        // x = 0, y in [1,2]
Circle(4) = {5, 1, 2};     // r = 1
Curve Loop(1) = {1, 2, 3, 4};   // counter-clockwise
Plane Surface(1) = {1};

Physical Surface("body", 1) = {1};
Physical Curve("inner", 2)  = {4};
Physical Curve("outer", 3)  = {2};
Physical Curve("sym_x", 4)  = {1};
Physical Curve("sym_y", 5)  = {3};

Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.MeshSizeExtendFromBoundary = 1;
Mesh.MeshSizeMin = h;
Mesh.MeshSizeMax = h;
Mesh.Algorithm = 6;
Mesh.RandomSeed = 1;
General.NumThreads = 1;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = linear;
Mesh.HighOrderOptimize = 0;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
Mesh.SaveAll = 0;
