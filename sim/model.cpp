#include "sim/model.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <type_traits>

#include "sim/error.h"
#include "sim/hinge.h"

namespace springy {
namespace {

std::string where(const BodyDesc& desc) { return "body '" + desc.name + "'"; }

double cornerAngle(const Vec3& at, const Vec3& b, const Vec3& c) {
  const Vec3 u = b - at, w = c - at;
  return std::atan2(length(cross(u, w)), dot(u, w));
}

struct DirectedEdge {
  uint32_t from, to, face;
  bool operator<(const DirectedEdge& o) const {
    return from != o.from ? from < o.from : (to != o.to ? to < o.to : face < o.face);
  }
};

// Renumbers the vertices of the body just appended (info) in order of their rest position along
// the longest side of the body's bounding box (ties by mesh index, so the order is a pure
// function of the mesh), and sorts its struts, hinges and faces by their first vertex, so the
// force loops stream through memory. Any contiguous index range is then a slab of the body cut
// by planes: few elements straddle two ranges, and the vertices a range's elements reach on the
// other side of a cut are a short run of consecutive indices, a few cache lines. (A Morton
// order also cuts few elements, but scatters the reached vertices over the whole of the other
// range, one cache line each; on two threads each line is a transfer between the cores every
// step: the gas ball's two-thread step took 73 us that way and 57 us in slabs, docs/benchmarks.md.)
void orderSpatially(Model& model, BodyInfo& info) {
  const uint32_t base = info.firstVertex, nv = info.vertexCount;
  const Bounds box = boundsOf(std::vector<Vec3>(model.restPosition.begin() + base, model.restPosition.end()));
  const Vec3 size = box.size();
  const int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
  std::vector<std::pair<double, uint32_t>> keys(nv);  // (coordinate along the axis, mesh index)
  for (uint32_t k = 0; k < nv; ++k) keys[k] = {model.restPosition[base + k][axis], k};
  std::sort(keys.begin(), keys.end());
  info.modelVertex.assign(nv, 0);
  for (uint32_t r = 0; r < nv; ++r) info.modelVertex[keys[r].second] = base + r;
  const auto renumber = [&](uint32_t& v) { v = info.modelVertex[v - base]; };
  const auto permute = [&](auto& values) {  // the body's own stretch of a per-vertex array
    const std::vector<typename std::decay_t<decltype(values)>::value_type> copy(values.begin() + base,
                                                                             values.begin() + base + nv);
    for (uint32_t k = 0; k < nv; ++k) values[info.modelVertex[k]] = copy[k];
  };
  permute(model.mass);
  permute(model.invMass);
  permute(model.restPosition);
  permute(model.initialVelocity);
  for (std::size_t s = info.firstStrut; s < model.struts.size(); ++s) {
    Strut& strut = model.struts[s];
    renumber(strut.i);
    renumber(strut.j);
    if (strut.j < strut.i) std::swap(strut.i, strut.j);
  }
  std::stable_sort(model.struts.begin() + info.firstStrut, model.struts.end(),
                   [](const Strut& a, const Strut& b) { return a.i != b.i ? a.i < b.i : a.j < b.j; });
  for (std::size_t h = info.firstHinge; h < model.hinges.size(); ++h) {
    for (uint32_t& v : model.hinges[h].v) renumber(v);
  }
  std::stable_sort(model.hinges.begin() + info.firstHinge, model.hinges.end(), [](const Hinge& a, const Hinge& b) {
    return std::min(a.v[0], a.v[1]) < std::min(b.v[0], b.v[1]);
  });
  for (std::size_t f = info.firstFace; f < model.faces.size(); ++f) {
    for (uint32_t& v : model.faces[f]) renumber(v);
  }
  // Faces too (each keeps its winding): a thread's share of the gas and wind stages, and a
  // chunk of the volume sum, then reads a compact stretch of positions.
  std::stable_sort(model.faces.begin() + info.firstFace, model.faces.end(), [](const Triangle& a, const Triangle& b) {
    return std::min({a[0], a[1], a[2]}) < std::min({b[0], b[1], b[2]});
  });
  for (uint32_t& p : model.pinned) {
    if (p >= base) renumber(p);
  }
  std::sort(model.pinned.begin(), model.pinned.end());
}


// Step: what a body's description must give before anything is built: enough vertices and
// triangles (a cloth: one triangle), a positive mass, and no gas in an open surface.
void checkBodyDesc(const BodyDesc& desc) {
  const TriMesh& mesh = desc.mesh;
  const std::size_t nv = mesh.positions.size();
  if (desc.cloth ? mesh.triangles.empty() : (nv < 4 || mesh.triangles.size() < 4)) {
    throw Error(where(desc) + (desc.cloth ? ": a cloth needs at least one triangle"
                                          : ": a closed body needs at least 4 vertices and 4 triangles"));
  }
  if (!(desc.mass > 0.0) || !std::isfinite(desc.mass)) throw Error(where(desc) + ": mass must be positive");
  if (desc.cloth && desc.volumePeriod > 0.0) {
    throw Error(where(desc) +
                ": volume_period (a gas) needs a closed body, but it is a cloth: an open surface "
                "encloses no volume");
  }
}

// Step: the geometry the forces divide by: every triangle's corners exist and it has an area
// (relative to the body's size [m], its bounding-box diagonal).
void checkTriangles(const BodyDesc& desc, double size) {
  const TriMesh& mesh = desc.mesh;
  const std::size_t nv = mesh.positions.size();
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    for (uint32_t v : t) {
      if (v >= nv) {
        throw Error(where(desc) + ": triangle " + std::to_string(f) + " refers to vertex " + std::to_string(v) +
                    " of " + std::to_string(nv));
      }
    }
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    if (!(length(cross(b - a, c - a)) > 1e-12 * size * size)) {
      throw Error(where(desc) + ": triangle " + std::to_string(f) + " (" + std::to_string(t[0]) + ", " +
                  std::to_string(t[1]) + ", " + std::to_string(t[2]) + ") has zero area");
    }
  }
}

// Step: the body's record before its elements are added: where its vertices, elements and faces
// start in the model, its mass, rest size [m] and contact settings.
BodyInfo newBodyInfo(const Model& model, const BodyDesc& desc, double size) {
  BodyInfo info;
  info.name = desc.name;
  info.firstVertex = static_cast<uint32_t>(model.mass.size());
  info.vertexCount = static_cast<uint32_t>(desc.mesh.positions.size());
  info.firstStrut = static_cast<uint32_t>(model.struts.size());
  info.firstHinge = static_cast<uint32_t>(model.hinges.size());
  info.firstFace = static_cast<uint32_t>(model.faces.size());
  info.faceCount = static_cast<uint32_t>(desc.mesh.triangles.size());
  info.mass = desc.mass;
  info.restSize = size;
  info.contact = desc.contact;
  info.selfContact = desc.selfContact;
  info.contactThickness = desc.contactThickness;
  info.contactFriction = desc.contactFriction;
  info.contactRestitution = desc.contactRestitution;
  return info;
}

// Step: each vertex's mass [kg]: its angle-weighted area's share of the body's (docs/model.md
// §4, eq. A6), or uniform. A vertex of no triangle would get none, and is refused.
std::vector<double> vertexMasses(const BodyDesc& desc) {
  const std::size_t nv = desc.mesh.positions.size();
  std::vector<double> m(nv, desc.mass / static_cast<double>(nv));
  if (desc.massDistribution == MassDistribution::AngleWeightedArea) {
    const std::vector<double> share = angleWeightedAreas(desc.mesh);
    double total = 0.0;
    for (double s : share) total += s;
    for (std::size_t i = 0; i < nv; ++i) {
      if (!(share[i] > 0.0)) {
        throw Error(where(desc) + ": vertex " + std::to_string(i) + " belongs to no triangle (it would get no mass)");
      }
      m[i] = desc.mass * share[i] / total;
    }
  }
  return m;
}

// Directed edges in (from, to, face) order, to pair each edge with its twin (the neighbouring
// face): bucketed by their first vertex, each vertex's few then sorted; a twin is looked up among
// its start vertex's edges.
class EdgeTable {
 public:
  explicit EdgeTable(const TriMesh& mesh) : start_(mesh.positions.size() + 1, 0), edges_(mesh.triangles.size() * 3) {
    const std::size_t nv = mesh.positions.size();
    for (const Triangle& t : mesh.triangles) {
      for (uint32_t v : t) ++start_[v + 1];
    }
    for (std::size_t i = 0; i < nv; ++i) start_[i + 1] += start_[i];
    std::vector<uint32_t> next(start_.begin(), start_.end() - 1);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      const Triangle& t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) edges_[next[t[k]]++] = {t[k], t[(k + 1) % 3], static_cast<uint32_t>(f)};
    }
    for (std::size_t i = 0; i < nv; ++i) std::sort(edges_.begin() + start_[i], edges_.begin() + start_[i + 1]);
  }
  // The edge a -> b of the lowest face, if any.
  const DirectedEdge* find(uint32_t a, uint32_t b) const {
    for (uint32_t k = start_[a]; k < start_[a + 1]; ++k) {
      if (edges_[k].to == b) return &edges_[k];  // the first: the lowest face
    }
    return nullptr;
  }
  const std::vector<DirectedEdge>& edges() const { return edges_; }

 private:
  std::vector<uint32_t> start_;  // per vertex: its first edge (and one past the last vertex's)
  std::vector<DirectedEdge> edges_;
};

