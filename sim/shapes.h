// springy: procedural shapes: closed ones (outward-oriented, single closed 2-manifolds) and the
// cloth, an open flat sheet.
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

// A jelly mould (issue 17): a tiered solid of revolution. From the flat base up: a wide lower
// tier, a rounded shoulder stepping in, a narrower upper tier, and a domed crown. Both tiers are
// fluted into `lobes` rounded lobes (radius R (1 - a + a sqrt|cos(lobes phi / 2)|): round
// lobes, sharp creases between them), fading out over the crown. The base is flat: an inner
// ring at half the base radius and a centre. `rings` rings along the profile (spaced by arc
// length), `segments` vertices per ring: rings * segments + segments + 2 vertices, ring 0 the
// base rim (vertices 1 .. segments). Centred on its bounding box.
TriMesh makeMould(double radius, double height, int lobes, int rings, int segments);

// A cloth: a flat rectangular sheet in the x-z plane (y = 0) centred at the origin, `width`
// along x and `depth` along z, split into columns x rows quads. Vertex (i, j) (i = 0 .. columns
// along x, j = 0 .. rows along z) is index i + (columns + 1) j. Each quad is cut into two
// triangles along alternating diagonals (a quad's diagonal turns where i + j changes parity), so
// the sheet has no preferred shear direction; every triangle faces +y (counter-clockwise seen
// from above). An open mesh: its 2 (columns + rows) border edges belong to one triangle each.
TriMesh makeCloth(double width, double depth, int columns, int rows);

}  // namespace springy
