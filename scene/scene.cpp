#include "scene/scene.h"

#include <toml++/toml.h>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <optional>
#include <sstream>

#include "sim/error.h"
#include "sim/limits.h"
#include "mesh/mesh_io.h"
#include "mesh/proxy.h"
#include "sim/shapes.h"

namespace springy {
namespace {

std::string location(const std::string& path, const toml::source_region& r) {
  return path + ":" + std::to_string(r.begin.line) + ":" + std::to_string(r.begin.column);
}

// A value as TOML writes it ([1, 0, 1], 0.5), for messages that quote a key.
std::string tomlText(const toml::node& node) {
  std::ostringstream text;
  if (const toml::array* a = node.as_array()) {
    text << "[";
    for (std::size_t i = 0; i < a->size(); ++i) text << (i ? ", " : "") << tomlText(*a->get(i));
    text << "]";
  } else if (const auto* d = node.as_floating_point()) {
    text << d->get();
  } else if (const auto* n = node.as_integer()) {
    text << n->get();
  } else if (const auto* str = node.as_string()) {
    text << '"' << str->get() << '"';
  } else {
    text << "...";
  }
  return text.str();
}

// Reads the keys of one table, remembering which were read, so that finish() can reject the
// rest as unknown (pbrt's ReportUnused). Every error carries file:line:column and the key.
class Reader {
 public:
  Reader(const toml::table& table, const std::string& path, std::string section)
      : table_(table), path_(path), section_(std::move(section)) {}

  [[noreturn]] void fail(const toml::node& node, std::string_view key, const std::string& message) const {
    throw Error(location(path_, node.source()) + ": " + section_ + " key '" + std::string(key) + "': " + message);
  }
  [[noreturn]] void failHere(const std::string& message) const {
    throw Error(location(path_, table_.source()) + ": " + section_ + ": " + message);
  }

  const toml::node* get(std::string_view key) {
    used_.push_back(std::string(key));
    return table_.get(key);
  }
  bool has(std::string_view key) const { return table_.contains(key); }

  double number(std::string_view key, double fallback) {
    const toml::node* n = get(key);
    return n ? asNumber(*n, key) : fallback;
  }
  std::optional<double> optionalInRange(std::string_view key, double lo, double hi) {
    if (!has(key)) {
      get(key);
      return std::nullopt;
    }
    return inRange(key, 0.0, lo, hi);
  }
  double positive(std::string_view key, double fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const double value = asNumber(*n, key);
    if (!(value > 0.0)) fail(*n, key, "must be positive, got " + format(value));
    return value;
  }
  double inRange(std::string_view key, double fallback, double lo, double hi) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const double value = asNumber(*n, key);
    if (!(value >= lo && value <= hi))
      fail(*n, key, "must be in [" + format(lo) + ", " + format(hi) + "], got " + format(value));
    return value;
  }
  int integer(std::string_view key, int fallback, int lo, int hi) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const auto* v = n->as_integer();
    if (!v) fail(*n, key, "must be an integer");
    if (v->get() < lo || v->get() > hi) {
      fail(
          *n, key,
          "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + std::to_string(v->get()));
    }
    return static_cast<int>(v->get());
  }
  bool boolean(std::string_view key, bool fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const auto* v = n->as_boolean();
    if (!v) fail(*n, key, "must be true or false");
    return v->get();
  }
  std::string string(std::string_view key, const std::string& fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const auto* v = n->as_string();
    if (!v) fail(*n, key, "must be a string");
    return v->get();
  }
  // One of a fixed set of words.
  std::string choice(std::string_view key, const std::string& fallback, const std::vector<std::string>& options) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    const auto* v = n->as_string();
    std::string all;
    for (const std::string& o : options) all += (all.empty() ? "" : ", ") + o;
    if (!v) fail(*n, key, "must be one of: " + all);
    if (std::find(options.begin(), options.end(), v->get()) == options.end()) {
      fail(*n, key, "'" + v->get() + "' is not one of: " + all);
    }
    return v->get();
  }
  Vec3 vec3(std::string_view key, const Vec3& fallback) {
    const toml::node* n = get(key);
    return n ? asVec3(*n, key) : fallback;
  }
  std::optional<Vec3> optionalVec3(std::string_view key) {
    const toml::node* n = get(key);
    return n ? std::optional<Vec3>(asVec3(*n, key)) : std::nullopt;
  }
  Vec3 color(std::string_view key, const Vec3& fallback) {
    const toml::node* n = get(key);
    if (!n) return fallback;
    // A grey level or [r, g, b], each in [0, 1].
    Vec3 c = n->is_number() ? Vec3{asNumber(*n, key), asNumber(*n, key), asNumber(*n, key)} : asVec3(*n, key);
    for (int i = 0; i < 3; ++i) {
      if (!(c[i] >= 0.0 && c[i] <= 1.0)) fail(*n, key, "colour components must be in [0, 1]");
    }
    return c;
  }
  const toml::table* subtable(std::string_view key) {
    const toml::node* n = get(key);
    if (!n) return nullptr;
    if (!n->is_table()) fail(*n, key, "must be a table");
    return n->as_table();
  }

  double asNumber(const toml::node& n, std::string_view key) const {
    if (const auto* d = n.as_floating_point()) return finite(n, key, d->get());
    if (const auto* i = n.as_integer()) return static_cast<double>(i->get());
    fail(n, key, "must be a number");
  }
  Vec3 asVec3(const toml::node& n, std::string_view key) const {
    const auto* a = n.as_array();
    if (!a || a->size() != 3) fail(n, key, "must be an array of three numbers [x, y, z]");
    return {asNumber(*a->get(0), key), asNumber(*a->get(1), key), asNumber(*a->get(2), key)};
  }

  // Rejects every key that was not read.
  void finish() const {
    for (auto&& [k, node] : table_) {
      if (std::find(used_.begin(), used_.end(), k.str()) == used_.end()) {
        throw Error(location(path_, k.source()) + ": unknown key '" + std::string(k.str()) + "' in " + section_ +
                    " (see scenes/README.md for the keys)");
      }
    }
  }

  const std::string& path() const { return path_; }

 private:
  double finite(const toml::node& n, std::string_view key, double v) const {
    if (!std::isfinite(v)) fail(n, key, "must be finite");
    return v;
  }
  static std::string format(double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  }

  const toml::table& table_;
  const std::string& path_;
  std::string section_;
  std::vector<std::string> used_;
};

// Euler angles in degrees, applied as in the original Unity scenes: z, then x, then y.
Vec3 rotate(const Vec3& p, const Vec3& degrees) {
  const double rx = degrees.x * kPi / 180, ry = degrees.y * kPi / 180, rz = degrees.z * kPi / 180;
  Vec3 q{p.x * std::cos(rz) - p.y * std::sin(rz), p.x * std::sin(rz) + p.y * std::cos(rz), p.z};
  q = {q.x, q.y * std::cos(rx) - q.z * std::sin(rx), q.y * std::sin(rx) + q.z * std::cos(rx)};
  return {q.x * std::cos(ry) + q.z * std::sin(ry), q.y, -q.x * std::sin(ry) + q.z * std::cos(ry)};
}

struct Transform {
  Vec3 scale{1, 1, 1}, rotation, position;
  Vec3 apply(const Vec3& p) const { return rotate({p.x * scale.x, p.y * scale.y, p.z * scale.z}, rotation) + position; }
};

Transform readTransform(Reader& r) {
  Transform t;
  if (const toml::node* n = r.get("scale")) {
    if (n->is_number()) {
      const double s = r.asNumber(*n, "scale");
      t.scale = {s, s, s};
    } else {
      t.scale = r.asVec3(*n, "scale");
    }
    if (!(t.scale.x > 0 && t.scale.y > 0 && t.scale.z > 0)) r.fail(*n, "scale", "must be positive");
  }
  t.rotation = r.vec3("rotation", {});
  t.position = r.vec3("position", {});
  return t;
}

