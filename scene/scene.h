// springy: scene files, the library above the simulation that reads them.
//
// A scene is a TOML file (human-editable, with comments): simulation settings, environment,
// bodies, colliders, props and render settings. Reading it gives two descriptions: what to
// simulate (SimulationDesc, sim/setup.h, which buildModel turns into the Model) and how to show
// it (ViewDesc: colours, props, camera, light, video settings), which only the renderer's side
// of the program reads. Every error names the file, line and key; an unknown key is an error,
// so a typo never passes silently as a default. The keys and their defaults are documented in
// scenes/README.md.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "sim/motion.h"
#include "sim/setup.h"

namespace springy {

struct Material {
  Vec3 color{0.8, 0.8, 0.8};  // linear RGB in [0, 1]
  double alpha = 1.0;         // 1 opaque, < 1 translucent
  double shininess = 32.0;    // Phong exponent
  bool flat = false;          // faceted shading (for boxy shapes)
};

struct CameraDesc {
  std::optional<Vec3> position;  // [m]
  std::optional<Vec3> target;    // looked-at point
  std::optional<Vec3> angles;    // Euler angles [deg] (pitch down, yaw, roll) instead of target
  double fov = 60.0;             // vertical field of view [deg]
};

struct LightDesc {
  Vec3 angles{50.0, -30.0, 0.0};  // Euler angles [deg] of a directional light (pitch, yaw, roll)
  Vec3 color{1.0, 0.957, 0.839};
  double ambient = 0.3;
};

struct RenderDesc {
  int width = 1280, height = 720;
  double fps = 30.0;
  int crf = 20;                     // H.264 quality, lower = better
  std::string preset = "veryfast";  // x264 preset
  bool shadows = true;
  bool antialias = true;
  bool overlay = true;
  int shadowMapSize = 2048;
  Vec3 skyTop{0.36, 0.56, 0.82}, skyBottom{0.85, 0.9, 0.95};
  CameraDesc camera;
  LightDesc light;
};

// Render-only geometry (the gallows), not a collider.
struct PropDesc {
  enum class Shape { Cylinder, Box } shape = Shape::Cylinder;
  Vec3 from, to;        // cylinder axis end points
  double radius = 0.5;  // cylinder radius
  Vec3 center, size;    // box
  Material material;
  Movement motion{};    // drawn where it takes the prop at each frame (a bar carrying pins)
};

// How a collider is drawn.
struct SurfaceLook {
  Material material;
  bool visible = true;
  double extent = 200.0;  // a plane's drawn half-size [m] (unused for triangle colliders)
};

// How a scene is shown: the looks are parallel to the simulation description's bodies, planes
// and triangle colliders.
struct ViewDesc {
  std::vector<Material> bodies;
  std::vector<SurfaceLook> planes;
  std::vector<SurfaceLook> triangleColliders;
  std::vector<PropDesc> props;  // drawn only, not colliders
  RenderDesc render;
};

// A scene: what to simulate (the SimulationDesc it is) and how to show it.
struct SceneDesc : SimulationDesc {
  std::string name;
  ViewDesc view;
  // The files the scene was read from (sceneInputs): no output of a run may replace one.
  std::vector<std::string> inputs;
};

// Reads and validates a scene file. Throws springy::Error "FILE:LINE:COLUMN: message".
SceneDesc loadScene(const std::string& path);
// The same from text in memory (`path` is used in messages and to resolve mesh paths).
SceneDesc parseScene(const std::string& text, const std::string& path);

// The files a scene's text reads, without reading them: the scene file `path`, each mesh file its
// bodies and [[triangles]] name and, where they exist, what a mesh reader reads beside a mesh (an
// OBJ's material libraries and the textures they name, a glTF's buffers and images). Every
// command checks the files it writes against them before it runs: a user's file is never an
// output. A text that is not TOML gives {path} (its error is reported when the scene is read).
std::vector<std::string> sceneInputs(const std::string& text, const std::string& path);

// Why a run with the scene's dt, substeps, duration and frame rate cannot be done, or nothing:
// a step longer than one frame (no step would fall between two frames), or more than kMaxSteps
// steps in all (sim/limits.h).
std::optional<std::string> runSettingsProblem(const SceneDesc& scene);

}  // namespace springy
