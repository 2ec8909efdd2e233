// Why: the renderer's GLSL sources in one place, apart from the GL calls that use them. Each
// program is a vertex + fragment pair; the mesh and FXAA fragment shaders are compiled in
// variants chosen by preprocessor switches (#define ... 0/1), because llvmpipe executes both
// sides of a branch, even on a uniform: a fragment should only run the code it needs.
// Internal to render/ (not part of the library's interface).
#pragma once
#include <string>

namespace springy::render {

// Meshes: position + normal in, world position, normal and light-space position out.
extern const char* const kMeshVs;
// The sRGB encoding and the tone curve (GLSL functions srgbEncode, toneMap, toDisplay).
extern const char* const kLookGlsl;
// The mesh fragment shader with SHADOWS (4-tap PCF), GROUND (box-filtered checker fading into
// the sky), FLAT (faceted normals from screen-space derivatives), JELLY (gelatine: wrap
// diffuse, thickness-driven transmission and opacity, Fresnel rim; premultiplied alpha) and
// CONTACT (contact shadows from the occluder list) switched on or off.
std::string meshVariantSource(bool shadows, bool ground, bool flat, bool jelly, bool contact);

// Shadow map: depth only, from the light.
extern const char* const kDepthVs;
extern const char* const kDepthFs;

// One screen-covering triangle on the far plane (depth 1): the sky, and the FXAA edge pass.
extern const char* const kSkyVs;
// One screen-covering triangle at depth 0.5: the FXAA blend pass.
extern const char* const kMidVs;
// Vertical sky gradient.
extern const char* const kSkyFs;

// FXAA-style anti-aliasing over the scene texture. edgePass: write each pixel's exact colour and
// mark edge pixels at depth 0; otherwise blend along the edge (drawn only over marked pixels).
std::string fxaaSource(bool edgePass);

// The overlay: a textured screen rectangle, premultiplied alpha.
extern const char* const kOverlayVs;
extern const char* const kOverlayFs;

}  // namespace springy::render