std::string resolvePath(const std::string& scenePath, const std::string& file) {
  std::filesystem::path p(file);
  if (p.is_absolute()) return file;
  return (std::filesystem::path(scenePath).parent_path() / p).lexically_normal().string();
}

Material readMaterial(Reader& r, const Material& fallback) {
  Material m = fallback;
  m.color = r.color("color", fallback.color);
  m.alpha = r.inRange("alpha", fallback.alpha, 0.0, 1.0);
  m.shininess = r.positive("shininess", fallback.shininess);
  m.flat = r.boolean("flat_shading", fallback.flat);
  return m;
}

ContactMaterial readContact(Reader& r) {
  ContactMaterial c;
  c.restitution = r.inRange("restitution", c.restitution, 0.0, 1.0);
  c.friction = r.inRange("friction", c.friction, 0.0, 100.0);
  return c;
}

const toml::array* arrayOfTables(const toml::table& root, std::string_view key, const std::string& path) {
  const toml::node* n = root.get(key);
  if (!n) return nullptr;
  const auto* a = n->as_array();
  if (!a || !a->is_array_of_tables()) {
    throw Error(location(path, n->source()) + ": '" + std::string(key) + "' must be an array of tables ([[" +
                std::string(key) + "]])");
  }
  return a;
}

// Pin rules a user can write without knowing vertex indices: a side of the body's bounding box,
// the axis (x 0, y 1, z 2) and whether it is the high end.
struct SideRule {
  const char* name;
  int axis;
  bool highest;
};
constexpr SideRule kSideRules[] = {{"top", 1, true},   {"bottom", 1, false}, {"right", 0, true},
                                   {"left", 0, false}, {"front", 2, false},  {"back", 2, true}};
constexpr const char* kSideRuleNames = "top, bottom, left, right, front, back";

const SideRule* findSideRule(const std::string& name) {
  for (const SideRule& rule : kSideRules) {
    if (name == rule.name) return &rule;
  }
  return nullptr;
}

// Two positive numbers [a, b], or one number for both.
std::array<double, 2> positivePair(Reader& r, std::string_view key, std::array<double, 2> fallback) {
  const toml::node* n = r.get(key);
  if (!n) return fallback;
  std::array<double, 2> out{};
  if (n->is_number()) {
    out[0] = out[1] = r.asNumber(*n, key);
  } else {
    const auto* a = n->as_array();
    if (!a || a->size() != 2) r.fail(*n, key, "must be a number or an array of two numbers [a, b]");
    out = {r.asNumber(*a->get(0), key), r.asNumber(*a->get(1), key)};
  }
  if (!(out[0] > 0.0 && out[1] > 0.0)) r.fail(*n, key, "must be positive");
  return out;
}

// Two integers [a, b] in [lo, hi], or one for both.
std::array<int, 2> integerPair(Reader& r, std::string_view key, std::array<int, 2> fallback, int lo, int hi) {
  const toml::node* n = r.get(key);
  if (!n) return fallback;
  const auto* a = n->as_array();
  if (!n->is_integer() && (!a || a->size() != 2)) {
    r.fail(*n, key, "must be an integer or an array of two integers [a, b]");
  }
  std::array<int, 2> out{};
  for (std::size_t k = 0; k < 2; ++k) {
    const toml::node& item = a ? *a->get(k) : *n;
    const auto* v = item.as_integer();
    if (!v) r.fail(item, key, "must be an integer or an array of two integers [a, b]");
    if (v->get() < lo || v->get() > hi) {
      r.fail(
          item, key,
          "must be between " + std::to_string(lo) + " and " + std::to_string(hi) + ", got " + std::to_string(v->get()));
    }
    out[k] = static_cast<int>(v->get());
  }
  return out;
}

uint32_t extremeVertex(const TriMesh& mesh, int axis, bool highest) {
  uint32_t best = 0;
  for (uint32_t i = 1; i < mesh.positions.size(); ++i) {
    const double a = mesh.positions[i][axis], b = mesh.positions[best][axis];
    if (highest ? a > b : a < b) best = i;
  }
  return best;
}

// A motion table (sim/motion.h): [SECTION.motion] of a plane or a triangle collider,
// [body.pin_motion] of a body's pins.
//   keys = [[t, x, y, z], ...]       translation keyframes, times strictly increasing
//   interpolation = "linear" | "cubic"
//   oscillate = [ax, ay, az], frequency = F [Hz], phase = P [deg]
//   spin = S [deg/s], axis = [x, y, z], centre = [x, y, z]
Movement readMotion(const toml::table& table, const std::string& path, const std::string& section) {
  Reader r(table, path, section);
  Movement m;
  if (const toml::node* n = r.get("keys")) {
    const auto* a = n->as_array();
    if (!a || a->empty()) r.fail(*n, "keys", "must be an array of keyframes [[t, x, y, z], ...]");
    for (const toml::node& item : *a) {
      const auto* k = item.as_array();
      if (!k || k->size() != 4) r.fail(item, "keys", "each keyframe is [t, x, y, z]: a time [s] and an offset [m]");
      Movement::Key key{r.asNumber(*k->get(0), "keys"),
                      {r.asNumber(*k->get(1), "keys"), r.asNumber(*k->get(2), "keys"), r.asNumber(*k->get(3), "keys")}};
      if (!m.keys.empty() && !(key.time > m.keys.back().time)) {
        r.fail(item, "keys", "keyframe times must increase (" + std::to_string(key.time) + " s after " +
                                 std::to_string(m.keys.back().time) + " s)");
      }
      m.keys.push_back(key);
    }
  }
  m.cubic = r.choice("interpolation", "linear", {"linear", "cubic"}) == "cubic";
  m.amplitude = r.vec3("oscillate", {});
  m.frequency = r.inRange("frequency", 0.0, 0.0, 1e4);
  m.phase = r.inRange("phase", 0.0, -3600.0, 3600.0) * 3.14159265358979323846 / 180.0;
  if ((m.frequency > 0.0) != (length(m.amplitude) > 0.0)) {
    r.failHere("an oscillation needs both oscillate (its amplitude, m) and frequency (Hz)");
  }
  m.spin = r.inRange("spin", 0.0, -1e5, 1e5) * 3.14159265358979323846 / 180.0;
  if (const toml::node* n = r.get("axis")) {
    const Vec3 axis = r.asVec3(*n, "axis");
    if (!(length(axis) > 0.0)) r.fail(*n, "axis", "must not be zero");
    m.axis = normalized(axis);
  }
  m.centre = r.vec3("centre", {});
  r.finish();
  if (!m.moves()) r.failHere("does not move: give keys (two or more), oscillate and frequency, or spin");
  return m;
}

// The mesh vertex nearest a point (the lowest index among equals), searched outward from the
// point's x in the vertices sorted by x: a few vertices per point instead of all of them.
class NearestVertex {
 public:
  explicit NearestVertex(const std::vector<Vec3>& x) : x_(x), byX_(x.size()) {
    for (uint32_t i = 0; i < x.size(); ++i) byX_[i] = {x[i].x, i};
    std::sort(byX_.begin(), byX_.end());
  }
  uint32_t operator()(const Vec3& p) const {
    const auto start = std::lower_bound(byX_.begin(), byX_.end(), std::pair<double, uint32_t>{p.x, 0});
    double best = std::numeric_limits<double>::infinity();
    uint32_t bestIndex = 0;
    const auto consider = [&](uint32_t i) {
      const double d = lengthSquared(x_[i] - p);
      if (d < best || (d == best && i < bestIndex)) best = d, bestIndex = i;
    };
    for (auto it = start; it != byX_.end() && (it->first - p.x) * (it->first - p.x) <= best; ++it) consider(it->second);
    for (auto it = start; it != byX_.begin() && (std::prev(it)->first - p.x) * (std::prev(it)->first - p.x) <= best;
         --it) {
      consider(std::prev(it)->second);
    }
    return bestIndex;
  }

