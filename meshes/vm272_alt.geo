// An independently built mesh of the VM272 scene, for cross-checks: the arcs are split only at
// the contact point, the size comes from a Box field around the contact (not a distance
// threshold), the 2-D algorithm is Frontal-Delaunay, and the file is ASCII.
// Same physical names as vm272.geo: lower_body, upper_body, bottom, top, lower_arc, upper_arc.
Geometry.AutoCoherence = 0;
DefineConstant[ h_in = {0.0133, Name "h_in"}, h_out = {0.8, Name "h_out"} ];
R = 8.0;
Point(1) = {0, 0, 0}; Point(2) = {-R, 0, 0}; Point(3) = {R, 0, 0}; Point(4) = {0, R, 0};
Line(1) = {2, 3}; Circle(2) = {3, 1, 4}; Circle(3) = {4, 1, 2};
Curve Loop(1) = {1, 2, 3}; Plane Surface(1) = {1};
Point(11) = {0, 2*R, 0}; Point(12) = {-R, 2*R, 0}; Point(13) = {R, 2*R, 0}; Point(14) = {0, R, 0};
Circle(11) = {12, 11, 14}; Circle(12) = {14, 11, 13}; Line(13) = {13, 12};
Curve Loop(2) = {11, 12, 13}; Plane Surface(2) = {2};
Physical Surface("lower_body", 1) = {1};
Physical Surface("upper_body", 2) = {2};
Physical Curve("bottom", 3) = {1};
Physical Curve("top", 4) = {13};
Physical Curve("lower_arc", 5) = {2, 3};
Physical Curve("upper_arc", 6) = {11, 12};
Field[1] = Box;
Field[1].VIn = h_in; Field[1].VOut = h_out;
Field[1].XMin = -1.1; Field[1].XMax = 1.1; Field[1].YMin = 7.6; Field[1].YMax = 8.4;
Field[1].Thickness = 2.0;
Background Field = 1;
Mesh.MeshSizeExtendFromBoundary = 0;
Mesh.MeshSizeFromPoints = 0;
Mesh.MeshSizeFromCurvature = 0;
Mesh.Algorithm = 6;
Mesh.ElementOrder = 2;
Mesh.SecondOrderLinear = 0;
Mesh.MshFileVersion = 4.1;
Mesh.Binary = 0;
