#include "render/look.h"

#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "render/error.h"
#include "render/gl_context.h"
#include "render/gl_program.h"
#include "render/shaders.h"

namespace springy::render {

glm::vec3 srgbToLinear(glm::vec3 display) {
  glm::vec3 out;
  for (int k = 0; k < 3; ++k) {
    const float c = std::clamp(display[k], 0.0f, 1.0f);
    out[k] = c <= 0.04045f ? c / 12.92f : std::pow((c + 0.055f) / 1.055f, 2.4f);
  }
  return out;
}

std::vector<glm::u8vec3> toneCurveOnGpu(std::span<const glm::vec3> linear) {
  if (linear.empty() || linear.size() > 16384) throw RenderError("toneCurveOnGpu: 1..16384 colours");
  const int n = static_cast<int>(linear.size());
  GlContext ctx(n, 1, SceneTarget::Plain);
  const std::string fs = std::string("#version 330 core\n") + kLookGlsl + R"(
uniform sampler2D uIn;
out vec4 fragColour;
void main() { fragColour = vec4(toDisplay(texelFetch(uIn, ivec2(gl_FragCoord.x, 0), 0).rgb), 1.0); }
)";
  Program prog(kSkyVs, fs.c_str(), "tone curve");
  GLuint tex = 0, vao = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB32F, n, 1, 0, GL_RGB, GL_FLOAT, linear.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glGenVertexArrays(1, &vao);
  ctx.bindFinalTarget();
  glDisable(GL_DEPTH_TEST);
  glDisable(GL_DITHER);
  prog.use();
  prog.set("uIn", 0);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glFinish();
  const GLenum err = glGetError();
  glDeleteVertexArrays(1, &vao);
  glDeleteTextures(1, &tex);
  if (err != GL_NO_ERROR) throw RenderError("toneCurveOnGpu: GL error " + std::to_string(err));
  std::vector<std::uint8_t> rgba;
  ctx.readPixels(rgba, true);
  std::vector<glm::u8vec3> out(linear.size());
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {rgba[4 * i], rgba[4 * i + 1], rgba[4 * i + 2]};
  return out;
}

}  // namespace springy::render