 private:
  const std::vector<Vec3>& x_;
  std::vector<std::pair<double, uint32_t>> byX_;
};

// [[attach]]: vertices of a body held to another body or to a [[triangles]] collider.
//   body = "NAME", points = [[x, y, z], ...] (the body's vertices nearest them), to = "NAME",
//   period = P [s] (a soft spring; none: hard, to a collider only), decay = T [s], release = t [s]
AttachDesc readAttach(const toml::table& table, const std::string& path, std::size_t index, const SceneDesc& scene) {
  Reader r(table, path, "[[attach]] #" + std::to_string(index + 1));
  AttachDesc a;
  a.where = location(path, table.source());
  const auto names = [&] {
    std::string list;
    for (const BodyDesc& b : scene.bodies) list += (list.empty() ? "'" : ", '") + b.name + "'";
    for (const TriangleCollider& c : scene.triangleColliders) list += (list.empty() ? "'" : ", '") + c.name + "'";
    return list.empty() ? std::string("none") : list;
  };
  const toml::node* bodyNode = r.get("body");
  if (!bodyNode || !bodyNode->as_string()) r.failHere("needs body = \"NAME\": the body whose vertices are attached");
  const std::string bodyName = bodyNode->as_string()->get();
  const auto body = std::find_if(scene.bodies.begin(), scene.bodies.end(), [&](const BodyDesc& b) { return b.name == bodyName; });
  if (body == scene.bodies.end()) r.fail(*bodyNode, "body", "no body is named '" + bodyName + "' (there are: " + names() + ")");
  a.body = static_cast<uint32_t>(body - scene.bodies.begin());
  const toml::node* toNode = r.get("to");
  if (!toNode || !toNode->as_string()) r.failHere("needs to = \"NAME\": another body or a [[triangles]] collider");
  const std::string toName = toNode->as_string()->get();
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    if (scene.bodies[b].name == toName) a.toBody = static_cast<int>(b);
  }
  for (std::size_t c = 0; c < scene.triangleColliders.size() && a.toBody < 0; ++c) {
    if (scene.triangleColliders[c].name == toName) a.toCollider = static_cast<int>(c);
  }
  if (a.toBody < 0 && a.toCollider < 0) {
    r.fail(*toNode, "to", "nothing is named '" + toName + "' (bodies and [[triangles]] colliders: " + names() + ")");
  }
  if (a.toBody == static_cast<int>(a.body)) r.fail(*toNode, "to", "a body is not attached to itself");
  const toml::node* pointsNode = r.get("points");
  const toml::array* points = pointsNode ? pointsNode->as_array() : nullptr;
  if (!points || points->empty()) r.failHere("needs points = [[x, y, z], ...]: the body's vertices nearest them are attached");
  if (points->size() > kMaxPinNear) {
    r.fail(*pointsNode, "points", std::to_string(points->size()) + " points, more than the limit of " + std::to_string(kMaxPinNear));
  }
  const NearestVertex nearest(body->mesh.positions);
  const std::optional<NearestVertex> nearestThere =
      a.toBody >= 0 ? std::optional<NearestVertex>(std::in_place, scene.bodies[static_cast<std::size_t>(a.toBody)].mesh.positions)
                    : std::nullopt;
  for (const toml::node& item : *points) {
    const uint32_t v = nearest(r.asVec3(item, "points"));
    if (std::find(a.vertices.begin(), a.vertices.end(), v) != a.vertices.end()) continue;  // once each
    a.vertices.push_back(v);
    if (nearestThere) a.targets.push_back((*nearestThere)(body->mesh.positions[v]));
  }
  if (r.has("period")) a.period = r.inRange("period", 0.0, 1e-6, 1e6);
  a.decay = r.inRange("decay", a.period, 1e-6, 1e9);
  if (!r.has("period") && r.has("decay")) r.failHere("decay is a soft attachment's: give its period too");
  if (r.has("release")) a.release = r.inRange("release", 0.0, 0.0, 1e9);
  r.finish();
  if (a.period <= 0.0 && a.toBody >= 0) {
    r.failHere("a hard attachment (no period) is to a [[triangles]] collider only; to body '" + toName +
               "' give period = P [s], a soft spring");
  }
  return a;
}

// Step: a generated shape's mesh, from that shape's own keys (each shape reads only its own; the
// others are then unknown keys).
TriMesh makeShape(Reader& r, const std::string& shape) {
  if (shape == "octahedron_sphere") {
    return makeOctahedronSphere(r.positive("radius", 1.0), r.integer("subdivisions", 6, 1, 256));
  } else if (shape == "icosphere") {
    return makeIcosphere(r.positive("radius", 1.0), r.integer("subdivisions", 3, 0, 8));
  } else if (shape == "cube") {
    return makeCube(r.positive("size", 1.0), r.integer("subdivisions", 1, 1, 256));
  } else if (shape == "tetrahedron") {
    return makeTetrahedron(r.positive("size", 1.0));
  } else if (shape == "jelly") {
    return makeJelly(r.positive("radius", 8.5), r.positive("height", 10.0), r.integer("ridges", 8, 0, 64),
                     r.integer("rings", 10, 2, 200), r.integer("segments", 48, 3, 1000));
  } else if (shape == "mould") {
    return makeMould(r.positive("radius", 8.5), r.positive("height", 10.0), r.integer("lobes", 8, 0, 64),
                     r.integer("rings", 12, 2, 200), r.integer("segments", 32, 3, 1000));
  }
  // cloth
  const std::array<double, 2> size = positivePair(r, "size", {1.0, 1.0});
  const std::array<int, 2> resolution = integerPair(r, "resolution", {20, 20}, 1, kMaxClothResolution);
  return makeCloth(size[0], size[1], resolution[0], resolution[1]);
}

// Step: a mesh file made fit to simulate. A cloth is validated as it is (one piece, every edge
// in one or two consistently oriented triangles, no zero-area triangle), never wrapped; a mesh
// that needs it (proxy = "auto": not a closed manifold, badly shaped or far finer than a body
// needs; proxy = "always") is simulated through a proxy that wraps it (mesh/proxy.h), the file's
// mesh kept in b.drawMesh to be drawn; any other is validated as a closed body.
TriMesh loadBodyMesh(const std::string& file, const std::string& proxy, int proxyVertices, BodyDesc& b) {
  TriMesh mesh = readWeldedMesh(file);
  std::optional<std::string> reason;
  if (proxy == "auto" && !b.cloth) reason = needsProxy(mesh, kProxyAutoMaxVertices);
  if (proxy == "always") reason = "proxy = \"always\"";
  if (b.cloth) {
    finishClothMesh(mesh, file);
  } else if (reason) {
    ProxyOptions options;
    options.targetVertices = proxyVertices > 0
                                 ? static_cast<std::size_t>(proxyVertices)
                                 : std::clamp<std::size_t>(mesh.positions.size(), 162, kProxyDefaultMaxVertices);
    const ProxyResult built = buildProxy(mesh, options);
    b.drawMesh = std::move(mesh);
    mesh = built.mesh;
    b.note = "simulated through a proxy (" + *reason + "): " + built.summary;
  } else {
    finishClosedMesh(mesh, file);
  }
  return mesh;
}

