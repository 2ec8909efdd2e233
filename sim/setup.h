// springy: what a simulation is set up from (a scene file's simulation part, or a program's own
// description), and the model it builds. The scene reader (scene/scene.h) fills it from TOML;
// the simulation knows nothing of files, cameras or colours.
#pragma once

#include <optional>
#include <limits>
#include <string>
#include <vector>

#include "sim/colliders.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy {

// Vertices of a body attached to another body or to a triangle collider ([[attach]]).
struct AttachDesc {
  std::string where;                // file:line, for errors
  uint32_t body = 0;                // into SimulationDesc::bodies
  std::vector<uint32_t> vertices;   // the body's mesh vertices
  int toBody = -1;                  // another body, its mesh vertex nearest each of `vertices`, or
  std::vector<uint32_t> targets;
  int toCollider = -1;              // a [[triangles]] collider
  double period = 0.0;              // a soft spring's period [s] (of the pair's reduced mass on it); 0: hard
  double decay = 0.0;               // its decay time [s]
  double release = std::numeric_limits<double>::infinity();
};

struct SimulationDesc {
  std::string path;  // where it was described (error messages name it when a body has no source)
  // Time.
  double duration = 10.0;  // [s]
  double dt = 0.002;       // [s]
  int substeps = 1;        // steps of dt / substeps per dt
  bool stepGiven = false;  // dt or substeps were given (otherwise the advisor chooses the step)
  Integrator integrator = Integrator::RK4;
  double tolerance = 1e-4;     // the adaptive integrator's (bs32): local error / body size per step
  int iterations = 8;          // vbd's sweeps per step (VbdSolver::kDefaultIterations)
  double restingSpeed = -1.0;  // < 0: automatic (see buildModel)
  // Environment.
  Vec3 gravity{0.0, -9.81, 0.0};
  double drag = 0.0;
  std::optional<Wind> wind;
  // Contents.
  std::vector<BodyDesc> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<TriangleCollider> triangleColliders;
  std::vector<AttachDesc> attachments;
};

// The model a description builds. Throws springy::Error naming the body's source (file, line)
// when a body cannot be built or starts inside a plane.
Model buildModel(const SimulationDesc& desc);

// The step the world takes: dt / substeps.
inline double stepSize(const SimulationDesc& desc) { return desc.dt / desc.substeps; }

// The fraction of the stability advisor's estimated limit (sim/stability.h, made at rest) that a
// scene giving no step is run at, a margin for impacts. Measured (docs/materials.md,
// scripts/step_margin.sh): the largest step that survives a whole drop is 1.35-1.78 times the
// estimate for the body material's corpus, but 0.21 times it for the element material's
// bunny_light (its landing crushes the ears' faces): a scene with an element-material body gets
// the smaller margin.
constexpr double kImpactMargin = 0.5;
constexpr double kImpactMarginElement = 0.2;
double impactMargin(const SimulationDesc& desc);
// Sets desc.substeps to the advisor's choice for a scene that gives no step (at most
// impactMargin of the estimated stable limit); returns the limit (infinite: stable at any step,
// desc unchanged).
double adviseSubsteps(SimulationDesc& desc);

}  // namespace springy
