// Tests for mesh import, welding, validation, orientation and simplification (mesh/mesh_io.h).
#include <gtest/gtest.h>

#include "error_of.h"

#include <cstdint>
#include <map>
#include <optional>
#include <regex>
#include <string>
#include <utility>

#include "sim/error.h"
#include "mesh/mesh_io.h"

namespace springy {
namespace {

std::string meshPath(const std::string& name) {
  return std::string(SPRINGY_SOURCE_DIR) + "/tests/data/meshes/" + name;
}

using test::errorOf;

// The first "edge (a, b)" in a message.
std::optional<std::pair<uint32_t, uint32_t>> edgeIn(const std::string& message) {
  std::smatch m;
  if (!std::regex_search(message, m, std::regex(R"(edge \((\d+), (\d+)\))"))) return std::nullopt;
  return std::pair{static_cast<uint32_t>(std::stoul(m[1])),
                   static_cast<uint32_t>(std::stoul(m[2]))};
}

int trianglesOnEdge(const TriMesh& mesh, uint32_t a, uint32_t b) {
  int n = 0;
  for (const Triangle& t : mesh.triangles) {
    const bool hasA = t[0] == a || t[1] == a || t[2] == a;
    const bool hasB = t[0] == b || t[1] == b || t[2] == b;
    if (hasA && hasB) ++n;
  }
  return n;
}

// What loadClosedMesh validates, before validation: read + weld with the default tolerance.
TriMesh readAndWeld(const std::string& path) {
  const TriMesh raw = readMeshFile(path);
  return weldVertices(raw, 1e-6 * length(boundsOf(raw.positions).size()));
}

TriMesh unitTetrahedron() {
  return {{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
          {{{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}}};
}

// Octahedron with every face split into 4 `levels` times, vertices projected to the unit sphere.
TriMesh subdividedSphere(int levels) {
  TriMesh m{
      {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}},
      {{{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4}, {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}}}};
  for (int level = 0; level < levels; ++level) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;
    auto midpoint = [&](uint32_t a, uint32_t b) {
      const auto key = std::minmax(a, b);
      auto it = midpoints.find(key);
      if (it != midpoints.end()) return it->second;
      const auto index = static_cast<uint32_t>(m.positions.size());
      m.positions.push_back(normalized(m.positions[a] + m.positions[b]));
      midpoints.emplace(key, index);
      return index;
    };
    std::vector<Triangle> finer;
    for (const Triangle& t : m.triangles) {
      const uint32_t ab = midpoint(t[0], t[1]);
      const uint32_t bc = midpoint(t[1], t[2]);
      const uint32_t ca = midpoint(t[2], t[0]);
      finer.push_back({t[0], ab, ca});
      finer.push_back({ab, t[1], bc});
      finer.push_back({ca, bc, t[2]});
      finer.push_back({ab, bc, ca});
    }
    m.triangles = std::move(finer);
  }
  return m;
}

// --- reading and welding -------------------------------------------------------------------------

TEST(MeshIo, CubeWithSplitCornersWeldsToEightVertices) {
  const std::string path = meshPath("cube_split.obj");
  const TriMesh raw = readMeshFile(path);
  EXPECT_EQ(raw.positions.size(), 24u);  // no welding in readMeshFile
  EXPECT_EQ(raw.triangles.size(), 12u);  // quads triangulated

  const TriMesh mesh = loadClosedMesh(path);
  EXPECT_EQ(mesh.positions.size(), 8u);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_EQ(findManifoldProblem(mesh), std::nullopt);
  EXPECT_NEAR(signedVolume(mesh.positions, mesh.triangles), 8.0, 1e-12);  // side 2
  const Bounds b = boundsOf(mesh.positions);
  EXPECT_EQ(b.lo, Vec3(1, 1, 1));
  EXPECT_EQ(b.hi, Vec3(3, 3, 3));
}

TEST(MeshIo, StlCubeWeldsToEightVertices) {
  const std::string path = meshPath("cube.stl");
  EXPECT_EQ(readMeshFile(path).positions.size(), 36u);  // STL stores every corner of every facet
  const TriMesh mesh = loadClosedMesh(path);
  EXPECT_EQ(mesh.positions.size(), 8u);
  EXPECT_EQ(mesh.triangles.size(), 12u);
  EXPECT_NEAR(signedVolume(mesh.positions, mesh.triangles), 8.0, 1e-12);
}

TEST(MeshIo, NodeTransformsAreApplied) {
  // One unit tetrahedron instanced twice: scaled by 2 at x = 10, and mirrored (scale -1 in x) at
  // x = -10. The mirrored instance must keep outward winding, so both enclose positive volume.
  const TriMesh mesh = readMeshFile(meshPath("tetrahedron_instances.gltf"));
  ASSERT_EQ(mesh.triangles.size(), 8u);
  const Bounds b = boundsOf(mesh.positions);
  EXPECT_NEAR(b.lo.x, -11.0, 1e-6);
  EXPECT_NEAR(b.hi.x, 12.0, 1e-6);
  EXPECT_NEAR(b.hi.y, 2.0, 1e-6);
  // 8/6 for the scaled copy plus 1/6 for the mirrored one (7/6 if its winding were left flipped).
  EXPECT_NEAR(signedVolume(mesh.positions, mesh.triangles), 1.5, 1e-9);
}

TEST(MeshIo, WeldMergesWithinToleranceDropsCollapsedAndUnused) {
  const TriMesh in{{{0, 0, 0},      // 0
                    {1, 0, 0},      // 1
                    {0, 1, 0},      // 2
                    {1e-7, 0, 0},   // 3: within 1e-6 of 0
                    {9, 9, 9},      // 4: unused
                    {1, 2e-6, 0}},  // 5: just beyond 1e-6 of 1
                   {{{3, 1, 2}, {0, 3, 2}, {1, 5, 2}}}};
  const TriMesh out = weldVertices(in, 1e-6);
  ASSERT_EQ(out.positions.size(), 4u);
  // Kept in original order; a merged vertex keeps the position of its lowest-index member.
  EXPECT_EQ(out.positions[0], Vec3(0, 0, 0));
  EXPECT_EQ(out.positions[1], Vec3(1, 0, 0));
  EXPECT_EQ(out.positions[2], Vec3(0, 1, 0));
  EXPECT_EQ(out.positions[3], Vec3(1, 2e-6, 0));
  ASSERT_EQ(out.triangles.size(), 2u);  // (0, 3, 2) collapsed to (0, 0, 2)
  EXPECT_EQ(out.triangles[0], (Triangle{0, 1, 2}));
  EXPECT_EQ(out.triangles[1], (Triangle{1, 3, 2}));
}

TEST(MeshIo, WeldFindsNeighboursAcrossGridCells) {
  // -1e-4 and +1e-4 fall in different cells of a 1e-3 grid but are 2e-4 apart: one vertex.
  const TriMesh in{{{-1e-4, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1e-4, 0, 0}}, {{{0, 1, 2}, {3, 2, 1}}}};
  const TriMesh out = weldVertices(in, 1e-3);
  EXPECT_EQ(out.positions.size(), 3u);
  EXPECT_EQ(out.triangles[1], (Triangle{0, 2, 1}));
  // Chains merge transitively: 0 -- 0.8 -- 1.6 with tolerance 1, although 0 and 1.6 are apart.
  const TriMesh chain{{{0, 0, 0}, {0.8, 0, 0}, {1.6, 0, 0}, {0, 5, 0}, {0, 0, 5}},
                      {{{0, 3, 4}, {2, 4, 3}, {1, 3, 4}}}};
  EXPECT_EQ(weldVertices(chain, 1.0).positions.size(), 3u);
}

TEST(MeshIo, WeldWithZeroToleranceMergesOnlyExactDuplicates) {
  const TriMesh in{{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 0}, {1e-300, 0, 0}},
                   {{{0, 1, 2}, {3, 2, 1}, {4, 1, 2}}}};
  const TriMesh out = weldVertices(in, 0.0);
  EXPECT_EQ(out.positions.size(), 4u);
  EXPECT_EQ(out.triangles[1], (Triangle{0, 2, 1}));
  EXPECT_EQ(out.triangles[2], (Triangle{3, 1, 2}));
}

TEST(MeshIo, WeldIsDeterministicAndIdempotent) {
  const TriMesh raw = readMeshFile(meshPath("cube_split.obj"));
  const TriMesh a = weldVertices(raw, 1e-6);
  const TriMesh b = weldVertices(raw, 1e-6);
  EXPECT_EQ(a.positions, b.positions);
  EXPECT_EQ(a.triangles, b.triangles);
  const TriMesh again = weldVertices(a, 1e-6);  // nothing left to weld: unchanged
  EXPECT_EQ(again.positions, a.positions);
  EXPECT_EQ(again.triangles, a.triangles);
}

// --- errors from files ---------------------------------------------------------------------------

TEST(MeshIo, MissingFileNamesThePath) {
  const std::string path = meshPath("does_not_exist.obj");
  EXPECT_NE(errorOf([&] { readMeshFile(path); }).find(path), std::string::npos);
  EXPECT_NE(errorOf([&] { loadClosedMesh(path); }).find(path), std::string::npos);
}

TEST(MeshIo, FileWithoutTrianglesIsAnError) {
  const std::string path = meshPath("no_triangles.obj");
  const std::string message = errorOf([&] { readMeshFile(path); });
  EXPECT_EQ(message.rfind(path, 0), 0u) << message;
}

TEST(MeshIo, HoleIsRejectedNamingTheEdge) {
  const std::string path = meshPath("cube_hole.obj");
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_EQ(message.rfind(path + ": edge (", 0), 0u) << message;
  EXPECT_NE(message.find("belongs to 1 triangle: the mesh has a hole"), std::string::npos)
      << message;
  // The named edge really is a border edge of the missing top face (z = 3).
  const auto edge = edgeIn(message);
  ASSERT_TRUE(edge) << message;
  const TriMesh mesh = readAndWeld(path);
  EXPECT_EQ(trianglesOnEdge(mesh, edge->first, edge->second), 1);
  EXPECT_EQ(mesh.positions.at(edge->first).z, 3.0);
  EXPECT_EQ(mesh.positions.at(edge->second).z, 3.0);
  EXPECT_LT(edge->first, edge->second);
}

TEST(MeshIo, NonManifoldEdgeIsRejected) {
  const std::string path = meshPath("cube_fin.obj");  // a fin on the cube edge x = y = 1
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_NE(message.find("is shared by 3 triangles: non-manifold edge"), std::string::npos)
      << message;
  const auto edge = edgeIn(message);
  ASSERT_TRUE(edge) << message;
  const TriMesh mesh = readAndWeld(path);
  EXPECT_EQ(trianglesOnEdge(mesh, edge->first, edge->second), 3);
  for (uint32_t v : {edge->first, edge->second}) {
    EXPECT_EQ(mesh.positions.at(v).x, 1.0);
    EXPECT_EQ(mesh.positions.at(v).y, 1.0);
  }
}

TEST(MeshIo, FlippedFaceIsRejectedNamingBothTriangles) {
  const std::string path = meshPath("cube_flipped_face.obj");  // triangle 7 wound backwards
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_NE(message.find("traversed twice in the same direction"), std::string::npos) << message;
  EXPECT_NE(message.find("flipped face"), std::string::npos) << message;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex(R"(\(triangles (\d+) and (\d+)\))")))
      << message;
  const auto t0 = std::stoul(m[1]);
  const auto t1 = std::stoul(m[2]);
  EXPECT_TRUE(t0 == 7 || t1 == 7) << message;
  // Both triangles contain the named edge.
  const auto edge = edgeIn(message);
  ASSERT_TRUE(edge);
  const TriMesh mesh = readAndWeld(path);
  for (auto t : {t0, t1}) {
    const Triangle& tri = mesh.triangles.at(t);
    int found = 0;
    for (uint32_t v : tri) found += (v == edge->first || v == edge->second) ? 1 : 0;
    EXPECT_EQ(found, 2);
  }
}