// Step: shape = "mesh": the file (relative to the scene file), how it is proxied, and the vertex
// count it is simplified to. Errors of the file are reported at its key.
TriMesh readMeshShape(Reader& r, const std::string& path, BodyDesc& b) {
  const toml::node* n = r.get("mesh");
  if (!n || !n->is_string()) r.failHere("shape = \"mesh\" needs mesh = \"FILE\" (relative to the scene file)");
  const std::string file = resolvePath(path, n->as_string()->get());
  const std::string proxy = r.choice("proxy", b.cloth ? "none" : "auto", {"auto", "none", "always"});
  const int proxyVertices = r.integer("proxy_vertices", 0, 4, kMaxProxyVertices);
  if (b.cloth && proxy != "none") {
    r.fail(*r.get("proxy"), "proxy", "cloth = true simulates the mesh as it is, never through a proxy");
  }
  if (b.cloth && r.has("proxy_vertices")) {
    r.fail(*r.get("proxy_vertices"), "proxy_vertices",
           "cloth = true simulates the mesh as it is, never through a proxy");
  }
  TriMesh mesh;
  try {
    mesh = loadBodyMesh(file, proxy, proxyVertices, b);
  } catch (const Error& e) {
    r.fail(*n, "mesh", e.what());
  }
  if (const toml::node* s = r.get("simplify")) {
    const auto* target = s->as_integer();
    if (!target || target->get() < 4) r.fail(*s, "simplify", "must be a vertex count of at least 4");
    if (b.cloth) {
      r.fail(*s, "simplify",
             "simplifies closed meshes only; with cloth = true, give the mesh at the resolution to simulate");
    }
    mesh = simplifyMesh(mesh, static_cast<std::size_t>(target->get()));
  }
  return mesh;
}

// Step: the body's mesh, generated or read. An error that does not already name the scene file
// (from a shape's generator or the mesh reader) is reported at the body's table.
TriMesh readShape(Reader& r, const std::string& shape, const std::string& path, BodyDesc& b) {
  TriMesh mesh;
  try {
    mesh = shape == "mesh" ? readMeshShape(r, path, b) : makeShape(r, shape);
  } catch (const Error& e) {
    if (std::string(e.what()).rfind(path, 0) == 0) throw;
    r.failHere(e.what());
  }
  return mesh;
}

// The first triangle of `x` with no area, as the model sees it (sim/model.cpp checkTriangles: the
// cross product at most 1e-12 of the square of the mesh's size), or -1. Triangles that refer to
// no vertex are left to the model, which names them.
long firstFlatTriangle(const std::vector<Triangle>& triangles, const std::vector<Vec3>& x) {
  const double size = length(boundsOf(x).size());
  for (std::size_t f = 0; f < triangles.size(); ++f) {
    const Triangle& t = triangles[f];
    if (t[0] >= x.size() || t[1] >= x.size() || t[2] >= x.size()) continue;
    if (!(length(cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]])) > 1e-12 * size * size)) return static_cast<long>(f);
  }
  return -1;
}

// Step of placeMesh: a triangle that the placement flattens is refused at the key that flattened
// it, found by applying the placement a part at a time (the shape's own size, then scale,
// rotation, position: a far position leaves too few digits for the body's size).
void refuseFlatTriangles(Reader& r, const TriMesh& mesh, const Transform& transform) {
  Transform partial;
  partial.scale = {1, 1, 1};
  const std::array<std::pair<const char*, std::function<void()>>, 4> steps{{
      {"", [] {}},
      {"scale", [&] { partial.scale = transform.scale; }},
      {"rotation", [&] { partial.rotation = transform.rotation; }},
      {"position", [&] { partial.position = transform.position; }},
  }};
  std::vector<Vec3> x(mesh.positions.size());
  for (const auto& [key, take] : steps) {
    take();
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = partial.apply(mesh.positions[i]);
    const long f = firstFlatTriangle(mesh.triangles, x);
    if (f < 0) continue;
    const Triangle& t = mesh.triangles[static_cast<std::size_t>(f)];
    // The shape's own size (radius, size, height), or the mesh file, made it flat.
    std::string at = key;
    for (const char* shapeKey : {"radius", "size", "height", "mesh"}) {
      if (at.empty() && r.has(shapeKey)) at = shapeKey;
    }
    if (at.empty()) return;  // the shape's defaults: the model names the triangle
    const toml::node& node = *r.get(at);
    std::ostringstream text;
    text << at << " = " << tomlText(node) << " at line " << node.source().begin.line << " flattens the mesh: triangle " << f
         << " (vertices " << t[0] << ", " << t[1] << ", " << t[2] << ") has zero area";
    r.fail(node, at, text.str());
  }
}

// Step: the mesh placed in the scene (scale, rotation, position), and the drawn mesh of a proxy
// with it, bound to the proxy's surface.
void placeMesh(Reader& r, TriMesh mesh, BodyDesc& b) {
  const Transform transform = readTransform(r);
  refuseFlatTriangles(r, mesh, transform);
  for (Vec3& p : mesh.positions) p = transform.apply(p);
  b.mesh = std::move(mesh);
  if (!b.drawMesh.positions.empty()) {
    for (Vec3& p : b.drawMesh.positions) p = transform.apply(p);
    b.drawBinding = bindToSurface(b.mesh, b.drawMesh.positions);
  }
}

// Step: the initial motion, the spring model and the mass and how it is spread. all_pairs is
// refused on a mesh whose struts (one per pair of vertices) would be too many.
void readModelAndMass(Reader& r, BodyDesc& b) {
  b.velocity = r.vec3("velocity", {});
  b.angularVelocity = r.vec3("angular_velocity", {});
  b.model = r.choice("model", "springy", {"springy", "all_pairs"}) == "all_pairs" ? SpringModel::AllPairs
                                                                                  : SpringModel::Springy;
  b.massDistribution = r.choice("mass_distribution", "area", {"area", "uniform"}) == "uniform"
                           ? MassDistribution::Uniform
                           : MassDistribution::AngleWeightedArea;
  if (b.model == SpringModel::AllPairs && b.mesh.positions.size() > kMaxAllPairsVertices) {
    r.fail(*r.get("model"), "model",
           "all_pairs joins every pair of vertices: " + std::to_string(b.mesh.positions.size()) +
               " vertices would make " + std::to_string(b.mesh.positions.size() * (b.mesh.positions.size() - 1) / 2) +
               " struts; it takes at most " + std::to_string(kMaxAllPairsVertices) + " vertices");
  }
  // Ranges that keep every derived constant finite and positive (a period of 1e-300 s or a mass
  // of 1e-300 kg overflows the stiffness or underflows the frequency).
  b.mass = r.inRange("mass", b.mass, kMinMass, kMaxMass);
}

