// Why: every pass of the renderer compiles, links and feeds uniforms to a GL program the same
// way. Program does that once: compile + link with the driver's log in the RenderError, and
// uniform locations cached by name (a lookup per set() would cost a driver call each time).
// Internal to render/; needs the current GL context of the thread that created it.
#pragma once
#include <GL/gl.h>
#include <GL/glext.h>

#include <glm/glm.hpp>
#include <glm/gtc/type_ptr.hpp>
#include <string>
#include <unordered_map>
#include <utility>

namespace springy::render {

class Program {
public:
  Program() = default;
  // Compiles and links; `what` names the program in errors. Throws RenderError.
  Program(const char* vs, const char* fs, const char* what);
  ~Program() {
    if (id_) glDeleteProgram(id_);
  }
  Program(const Program&) = delete;
  Program& operator=(const Program&) = delete;
  Program(Program&& o) noexcept : id_(std::exchange(o.id_, 0u)), locs_(std::move(o.locs_)) {}
  Program& operator=(Program&& o) noexcept {
    std::swap(id_, o.id_);
    std::swap(locs_, o.locs_);
    return *this;
  }
  void use() const { glUseProgram(id_); }
  GLint loc(const char* name) {
    auto it = locs_.find(name);
    if (it != locs_.end()) return it->second;
    const GLint l = glGetUniformLocation(id_, name);
    locs_.emplace(name, l);
    return l;
  }
  void set(const char* n, int v) { glUniform1i(loc(n), v); }
  void set(const char* n, float v) { glUniform1f(loc(n), v); }
  void set(const char* n, glm::vec2 v) { glUniform2fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, glm::vec3 v) { glUniform3fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, glm::vec4 v) { glUniform4fv(loc(n), 1, glm::value_ptr(v)); }
  void set(const char* n, const glm::mat4& m) { glUniformMatrix4fv(loc(n), 1, GL_FALSE, glm::value_ptr(m)); }

private:
  GLuint id_ = 0;
  std::unordered_map<std::string, GLint> locs_;
};

}  // namespace springy::render