// The corner of `face` that is neither a nor b.
uint32_t thirdVertex(const TriMesh& mesh, uint32_t face, uint32_t a, uint32_t b) {
  for (uint32_t v : mesh.triangles[face]) {
    if (v != a && v != b) return v;
  }
  return a;
}

// Step: whether the body is an open surface (a cloth, docs/model.md §18): marked so, or with a
// border edge (an edge of one triangle, no twin). It encloses no volume, so a gas in it is refused.
bool isOpenSurface(const BodyDesc& desc, const EdgeTable& table) {
  bool open = desc.cloth;
  const std::vector<DirectedEdge>& edges = table.edges();
  for (std::size_t k = 0; k < edges.size() && !open; ++k) {
    if (!table.find(edges[k].to, edges[k].from)) {
      if (desc.volumePeriod > 0.0) {
        throw Error(where(desc) + ": volume_period needs a closed mesh, but edge (" + std::to_string(edges[k].from) +
                    ", " + std::to_string(edges[k].to) + ") borders only triangle " + std::to_string(edges[k].face));
      }
      open = true;
    }
  }
  return open;
}

// Step: each face's area [m^2], and their sum in `area`.
std::vector<double> faceAreas(const TriMesh& mesh, double& area) {
  std::vector<double> faceArea(mesh.triangles.size());
  area = 0.0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    faceArea[f] = 0.5 * length(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
    area += faceArea[f];
  }
  return faceArea;
}