TEST(MeshIo, TwoPiecesAreRejected) {
  const std::string path = meshPath("two_tetrahedra.obj");
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_EQ(message,
            path + ": the mesh has 2 separate pieces (vertex 0 and vertex 4 are not connected)");
  const TriMesh mesh = readAndWeld(path);
  EXPECT_LT(mesh.positions.at(0).x, 2.0);  // first tetrahedron
  EXPECT_GE(mesh.positions.at(4).x, 5.0);  // second one
}

TEST(MeshIo, TetrahedraTouchingAtACornerAreRejected) {
  // Every edge is fine, yet the shared corner joins two separate fans.
  const std::string path = meshPath("tetrahedra_touching.obj");
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_NE(message.find("joins 2 separate fans of triangles: non-manifold vertex"),
            std::string::npos)
      << message;
  std::smatch m;
  ASSERT_TRUE(std::regex_search(message, m, std::regex(R"(vertex (\d+))")));
  EXPECT_EQ(readAndWeld(path).positions.at(std::stoul(m[1])), Vec3(0, 0, 0));
}

TEST(MeshIo, ZeroAreaTriangleIsRejected) {
  const std::string path = meshPath("zero_area.obj");  // triangle 4 has collinear corners
  const std::string message = errorOf([&] { loadClosedMesh(path); });
  EXPECT_NE(message.find(": triangle 4 ("), std::string::npos) << message;
  EXPECT_NE(message.find(") has zero area"), std::string::npos) << message;
}

