// springy: the immutable part of a simulation, built once from a scene.
//
// Following MuJoCo's mjModel / mjData split, everything that does not change while stepping
// lives here as flat arrays indexed by uint32_t: per-vertex masses, struts (one per mesh
// edge, or one per vertex pair in the legacy model), hinges (one per interior edge: a torsion
// spring across the two faces that share it), faces, pins, forces and colliders. The mutable
// state (positions, velocities) and the scratch space live in World.
//
// All bodies share one global vertex array; a body is a contiguous range of it.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "sim/colliders.h"
#include "sim/embedding.h"
#include "sim/mesh.h"
#include "sim/vec3.h"

namespace springy {

// A damped spring between two vertices (seed eq. 1-4; House & Keyser, springy meshes).
struct Strut {
  uint32_t i, j;
  double restLength;  // [m]
  double stiffness;   // k [N/m]
  double damping;     // d [N s/m]
};

// A torsion spring about the edge v0 -> v1 shared by the faces (v0, v1, v2) and (v1, v0, v3)
// (seed eq. 5-20). The angle is the signed dihedral angle between the two outward face
// normals, measured with the same function that computes the forces, so the rest angle is in
// the forces' own convention.
struct Hinge {
  uint32_t v[4];
  double restAngle;  // theta0 [rad]
  double stiffness;  // k_theta [N m / rad]
  double damping;    // d_theta [N m s / rad]
  double minLever[2] = {0.0, 0.0};  // below these |r_l|, |r_r| the hinge fades out (1/5 of rest) [m]
};

enum class SpringModel {
  Springy,   // struts on mesh edges + hinges on interior edges
  AllPairs,  // the seed's legacy model: struts between every pair of vertices, no hinges
};

enum class MassDistribution { AngleWeightedArea, Uniform };

// The user's description of one soft body, after its shape has been generated or loaded.
struct BodyDesc {
  std::string name;
  std::string source;  // where it was described, e.g. "scene.toml:12:1: [[body]] #2" (for messages)
  std::string note;    // what loading did that the user should know (a proxy built), or empty
  // When the body simulates a proxy: the mesh the user gave (world coordinates, its own topology),
  // which is what is drawn, bound to the proxy (`mesh`) at rest. Empty otherwise.
  TriMesh drawMesh;
  Embedding drawBinding;
  TriMesh mesh;  // rest shape, already scaled, rotated and placed in the world
  Vec3 velocity;  // initial velocity of every vertex [m/s]
  Vec3 angularVelocity;  // initial spin about the centroid [rad/s]
  SpringModel model = SpringModel::Springy;
  MassDistribution massDistribution = MassDistribution::AngleWeightedArea;
  double mass = 1.0;  // total [kg]
  // Either periods and decay times (seed eq. 22-25) or direct constants; direct wins when set.
  double strutDecay = 0.03, strutPeriod = 0.07;  // T, P [s]
  double hingeDecay = 2.0, hingePeriod = 0.5;    // T_theta, P_theta [s]; hingePeriod <= 0: no hinges
  std::optional<double> strutStiffness, strutDamping, hingeStiffness, hingeDamping;
  // Enclosed gas (Matyka & Ollila 2004): the period of the gas's breathing mode [s], from which
  // its pressure p0 is derived; 0: no gas. Needs a closed mesh.
  double volumePeriod = 0.0;
  std::vector<uint32_t> pinned;  // body-local vertex indices held fixed in place
};

struct BodyInfo {
  std::string name;
  uint32_t firstVertex = 0, vertexCount = 0;
  uint32_t firstStrut = 0, strutCount = 0;
  uint32_t firstHinge = 0, hingeCount = 0;
  uint32_t firstFace = 0, faceCount = 0;
  double mass = 0.0;        // [kg]
  double restVolume = 0.0;  // [m^3]
  double restSize = 0.0;    // bounding-box diagonal at rest [m]
  // Enclosed isothermal ideal gas at the ambient pressure p0 when the volume is restVolume: its
  // pressure over the ambient is p0 (V0 / V - 1). 0: the body holds no gas. [Pa]
  double gasPressure = 0.0;
  // The model's vertices are the mesh's in order along the body's longest side, so that
  // vertices near in space are near in memory and a contiguous index range is a slab of the
  // body (what one thread owns). modelVertex[k] is the global model index of the mesh's vertex
  // k; messages and scene keys (pins) speak of mesh indices.
  std::vector<uint32_t> modelVertex;
};

// Wind: the air moves with velocity w(t) = base * (1 + gust(t)), gust a smooth seeded
// pseudo-random signal (a sum of sinusoids with random phases), so runs repeat exactly.
struct Wind {
  Vec3 velocity;               // base air velocity [m/s]
  double gustStrength = 0.0;   // relative amplitude of gusts (0 = steady)
  double gustPeriod = 2.0;     // typical gust period [s]
  uint64_t seed = 1;
  double pressure = 0.0;       // face pressure coefficient [kg / (m^2 s)]
  double phase[4] = {0, 0, 0, 0};  // derived from seed at build time
  double frequency[4] = {0, 0, 0, 0};
  Vec3 airVelocity(double t) const;
};

struct Model {
  // Per vertex.
  std::vector<double> mass;     // [kg]
  std::vector<double> invMass;  // 1/mass, 0 for pinned vertices [1/kg]
  std::vector<Vec3> restPosition;
  std::vector<uint32_t> body;   // owning body of each vertex
  // Elements.
  std::vector<Strut> struts;
  std::vector<Hinge> hinges;
  std::vector<Triangle> faces;  // global vertex indices, outward-oriented
  std::vector<BodyInfo> bodies;
  std::vector<uint32_t> pinned;  // global indices
  // Initial state.
  std::vector<Vec3> initialVelocity;
  // Environment.
  Vec3 gravity{0.0, -9.81, 0.0};  // [m/s^2]
  double drag = 0.0;              // linear drag relative to the air [1/s]: f = -drag m (v - w)
  std::optional<Wind> wind;
  Colliders colliders;

