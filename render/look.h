// Why: the look of a frame (linear-light shading, the tone curve, sRGB output) is GLSL run inside
// the mesh shader; tests need to see that curve exactly as the GPU runs it, and the renderer needs
// the matching CPU decoding of display colours.
#pragma once
#include <cstdint>
#include <glm/glm.hpp>
#include <span>
#include <vector>

namespace springy::render {

// IEC 61966-2-1 sRGB decoding of a display colour (0..1) to linear light.
glm::vec3 srgbToLinear(glm::vec3 display);

// The mesh shader's toDisplay (tone curve, then sRGB encoding) applied on the GPU to each linear
// colour: one RGBA8 pixel (display bytes, as a frame would hold them) per input, in order.
// Creates its own offscreen GL context. Throws RenderError.
std::vector<glm::u8vec3> toneCurveOnGpu(std::span<const glm::vec3> linear);

}  // namespace springy::render
