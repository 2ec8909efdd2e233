// springy: procedural closed shapes (all outward-oriented, single closed 2-manifolds).
//
// The octahedron sphere is the original project's sphere: an octahedron whose faces are split
// into n x n triangles and pushed onto the sphere. Its vertex count is 4n^2 + 2 and vertex 0 is
// the top pole (+y), which the hanging-sphere scene pins.
#pragma once

#include "sim/mesh.h"

namespace springy {

TriMesh makeCube(double size, int subdivisions = 1);  // axis-aligned, centred at the origin
TriMesh makeTetrahedron(double edgeLength);           // regular, centred at its centroid
TriMesh makeIcosphere(double radius, int level);      // 10 * 4^level + 2 vertices
TriMesh makeOctahedronSphere(double radius, int n);   // 4 n^2 + 2 vertices, vertex 0 = (0, r, 0)

// A jelly (gelatin dessert): a solid of revolution with a fluted side (vertical ridges) and a
// wavy rim, a rounded top and a flat base. `height` along +y, base at y = 0 before centring;
// the result is centred on its bounding box. rings x segments controls resolution.
TriMesh makeJelly(double radius, double height, int ridges, int rings, int segments);

}  // namespace springy
