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

#include <algorithm>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "sim/colliders.h"
#include "sim/embedding.h"
#include "sim/mesh.h"
#include "sim/vec3.h"

namespace springy {

// A damped spring between two vertices (docs/model.md, eq. S1-S4; House & Keyser, springy meshes).
struct Strut {
  uint32_t i, j;
  double restLength;  // [m]
  double stiffness;   // k [N/m]
  double damping;     // d [N s/m]
};

// A torsion spring about the edge v0 -> v1 shared by the faces (v0, v1, v2) and (v1, v0, v3)
// (docs/model.md, eq. S5-S20, A1-A5). The angle is the signed dihedral angle between the two
// outward face normals, measured with the same function that computes the forces, so the rest
// angle is in the forces' own convention.
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
             // (docs/model.md §9)
};

enum class MassDistribution { AngleWeightedArea, Uniform };

// How a body's stiffness and damping are given.
enum class MaterialModel {
  // The seed's (docs/model.md, eq. S22-S25): every strut and hinge gets its own period and
  // decay time, as a mass on that one spring. A body's behaviour then changes with its mesh:
  // for given periods the bending stiffness falls with the cube of the mesh spacing.
  Element,
  // A material of the body, the same at every resolution: a membrane modulus and a bending
  // modulus, each element's constant scaled by its rest geometry (struts Y A_e / l^2, hinges
  // D |e|^2 / (A_1 + A_2), Grinspun et al. 2003, "Discrete Shells"), and damping of the
  // body's deformation relative to its rigid motion at one rate for every mode.
  Body,
};

// The body material's moduli from periods at the body's own size: with the area density
// rho = M / A and the length L = sqrt(A / 4 pi) (the radius of a sphere of the same area),
//   Y = rho L^2 (2 pi / P_stretch)^2     [N/m]    (energy density 1/2 Y e^2 under an equal
//                                                  stretch e in every direction)
//   D = rho L^4 (2 pi / P_bend)^2        [N m]    (energy density 1/2 D / R^2 bent to radius R)
// so that a body with its mass spread as a membrane of its own size stretches with about the
// period P_stretch and bends with about P_bend. The periods' defaults scale with L (a 1 m body:
// kDefaultStretchPeriod and kDefaultBendPeriod), so a drop from a given height squashes a
// small ball as much as a large one.
constexpr double kDefaultStretchPeriod = 0.05;    // [s] for L = 1 m
constexpr double kDefaultBendPeriod = 0.7;        // [s] for L = 1 m
constexpr double kDefaultDeformationDecay = 0.1;  // [s]
// An open surface's (a cloth's) defaults, also for L = 1 m (docs/model.md §18). Stretch: twice
// the period, a membrane a quarter as stiff: a 1 m cloth hung by two corners stretches 0.3% on
// average, 4% at the corners (tests/test_cloth.cpp), and the stable step is twice as long. Bend:
// 70 times the period, 5000 times softer: a 1.5 m square's bending length (D / (rho g))^(1/3)
// is 6.6 cm (a heavy fabric; the body default's, 1.1 m, is a sheet of cardboard). Stiffer (a
// shorter bend_period) for a flag that flaps without self contact (scenes/flag.toml).
constexpr double kClothStretchPeriod = 0.1;  // [s] for L = 1 m
constexpr double kClothBendPeriod = 50.0;    // [s] for L = 1 m

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
  // An open surface (a cloth, docs/model.md §18): the mesh may have border edges (they get struts,
  // no hinges); the body has no volume (no gas, no volume checks) and the cloth's material
  // defaults. A mesh with border edges is an open surface whether or not this is set.
  bool cloth = false;
  Vec3 velocity;  // initial velocity of every vertex [m/s]
  Vec3 angularVelocity;  // initial spin about the centroid [rad/s]
  SpringModel model = SpringModel::Springy;
  MassDistribution massDistribution = MassDistribution::AngleWeightedArea;
  double mass = 1.0;  // total [kg]
  // Either periods and decay times (docs/model.md, eq. S22-S25) or direct constants; direct wins
  // when set.
  double strutDecay = 0.03, strutPeriod = 0.07;  // T, P [s]
  double hingeDecay = 2.0, hingePeriod = 0.5;    // T_theta, P_theta [s]; hingePeriod <= 0: no hinges
  std::optional<double> strutStiffness, strutDamping, hingeStiffness, hingeDamping;
  // Enclosed gas (Matyka & Ollila 2004): the period of the gas's breathing mode [s], from which
  // its pressure p0 is derived; 0: no gas. Needs a closed mesh.
  double volumePeriod = 0.0;
  // MaterialModel::Body: the periods at the body's size (unset: the defaults scaled by L) and
  // the time in which the body's deformation (its motion less the best rigid motion) decays
  // by e. The element keys above are then not used.
  MaterialModel material = MaterialModel::Element;
  std::optional<double> stretchPeriod, bendPeriod;  // P_stretch, P_bend [s]; bendPeriod 0: no hinges
  double deformationDecay = kDefaultDeformationDecay;  // [s]
  std::vector<uint32_t> pinned;  // body-local vertex indices held fixed in place
  // The pins move on their own: each pinned vertex is where the motion takes its rest position
  // (a frame carrying a cape, a hand holding a cloth); until `pinRelease` [s], then free (at the
  // velocity the motion gave it). No motion and an infinite release: held in place for good.
  Movement pinMotion;
  double pinRelease = std::numeric_limits<double>::infinity();
  // Contact with other bodies (sim/contact.h) and within itself; the thickness [m] (0: a tenth
  // of the mean edge length), the Coulomb friction coefficient and the restitution of impacts.
  bool contact = true;
  bool selfContact = false;
  double contactThickness = 0.0;
  double contactFriction = 0.3;
  double contactRestitution = 0.0;
};

