#include "sim/shapes.h"

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <map>
#include <utility>
#include <vector>

namespace springy {
namespace {

uint32_t u32(std::size_t i) { return static_cast<uint32_t>(i); }

// Flips every triangle if the mesh encloses negative volume, so generators need not track
// winding by hand through every symmetry they use.
void orient(TriMesh& m) {
  if (signedVolume(m.positions, m.triangles) < 0.0) {
    for (Triangle& t : m.triangles) std::swap(t[1], t[2]);
  }
}

}  // namespace

TriMesh makeCube(double size, int subdivisions) {
  assert(subdivisions >= 1);
  const int n = subdivisions;
  const double h = 0.5 * size;
  TriMesh m;
  // Shared vertices between faces: index lattice points on the cube surface through a map.
  std::map<std::array<int, 3>, uint32_t> index;
  auto vertex = [&](int i, int j, int k) {
    auto [it, inserted] = index.try_emplace({i, j, k}, u32(m.positions.size()));
    if (inserted) {
      m.positions.push_back({-h + size * i / n, -h + size * j / n, -h + size * k / n});
    }
    return it->second;
  };
  // Each face: a fixed axis at 0 or n, two free axes (a, b) walked in a grid.
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      const int fixed = side * n;
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      for (int p = 0; p < n; ++p) {
        for (int q = 0; q < n; ++q) {
          auto at = [&](int pp, int qq) {
            std::array<int, 3> c{};
            c[static_cast<std::size_t>(axis)] = fixed;
            c[static_cast<std::size_t>(a)] = pp;
            c[static_cast<std::size_t>(b)] = qq;
            return vertex(c[0], c[1], c[2]);
          };
          uint32_t v00 = at(p, q), v10 = at(p + 1, q), v11 = at(p + 1, q + 1), v01 = at(p, q + 1);
          // (a, b, axis) is right-handed, so (v00, v10, v11) faces +axis; flip on the - side.
          if (side == 1) {
            m.triangles.push_back({v00, v10, v11});
            m.triangles.push_back({v00, v11, v01});
          } else {
            m.triangles.push_back({v00, v11, v10});
            m.triangles.push_back({v00, v01, v11});
          }
        }
      }
    }
  }
  return m;
}

TriMesh makeTetrahedron(double edgeLength) {
  // Alternate corners of a cube of side s have edge s*sqrt(2).
  const double s = edgeLength / std::sqrt(2.0) * 0.5;
  TriMesh m;
  m.positions = {{s, s, s}, {s, -s, -s}, {-s, s, -s}, {-s, -s, s}};
  m.triangles = {{0, 1, 2}, {0, 3, 1}, {0, 2, 3}, {1, 3, 2}};
  orient(m);
  return m;
}

