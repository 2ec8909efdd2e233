#include "sim/cases.h"

#include <algorithm>
#include <cmath>

#include "sim/error.h"
#include "sim/hinge.h"
#include "sim/shapes.h"

namespace springy {

// One free vertex of the given mass, no colliders.
Model vertexModel(const Vec3& position, const Vec3& velocity, const Vec3& gravity, double mass) {
  Model model;
  model.gravity = gravity;
  model.mass = {mass};
  model.invMass = {1.0 / mass};
  model.restPosition = {position};
  model.initialVelocity = {velocity};
  model.body = {0};
  BodyInfo info;
  info.name = "vertex";
  info.vertexCount = 1;
  info.mass = mass;
  model.bodies = {info};
  return model;
}

// Two vertices joined by one strut along x, no gravity, no colliders.
Model strutModel(double m0, double m1, double restLength, double k, double d, bool pinFirst) {
  Model model;
  model.gravity = {};
  model.mass = {m0, m1};
  model.invMass = {pinFirst ? 0.0 : 1.0 / m0, 1.0 / m1};
  model.restPosition = {{0, 0, 0}, {restLength, 0, 0}};
  model.initialVelocity = {{}, {}};
  model.body = {0, 0};
  model.struts = {{0, 1, restLength, k, d}};
  BodyInfo info;
  info.name = "strut";
  info.vertexCount = 2;
  info.strutCount = 1;
  info.mass = m0 + m1;
  model.bodies = {info};
  if (pinFirst) model.pinned = {0};
  return model;
}

// Two triangles (0, 1, 2) and (1, 0, 3) sharing the edge 0-1 along x, folded to `angle`
// (the signed dihedral angle), unit masses, one hinge, optionally the five struts.
void applyHingesDerivingTerms(const Hinge* hinges, std::size_t begin, std::size_t end, const Vec3* x, const Vec3* v,
                              Vec3* f) {
  for (std::size_t k = begin; k < end; ++k) {
    const HingeTerms terms = hingeTerms(hinges[k]);
    applyHinges(hinges + k, &terms, Elements::range(0, 1), x, v, f);
  }
}

std::vector<Vec3> hingePositions(double angle) {
  // Left wing in the y > 0 half-plane tilted down by angle/2, right wing mirrored: the
  // dihedral angle of this pair is `angle` (positive = convex, normals along +z when flat).
  const double a = angle / 2;
  return {{0, 0, 0}, {1, 0, 0}, {0.4, std::cos(a), -std::sin(a)}, {0.6, -std::cos(a), -std::sin(a)}};
}

Model hingeModel(double restAngle, double k, double d, bool withStruts, double strutK,
                         double strutD) {
  Model model;
  model.gravity = {};
  model.mass = {1, 1, 1, 1};
  model.invMass = {1, 1, 1, 1};
  model.restPosition = hingePositions(restAngle);
  model.initialVelocity = std::vector<Vec3>(4);
  model.body = {0, 0, 0, 0};
  model.faces = {{0, 1, 2}, {1, 0, 3}};
  model.hinges = {{{0, 1, 2, 3}, restAngle, k, d}};
  if (withStruts) {
    const auto& p = model.restPosition;
    for (auto [i, j] : std::vector<std::pair<uint32_t, uint32_t>>{{0, 1}, {0, 2}, {1, 2}, {0, 3}, {1, 3}}) {
      model.struts.push_back({i, j, length(p[j] - p[i]), strutK, strutD});
    }
  }
  BodyInfo info;
  info.name = "hinge";
  info.vertexCount = 4;
  info.strutCount = static_cast<uint32_t>(model.struts.size());
  info.hingeCount = 1;
  info.faceCount = 2;
  info.mass = 4;
  model.bodies = {info};
  return model;
}

namespace {

BodyInfo singleBody(const std::string& name, const Model& model) {
  BodyInfo info;
  info.name = name;
  info.vertexCount = static_cast<uint32_t>(model.mass.size());
  info.strutCount = static_cast<uint32_t>(model.struts.size());
  info.hingeCount = static_cast<uint32_t>(model.hinges.size());
  info.faceCount = static_cast<uint32_t>(model.faces.size());
  for (double m : model.mass) info.mass += m;
  info.restSize = length(boundsOf(model.restPosition).size());
  return info;
}


// A ball (icosphere, 42 vertices, radius 1, mass 1) with the given parameters.
BodyDesc ball(double strutPeriod, double strutDecay, double hingePeriod, double hingeDecay) {
  BodyDesc desc;
  desc.name = "ball";
  desc.mesh = makeIcosphere(1.0, 1);
  desc.mass = 1.0;
  desc.strutPeriod = strutPeriod;
  desc.hingePeriod = hingePeriod;
  if (strutDecay > 0) desc.strutDecay = strutDecay;
  else desc.strutDamping = 0.0;
  if (hingeDecay > 0) desc.hingeDecay = hingeDecay;
  else desc.hingeDamping = 0.0;
  return desc;
}

StabilityCase fromBody(const std::string& name, const std::string& description, const BodyDesc& desc,
                       Vec3 gravity = {}) {
  StabilityCase c;
  c.name = name;
  c.description = description;
  c.model.gravity = gravity;
  addBody(c.model, desc);
  c.positions = c.model.restPosition;
  return c;
}

// The cases of stabilityCases(), one function each.

StabilityCase stiffStrut() {
  StabilityCase c = strutCase(0.001, 0.1);
  c.name = "stiff strut";
  c.description = "two masses, one strut, P = 1 ms, T = 0.1 s";
  return c;
}

StabilityCase stiffHinge() {
  StabilityCase c = hingeCase(0.001, 0.1);
  c.name = "stiff hinge";
  c.description = "two triangles, one hinge, P_theta = 1 ms, T_theta = 0.1 s, released bent";
  return c;
}

StabilityCase stiffBall() {
  StabilityCase c = fromBody("stiff ball", "icosphere, P = P_theta = 1 ms, released squashed to 0.7",
                             ball(0.001, 0.1, 0.001, 0.1));
  for (Vec3& p : c.positions) p.y *= 0.7;
  return c;
}

// The gas is the stiff term, and it stiffens as the volume falls (p V = const).
StabilityCase stiffGas() {
  BodyDesc desc = ball(0.05, 0.1, 0.0, 0.0);
  desc.volumePeriod = 0.0002;
  StabilityCase c = fromBody("stiff gas", "icosphere, P = 50 ms, no hinges, gas P_V = 0.2 ms, released squashed to 0.7",
                             desc);
  for (Vec3& p : c.positions) p.y *= 0.7;
  return c;
}

StabilityCase overdamped() {
  StabilityCase c = fromBody("overdamped", "icosphere, P = 50 ms, T = 0.1 ms (T << P: damping is the stiff term)",
                             ball(0.05, 1e-4, 0.5, 2.0));
  for (Vec3& p : c.positions) p.y *= 0.7;
  return c;
}

StabilityCase undamped() {
  StabilityCase c = fromBody("undamped", "icosphere, P = 50 ms, P_theta = 0.5 s, no damping at all",
                             ball(0.05, 0.0, 0.5, 0.0));
  for (Vec3& p : c.positions) p.y *= 0.7;
  return c;
}

// Tiny triangles beside large ones: a cube whose corner vertices are pulled almost onto their
// neighbours would do it geometrically; the masses are what matter for stability, so every other
// vertex of the ball gets 1e-4 of its mass (springs keep their constants).
StabilityCase massRatio() {
  StabilityCase c = fromBody("mass ratio 1:1e4", "icosphere, P = 50 ms, every other vertex 1e-4 times lighter",
                             ball(0.05, 0.03, 0.5, 2.0));
  for (std::size_t i = 0; i < c.model.mass.size(); i += 2) {
    c.model.mass[i] *= 1e-4;
    c.model.invMass[i] = 1.0 / c.model.mass[i];
  }
  for (Vec3& p : c.positions) p.y *= 0.9;
  return c;
}

// A tetrahedron whose apex is pushed down to 1 % of its height: four sliver faces.
StabilityCase sliver() {
  BodyDesc desc = ball(0.05, 0.03, 0.5, 2.0);
  desc.name = "sliver";
  desc.mesh = makeTetrahedron(1.0);
  const Vec3 base = (desc.mesh.positions[0] + desc.mesh.positions[1] + desc.mesh.positions[2]) / 3.0;
  Vec3& apex = desc.mesh.positions[3];
  apex = base + (apex - base) * 0.01;
  StabilityCase c = fromBody("sliver", "tetrahedron flattened to 1 % of its height (hinge levers 1 % of edge)", desc);
  Vec3& lifted = c.positions[c.model.bodies[0].modelVertex[3]];  // the apex, in model numbering
  lifted = lifted + (lifted - base) * 0.5;
  return c;
}

StabilityCase degenerateSliver() {
  BodyDesc desc = ball(0.05, 0.03, 0.5, 2.0);
  desc.name = "degenerate";
  desc.mesh = makeTetrahedron(1.0);
  // Apex on the base plane's edge line: a hinge with |r| = 0 and a zero-area face.
  desc.mesh.positions[3] = (desc.mesh.positions[0] + desc.mesh.positions[1]) * 0.5;
  return fromBody("degenerate sliver", "tetrahedron with its apex on an edge (|r| = 0): refused at load", desc);
}

StabilityCase flatHinge() {
  StabilityCase c = hingeCase(0.01, 0.1, 1e-6, 0.3);
  c.name = "flat hinge";
  c.description = "hinge with theta0 = 1e-6 (flat), P_theta = 10 ms, released at 0.3 rad";
  return c;
}

StabilityCase foldedHinge() {
  StabilityCase c = hingeCase(0.01, 0.1, 3.1, -3.0);
  c.name = "folded hinge";
  c.description = "hinge with theta0 = 3.1 rad, released at -3.0 (through +-pi, where the angle wraps)";
  return c;
}

StabilityCase squashed() {
  StabilityCase c = fromBody("squashed", "icosphere (P = 50 ms) squashed to a tenth of its height at t = 0",
                             ball(0.05, 0.03, 0.5, 2.0));
  for (Vec3& p : c.positions) p.y *= 0.1;
  return c;
}

// Ten times the free-fall speed from 1 m (44 m/s) onto a thin triangle plate. The ball is stiffer
// than the others (P = 20 ms, P_theta = 0.2 s) so that it physically survives the impact: with
// P = 50 ms it turns inside out at any step (measured with RK4 at 20 us), and the case would
// measure the physics, not the integrators.
StabilityCase impact() {
  BodyDesc desc = ball(0.02, 0.03, 0.2, 2.0);
  desc.velocity = {0, -10.0 * std::sqrt(2 * 9.81 * 1.0), 0};
  for (Vec3& p : desc.mesh.positions) p.y += 1.5;
  StabilityCase c = fromBody("impact", "icosphere at 10x free-fall speed (44 m/s) onto a thin triangle", desc,
                             {0, -9.81, 0});
  TriangleCollider plate;
  plate.name = "plate";
  plate.mesh.positions = {{-3, 0, -3}, {3, 0, -3}, {0, 0, 4}};
  plate.mesh.triangles = {{0, 2, 1}};
  plate.buildBvh();
  c.model.colliders.meshes.push_back(plate);
  c.model.colliders.restingSpeed = 0.1;
  c.model.initialVelocity = std::vector<Vec3>(c.model.mass.size(), desc.velocity);
  return c;
}

// Stiffened as the impact case (P = 20 ms, P_theta = 0.2 s): with P = 50 ms the ball, hitting at
// 31 m/s, physically squashes to 9% of its volume (RK4 at 20 us) and backward Euler's flattening
// to 0% or just above was decided by rounding.
StabilityCase gravity100g() {
  BodyDesc desc = ball(0.02, 0.03, 0.2, 2.0);
  for (Vec3& p : desc.mesh.positions) p.y += 1.5;
  StabilityCase c = fromBody("gravity 100 g", "icosphere dropped from 0.5 m onto the ground under 981 m/s^2", desc,
                             {0, -981.0, 0});
  c.model.colliders.planes.push_back({{0, 0, 0}, {0, 1, 0}, {}});
  c.model.colliders.restingSpeed = 4.0 * 981.0 * 1e-3;
  return c;
}

}  // namespace

StabilityCase strutCase(double period, double decay) {
  StabilityCase c;
  c.name = "strut";
  c.model = strutModel(1.0, 1.0, 1.0, stiffnessFromPeriod(1.0, period), decay > 0 ? dampingFromDecay(1.0, decay) : 0.0,
                       false);
  c.model.bodies = {singleBody("strut", c.model)};
  c.positions = {{0, 0, 0}, {1.1, 0, 0}};
  return c;
}

StabilityCase hingeCase(double period, double decay, double restAngle, double startAngle) {
  StabilityCase c;
  c.name = "hinge";
  const std::vector<Vec3> x = hingePositions(restAngle);
  HingeGeometry g;
  hingeGeometry(x[0], x[1], x[2], x[3], g);
  const double r = 0.5 * (g.leverLeft + g.leverRight);
  // Struts of twice the hinge's period hold the triangles' shape (softer struts would let the
  // hinge crush its own faces).
  c.model = hingeModel(g.theta, torsionStiffnessFromPeriod(1.0, r, period),
                       decay > 0 ? torsionDampingFromDecay(1.0, r, decay) : 0.0, true,
                       stiffnessFromPeriod(1.0, 2 * period), decay > 0 ? dampingFromDecay(1.0, decay) : 0.0);
  c.model.hinges[0].minLever[0] = 0.2 * g.leverLeft;
  c.model.hinges[0].minLever[1] = 0.2 * g.leverRight;
  c.model.bodies = {singleBody("hinge", c.model)};
  c.positions = hingePositions(startAngle);
  return c;
}

std::vector<CaseFactory> stabilityCases() {
  // name, degenerate (must be refused at load), stiff, the case
  return {{"stiff strut", false, false, stiffStrut},
          {"stiff hinge", false, false, stiffHinge},
          {"stiff ball", false, true, stiffBall},
          {"stiff gas", false, true, stiffGas},
          {"overdamped", false, true, overdamped},
          {"undamped", false, false, undamped},
          {"mass ratio 1:1e4", false, true, massRatio},
          {"sliver", false, false, sliver},
          {"degenerate sliver", true, false, degenerateSliver},
          {"flat hinge", false, false, flatHinge},
          {"folded hinge", false, false, foldedHinge},
          {"squashed", false, false, squashed},
          {"impact", false, false, impact},
          {"gravity 100 g", false, false, gravity100g}};
}

}  // namespace springy