// Step: the body material (MaterialModel::Body): its periods (given, or the defaults at the
// body's size) and the membrane and bending moduli they give, for a body of this area [m^2].
void setBodyMaterial(const BodyDesc& desc, double area, BodyInfo& info) {
  const double density = desc.mass / area, scale = std::sqrt(area / (4 * kPi));
  const double stretch = desc.stretchPeriod.value_or((info.open ? kClothStretchPeriod : kDefaultStretchPeriod) * scale);
  const double bend = desc.bendPeriod.value_or((info.open ? kClothBendPeriod : kDefaultBendPeriod) * scale);
  info.stretchPeriod = stretch;
  info.bendPeriod = bend;
  info.membraneModulus = density * scale * scale * (2 * kPi / stretch) * (2 * kPi / stretch);
  info.bendingModulus = bend > 0.0 ? density * std::pow(scale, 4) * (2 * kPi / bend) * (2 * kPi / bend) : 0.0;
  info.deformationDamping = desc.deformationDecay > 0.0 ? 2.0 / desc.deformationDecay : 0.0;
}

// Adds one body's struts and hinges to the model, with the constants of its material: the body
// material's moduli (shared by the element's faces) or the element material's periods and
// decay times (at the element's mean vertex mass).
class ElementBuilder {
 public:
  ElementBuilder(Model& model, const BodyDesc& desc, const BodyInfo& info, const std::vector<double>& mass,
                 const std::vector<double>& faceArea, double size)
      : model_(model), desc_(desc), mesh_(desc.mesh), info_(info), m_(mass), faceArea_(faceArea), size_(size),
        base_(info.firstVertex), bodyMaterial_(desc.material == MaterialModel::Body) {}

