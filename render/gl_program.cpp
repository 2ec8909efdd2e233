#include "render/gl_program.h"

#include <algorithm>

#include "render/error.h"

namespace springy::render {

namespace {

GLuint compile(GLenum type, const char* src, const char* what) {
  const GLuint s = glCreateShader(type);
  glShaderSource(s, 1, &src, nullptr);
  glCompileShader(s);
  GLint ok = 0;
  glGetShaderiv(s, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetShaderiv(s, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetShaderInfoLog(s, len, nullptr, log.data());
    glDeleteShader(s);
    throw RenderError(std::string("Renderer: ") + what + " shader failed to compile: " + log);
  }
  return s;
}

}  // namespace

Program::Program(const char* vs, const char* fs, const char* what) {
  const GLuint v = compile(GL_VERTEX_SHADER, vs, what);
  GLuint f = 0;
  try {
    f = compile(GL_FRAGMENT_SHADER, fs, what);
  } catch (...) {
    glDeleteShader(v);
    throw;
  }
  id_ = glCreateProgram();
  glAttachShader(id_, v);
  glAttachShader(id_, f);
  glLinkProgram(id_);
  glDeleteShader(v);
  glDeleteShader(f);
  GLint ok = 0;
  glGetProgramiv(id_, GL_LINK_STATUS, &ok);
  if (!ok) {
    GLint len = 0;
    glGetProgramiv(id_, GL_INFO_LOG_LENGTH, &len);
    std::string log(static_cast<std::size_t>(std::max(len, 1)), '\0');
    glGetProgramInfoLog(id_, len, nullptr, log.data());
    throw RenderError(std::string("Renderer: ") + what + " program failed to link: " + log);
  }
}

}  // namespace springy::render