TEST(MeshIo, ClosedSurfaceWithoutVolumeIsRejected) {
  const std::string path = meshPath("flat_pillow.obj");
  EXPECT_EQ(findManifoldProblem(readAndWeld(path)), std::nullopt);  // topologically fine
  EXPECT_EQ(errorOf([&] { loadClosedMesh(path); }), path + ": the mesh encloses no volume");
}

// --- validation on in-memory meshes
// ---------------------------------------------------------------

TEST(MeshIo, ValidTetrahedronPasses) {
  EXPECT_EQ(findManifoldProblem(unitTetrahedron()), std::nullopt);
  // The zero-area threshold is relative: a tetrahedron a micron across is still fine.
  TriMesh tiny = unitTetrahedron();
  for (Vec3& p : tiny.positions) p *= 1e-6;
  EXPECT_EQ(findManifoldProblem(tiny), std::nullopt);
}

TEST(MeshIo, RepeatedCornerIsZeroArea) {
  TriMesh m = unitTetrahedron();
  m.triangles.push_back({2, 2, 1});
  EXPECT_EQ(findManifoldProblem(m), "triangle 4 (2, 2, 1) has zero area");
}

TEST(MeshIo, IndexOutOfRangeAndUnusedVertex) {
  TriMesh m = unitTetrahedron();
  m.triangles[3] = {1, 2, 9};
  EXPECT_EQ(findManifoldProblem(m),
            "triangle 3 (1, 2, 9) refers to vertex 9, but the mesh has only 4 vertices");
  TriMesh unused = unitTetrahedron();
  unused.positions.push_back({3, 3, 3});
  EXPECT_EQ(findManifoldProblem(unused), "vertex 4 is not used by any triangle");
  EXPECT_EQ(findManifoldProblem(TriMesh{}), "the mesh has no triangles");
}