TriMesh makeIcosphere(double radius, int level) {
  assert(level >= 0);
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  TriMesh m;
  m.positions = {{-1, t, 0}, {1, t, 0},  {-1, -t, 0}, {1, -t, 0}, {0, -1, t},  {0, 1, t},
                 {0, -1, -t}, {0, 1, -t}, {t, 0, -1},  {t, 0, 1},  {-t, 0, -1}, {-t, 0, 1}};
  m.triangles = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                 {11, 10, 2}, {10, 7, 6}, {7, 1, 8},   {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                 {3, 8, 9},  {4, 9, 5},  {2, 4, 11},  {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
  for (Vec3& p : m.positions) p = normalized(p);
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<uint32_t, uint32_t>, uint32_t> midpoints;  // ordered: deterministic
    auto midpoint = [&](uint32_t a, uint32_t b) {
      auto key = std::minmax(a, b);
      auto [it, inserted] = midpoints.try_emplace({key.first, key.second}, u32(m.positions.size()));
      if (inserted) m.positions.push_back(normalized(m.positions[a] + m.positions[b]));
      return it->second;
    };
    std::vector<Triangle> finer;
    finer.reserve(m.triangles.size() * 4);
    for (const Triangle& tri : m.triangles) {
      uint32_t ab = midpoint(tri[0], tri[1]), bc = midpoint(tri[1], tri[2]), ca = midpoint(tri[2], tri[0]);
      finer.push_back({tri[0], ab, ca});
      finer.push_back({tri[1], bc, ab});
      finer.push_back({tri[2], ca, bc});
      finer.push_back({ab, bc, ca});
    }
    m.triangles = std::move(finer);
  }
  for (Vec3& p : m.positions) p = p * radius;
  orient(m);
  return m;
}

TriMesh makeOctahedronSphere(double radius, int n) {
  assert(n >= 1);
  // Rings of latitude on the octahedron |x| + |y| + |z| = 1, from the top pole (ring 0) to the
  // bottom pole (ring 2n). Ring i holds 4k vertices, k = min(i, 2n - i), spaced 1/n apart
  // along the diamond |x| + |z| = k/n, starting on +x and turning toward +z.
  TriMesh m;
  std::vector<uint32_t> ringStart(static_cast<std::size_t>(2 * n + 1));
  auto ringCount = [n](int i) { int k = std::min(i, 2 * n - i); return k == 0 ? 1 : 4 * k; };
  for (int i = 0; i <= 2 * n; ++i) {
    ringStart[static_cast<std::size_t>(i)] = u32(m.positions.size());
    const int k = std::min(i, 2 * n - i);
    const double y = 1.0 - static_cast<double>(i) / n;
    if (k == 0) {
      m.positions.push_back({0.0, y, 0.0});
      continue;
    }
    for (int q = 0; q < 4; ++q) {
      for (int j = 0; j < k; ++j) {
        double a = static_cast<double>(k - j) / n, b = static_cast<double>(j) / n;  // quadrant 0: +x -> +z
        Vec3 p;
        switch (q) {
          case 0: p = {a, y, b}; break;
          case 1: p = {-b, y, a}; break;
          case 2: p = {-a, y, -b}; break;
          default: p = {b, y, -a}; break;
        }
        m.positions.push_back(p);
      }
    }
  }
  auto at = [&](int ring, int idx) {
    const int count = ringCount(ring);
    return ringStart[static_cast<std::size_t>(ring)] + u32(static_cast<std::size_t>(((idx % count) + count) % count));
  };
  // Strips between a ring with a vertices per quadrant (u) and one with a + 1 (w).
  auto strip = [&](int u, int w, int a, bool flip) {
    for (int q = 0; q < 4; ++q) {
      auto U = [&](int j) { return a == 0 ? at(u, 0) : at(u, q * a + j); };
      auto W = [&](int j) { return at(w, q * (a + 1) + j); };
      auto add = [&](uint32_t p0, uint32_t p1, uint32_t p2) {
        if (flip) m.triangles.push_back({p0, p2, p1}); else m.triangles.push_back({p0, p1, p2});
      };
      for (int j = 0; j <= a; ++j) add(U(j), W(j + 1), W(j));
      for (int j = 0; j < a; ++j) add(U(j), U(j + 1), W(j + 1));
    }
  };
  for (int i = 0; i < n; ++i) {
    strip(i, i + 1, i, false);                  // upper hemisphere
    strip(2 * n - i, 2 * n - i - 1, i, true);   // its mirror image below the equator
  }
  for (Vec3& p : m.positions) p = normalized(p) * radius;
  orient(m);
  return m;
}

namespace {
// The side of a body of revolution between segment k and k + 1: two triangles per pair of
// neighbouring rings, ring(r, k) the vertex of ring r at segment k (k wraps).
template <class Ring>
void addSideColumn(TriMesh& m, const Ring& ring, int rings, int k) {
  for (int r = 0; r + 1 < rings; ++r) {
    m.triangles.push_back({ring(r, k), ring(r + 1, k), ring(r + 1, k + 1)});
    m.triangles.push_back({ring(r, k), ring(r + 1, k + 1), ring(r, k + 1)});
  }
}
}  // namespace

TriMesh makeJelly(double radius, double height, int ridges, int rings, int segments) {
  assert(rings >= 2 && segments >= 3);
  // Profile: radius as a function of height fraction s in [0, 1] (0 = base, 1 = top centre).
  // The side narrows slightly upward and rounds over into a domed top.
  auto profileRadius = [&](double s) {
    const double side = 0.75;  // fraction of the height that is the fluted side
    if (s <= side) return radius * (1.0 - 0.18 * s / side);
    const double u = (s - side) / (1.0 - side);  // 0..1 across the dome
    return radius * 0.82 * std::sqrt(std::fmax(0.0, 1.0 - u * u));
  };
  auto profileHeight = [&](double s) {
    const double side = 0.75;
    if (s <= side) return height * 0.8 * s / side;
    const double u = (s - side) / (1.0 - side);
    return height * (0.8 + 0.2 * std::sin(u * kPi / 2));
  };
  TriMesh m;
  const uint32_t bottomCentre = 0;
  m.positions.push_back({0.0, 0.0, 0.0});
  // rings 0..rings-1 around the axis (ring 0 at the base rim), then the top centre.
  for (int r = 0; r < rings; ++r) {
    const double s = static_cast<double>(r) / rings;
    const double baseR = profileRadius(s), y = profileHeight(s);
    for (int k = 0; k < segments; ++k) {
      const double phi = 2.0 * kPi * k / segments;
      // Vertical ridges (flutes) fade out over the dome; the rim waves along the base.
      const double fade = s < 0.75 ? 1.0 : std::fmax(0.0, 1.0 - (s - 0.75) / 0.25);
      const double rr = baseR * (1.0 + 0.08 * fade * std::cos(ridges * phi));
      const double wave = (r == 0 ? 0.0 : 0.03 * height * fade * std::sin(ridges * phi) * s);
      m.positions.push_back({rr * std::cos(phi), y + wave, rr * std::sin(phi)});
    }
  }
  const uint32_t topCentre = u32(m.positions.size());
  m.positions.push_back({0.0, height, 0.0});
  auto ring = [&](int r, int k) { return 1u + u32(static_cast<std::size_t>(r * segments + (k % segments))); };
  for (int k = 0; k < segments; ++k) {
    m.triangles.push_back({bottomCentre, ring(0, k), ring(0, k + 1)});
    addSideColumn(m, ring, rings, k);
    m.triangles.push_back({ring(rings - 1, k), topCentre, ring(rings - 1, k + 1)});
  }
  orient(m);
  // Centre on the bounding box.
  const Vec3 c = boundsOf(m.positions).center();
  for (Vec3& p : m.positions) p -= c;
  return m;
}

TriMesh makeMould(double radius, double height, int lobes, int rings, int segments) {
  assert(rings >= 2 && segments >= 3);
  // The profile: (height, radius) as fractions of height and radius, from the base rim over
  // the tiers to the top centre; interpolated by Catmull-Rom and resampled by arc length.
  static const double kProfile[][2] = {{0.00, 0.90}, {0.04, 0.98}, {0.12, 1.00}, {0.30, 0.97},
                                       {0.42, 0.92},                                             // lower tier
                                       {0.48, 0.86}, {0.52, 0.76}, {0.55, 0.70},                 // shoulder
                                       {0.62, 0.68}, {0.74, 0.65}, {0.82, 0.60},                 // upper tier
                                       {0.89, 0.50}, {0.95, 0.34}, {0.99, 0.14}, {1.00, 0.00}};  // crown
  constexpr int kPoints = static_cast<int>(sizeof kProfile / sizeof kProfile[0]);
  auto point = [&](int i) {
    i = std::clamp(i, 0, kPoints - 1);
    return std::array<double, 2>{kProfile[i][0] * height, kProfile[i][1] * radius};
  };
  std::vector<std::array<double, 2>> dense;  // (y, r)
  for (int i = 0; i + 1 < kPoints; ++i) {
    const auto p0 = point(i - 1), p1 = point(i), p2 = point(i + 1), p3 = point(i + 2);
    for (int k = 0; k < 32; ++k) {
      const double t = k / 32.0, t2 = t * t, t3 = t2 * t;
      std::array<double, 2> q;
      for (int c = 0; c < 2; ++c) {
        q[c] = 0.5 * (2 * p1[c] + (p2[c] - p0[c]) * t + (2 * p0[c] - 5 * p1[c] + 4 * p2[c] - p3[c]) * t2 +
                      (3 * p1[c] - p0[c] - 3 * p2[c] + p3[c]) * t3);
      }
      dense.push_back(q);
    }
  }
  dense.push_back(point(kPoints - 1));
  std::vector<double> arc(dense.size(), 0.0);
  for (std::size_t i = 1; i < dense.size(); ++i) {
    arc[i] = arc[i - 1] + std::hypot(dense[i][0] - dense[i - 1][0], dense[i][1] - dense[i - 1][1]);
  }
  auto at = [&](double s) {  // (y, r) at arc length s
    const auto it = std::lower_bound(arc.begin(), arc.end(), s);
    const std::size_t i = std::clamp<std::size_t>(static_cast<std::size_t>(it - arc.begin()), 1, arc.size() - 1);
    const double f = (s - arc[i - 1]) / std::max(arc[i] - arc[i - 1], 1e-12);
    return std::array<double, 2>{dense[i - 1][0] + f * (dense[i][0] - dense[i - 1][0]),
                                 dense[i - 1][1] + f * (dense[i][1] - dense[i - 1][1])};
  };
  auto lobed = [&](double r, double y, double phi) {
    const double crown = std::clamp((y / height - 0.86) / 0.1, 0.0, 1.0);
    const double a = 0.12 * (1.0 - crown * crown * (3 - 2 * crown));
    return r * (1.0 - a + a * std::sqrt(std::fabs(std::cos(0.5 * lobes * phi))));
  };
  TriMesh m;
  m.positions.push_back({0.0, 0.0, 0.0});  // base centre; then ring 0 (the base rim) upwards
  for (int r = 0; r < rings; ++r) {
    const auto [y, rr] = at(arc.back() * r / rings);
    for (int k = 0; k < segments; ++k) {
      const double phi = 2.0 * kPi * k / segments;
      const double rl = lobed(rr, y, phi);
      m.positions.push_back({rl * std::cos(phi), y, rl * std::sin(phi)});
    }
  }
  const uint32_t inner = u32(m.positions.size());
  for (int k = 0; k < segments; ++k) {  // the base's inner ring, half the rim's radius
    const Vec3& rim = m.positions[1 + static_cast<std::size_t>(k)];
    m.positions.push_back({0.5 * rim.x, 0.0, 0.5 * rim.z});
  }
  const uint32_t top = u32(m.positions.size());
  m.positions.push_back({0.0, height, 0.0});
  auto ring = [&](int r, int k) { return 1u + u32(static_cast<std::size_t>(r * segments + (k % segments))); };
  auto innerAt = [&](int k) { return inner + u32(static_cast<std::size_t>(k % segments)); };
  for (int k = 0; k < segments; ++k) {
    m.triangles.push_back({0, innerAt(k), innerAt(k + 1)});
    m.triangles.push_back({innerAt(k), ring(0, k), ring(0, k + 1)});
    m.triangles.push_back({innerAt(k), ring(0, k + 1), innerAt(k + 1)});
    addSideColumn(m, ring, rings, k);
    m.triangles.push_back({ring(rings - 1, k), top, ring(rings - 1, k + 1)});
  }
  orient(m);
  const Vec3 c = boundsOf(m.positions).center();
  for (Vec3& p : m.positions) p -= c;
  return m;
}

TriMesh makeCloth(double width, double depth, int columns, int rows) {
  assert(columns >= 1 && rows >= 1);
  TriMesh m;
  const auto n = static_cast<std::size_t>(columns), k = static_cast<std::size_t>(rows);
  m.positions.reserve((n + 1) * (k + 1));
  for (std::size_t j = 0; j <= k; ++j) {
    for (std::size_t i = 0; i <= n; ++i) {
      m.positions.push_back({-0.5 * width + width * static_cast<double>(i) / static_cast<double>(n), 0.0,
                             -0.5 * depth + depth * static_cast<double>(j) / static_cast<double>(k)});
    }
  }
  m.triangles.reserve(2 * n * k);
  auto at = [n](std::size_t i, std::size_t j) { return u32(i + (n + 1) * j); };
  for (std::size_t j = 0; j < k; ++j) {
    for (std::size_t i = 0; i < n; ++i) {
      const uint32_t v00 = at(i, j), v10 = at(i + 1, j), v01 = at(i, j + 1), v11 = at(i + 1, j + 1);
      // (x along i, z along j): (v00, v01, v11) turns counter-clockwise seen from +y.
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({v00, v01, v11});
        m.triangles.push_back({v00, v11, v10});
      } else {
        m.triangles.push_back({v00, v01, v10});
        m.triangles.push_back({v10, v01, v11});
      }
    }
  }
  return m;
}

}  // namespace springy
