// Meshes as a user brings them: made here the way common primitive generators and modelling
// tools make them (UV spheres with pole fans, capsules, rounded boxes, tori, ellipsoids, cones,
// each with its vertices duplicated along seams as OBJ exporters write them), and broken ones
// (a hole, overlapping pieces, a flipped face, a non-manifold fin, a mesh far finer than a body
// needs). Each is a body given only mesh, scale, position and mass over one ground plane, run
// as a user runs it: `springy check` on the step springy chooses keeps at least 70% of the
// body's volume through a 2 m drop and ends at 85% or more, and `springy frames` draws it.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "render/image.h"
#include "run_springy.h"
#include "sim/vec3.h"

namespace springy {
namespace {

namespace fs = std::filesystem;
using test::runSpringy;

// A triangle soup written as OBJ: every triangle has its own three corners, as many exporters
// write seams; springy welds equal positions.
struct Soup {
  std::vector<Vec3> corners;  // three per triangle
  void add(const Vec3& a, const Vec3& b, const Vec3& c) { corners.insert(corners.end(), {a, b, c}); }
  void quad(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {  // counter-clockwise
    add(a, b, c);
    add(a, c, d);
  }
  void write(const fs::path& path) const {
    std::ofstream out(path);
    out.precision(17);
    for (const Vec3& p : corners) out << "v " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    for (std::size_t t = 0; t < corners.size(); t += 3) out << "f " << t + 1 << ' ' << t + 2 << ' ' << t + 3 << '\n';
  }
};

// A surface of revolution about y from a profile (radius, height) running from the bottom pole
// to the top pole: UV spheres, capsules, ellipsoids and cones alike, with fans at the poles.
Soup revolve(const std::vector<std::pair<double, double>>& profile, int segments) {
  Soup s;
  auto at = [&](std::size_t k, int j) {
    const double phi = 2 * kPi * j / segments;
    return Vec3{profile[k].first * std::cos(phi), profile[k].second, -profile[k].first * std::sin(phi)};
  };
  for (std::size_t k = 0; k + 1 < profile.size(); ++k) {
    for (int j = 0; j < segments; ++j) {
      const Vec3 a = at(k, j), b = at(k, j + 1), c = at(k + 1, j + 1), d = at(k + 1, j);
      if (profile[k].first == 0.0) s.add(a, c, d);  // fan at the bottom pole
      else if (profile[k + 1].first == 0.0) s.add(a, b, c);  // fan at the top pole
      else s.quad(a, b, c, d);
    }
  }
  return s;
}

Soup uvSphere(int segments, int rings, Vec3 radii = {1, 1, 1}) {
  std::vector<std::pair<double, double>> profile;
  for (int k = 0; k <= rings; ++k) {
    const double theta = kPi * k / rings;  // from the bottom
    profile.push_back({k == 0 || k == rings ? 0.0 : std::sin(theta), -std::cos(theta)});
  }
  Soup s = revolve(profile, segments);
  for (Vec3& p : s.corners) p = {p.x * radii.x, p.y * radii.y, p.z * radii.z};
  return s;
}

Soup capsule(double radius, double length, int segments, int rings) {
  std::vector<std::pair<double, double>> profile;
  for (int k = 0; k <= rings; ++k) {  // bottom half sphere, then the top one raised by length
    const double theta = kPi * k / rings;
    const double r = k == 0 || k == rings ? 0.0 : radius * std::sin(theta);
    const double y = -radius * std::cos(theta) + (k > rings / 2 ? length : 0.0);
    profile.push_back({r, y});
    if (k == rings / 2) profile.push_back({r, y + length});
  }
  return revolve(profile, segments);
}

Soup cone(double radius, double height, int segments) {
  // A base disc fanned about its centre and a side fanned to the apex.
  return revolve({{0.0, 0.0}, {radius, 0.0}, {0.0, height}}, segments);
}

Soup torus(double major, double minor, int around, int tube) {
  Soup s;
  auto at = [&](int i, int j) {
    const double u = 2 * kPi * i / around, v = 2 * kPi * j / tube;
    const double r = major + minor * std::cos(v);
    return Vec3{r * std::cos(u), minor * std::sin(v), -r * std::sin(u)};
  };
  for (int i = 0; i < around; ++i) {
    for (int j = 0; j < tube; ++j) s.quad(at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  }
  return s;
}

Soup roundedBox(Vec3 half, double radius, int n) {
  // A cube's six faces as n x n grids, each point pushed onto the rounded box: the nearest
  // point of the inner box plus radius along the way out.
  Soup s;
  const Vec3 inner{half.x - radius, half.y - radius, half.z - radius};
  auto round = [&](Vec3 p) {
    const Vec3 q{std::clamp(p.x, -inner.x, inner.x), std::clamp(p.y, -inner.y, inner.y), std::clamp(p.z, -inner.z, inner.z)};
    const Vec3 d = p - q;
    return q + d * (radius / length(d));
  };
  for (int axis = 0; axis < 3; ++axis) {
    for (int sign = -1; sign <= 1; sign += 2) {
      auto point = [&](int i, int j) {
        const double a = -1.0 + 2.0 * i / n, b = -1.0 + 2.0 * j / n;
        Vec3 p;
        p[axis] = sign;
        p[(axis + 1) % 3] = a * sign;
        p[(axis + 2) % 3] = b;
        return round(Vec3{p.x * half.x, p.y * half.y, p.z * half.z});
      };
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) s.quad(point(i, j), point(i + 1, j), point(i + 1, j + 1), point(i, j + 1));
      }
    }
  }
  return s;
}

double lowestY(const Soup& s) {
  double y = INFINITY;
  for (const Vec3& p : s.corners) y = std::min(y, p.y);
  return y;
}

struct Case {
  std::string name;
  std::function<Soup()> make;
  double scale = 1.0;
  double mass = 1.0;
};

class Corpus : public ::testing::TestWithParam<Case> {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("springy_corpus_" + std::to_string(::getpid()) + "_" + GetParam().name);
    fs::create_directories(dir_);
  }
  // SPRINGY_CORPUS_KEEP=1 keeps the meshes, scenes and stills (to look at them).
  void TearDown() override {
    if (!std::getenv("SPRINGY_CORPUS_KEEP")) fs::remove_all(dir_);
  }
  fs::path dir_;
};

TEST_P(Corpus, DropsKeepsItsShapeAndRenders) {
  const Case& c = GetParam();
  const Soup soup = c.make();
  soup.write(dir_ / "mesh.obj");
  // Its lowest point 2 m above the ground.
  const double y = 2.0 - c.scale * lowestY(soup);
  std::ostringstream scene;
  scene << "[scene]\nduration = 2.5\n[[body]]\nshape = \"mesh\"\nmesh = \"mesh.obj\"\nscale = " << c.scale
        << "\nposition = [0.0, " << y << ", 0.0]\nmass = " << c.mass
        << "\n[[plane]]\n[render]\nwidth = 320\nheight = 180\nfps = 10\n";
  std::ofstream(dir_ / "scene.toml") << scene.str();
  const std::string file = (dir_ / "scene.toml").string();

  const auto checked = runSpringy("check " + file + " --min-volume 0.7 --end-volume 0.85");
  EXPECT_EQ(checked.status, 0) << checked.output;
  // springy chose the step and said so.
  EXPECT_NE(checked.output.find("the scene gives none, so the advisor's"), std::string::npos) << checked.output;

  const auto drawn = runSpringy("frames " + file + " --times 0.75 --no-overlay -o " + dir_.string());
  ASSERT_EQ(drawn.status, 0) << drawn.output;
  // The body is in the picture: the default body colour is red, the ground and sky are not.
  const render::Image image = render::readPng((dir_ / "scene_t000.75.png").string());
  int red = 0;
  for (std::size_t i = 0; i < image.rgba.size(); i += 4) {
    if (image.rgba[i] > 100 && image.rgba[i] > 2 * image.rgba[i + 1] && image.rgba[i] > 2 * image.rgba[i + 2]) ++red;
  }
  EXPECT_GT(red, image.width * image.height / 200) << "the body is not drawn";
}

Soup withHole() {
  Soup s = uvSphere(24, 12);
  s.corners.erase(s.corners.begin() + 3 * 100, s.corners.begin() + 3 * 104);  // four faces out
  return s;
}
Soup overlappingPieces() {
  Soup s = uvSphere(24, 12);
  Soup other = uvSphere(24, 12);
  for (Vec3& p : other.corners) p += Vec3{0.8, 0.3, 0.0};
  s.corners.insert(s.corners.end(), other.corners.begin(), other.corners.end());
  return s;
}
Soup flippedFace() {
  Soup s = uvSphere(24, 12);
  std::swap(s.corners[3 * 150 + 1], s.corners[3 * 150 + 2]);
  return s;
}
Soup withFin() {
  Soup s = uvSphere(24, 12);
  // A triangle on an existing edge, sticking out: that edge then borders three triangles.
  const Vec3 a = s.corners[3 * 150], b = s.corners[3 * 150 + 1];
  const Vec3 mid = (a + b) * 0.5;
  s.add(a, b, mid * 1.6);
  return s;
}
Soup finerThanNeeded() {
  // 100 times the vertices a body needs: a UV sphere of 400 x 200 (about 80k vertices).
  return uvSphere(400, 200);
}

INSTANTIATE_TEST_SUITE_P(
    UserMeshes, Corpus,
    ::testing::Values(Case{"uv_sphere_coarse", [] { return uvSphere(16, 8); }, 1.0, 1.0},
                      Case{"uv_sphere_fine", [] { return uvSphere(64, 32); }, 0.5, 0.3},
                      Case{"capsule", [] { return capsule(0.5, 1.0, 24, 12); }, 1.0, 2.0},
                      Case{"rounded_box", [] { return roundedBox({1.0, 0.6, 0.8}, 0.2, 8); }, 1.0, 5.0},
                      Case{"torus", [] { return torus(1.0, 0.35, 48, 16); }, 1.0, 1.0},
                      Case{"ellipsoid", [] { return uvSphere(32, 16, {1.5, 0.7, 1.0}); }, 1.0, 2.0},
                      Case{"cone", [] { return cone(1.0, 1.5, 32); }, 1.0, 1.0},
                      Case{"finer_than_needed", finerThanNeeded, 1.0, 1.0},
                      Case{"hole", withHole, 1.0, 1.0},
                      Case{"overlapping_pieces", overlappingPieces, 1.0, 1.0},
                      Case{"flipped_face", flippedFace, 1.0, 1.0},
                      Case{"fin", withFin, 1.0, 1.0}),
    [](const ::testing::TestParamInfo<Case>& p) { return p.param.name; });

}  // namespace
}  // namespace springy