// Step: which material the body has, the body's own (resolution independent, the default) or
// the seed's per element (docs/model.md §5), which any element key selects (the showcase scenes'
// values keep their meaning); a key of the other material is refused. Reads the body material's
// periods.
void readMaterialModel(Reader& r, BodyDesc& b) {
  static const char* const elementKeys[] = {"strut_period",    "strut_decay",   "hinge_period",    "hinge_decay",
                                            "strut_stiffness", "strut_damping", "hinge_stiffness", "hinge_damping"};
  static const char* const bodyKeys[] = {"stretch_period", "bend_period", "deformation_decay"};
  const char* elementKey = nullptr;
  for (const char* k : elementKeys) {
    if (!elementKey && r.has(k)) elementKey = k;
  }
  const bool allPairs = b.model == SpringModel::AllPairs;
  const std::string stiffness = r.choice("material", elementKey || allPairs ? "element" : "body", {"body", "element"});
  if (stiffness == "body") {
    if (allPairs) r.fail(*r.get("material"), "material", "model = \"all_pairs\" takes material = \"element\"");
    if (elementKey) {
      r.fail(*r.get(elementKey), elementKey,
             "is an element key (material = \"element\"); a body material takes stretch_period, bend_period and "
             "deformation_decay");
    }
    b.material = MaterialModel::Body;
    b.stretchPeriod = r.optionalInRange("stretch_period", kMinTime, kMaxTime);
    if (r.has("bend_period")) {
      b.bendPeriod = r.number("bend_period", 0.0);
      if (*b.bendPeriod != 0.0) b.bendPeriod = r.inRange("bend_period", 0.0, kMinTime, kMaxTime);
    }
    b.deformationDecay = r.number("deformation_decay", b.deformationDecay);
    if (b.deformationDecay != 0.0) {
      b.deformationDecay = r.inRange("deformation_decay", b.deformationDecay, kMinTime, kMaxTime);
    }
  } else {
    for (const char* k : bodyKeys) {
      if (r.has(k)) {
        r.fail(*r.get(k), k,
               "is a body material key (material = \"body\"); material = \"element\" takes strut_period, "
               "strut_decay, hinge_period and hinge_decay");
      }
    }
  }
}

// Step: the element material's periods and decay times (or constants given outright), and the
// gas's period.
void readElementMaterial(Reader& r, BodyDesc& b) {
  b.strutDecay = r.inRange("strut_decay", b.strutDecay, kMinTime, kMaxTime);
  b.strutPeriod = r.inRange("strut_period", b.strutPeriod, kMinTime, kMaxTime);
  b.hingeDecay = r.number("hinge_decay", b.hingeDecay);
  if (b.hingeDecay > 0.0) b.hingeDecay = r.inRange("hinge_decay", b.hingeDecay, kMinTime, kMaxTime);
  b.hingePeriod = r.number("hinge_period", b.hingePeriod);
  if (b.hingePeriod > 0.0) b.hingePeriod = r.inRange("hinge_period", b.hingePeriod, kMinTime, kMaxTime);
  b.volumePeriod = r.optionalInRange("volume_period", kMinTime, kMaxTime).value_or(0.0);
  b.strutStiffness = r.optionalInRange("strut_stiffness", 0.0, kMaxConstant);
  b.strutDamping = r.optionalInRange("strut_damping", 0.0, kMaxConstant);
  b.hingeStiffness = r.optionalInRange("hinge_stiffness", 0.0, kMaxConstant);
  b.hingeDamping = r.optionalInRange("hinge_damping", 0.0, kMaxConstant);
}

// Step: contact with other bodies and within the body (sim/contact.h).
void readBodyContact(Reader& r, BodyDesc& b) {
  b.contact = r.boolean("contact", b.contact);
  b.selfContact = r.boolean("self_contact", b.selfContact);
  b.contactThickness = r.optionalInRange("contact_thickness", 1e-9, 1e3).value_or(0.0);
  b.contactFriction = r.inRange("contact_friction", b.contactFriction, 0.0, 10.0);
  b.contactRestitution = r.inRange("contact_restitution", b.contactRestitution, 0.0, 1.0);
}

// Step: pin = [...]: vertex indices or rules ("top", "bottom", "left", "right", "front", "back":
// the extreme vertex along y, x or z; "all": every vertex). Each rule's vertex is found once
// however often it is named (a scan of every vertex per pin made 16 KB of rules take seconds on
// a fine sphere: found by the fuzzer).
void readPinList(Reader& r, BodyDesc& b) {
  const toml::node* n = r.get("pin");
  if (!n) return;
  std::array<std::optional<uint32_t>, 6> ruleVertex;
  bool pinnedAll = false;
  const auto* a = n->as_array();
  if (!a) r.fail(*n, "pin", "must be an array of vertex indices or rules, e.g. [\"top\"] or [0, 5]");
  for (const toml::node& item : *a) {
    if (const auto* i = item.as_integer()) {
      if (i->get() < 0 || static_cast<std::size_t>(i->get()) >= b.mesh.positions.size()) {
        r.fail(item, "pin",
               "vertex " + std::to_string(i->get()) + " does not exist (the body has " +
                   std::to_string(b.mesh.positions.size()) + " vertices)");
      }
      b.pinned.push_back(static_cast<uint32_t>(i->get()));
    } else if (const auto* s = item.as_string()) {
      if (s->get() == "all") {  // every vertex: a static body that still takes part in contact
        if (!pinnedAll) {
          for (uint32_t v = 0; v < b.mesh.positions.size(); ++v) b.pinned.push_back(v);
        }
        pinnedAll = true;
        continue;
      }
      const SideRule* rule = findSideRule(s->get());
      if (!rule) r.fail(item, "pin", "unknown rule '" + s->get() + "' (" + kSideRuleNames + ", all)");
      std::optional<uint32_t>& v = ruleVertex[static_cast<std::size_t>(rule - kSideRules)];
      if (!v) v = extremeVertex(b.mesh, rule->axis, rule->highest);
      b.pinned.push_back(*v);
    } else {
      r.fail(item, "pin", "entries must be vertex indices or rule names");
    }
  }
}

// One entry of pin_side: marks its side as named.
void nameSide(Reader& r, const toml::node& item, std::array<bool, std::size(kSideRules)>& named) {
  const auto* s = item.as_string();
  if (!s) r.fail(item, "pin_side", std::string("entries must be sides (") + kSideRuleNames + ")");
  const SideRule* rule = findSideRule(s->get());
  if (!rule) r.fail(item, "pin_side", "unknown side '" + s->get() + "' (" + kSideRuleNames + ")");
  named[static_cast<std::size_t>(rule - kSideRules)] = true;
}

// Step: pin_side = "left" or ["left", "top", ...]: every vertex on that side of the body's
// bounding box (within 1e-6 of its diagonal), e.g. the whole edge of a flag along its pole. Each
// side once however often it is named.
void readPinSides(Reader& r, BodyDesc& b) {
  const toml::node* n = r.get("pin_side");
  if (!n) return;
  const auto* a = n->as_array();
  if (!a && !n->is_string())
    r.fail(*n, "pin_side", "must be a side or an array of sides, e.g. \"left\" or [\"left\", \"top\"]");
  std::array<bool, std::size(kSideRules)> named{};
  if (a) {
    for (const toml::node& item : *a) nameSide(r, item, named);
  } else {
    nameSide(r, *n, named);
  }
  const std::vector<Vec3>& x = b.mesh.positions;
  const double tolerance = 1e-6 * length(boundsOf(x).size());
  for (std::size_t k = 0; k < named.size(); ++k) {
    if (!named[k]) continue;
    const SideRule& rule = kSideRules[k];
    const double extreme = x[extremeVertex(b.mesh, rule.axis, rule.highest)][rule.axis];
    for (uint32_t i = 0; i < x.size(); ++i) {
      if (std::fabs(x[i][rule.axis] - extreme) <= tolerance) b.pinned.push_back(i);
    }
  }
}

// Step: pin_near = [[x, y, z], ...]: the vertex nearest each point.
void readPinNear(Reader& r, BodyDesc& b) {
  const toml::node* n = r.get("pin_near");
  if (!n) return;
  const auto* a = n->as_array();
  if (!a) r.fail(*n, "pin_near", "must be an array of points [[x, y, z], ...]");
  // A point as far from every vertex as the centre of a sphere has all of them at nearly one
  // distance, and any exact search examines them all: the count of points is what bounds it.
  if (a->size() > kMaxPinNear) {
    r.fail(*n, "pin_near",
           std::to_string(a->size()) + " points, more than the limit of " + std::to_string(kMaxPinNear) +
               " (pin vertex indices instead)");
  }
  const NearestVertex nearest(b.mesh.positions);
  for (const toml::node& item : *a) b.pinned.push_back(nearest(r.asVec3(item, "pin_near")));
}