struct BodyInfo {
  std::string name;
  uint32_t firstVertex = 0, vertexCount = 0;
  uint32_t firstStrut = 0, strutCount = 0;
  uint32_t firstHinge = 0, hingeCount = 0;
  uint32_t firstFace = 0, faceCount = 0;
  double mass = 0.0;        // [kg]
  double restVolume = 0.0;  // [m^3]; 0 for an open surface
  // An open surface (BodyDesc::cloth, or a mesh with a border edge): it encloses no volume, and
  // wind pushes its faces from either side.
  bool open = false;
  double restSize = 0.0;    // bounding-box diagonal at rest [m]
  // Enclosed isothermal ideal gas at the ambient pressure p0 when the volume is restVolume: its
  // pressure over the ambient is p0 (V0 / V - 1). 0: the body holds no gas. [Pa]
  double gasPressure = 0.0;
  // Damping of the deformation, f_i = -c m_i (v_i - v_rigid(x_i)) with v_rigid the body's
  // rigid motion that carries its linear and angular momentum (Mueller et al. 2007, "Position
  // Based Dynamics", section 3.5): every deformation mode decays at the rate c / 2, rigid motion
  // is untouched, momentum and angular momentum are kept. 0: none. [1/s]
  double deformationDamping = 0.0;
  // MaterialModel::Body: the periods used (given or default) and the moduli they gave (0
  // otherwise). [s], [N/m], [N m]
  double stretchPeriod = 0.0, bendPeriod = 0.0;
  double membraneModulus = 0.0, bendingModulus = 0.0;
  // Contact (BodyDesc's): with other bodies, within itself; thickness (0: automatic) [m]; friction.
  bool contact = true, selfContact = false;
  double contactThickness = 0.0, contactFriction = 0.3, contactRestitution = 0.0;
  // The model's vertices are the mesh's in order along the body's longest side, so that
  // vertices near in space are near in memory and a contiguous index range is a slab of the
  // body (what one thread owns). modelVertex[k] is the global model index of the mesh's vertex
  // k; messages and scene keys (pins) speak of mesh indices.
  std::vector<uint32_t> modelVertex;
  // The mesh's index of one of this body's model vertices (the inverse of modelVertex).
  uint32_t meshVertex(uint32_t modelIndex) const {
    const auto it = std::find(modelVertex.begin(), modelVertex.end(), modelIndex);
    return static_cast<uint32_t>(it - modelVertex.begin());
  }
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
  // A body whose pins move or are released (BodyDesc::pinMotion, pinRelease).
  struct PinTrack {
    uint32_t body = 0;
    Movement motion;  // may not move: pins that are only released
    double release = std::numeric_limits<double>::infinity();
    // Empty: every pinned vertex of the body. Otherwise these (global) vertices only, held
    // where they are relative to the moving thing (a hard attachment to a collider: each at
    // pose(t) pose(0)^-1 of its rest position).
    std::vector<uint32_t> vertices;
  };
  std::vector<PinTrack> pinTracks;
  // A soft attachment (AttachDesc): a damped spring from a vertex to a vertex of another body, or
  // to a point carried by a collider, until `release` [s]. Force on `vertex`, with D the vector
  // from it to the other end and u the other end's velocity relative to it:
  //   rest > 0: (k (|D| - rest) + d (u . D/|D|)) D/|D|;  rest 0: k D + d u
  // and the opposite on the other vertex.
  struct Attachment {
    static constexpr uint32_t kNone = 0xFFFFFFFFu;
    uint32_t vertex = 0;
    uint32_t other = kNone;     // a vertex of another body, or
    uint32_t collider = kNone;  // a triangle collider: the point `anchor` of it (at its rest placement)
    Vec3 anchor;
    double rest = 0.0, k = 0.0, d = 0.0;
    double release = std::numeric_limits<double>::infinity();
  };
  std::vector<Attachment> attachments;
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
double volumeModeSum(const Model& model, const BodyInfo& body, const Vec3* x, const double* invMass = nullptr);

// Area share of each vertex of a mesh: each face gives its area to its corners in proportion
// to the corner's interior angle (angle / pi), docs/model.md §4, eq. A6. Sums to the total
// surface area.
std::vector<double> angleWeightedAreas(const TriMesh& mesh);

// docs/model.md, eq. S22-S25 (the seed's): spring constants from a period P and a decay time T
// for a mass m.
// P is the period of a mass m on the spring against a fixed end; T the time in which the
// amplitude falls by a factor e. r is the lever arm of a torsion spring.
inline double stiffnessFromPeriod(double m, double period) { return m * (2 * kPi / period) * (2 * kPi / period); }
inline double dampingFromDecay(double m, double decay) { return 2 * m / decay; }
inline double torsionStiffnessFromPeriod(double m, double r, double period) {
  return m * r * r * (2 * kPi / period) * (2 * kPi / period);
}
inline double torsionDampingFromDecay(double m, double r, double decay) { return 2 * m * r * r / decay; }

}  // namespace springy
