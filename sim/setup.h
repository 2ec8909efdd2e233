// springy: what a simulation is set up from (a scene file's simulation part, or a program's own
// description), and the model it builds. The scene reader (scene/scene.h) fills it from TOML;
// the simulation knows nothing of files, cameras or colours.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sim/colliders.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy {

struct SimulationDesc {
  std::string path;  // where it was described (error messages name it when a body has no source)
  // Time.
  double duration = 10.0;  // [s]
  double dt = 0.002;       // [s]
  int substeps = 1;        // steps of dt / substeps per dt
  bool stepGiven = false;  // dt or substeps were given (otherwise the advisor chooses the step)
  Integrator integrator = Integrator::RK4;
  double restingSpeed = -1.0;  // < 0: automatic (see buildModel)
  // Environment.
  Vec3 gravity{0.0, -9.81, 0.0};
  double drag = 0.0;
  std::optional<Wind> wind;
  // Contents.
  std::vector<BodyDesc> bodies;
  std::vector<PlaneCollider> planes;
  std::vector<TriangleCollider> triangleColliders;
};

// The model a description builds. Throws springy::Error naming the body's source (file, line)
// when a body cannot be built or starts inside a plane.
Model buildModel(const SimulationDesc& desc);

// The step the world takes: dt / substeps.
inline double stepSize(const SimulationDesc& desc) { return desc.dt / desc.substeps; }

}  // namespace springy