// Step: how the pinned vertices move (pin_motion) and when they are let go (pin_release); either
// needs pinned vertices.
void readPinMotion(Reader& r, const std::string& path, std::size_t index, BodyDesc& b) {
  if (const toml::table* t = r.subtable("pin_motion")) {
    b.pinMotion = readMotion(*t, path, "[[body]] #" + std::to_string(index + 1) + " pin_motion");
  }
  if (r.has("pin_release")) b.pinRelease = r.inRange("pin_release", 0.0, 0.0, 1e9);
  if ((b.pinMotion.moves() || std::isfinite(b.pinRelease)) && b.pinned.empty()) {
    r.failHere("pin_motion and pin_release move or free the pinned vertices: pin some (pin, pin_side, pin_near)");
  }
}

// [[body]]: its shape and placement, spring model, mass, material, contact and pins, in that
// order (the order in which a key's error is reported), and how it is drawn (`material`).
BodyDesc readBody(const toml::table& table, const std::string& path, std::size_t index, Material& material) {
  Reader r(table, path, "[[body]] #" + std::to_string(index + 1));
  BodyDesc b;
  b.source = location(path, table.source()) + ": [[body]] #" + std::to_string(index + 1);
  b.name = r.string("name", "body " + std::to_string(index + 1));
  const std::string shape =
      r.choice("shape", "octahedron_sphere",
               {"octahedron_sphere", "icosphere", "cube", "tetrahedron", "jelly", "mould", "mesh", "cloth"});
  // cloth = true: an open surface, simulated as it is (docs/model.md §18); the cloth shape is one.
  b.cloth = r.boolean("cloth", shape == "cloth");
  if (shape == "cloth" && !b.cloth) {
    r.fail(*r.get("cloth"), "cloth", "shape = \"cloth\" is an open surface: it is always cloth = true");
  }
  placeMesh(r, readShape(r, shape, path, b), b);
  readModelAndMass(r, b);
  readMaterialModel(r, b);
  readElementMaterial(r, b);
  readBodyContact(r, b);
  // Pins: pin (indices and rules), pin_side (every vertex on a side), pin_near (the nearest vertex).
  readPinList(r, b);
  readPinSides(r, b);
  readPinNear(r, b);
  readPinMotion(r, path, index, b);
  material = readMaterial(r, Material{{0.75, 0.2, 0.2}, 1.0, 48.0});
  r.finish();
  return b;
}

TriangleCollider readTriangleCollider(const toml::table& table, const std::string& path, std::size_t index,
                                      SurfaceLook& look) {
  Reader r(table, path, "[[triangles]] #" + std::to_string(index + 1));
  TriangleCollider c;
  c.name = r.string("name", "triangles " + std::to_string(index + 1));
  TriMesh& m = c.mesh;
  if (const toml::node* n = r.get("mesh")) {
    if (!n->is_string()) r.fail(*n, "mesh", "must be a file name");
    try {
      m = weldVertices(readMeshFile(resolvePath(path, n->as_string()->get())), 0.0);
    } catch (const Error& e) {
      r.fail(*n, "mesh", e.what());
    }
  }
  if (const toml::node* n = r.get("vertices")) {
    const auto* a = n->as_array();
    if (!a) r.fail(*n, "vertices", "must be an array of points");
    for (const toml::node& item : *a) m.positions.push_back(r.asVec3(item, "vertices"));
    const toml::node* tn = r.get("indices");
    if (!tn || !tn->as_array()) r.fail(*n, "vertices", "needs indices = [[i, j, k], ...]");
    for (const toml::node& item : *tn->as_array()) {
      const Vec3 t = r.asVec3(item, "indices");
      Triangle tri{};
      for (int k = 0; k < 3; ++k) {
        if (t[k] < 0 || t[k] >= static_cast<double>(m.positions.size()) || t[k] != std::floor(t[k])) {
          r.fail(item, "indices", "must be indices of vertices");
        }
        tri[static_cast<std::size_t>(k)] = static_cast<uint32_t>(t[k]);
      }
      m.triangles.push_back(tri);
    }
  }
  if (!r.has("vertices") && r.has("indices")) {
    const toml::node* n = r.get("indices");
    r.fail(*n, "indices", "needs vertices = [[x, y, z], ...] too: indices number the vertices, and a mesh given "
                          "in the scene needs both");
  }
  // quads = [[a, b, c, d], ...]: each a flat quadrilateral plate of four corners.
  if (const toml::node* n = r.get("quads")) {
    const auto* a = n->as_array();
    if (!a) r.fail(*n, "quads", "must be an array of quads, each [[x,y,z] x 4]");
    for (const toml::node& item : *a) {
      const auto* q = item.as_array();
      if (!q || q->size() != 4) r.fail(item, "quads", "each quad needs four corners");
      const uint32_t base = static_cast<uint32_t>(m.positions.size());
      for (const toml::node& corner : *q) m.positions.push_back(r.asVec3(corner, "quads"));
      m.triangles.push_back({base, base + 1, base + 2});
      m.triangles.push_back({base, base + 2, base + 3});
    }
  }
  const Transform transform = readTransform(r);
  for (Vec3& p : m.positions) p = transform.apply(p);
  c.material = readContact(r);
  if (const toml::table* t = r.subtable("motion")) {
    c.motion = readMotion(*t, path, "[[triangles]] #" + std::to_string(index + 1) + " motion");
  }
  look.material = readMaterial(r, Material{{0.55, 0.5, 0.45}, 1.0, 16.0});
  look.visible = r.boolean("visible", true);
  r.finish();  // first: a misspelt `quads` is an unknown key, not missing geometry
  if (m.triangles.empty()) r.failHere("needs triangles: mesh = \"FILE\", vertices + indices, or quads");
  return c;
}

// Step: the TOML text parsed, its syntax errors reported at file:line:column.
toml::table parseToml(const std::string& text, const std::string& path) {
  try {
    return toml::parse(text, path);
  } catch (const toml::parse_error& e) {
    throw Error(location(path, e.source()) + ": " + std::string(e.description()));
  }
}

// Step: [scene]: the run's name, duration, step, integrator and its settings.
void readRunSettings(const toml::table& table, const std::string& path, SceneDesc& scene) {
  Reader r(table, path, "[scene]");
  scene.name = r.string("name", scene.name);
  scene.duration = r.positive("duration", scene.duration);
  scene.stepGiven = r.has("dt") || r.has("substeps");
  scene.dt = r.positive("dt", scene.dt);
  scene.substeps = r.integer("substeps", 1, 1, kMaxSubsteps);
  if (const toml::node* n = r.get("integrator")) {
    if (!n->is_string() || !parseIntegrator(n->as_string()->get(), scene.integrator)) {
      r.fail(*n, "integrator", "must be one of: " + integratorNames());
    }
  }
  if (r.has("tolerance")) {
    scene.tolerance = r.inRange("tolerance", scene.tolerance, 1e-12, 0.5);
    if (!isAdaptive(scene.integrator)) scene.integrator = kDefaultAdaptive;  // a tolerance asks for one
  }
  scene.iterations = r.integer("iterations", scene.iterations, 1, kMaxIterations);
  if (const toml::node* n = r.get("iterations"); n != nullptr && !integratorTraits(scene.integrator).takesIterations) {
    // Only vbd sweeps; any other integrator would ignore the key without a word.
    r.fail(*n, "iterations", "sets vbd's sweeps a step, but the integrator is " +
                                 std::string(integratorName(scene.integrator)) + " (set integrator = \"vbd\" or remove the key)");
  }
  scene.restingSpeed = r.number("resting_speed", scene.restingSpeed);
  r.finish();
}