TEST(MeshIo, EdgeMessagesOnTetrahedron) {
  TriMesh open = unitTetrahedron();
  open.triangles.pop_back();  // remove (1, 2, 3)
  EXPECT_EQ(findManifoldProblem(open), "edge (1, 2) belongs to 1 triangle: the mesh has a hole");
  TriMesh flipped = unitTetrahedron();
  flipped.triangles[3] = {1, 3, 2};
  EXPECT_EQ(
      findManifoldProblem(flipped),
      "edge (2, 1) is traversed twice in the same direction (triangles 0 and 3): flipped face");
}

// --- orientation
// -----------------------------------------------------------------------------------

TEST(MeshIo, InsideOutCubeIsFlipped) {
  const std::string path = meshPath("cube_inside_out.obj");
  TriMesh mesh = readAndWeld(path);
  EXPECT_EQ(findManifoldProblem(mesh), std::nullopt);  // consistent, just the wrong way round
  EXPECT_NEAR(signedVolume(mesh.positions, mesh.triangles), -8.0, 1e-12);
  EXPECT_TRUE(orientOutward(mesh));
  EXPECT_NEAR(signedVolume(mesh.positions, mesh.triangles), 8.0, 1e-12);
  EXPECT_FALSE(orientOutward(mesh));  // already outward now
  EXPECT_EQ(findManifoldProblem(mesh), std::nullopt);

  const TriMesh loaded = loadClosedMesh(path);
  EXPECT_NEAR(signedVolume(loaded.positions, loaded.triangles), 8.0, 1e-12);
}