  // Step: a strut on every edge (all pairs: on every pair of vertices), and a hinge across every
  // edge between two faces when the material bends.
  void addAll(const EdgeTable& table) {
    const uint32_t nv = info_.vertexCount;
    const bool useHinges =
        desc_.model == SpringModel::Springy &&
        (bodyMaterial_ ? info_.bendingModulus > 0.0 : (desc_.hingeStiffness || desc_.hingePeriod > 0.0));
    if (desc_.model == SpringModel::AllPairs) {
      for (uint32_t i = 0; i < nv; ++i) {
        for (uint32_t j = i + 1; j < nv; ++j) addStrut(i, j, 0, 0);
      }
      return;
    }
    for (const DirectedEdge& e : table.edges()) {
      // Each undirected edge once: at its direction with from < to, or at the only direction
      // it has (a border edge of an open mesh).
      const DirectedEdge* twin = table.find(e.to, e.from);
      if (e.from > e.to && twin) continue;
      addStrut(e.from, e.to, e.face, twin ? twin->face : e.face);
      if (!useHinges || !twin) continue;
      addHinge(e, *twin);
    }
  }

 private:
  // A strut's stiffness k and damping d. faces: the one or two faces beside the edge (the second
  // is the first for a border edge).
  void strutConstants(uint32_t i, uint32_t j, double rest, uint32_t face0, uint32_t face1, double& k, double& d) const {
    if (bodyMaterial_) {
      // A membrane of modulus Y: the edge's share of the area beside it (a third of each face,
      // so the shares sum to the body's area) over its length squared; equal stretch e of
      // every edge then stores 1/2 Y e^2 per unit area.
      const double share = (faceArea_[face0] + (face1 != face0 ? faceArea_[face1] : 0.0)) / 3.0;
      k = info_.membraneModulus * share / (rest * rest);
      d = 0.0;
      return;
    }
    const double mean = 0.5 * (m_[i] + m_[j]);
    k = desc_.strutStiffness ? *desc_.strutStiffness : stiffnessFromPeriod(mean, desc_.strutPeriod);
    d = desc_.strutDamping ? *desc_.strutDamping : dampingFromDecay(mean, desc_.strutDecay);
  }

  // The strut between mesh vertices i and j, at their rest distance (which must not be zero).
  void addStrut(uint32_t i, uint32_t j, uint32_t face0, uint32_t face1) {
    const double rest = length(mesh_.positions[j] - mesh_.positions[i]);
    if (!(rest > 1e-12 * size_)) {
      throw Error(where(desc_) + ": edge (" + std::to_string(i) + ", " + std::to_string(j) + ") has zero length");
    }
    Strut s{base_ + i, base_ + j, rest, 0.0, 0.0};
    strutConstants(i, j, rest, face0, face1, s.stiffness, s.damping);
    model_.struts.push_back(s);
  }

