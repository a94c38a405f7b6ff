// An aluminium C-channel, 60 mm deep, 40 mm flanges, 4 mm walls, inner fillets of 4 mm,
// with steel lips at the flange tips. Meshed by Gmsh into 6-node triangles:
//   gmsh -2 -order 2 -format msh41 channel.geo -o channel.msh
// (units: metres; the mesh x, y become the section's y, z)
t = 0.004;  h = 0.060;  b = 0.040;  r = 0.004;  lip = 0.006;
lc = 0.0025;
// Outer contour, counter-clockwise from the web's lower outer corner.
Point(1) = {0, -h/2, 0, lc};
Point(2) = {b - lip, -h/2, 0, lc};
Point(3) = {b - lip, -h/2 + t, 0, lc};
Point(4) = {t + r, -h/2 + t, 0, lc};
Point(5) = {t + r, -h/2 + t + r, 0, lc};   // fillet centre
Point(6) = {t, -h/2 + t + r, 0, lc};
Point(7) = {t, h/2 - t - r, 0, lc};
Point(8) = {t + r, h/2 - t - r, 0, lc};    // fillet centre
Point(9) = {t + r, h/2 - t, 0, lc};
Point(10) = {b - lip, h/2 - t, 0, lc};
Point(11) = {b - lip, h/2, 0, lc};
Point(12) = {0, h/2, 0, lc};
Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Circle(4) = {4, 5, 6};
Line(5) = {6, 7};
Circle(6) = {7, 8, 9};
Line(7) = {9, 10};
Line(8) = {10, 11};
Line(9) = {11, 12};
Line(10) = {12, 1};
Curve Loop(1) = {1, 2, 3, 4, 5, 6, 7, 8, 9, 10};
Plane Surface(1) = {1};
// Steel lips at the flange tips.
Point(13) = {b, -h/2, 0, lc};
Point(14) = {b, -h/2 + t, 0, lc};
Line(11) = {2, 13};
Line(12) = {13, 14};
Line(13) = {14, 3};
Curve Loop(2) = {11, 12, 13, -2};
Plane Surface(2) = {2};
Point(15) = {b, h/2 - t, 0, lc};
Point(16) = {b, h/2, 0, lc};
Line(14) = {10, 15};
Line(15) = {15, 16};
Line(16) = {16, 11};
Curve Loop(3) = {14, 15, 16, -8};
Plane Surface(3) = {3};
Physical Surface("channel") = {1};
Physical Surface("lips") = {2, 3};