// Step: [environment.wind]: the air's velocity, its gusts and its pressure on faces.
Wind readWind(const toml::table& table, const std::string& path) {
  Reader wr(table, path, "[environment.wind]");
  Wind wind;
  wind.velocity = wr.vec3("velocity", {});
  wind.gustStrength = wr.inRange("gust_strength", 0.0, 0.0, 10.0);
  wind.gustPeriod = wr.positive("gust_period", 2.0);
  wind.pressure = wr.inRange("pressure", 0.0, 0.0, 1e6);
  wind.seed = static_cast<uint64_t>(wr.integer("seed", 1, 0, 2147483647));
  wr.finish();
  return wind;
}

// Step: [environment]: gravity, drag and the wind.
void readEnvironment(const toml::table& table, const std::string& path, SceneDesc& scene) {
  Reader r(table, path, "[environment]");
  scene.gravity = r.vec3("gravity", scene.gravity);
  scene.drag = r.inRange("drag", 0.0, 0.0, 1e6);
  if (const toml::table* w = r.subtable("wind")) scene.wind = readWind(*w, path);
  r.finish();
}

// Step: every [[body]], with its look. The vertices are counted body by body, so that memory
// stops growing at the body that crosses the limit.
void readBodies(const toml::array& bodies, const std::string& path, SceneDesc& scene) {
  std::uint64_t vertices = 0;
  for (std::size_t i = 0; i < bodies.size(); ++i) {
    Material material;
    scene.bodies.push_back(readBody(*bodies.get(i)->as_table(), path, i, material));
    scene.view.bodies.push_back(material);
    vertices += scene.bodies.back().mesh.positions.size();
    if (vertices > kMaxSceneVertices) {
      throw Error(scene.bodies.back().source + ": the bodies up to this one have " + std::to_string(vertices) +
                  " vertices in all, more than the limit of " + std::to_string(kMaxSceneVertices));
    }
  }
}

// Step: one [[plane]]: a collider (point, normal, contact, soft ground, motion) and its look.
void readPlane(const toml::table& table, const std::string& path, std::size_t index, SceneDesc& scene) {
  Reader r(table, path, "[[plane]] #" + std::to_string(index + 1));
  PlaneCollider p;
  SurfaceLook look;
  p.point = r.vec3("point", {});
  const toml::node* nn = r.get("normal");
  const Vec3 normal = nn ? r.asVec3(*nn, "normal") : Vec3{0, 1, 0};
  if (!(length(normal) > 0.0)) r.fail(*nn, "normal", "must not be zero");
  p.normal = normalized(normal);
  p.material = readContact(r);
  p.damping = r.inRange("damping", 0.0, 0.0, 1e6);
  p.layer = r.inRange("damping_layer", 0.0, 0.0, 1e6);
  if ((p.damping > 0.0) != (p.layer > 0.0)) {
    r.failHere("soft ground needs both damping (the rate, 1/s) and damping_layer (the thickness, m) positive");
  }
  if (const toml::table* t = r.subtable("motion")) {
    p.motion = readMotion(*t, path, "[[plane]] #" + std::to_string(index + 1) + " motion");
    if (p.layer > 0.0) r.failHere("soft ground (damping, damping_layer) does not move: give it no motion");
  }
  look.material = readMaterial(r, Material{{0.575, 0.54, 0.54}, 1.0, 8.0});
  look.visible = r.boolean("visible", true);
  look.extent = r.positive("extent", look.extent);
  r.finish();
  scene.planes.push_back(p);
  scene.view.planes.push_back(look);
}

// Step: one [[prop]]: a cylinder or a box that is drawn only (it takes no part in the simulation).
PropDesc readProp(const toml::table& table, const std::string& path, std::size_t index) {
  Reader r(table, path, "[[prop]] #" + std::to_string(index + 1));
  PropDesc p;
  if (r.choice("shape", "cylinder", {"cylinder", "box"}) == "box") {
    p.shape = PropDesc::Shape::Box;
    p.center = r.vec3("center", {});
    p.size = r.vec3("size", {1, 1, 1});
  } else {
    p.from = r.vec3("from", {});
    p.to = r.vec3("to", {0, 1, 0});
    p.radius = r.positive("radius", p.radius);
  }
  p.material = readMaterial(r, Material{{0.45, 0.3, 0.2}, 1.0, 16.0});
  if (const toml::table* t = r.subtable("motion")) {
    p.motion = readMotion(*t, path, "[[prop]] #" + std::to_string(index + 1) + " motion");
  }
  r.finish();
  return p;
}

// Step: [render.camera]: where the camera stands and looks (a target or angles, not both).
void readCamera(const toml::table& table, const std::string& path, CameraDesc& camera) {
  Reader cr(table, path, "[render.camera]");
  camera.position = cr.optionalVec3("position");
  camera.target = cr.optionalVec3("target");
  camera.angles = cr.optionalVec3("angles");
  if (camera.target && camera.angles) cr.failHere("give either target or angles, not both");
  if (camera.position && camera.target && *camera.position == *camera.target) {
    cr.fail(*table.get("target"), "target",
            "position and target are the same point " + tomlText(*table.get("position")) +
                ": the camera has no direction to look in; move one of them");
  }
  camera.fov = cr.inRange("fov", camera.fov, 1.0, 170.0);
  cr.finish();
}

// Step: [render.light]: the light's direction, colour and ambient share.
void readLight(const toml::table& table, const std::string& path, RenderDesc& rd) {
  Reader lr(table, path, "[render.light]");
  rd.light.angles = lr.vec3("angles", rd.light.angles);
  rd.light.color = lr.color("color", rd.light.color);
  rd.light.ambient = lr.inRange("ambient", rd.light.ambient, 0.0, 1.0);
  lr.finish();
}

// Step: [render]: the video's size, rate and quality, the picture's options, camera and light.
void readRender(const toml::table& table, const std::string& path, RenderDesc& rd) {
  Reader r(table, path, "[render]");
  rd.width = r.integer("width", rd.width, 16, 7680);
  rd.height = r.integer("height", rd.height, 16, 4320);
  if (rd.width % 2 || rd.height % 2) r.failHere("width and height must be even (the video is yuv420p)");
  rd.fps = r.inRange("fps", rd.fps, 1.0, 240.0);
  rd.crf = r.integer("crf", rd.crf, 0, 51);
  rd.preset =
      r.choice("preset", rd.preset,
               {"ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower", "veryslow"});
  rd.shadows = r.boolean("shadows", rd.shadows);
  rd.antialias = r.boolean("antialias", rd.antialias);
  rd.overlay = r.boolean("overlay", rd.overlay);
  rd.shadowMapSize = r.integer("shadow_map_size", rd.shadowMapSize, 256, 8192);
  rd.skyTop = r.color("sky_top", rd.skyTop);
  rd.skyBottom = r.color("sky_bottom", rd.skyBottom);
  if (const toml::table* c = r.subtable("camera")) readCamera(*c, path, rd.camera);
  if (const toml::table* l = r.subtable("light")) readLight(*l, path, rd);
  r.finish();
}