// --- simplification
// --------------------------------------------------------------------------------

TEST(MeshIo, SimplifySphereKeepsItClosed) {
  const TriMesh sphere = subdividedSphere(5);
  ASSERT_EQ(sphere.positions.size(), 4098u);
  ASSERT_EQ(findManifoldProblem(sphere), std::nullopt);
  const double volumeBefore = signedVolume(sphere.positions, sphere.triangles);

  const TriMesh coarse = simplifyMesh(sphere, 500);
  EXPECT_GE(coarse.positions.size(), 450u);
  EXPECT_LE(coarse.positions.size(), 550u);
  EXPECT_EQ(findManifoldProblem(coarse), std::nullopt);
  EXPECT_EQ(coarse.triangles.size(), 2 * coarse.positions.size() - 4);  // closed genus 0
  const double volumeAfter = signedVolume(coarse.positions, coarse.triangles);
  EXPECT_GT(volumeAfter, 0.9 * volumeBefore);  // still outward and still a sphere
  EXPECT_LT(volumeAfter, 1.02 * volumeBefore);
  for (const Vec3& p : coarse.positions) EXPECT_NEAR(length(p), 1.0, 1e-12);  // original vertices

  // Nothing to do when the target is not below the current count.
  const TriMesh same = simplifyMesh(sphere, 5000);
  EXPECT_EQ(same.positions, sphere.positions);
  EXPECT_EQ(same.triangles, sphere.triangles);
}

TEST(MeshIo, SimplifyRejectsBrokenInput) {
  TriMesh open = unitTetrahedron();
  open.triangles.pop_back();
  EXPECT_NE(errorOf([&] { simplifyMesh(open, 3); }).find("hole"), std::string::npos);
}

// --- the bunny asset
// ---------------------------------------------------------------------------------

TEST(MeshIo, BunnyAssetIsClosedAndOutward) {
  const std::string path = std::string(SPRINGY_SOURCE_DIR) + "/scenes/assets/bunny.ply";
  const TriMesh bunny = loadClosedMesh(path);
  EXPECT_EQ(bunny.positions.size(), 1839u);
  EXPECT_EQ(bunny.triangles.size(), 3674u);
  EXPECT_EQ(bunny.triangles.size(), 2 * bunny.positions.size() - 4);  // genus 0
  EXPECT_GT(signedVolume(bunny.positions, bunny.triangles), 0.0);

  TriMesh asStored = readAndWeld(path);
  EXPECT_FALSE(orientOutward(asStored));  // the file itself is outward-wound

  const TriMesh coarse = simplifyMesh(bunny, 500);
  EXPECT_GE(coarse.positions.size(), 450u);
  EXPECT_LE(coarse.positions.size(), 550u);
  EXPECT_EQ(findManifoldProblem(coarse), std::nullopt);
}

}  // namespace
}  // namespace springy