  std::size_t vertexCount() const { return mass.size(); }
};

// Adds one body to the model: distributes mass, builds struts and hinges and converts the
// user's periods and decay times into spring constants. Throws springy::Error naming the body
// and the offending edge or vertex for degenerate geometry (zero-length edge, zero-area face,
// a hinge whose wing vertex lies on the hinge line) or an invalid parameter.
void addBody(Model& model, const BodyDesc& desc);

// Gas pressure p0 [Pa] that gives a closed body's breathing mode (the volume's oscillation
// against the gas alone) the angular frequency 2 pi / period: omega^2 = p0 sum_i |g_i|^2 / m_i
// / V0, with g_i = dV/dx_i at rest. Pinned vertices do not take part.
double gasPressureFromPeriod(const Model& model, const BodyInfo& body, double period);
// g_k = dV/dx_k of a closed body's enclosed volume for its vertices k = 0 .. vertexCount - 1
// (body-local) at positions x (global).
void volumeGradient(const Model& model, const BodyInfo& body, const Vec3* x, Vec3* g);
// sum_i |dV/dx_i|^2 / m_i over a body's free vertices at positions x [m^4 / kg].
double volumeModeSum(const Model& model, const BodyInfo& body, const Vec3* x);

// Area share of each vertex of a mesh: each face gives its area to its corners in proportion
// to the corner's interior angle (angle / pi), seed 3.3.1. Sums to the total surface area.
std::vector<double> angleWeightedAreas(const TriMesh& mesh);

// Seed eq. 22-25: spring constants from a period P and a decay time T for a mass m.
// P is the period of a mass m on the spring against a fixed end; T the time in which the
// amplitude falls by a factor e. r is the lever arm of a torsion spring.
inline double stiffnessFromPeriod(double m, double period) { return m * (2 * kPi / period) * (2 * kPi / period); }
inline double dampingFromDecay(double m, double decay) { return 2 * m / decay; }
inline double torsionStiffnessFromPeriod(double m, double r, double period) {
  return m * r * r * (2 * kPi / period) * (2 * kPi / period);
}
inline double torsionDampingFromDecay(double m, double r, double decay) { return 2 * m * r * r / decay; }

}  // namespace springy