// Step: every body and [[triangles]] collider has a name of its own: [[attach]] and the messages
// find them by name, and two of one name would leave it to chance which is meant. Said at the
// second, naming where the first is. ([[plane]] and [[prop]] take no name.)
void refuseSharedNames(const toml::table& root, const std::string& path, const SceneDesc& scene) {
  std::vector<std::pair<std::string, std::string>> seen;  // (name, where it is given)
  const auto add = [&](const char* kind, std::size_t i, const std::string& name) {
    const toml::table& table = *root.get(kind)->as_array()->get(i)->as_table();
    const toml::node* n = table.get("name");
    const std::string where =
        location(path, n ? n->source() : table.source()) + ": [[" + kind + "]] #" + std::to_string(i + 1);
    for (const auto& [other, at] : seen) {
      if (other != name) continue;
      throw Error(where + ": the name '" + name + "' is taken by " + at +
                  "; bodies and [[triangles]] colliders need names of their own (an [[attach]] names what it "
                  "holds)");
    }
    seen.emplace_back(name, where);
  };
  for (std::size_t i = 0; i < scene.bodies.size(); ++i) add("body", i, scene.bodies[i].name);
  for (std::size_t i = 0; i < scene.triangleColliders.size(); ++i) add("triangles", i, scene.triangleColliders[i].name);
}

}  // namespace

namespace {

bool fileExists(const std::string& path) {
  std::error_code error;
  return std::filesystem::is_regular_file(path, error);
}

// The whitespace-separated words of a line.
std::vector<std::string> wordsOf(const std::string& line) {
  std::istringstream in(line);
  return {std::istream_iterator<std::string>(in), std::istream_iterator<std::string>()};
}

// What a mesh reader (assimp) reads beside the mesh `file`: an OBJ's material libraries ("mtllib
// A.mtl B.mtl") and the textures they name (map_Kd, bump, ...: the last word of the line, after
// its options); a glTF's buffers and images (each "uri" that is not a data: URI). Files that exist.
void filesBeside(const std::string& file, std::vector<std::string>& out) {
  namespace fs = std::filesystem;
  std::string extension = fs::path(file).extension().string();
  for (char& c : extension) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const auto add = [&](const std::string& name) {
    const std::string f = resolvePath(file, name);
    if (fileExists(f) && std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
  };
  std::ifstream in(file, std::ios::binary);
  std::string line;
  if (extension == ".obj") {
    while (std::getline(in, line)) {
      const std::vector<std::string> words = wordsOf(line);
      if (words.size() < 2 || words[0] != "mtllib") continue;
      for (std::size_t k = 1; k < words.size(); ++k) {
        const std::size_t before = out.size();
        add(words[k]);
        if (out.size() > before) filesBeside(out.back(), out);
      }
    }
  } else if (extension == ".mtl") {
    while (std::getline(in, line)) {
      const std::vector<std::string> words = wordsOf(line);
      if (words.size() < 2) continue;
      const std::string& key = words[0];
      if (key.rfind("map_", 0) == 0 || key == "bump" || key == "disp" || key == "decal" || key == "refl" ||
          key == "norm") {
        add(words.back());
      }
    }
  } else if (extension == ".gltf") {
    const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    for (std::size_t at = text.find("\"uri\""); at != std::string::npos; at = text.find("\"uri\"", at + 5)) {
      const std::size_t open = text.find('"', text.find(':', at + 5));
      const std::size_t close = open == std::string::npos ? open : text.find('"', open + 1);
      if (close == std::string::npos) break;
      const std::string uri = text.substr(open + 1, close - open - 1);
      if (uri.rfind("data:", 0) != 0) add(uri);
    }
  }
}

// The mesh files named by the tables of `key` ("body", "triangles") in a parsed scene.
void meshesOf(const toml::table& root, std::string_view key, const std::string& path, std::vector<std::string>& out) {
  const toml::array* tables = root[key].as_array();
  if (!tables) return;
  for (const toml::node& item : *tables) {
    const toml::table* table = item.as_table();
    const toml::node* mesh = table ? table->get("mesh") : nullptr;
    if (!mesh || !mesh->is_string()) continue;
    const std::string file = resolvePath(path, mesh->as_string()->get());
    if (std::find(out.begin(), out.end(), file) != out.end()) continue;
    out.push_back(file);
    filesBeside(file, out);
  }
}

std::vector<std::string> inputsOf(const toml::table& root, const std::string& path) {
  std::vector<std::string> out{path};
  meshesOf(root, "body", path, out);
  meshesOf(root, "triangles", path, out);
  return out;
}

}  // namespace

std::vector<std::string> sceneInputs(const std::string& text, const std::string& path) {
  try {
    return inputsOf(toml::parse(text, path), path);
  } catch (const toml::parse_error&) {
    return {path};
  }
}

SceneDesc parseScene(const std::string& text, const std::string& path) {
  const toml::table root = parseToml(text, path);
  SceneDesc scene;
  scene.path = path;
  scene.inputs = inputsOf(root, path);
  Reader top(root, path, "the scene");
  scene.name = std::filesystem::path(path).stem().string();

  if (const toml::table* t = top.subtable("scene")) readRunSettings(*t, path, scene);
  if (const toml::table* t = top.subtable("environment")) readEnvironment(*t, path, scene);
  if (const toml::array* bodies = arrayOfTables(root, "body", path)) {
    top.get("body");
    readBodies(*bodies, path, scene);
  }
  if (const toml::array* planes = arrayOfTables(root, "plane", path)) {
    top.get("plane");
    for (std::size_t i = 0; i < planes->size(); ++i) readPlane(*planes->get(i)->as_table(), path, i, scene);
  }
  if (const toml::array* tris = arrayOfTables(root, "triangles", path)) {
    top.get("triangles");
    for (std::size_t i = 0; i < tris->size(); ++i) {
      SurfaceLook look;
      scene.triangleColliders.push_back(readTriangleCollider(*tris->get(i)->as_table(), path, i, look));
      scene.view.triangleColliders.push_back(look);
    }
  }
  refuseSharedNames(root, path, scene);
  if (const toml::array* attach = arrayOfTables(root, "attach", path)) {
    top.get("attach");
    for (std::size_t i = 0; i < attach->size(); ++i) {
      scene.attachments.push_back(readAttach(*attach->get(i)->as_table(), path, i, scene));
    }
  }
  if (const toml::array* props = arrayOfTables(root, "prop", path)) {
    top.get("prop");
    for (std::size_t i = 0; i < props->size(); ++i) {
      scene.view.props.push_back(readProp(*props->get(i)->as_table(), path, i));
    }
  }
  if (const toml::table* t = top.subtable("render")) readRender(*t, path, scene.view.render);
  top.finish();
  if (scene.bodies.empty()) throw Error(path + ": the scene has no [[body]]");
  if (auto problem = runSettingsProblem(scene)) {
    const toml::node* table = root.get("scene");
    throw Error((table ? location(path, table->source()) + ": [scene]" : path) + ": " + *problem);
  }
  return scene;
}

std::optional<std::string> runSettingsProblem(const SceneDesc& scene) {
  std::ostringstream text;
  const double frame = 1.0 / scene.view.render.fps;
  if (!(scene.dt <= frame * (1.0 + 1e-9))) {
    text << "dt = " << scene.dt << " s is longer than one frame (1/fps = " << frame
         << " s): the step must fit between two frames";
    return text.str();
  }
  const double steps = scene.duration / stepSize(scene);
  if (!isAdaptive(scene.integrator) && !(steps <= kMaxSteps)) {
    text << "duration " << scene.duration << " s in steps of " << stepSize(scene) << " s (dt / substeps) is " << steps
         << " steps, more than the limit of " << kMaxSteps;
    return text.str();
  }
  return std::nullopt;
}

SceneDesc loadScene(const std::string& path) {
  checkInputFile(path, kMaxSceneFileBytes, "scene file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open the scene file");
  std::ostringstream text;
  text << in.rdbuf();
  return parseScene(text.str(), path);
}

}  // namespace springy
