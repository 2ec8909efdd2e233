// Why: one exception type for everything render/ can fail at (GL context, shaders, files,
// encoding), so the app can catch render failures separately from simulation ones.
#pragma once
#include <stdexcept>
#include <string>

namespace springy::render {

class RenderError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

}  // namespace springy::render
