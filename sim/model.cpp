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
  const double size = length(boundsOf(mesh.positions).size());

  // Validate the geometry the forces divide by: edges and faces.
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

  BodyInfo info;
  info.name = desc.name;
  info.firstVertex = static_cast<uint32_t>(model.mass.size());
  info.vertexCount = static_cast<uint32_t>(nv);
  info.firstStrut = static_cast<uint32_t>(model.struts.size());
  info.firstHinge = static_cast<uint32_t>(model.hinges.size());
  info.firstFace = static_cast<uint32_t>(model.faces.size());
  info.faceCount = static_cast<uint32_t>(mesh.triangles.size());
  info.mass = desc.mass;
  info.restSize = size;
  info.contact = desc.contact;
  info.selfContact = desc.selfContact;
  info.contactThickness = desc.contactThickness;
  info.contactFriction = desc.contactFriction;
  info.contactRestitution = desc.contactRestitution;
  const uint32_t base = info.firstVertex;

  // Mass: angle-weighted area (docs/model.md §4, eq. A6) or uniform.
  std::vector<double> m(nv, desc.mass / static_cast<double>(nv));
  if (desc.massDistribution == MassDistribution::AngleWeightedArea) {
    const std::vector<double> share = angleWeightedAreas(mesh);
    double total = 0.0;
    for (double s : share) total += s;
    for (std::size_t i = 0; i < nv; ++i) {
      if (!(share[i] > 0.0)) {
        throw Error(where(desc) + ": vertex " + std::to_string(i) + " belongs to no triangle (it would get no mass)");
      }
      m[i] = desc.mass * share[i] / total;
    }
  }

  // Directed edges in (from, to, face) order, to pair each edge with its twin (the
  // neighbouring face): bucketed by their first vertex, each vertex's few then sorted; a twin
  // is looked up among its start vertex's edges.
  std::vector<uint32_t> edgeStart(nv + 1, 0);
  for (const Triangle& t : mesh.triangles) {
    for (uint32_t v : t) ++edgeStart[v + 1];
  }
  for (std::size_t i = 0; i < nv; ++i) edgeStart[i + 1] += edgeStart[i];
  std::vector<DirectedEdge> edges(mesh.triangles.size() * 3);
  {
    std::vector<uint32_t> next(edgeStart.begin(), edgeStart.end() - 1);
    for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
      const Triangle& t = mesh.triangles[f];
      for (int k = 0; k < 3; ++k) edges[next[t[k]]++] = {t[k], t[(k + 1) % 3], static_cast<uint32_t>(f)};
    }
  }
  for (std::size_t i = 0; i < nv; ++i) std::sort(edges.begin() + edgeStart[i], edges.begin() + edgeStart[i + 1]);
  auto findEdge = [&](uint32_t a, uint32_t b) -> const DirectedEdge* {
    for (uint32_t k = edgeStart[a]; k < edgeStart[a + 1]; ++k) {
      if (edges[k].to == b) return &edges[k];  // the first: the lowest face
    }
    return nullptr;
  };
  auto thirdVertex = [&](uint32_t face, uint32_t a, uint32_t b) {
    for (uint32_t v : mesh.triangles[face]) {
      if (v != a && v != b) return v;
    }
    return a;
  };

  // An open surface (a cloth, docs/model.md §18): marked so, or with a border edge (an edge of
  // one triangle, no twin). It encloses no volume.
  info.open = desc.cloth;
  for (std::size_t k = 0; k < edges.size() && !info.open; ++k) {
    if (!findEdge(edges[k].to, edges[k].from)) {
      if (desc.volumePeriod > 0.0) {
        throw Error(where(desc) + ": volume_period needs a closed mesh, but edge (" + std::to_string(edges[k].from) +
                    ", " + std::to_string(edges[k].to) + ") borders only triangle " + std::to_string(edges[k].face));
      }
      info.open = true;
    }
  }
  info.restVolume = info.open ? 0.0 : signedVolume(mesh.positions, mesh.triangles);

  // The body material (MaterialModel::Body): moduli from the periods at the body's size.
  const bool bodyMaterial = desc.material == MaterialModel::Body;
  if (bodyMaterial && desc.model == SpringModel::AllPairs) {
    throw Error(where(desc) + ": the all-pairs model takes the element material (periods per strut)");
  }
  std::vector<double> faceArea(mesh.triangles.size());
  double area = 0.0;
  for (std::size_t f = 0; f < mesh.triangles.size(); ++f) {
    const Triangle& t = mesh.triangles[f];
    faceArea[f] = 0.5 * length(cross(mesh.positions[t[1]] - mesh.positions[t[0]], mesh.positions[t[2]] - mesh.positions[t[0]]));
    area += faceArea[f];
  }
  if (bodyMaterial) {
    const double density = desc.mass / area, scale = std::sqrt(area / (4 * kPi));
    const double stretch =
        desc.stretchPeriod.value_or((info.open ? kClothStretchPeriod : kDefaultStretchPeriod) * scale);
    const double bend = desc.bendPeriod.value_or((info.open ? kClothBendPeriod : kDefaultBendPeriod) * scale);
    info.stretchPeriod = stretch;
    info.bendPeriod = bend;
    info.membraneModulus = density * scale * scale * (2 * kPi / stretch) * (2 * kPi / stretch);
    info.bendingModulus = bend > 0.0 ? density * std::pow(scale, 4) * (2 * kPi / bend) * (2 * kPi / bend) : 0.0;
    info.deformationDamping = desc.deformationDecay > 0.0 ? 2.0 / desc.deformationDecay : 0.0;
  }

  // faces: the one or two faces beside the edge (the second is the first for a border edge).
  auto strutConstants = [&](uint32_t i, uint32_t j, double rest, uint32_t face0, uint32_t face1, double& k, double& d) {
    if (bodyMaterial) {
      // A membrane of modulus Y: the edge's share of the area beside it (a third of each face,
      // so the shares sum to the body's area) over its length squared; equal stretch e of
      // every edge then stores 1/2 Y e^2 per unit area.
      const double share = (faceArea[face0] + (face1 != face0 ? faceArea[face1] : 0.0)) / 3.0;
      k = info.membraneModulus * share / (rest * rest);
      d = 0.0;
      return;
    }
    const double mean = 0.5 * (m[i] + m[j]);
    k = desc.strutStiffness ? *desc.strutStiffness : stiffnessFromPeriod(mean, desc.strutPeriod);
    d = desc.strutDamping ? *desc.strutDamping : dampingFromDecay(mean, desc.strutDecay);
  };
  auto addStrut = [&](uint32_t i, uint32_t j, uint32_t face0, uint32_t face1) {
    const double rest = length(mesh.positions[j] - mesh.positions[i]);
    if (!(rest > 1e-12 * size)) {
      throw Error(where(desc) + ": edge (" + std::to_string(i) + ", " + std::to_string(j) + ") has zero length");
    }
    Strut s{base + i, base + j, rest, 0.0, 0.0};
    strutConstants(i, j, rest, face0, face1, s.stiffness, s.damping);
    model.struts.push_back(s);
  };

  const bool useHinges =
      desc.model == SpringModel::Springy &&
      (bodyMaterial ? info.bendingModulus > 0.0 : (desc.hingeStiffness || desc.hingePeriod > 0.0));
  if (desc.model == SpringModel::AllPairs) {
    for (uint32_t i = 0; i < nv; ++i) {
      for (uint32_t j = i + 1; j < nv; ++j) addStrut(i, j, 0, 0);
    }
  } else {
    for (const DirectedEdge& e : edges) {
      // Each undirected edge once: at its direction with from < to, or at the only direction
      // it has (a border edge of an open mesh).
      const DirectedEdge* twin = findEdge(e.to, e.from);
      if (e.from > e.to && twin) continue;
      addStrut(e.from, e.to, e.face, twin ? twin->face : e.face);
      if (!useHinges || !twin) continue;
      Hinge h{{base + e.from, base + e.to, base + thirdVertex(e.face, e.from, e.to),
               base + thirdVertex(twin->face, e.from, e.to)},
              0.0, 0.0, 0.0};
      HingeGeometry g;
      const Vec3 &x0 = mesh.positions[e.from], &x1 = mesh.positions[e.to];
      if (!hingeGeometry(x0, x1, mesh.positions[h.v[2] - base], mesh.positions[h.v[3] - base], g) ||
          !(g.leverLeft > 1e-9 * size) || !(g.leverRight > 1e-9 * size)) {
        throw Error(where(desc) + ": hinge on edge (" + std::to_string(e.from) + ", " + std::to_string(e.to) +
                    ") has a wing vertex on the hinge line (a sliver face): it has no lever arm");
      }
      h.restAngle = g.theta;
      h.minLever[0] = 0.2 * g.leverLeft;
      h.minLever[1] = 0.2 * g.leverRight;
      if (bodyMaterial) {
        // Discrete shells' weight |e|^2 / (A_1 + A_2): a sheet of equilateral triangles bent
        // into a cylinder of radius R stores 1/2 D / R^2 per unit area, in any direction (the
        // hinges across the bend turn by h / R, h a triangle's height; test_material).
        const double rest = length(x1 - x0);
        h.stiffness = info.bendingModulus * rest * rest / (faceArea[e.face] + faceArea[twin->face]);
        h.damping = 0.0;
        model.hinges.push_back(h);
        continue;
      }
      const double mean = 0.5 * (m[e.from] + m[e.to]);
      const double r = 0.5 * (g.leverLeft + g.leverRight);  // at rest, once
      h.stiffness = desc.hingeStiffness ? *desc.hingeStiffness : torsionStiffnessFromPeriod(mean, r, desc.hingePeriod);
      h.damping = desc.hingeDamping ? *desc.hingeDamping
                  : desc.hingeDecay > 0.0 ? torsionDampingFromDecay(mean, r, desc.hingeDecay)
                                          : 0.0;
      model.hinges.push_back(h);
    }
  }
  info.strutCount = static_cast<uint32_t>(model.struts.size()) - info.firstStrut;
  info.hingeCount = static_cast<uint32_t>(model.hinges.size()) - info.firstHinge;

  // Vertices, initial velocity (translation + spin about the centroid), pins.
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
  orderSpatially(model, info);
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

double volumeModeSum(const Model& model, const BodyInfo& body, const Vec3* x) {
  std::vector<Vec3> g(body.vertexCount);
  volumeGradient(model, body, x, g.data());
  double sum = 0.0;
  for (uint32_t k = 0; k < body.vertexCount; ++k) sum += lengthSquared(g[k]) * model.invMass[body.firstVertex + k];
  return sum;
}

double gasPressureFromPeriod(const Model& model, const BodyInfo& body, double period) {
  const double sum = volumeModeSum(model, body, model.restPosition.data());
  const double omega = 2 * kPi / period;
  return sum > 0.0 ? omega * omega * body.restVolume / sum : 0.0;
}

}  // namespace springy
