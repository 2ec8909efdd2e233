// The jelly mould shape (sim/shapes.h makeMould): closed, outward, flat-based and lobed.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "sim/mesh.h"
#include "sim/shapes.h"

namespace springy {
namespace {

TEST(LookMould, ClosedOutwardFlatBasedAndLobed) {
  const double radius = 8.5, height = 10.0;
  const TriMesh m = makeMould(radius, height, 8, 12, 32);
  ASSERT_EQ(m.positions.size(), 12u * 32u + 32u + 2u);
  // Closed and consistently oriented: every directed edge once, its reverse once.
  std::map<std::pair<uint32_t, uint32_t>, int> directed;
  for (const Triangle& t : m.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1);
    EXPECT_EQ(directed.count({e.second, e.first}), 1u);
  }
  EXPECT_GT(signedVolume(m.positions, m.triangles), 0.0);
  const Bounds b = boundsOf(m.positions);
  EXPECT_NEAR(b.hi.y - b.lo.y, height, 1e-9);
  EXPECT_NEAR(b.hi.x - b.lo.x, 2.0 * radius, 0.05 * radius);
  // The base (centre, inner ring, rim) lies flat at the bottom.
  EXPECT_NEAR(m.positions[0].y, b.lo.y, 1e-12);
  for (int k = 0; k < 32; ++k) EXPECT_NEAR(m.positions[1 + static_cast<std::size_t>(k)].y, b.lo.y, 1e-12);
  // Lobes: on the rim, a lobe's middle (vertex 0) stands out from the crease (vertex 2) by
  // 12% of the radius.
  const double r0 = std::hypot(m.positions[1].x, m.positions[1].z), r2 = std::hypot(m.positions[3].x, m.positions[3].z);
  EXPECT_NEAR((r0 - r2) / r0, 0.12, 0.01);
  // Tiers: the upper tier (60% of the height) is narrower than the lower (20%) by a step.
  auto widestAt = [&](double y) {
    double w = 0.0;
    for (const Vec3& p : m.positions)
      if (std::fabs(p.y - b.lo.y - y) < 0.06 * height) w = std::max(w, std::hypot(p.x, p.z));
    return w;
  };
  EXPECT_LT(widestAt(0.65 * height), 0.8 * widestAt(0.2 * height));
}

}  // namespace
}  // namespace springy