  // The hinge across edge e (and its twin), at its rest angle; refused where a wing vertex lies
  // on the hinge line (a sliver face: no lever arm).
  void addHinge(const DirectedEdge& e, const DirectedEdge& twin) {
    Hinge h{{base_ + e.from, base_ + e.to, base_ + thirdVertex(mesh_, e.face, e.from, e.to),
             base_ + thirdVertex(mesh_, twin.face, e.from, e.to)},
            0.0, 0.0, 0.0};
    HingeGeometry g;
    const Vec3 &x0 = mesh_.positions[e.from], &x1 = mesh_.positions[e.to];
    if (!hingeGeometry(x0, x1, mesh_.positions[h.v[2] - base_], mesh_.positions[h.v[3] - base_], g) ||
        !(g.leverLeft > 1e-9 * size_) || !(g.leverRight > 1e-9 * size_)) {
      throw Error(where(desc_) + ": hinge on edge (" + std::to_string(e.from) + ", " + std::to_string(e.to) +
                  ") has a wing vertex on the hinge line (a sliver face): it has no lever arm");
    }
    h.restAngle = g.theta;
    h.minLever[0] = 0.2 * g.leverLeft;
    h.minLever[1] = 0.2 * g.leverRight;
    if (bodyMaterial_) {
      // Discrete shells' weight |e|^2 / (A_1 + A_2): a sheet of equilateral triangles bent
      // into a cylinder of radius R stores 1/2 D / R^2 per unit area, in any direction (the
      // hinges across the bend turn by h / R, h a triangle's height; test_material).
      const double rest = length(x1 - x0);
      h.stiffness = info_.bendingModulus * rest * rest / (faceArea_[e.face] + faceArea_[twin.face]);
      h.damping = 0.0;
      model_.hinges.push_back(h);
      return;
    }
    const double mean = 0.5 * (m_[e.from] + m_[e.to]);
    const double r = 0.5 * (g.leverLeft + g.leverRight);  // at rest, once
    h.stiffness = desc_.hingeStiffness ? *desc_.hingeStiffness : torsionStiffnessFromPeriod(mean, r, desc_.hingePeriod);
    h.damping = desc_.hingeDamping ? *desc_.hingeDamping
                : desc_.hingeDecay > 0.0 ? torsionDampingFromDecay(mean, r, desc_.hingeDecay)
                                         : 0.0;
    model_.hinges.push_back(h);
  }

  Model& model_;
  const BodyDesc& desc_;
  const TriMesh& mesh_;
  const BodyInfo& info_;
  const std::vector<double>& m_;         // per mesh vertex [kg]
  const std::vector<double>& faceArea_;  // per face [m^2]
  double size_;                          // the body's bounding-box diagonal [m]
  uint32_t base_;                        // the body's first model vertex
  bool bodyMaterial_;
};

// Step: the body's vertices appended to the model (mass m per mesh vertex [kg]): their rest
// positions, initial velocity (translation + spin about the centroid) and pins, and its faces.
void addVertices(Model& model, const BodyDesc& desc, const std::vector<double>& m, uint32_t base) {
  const TriMesh& mesh = desc.mesh;
  const std::size_t nv = mesh.positions.size();
  Vec3 centroid;
  for (const Vec3& p : mesh.positions) centroid += p;
  centroid = centroid / static_cast<double>(nv);
  std::vector<bool> pinned(nv, false);
  for (uint32_t p : desc.pinned) {
    if (p >= nv) {
      throw Error(where(desc) + ": pinned vertex " + std::to_string(p) + " does not exist (the body has " +
                  std::to_string(nv) + " vertices)");
    }
    pinned[p] = true;
  }
  for (uint32_t i = 0; i < nv; ++i) {
    model.mass.push_back(m[i]);
    model.invMass.push_back(pinned[i] ? 0.0 : 1.0 / m[i]);
    model.restPosition.push_back(mesh.positions[i]);
    model.body.push_back(static_cast<uint32_t>(model.bodies.size()));
    model.initialVelocity.push_back(
        pinned[i] ? Vec3{} : desc.velocity + cross(desc.angularVelocity, mesh.positions[i] - centroid));
    if (pinned[i]) model.pinned.push_back(base + i);
  }
  for (const Triangle& t : mesh.triangles) model.faces.push_back({base + t[0], base + t[1], base + t[2]});
}

// Step: what the body does over time besides its forces: its gas's pressure (from volume_period,
// in a positive rest volume) and its pins' track (pin_motion, pin_release).
void addGasAndPinTrack(Model& model, const BodyDesc& desc, BodyInfo& info) {
  if (desc.volumePeriod > 0.0) {
    if (!(info.restVolume > 0.0)) {
      throw Error(where(desc) + ": volume_period needs a mesh that encloses a positive volume (outward faces); its "
                  "signed volume is " + std::to_string(info.restVolume));
    }
    info.gasPressure = gasPressureFromPeriod(model, info, desc.volumePeriod);
  }
  if (desc.pinMotion.moves() || std::isfinite(desc.pinRelease)) {
    if (desc.pinned.empty()) throw Error(where(desc) + ": pin_motion and pin_release need pinned vertices (pin = [...])");
    model.pinTracks.push_back({static_cast<uint32_t>(model.bodies.size()), desc.pinMotion, desc.pinRelease, {}});
  }
}

}  // namespace

