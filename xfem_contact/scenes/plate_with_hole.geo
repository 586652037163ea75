// Square plate [0, 1] x [0, 1] m with a circular hole of radius 0.15 m at (0.5, 0.5).
// Physical curves (boundary parts): "bottom", "right", "top", "left", "hole".
// Physical surface (cells): "plate". Characteristic length lc (m) at every point.
lc = 0.05;
r = 0.15;
xc = 0.5;
yc = 0.5;

Point(1) = {0, 0, 0, lc};
Point(2) = {1, 0, 0, lc};
Point(3) = {1, 1, 0, lc};
Point(4) = {0, 1, 0, lc};

Point(5) = {xc, yc, 0, lc};  // centre of the hole (construction point only)
Point(6) = {xc + r, yc, 0, lc};
Point(7) = {xc, yc + r, 0, lc};
Point(8) = {xc - r, yc, 0, lc};
Point(9) = {xc, yc - r, 0, lc};

Line(1) = {1, 2};
Line(2) = {2, 3};
Line(3) = {3, 4};
Line(4) = {4, 1};
Circle(5) = {6, 5, 7};
Circle(6) = {7, 5, 8};
Circle(7) = {8, 5, 9};
Circle(8) = {9, 5, 6};

Curve Loop(1) = {1, 2, 3, 4};
Curve Loop(2) = {5, 6, 7, 8};
Plane Surface(1) = {1, 2};

Physical Curve("bottom", 1) = {1};
Physical Curve("right", 2) = {2};
Physical Curve("top", 3) = {3};
Physical Curve("left", 4) = {4};
Physical Curve("hole", 5) = {5, 6, 7, 8};
Physical Surface("plate", 10) = {1};
