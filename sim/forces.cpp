#include "sim/forces.h"

namespace springy {

void applyGravity(const Model& model, std::size_t begin, std::size_t end, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] += model.gravity * model.mass[i];
}

void applyDrag(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* v, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] -= (v[i] - air) * (model.drag * model.mass[i]);
}

void applyWindPressure(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* x,
                       const Vec3* v, Vec3* f) {
  const double c = model.wind->pressure;
  for (std::size_t k = begin; k < end; ++k) {
    const Triangle& t = model.faces[k];
    const Vec3 areaNormal = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]) * 0.5;  // |.| = area
    const Vec3 relative = air - (v[t[0]] + v[t[1]] + v[t[2]]) / 3.0;
    const double flux = dot(relative, areaNormal);  // = A (w - v) . n
    if (flux >= 0.0) continue;                       // leeward face
    const double area = length(areaNormal);
    if (!(area > 0.0)) continue;
    const Vec3 force = areaNormal * (c * flux / area / 3.0);  // c A ((w - v) . n) n / 3
    for (uint32_t i : t) f[i] += force;
  }
}

}  // namespace springy