Vec3 Wind::airVelocity(double t) const {
  if (gustStrength == 0.0) return velocity;
  // Four incommensurate sinusoids around the gust frequency: smooth, repeatable, and without
  // a visible period.
  double g = 0.0;
  for (int i = 0; i < 4; ++i) g += std::sin(2 * kPi * frequency[i] * t + phase[i]);
  return velocity * (1.0 + gustStrength * 0.5 * g);
}

std::vector<double> angleWeightedAreas(const TriMesh& mesh) {
  std::vector<double> share(mesh.positions.size(), 0.0);
  for (const Triangle& t : mesh.triangles) {
    const Vec3 &a = mesh.positions[t[0]], &b = mesh.positions[t[1]], &c = mesh.positions[t[2]];
    const double area = 0.5 * length(cross(b - a, c - a));
    // The three interior angles sum to pi, so the shares of one face sum to its area.
    share[t[0]] += area * cornerAngle(a, b, c) / kPi;
    share[t[1]] += area * cornerAngle(b, c, a) / kPi;
    share[t[2]] += area * cornerAngle(c, a, b) / kPi;
  }
  return share;
}

void addBody(Model& model, const BodyDesc& desc) {
  const TriMesh& mesh = desc.mesh;
  checkBodyDesc(desc);
  const double size = length(boundsOf(mesh.positions).size());
  checkTriangles(desc, size);
  BodyInfo info = newBodyInfo(model, desc, size);
  const std::vector<double> m = vertexMasses(desc);
  const EdgeTable edges(mesh);
  info.open = isOpenSurface(desc, edges);
  info.restVolume = info.open ? 0.0 : signedVolume(mesh.positions, mesh.triangles);
  if (desc.material == MaterialModel::Body && desc.model == SpringModel::AllPairs) {
    throw Error(where(desc) + ": the all-pairs model takes the element material (periods per strut)");
  }
  double area = 0.0;
  const std::vector<double> faceArea = faceAreas(mesh, area);
  if (desc.material == MaterialModel::Body) setBodyMaterial(desc, area, info);
  ElementBuilder(model, desc, info, m, faceArea, size).addAll(edges);
  info.strutCount = static_cast<uint32_t>(model.struts.size()) - info.firstStrut;
  info.hingeCount = static_cast<uint32_t>(model.hinges.size()) - info.firstHinge;
  addVertices(model, desc, m, info.firstVertex);
  orderSpatially(model, info);
  addGasAndPinTrack(model, desc, info);
  model.bodies.push_back(info);
}

void volumeGradient(const Model& model, const BodyInfo& body, const Vec3* x, Vec3* g) {
  // Each face adds (x1 - x0) x (x2 - x0) / 6, a third of its area vector, to each corner.
  std::fill(g, g + body.vertexCount, Vec3{});
  for (uint32_t f = body.firstFace; f < body.firstFace + body.faceCount; ++f) {
    const Triangle& t = model.faces[f];
    const Vec3 n = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]) / 6.0;
    for (uint32_t i : t) g[i - body.firstVertex] += n;
  }
}

double volumeModeSum(const Model& model, const BodyInfo& body, const Vec3* x, const double* invMass) {
  if (!invMass) invMass = model.invMass.data();
  std::vector<Vec3> g(body.vertexCount);
  volumeGradient(model, body, x, g.data());
  double sum = 0.0;
  for (uint32_t k = 0; k < body.vertexCount; ++k) sum += lengthSquared(g[k]) * invMass[body.firstVertex + k];
  return sum;
}

double gasPressureFromPeriod(const Model& model, const BodyInfo& body, double period) {
  const double sum = volumeModeSum(model, body, model.restPosition.data());
  const double omega = 2 * kPi / period;
  return sum > 0.0 ? omega * omega * body.restVolume / sum : 0.0;
}

}  // namespace springy
