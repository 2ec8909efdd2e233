// The jelly at rest (issue 17): scenes/jelly.toml, run to its end as `springy check` runs it,
// still shows its mould's lobes and keeps its volume.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "scene/scene.h"
#include "sim/diagnostics.h"
#include "sim/shapes.h"

namespace springy {
namespace {

// Horizontal distances of the base rim's vertices (mesh vertices 1 .. segments of a mould) from
// their centroid, and how much more the lobes' middles stand out than the creases between them:
// mean radius at the lobe centres (every (segments / lobes)-th vertex from 0) minus the mean at
// the creases (half a lobe further on).
struct Rim {
  double spread = 0.0;     // max - min radius
  double lobeDepth = 0.0;  // mean(lobe centres) - mean(creases)
};
Rim measureRim(const std::vector<Vec3>& x, const BodyInfo& info, int segments, int lobes) {
  std::vector<Vec3> rim;
  for (int k = 0; k < segments; ++k) rim.push_back(x[info.modelVertex[1 + static_cast<std::size_t>(k)]]);
  Vec3 c{0, 0, 0};
  for (const Vec3& p : rim) c += p;
  c = c * (1.0 / static_cast<double>(segments));
  std::vector<double> r;
  for (const Vec3& p : rim) r.push_back(std::hypot(p.x - c.x, p.z - c.z));
  Rim out;
  out.spread = *std::max_element(r.begin(), r.end()) - *std::min_element(r.begin(), r.end());
  const int perLobe = segments / lobes;
  double centres = 0.0, creases = 0.0;
  for (int l = 0; l < lobes; ++l) {
    centres += r[static_cast<std::size_t>(l * perLobe)];
    creases += r[static_cast<std::size_t>(l * perLobe + perLobe / 2)];
  }
  out.lobeDepth = (centres - creases) / lobes;
  return out;
}

TEST(LookJelly, KeepsItsLobesAndVolumeAtRest) {
  SceneDesc scene = loadScene(std::string(SPRINGY_SOURCE_DIR) + "/scenes/jelly.toml");
  World world(buildModel(scene), scene.integrator, stepSize(scene));
  const BodyInfo& info = world.model().bodies[0];
  // The scene's mould: 8 lobes, 32 segments (a change to the scene must change this test).
  const int segments = 32, lobes = 8;
  ASSERT_EQ(info.vertexCount, 12u * 32u + 32u + 2u);
  const Rim start = measureRim(world.positions(), info, segments, lobes);
  ASSERT_GT(start.lobeDepth, 0.05 * 8.5);  // the mould's rim is lobed to begin with
  while (world.time() < scene.duration - 0.5 * world.dt()) world.step();
  const Rim end = measureRim(world.positions(), info, segments, lobes);
  const double volume = measureBody(world, 0).volume / info.restVolume;
  std::printf("rim radius spread %.3f -> %.3f m, lobe depth %.3f -> %.3f m, volume %.4f of rest\n", start.spread,
              end.spread, start.lobeDepth, end.lobeDepth, volume);
  EXPECT_GE(end.spread, 0.5 * start.spread) << "rim radius spread " << start.spread << " -> " << end.spread;
  EXPECT_GE(end.lobeDepth, 0.5 * start.lobeDepth) << "lobe depth " << start.lobeDepth << " -> " << end.lobeDepth;
  EXPECT_NEAR(volume, 1.0, 0.05);
}

}  // namespace
}  // namespace springy
