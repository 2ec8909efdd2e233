#include "sim/forces.h"

namespace springy {
namespace {

// The wind's force on each corner of face t; false for a leeward or degenerate face.
inline bool windForce(const Triangle& t, double c, const Vec3& air, const Vec3* x, const Vec3* v,
                      Vec3& force) {
  const Vec3 areaNormal = cross(x[t[1]] - x[t[0]], x[t[2]] - x[t[0]]) * 0.5;  // |.| = area
  const Vec3 relative = air - (v[t[0]] + v[t[1]] + v[t[2]]) / 3.0;
  const double flux = dot(relative, areaNormal);  // = A (w - v) . n
  if (flux >= 0.0) return false;                   // leeward face
  const double area = length(areaNormal);
  if (!(area > 0.0)) return false;
  force = areaNormal * (c * flux / area / 3.0);  // c A ((w - v) . n) n / 3
  return true;
}

}  // namespace

void applyGravity(const Model& model, std::size_t begin, std::size_t end, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] += model.gravity * model.mass[i];
}

void applyDrag(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* v, Vec3* f) {
  for (std::size_t i = begin; i < end; ++i) f[i] -= (v[i] - air) * (model.drag * model.mass[i]);
}

void applyWindPressure(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* x,
                       const Vec3* v, Vec3* f) {
  const double c = model.wind->pressure;
  Vec3 force;
  for (std::size_t k = begin; k < end; ++k) {
    const Triangle& t = model.faces[k];
    if (!windForce(t, c, air, x, v, force)) continue;
    for (uint32_t i : t) f[i] += force;
  }
}

void applyWindPressureOwned(const Model& model, const ElementRef* list, std::size_t count, const Vec3& air,
                       const Vec3* x, const Vec3* v, Vec3* f) {
  const double c = model.wind->pressure;
  Vec3 force;
  for (std::size_t r = 0; r < count; ++r) {
    const Triangle& t = model.faces[list[r].index];
    if (!windForce(t, c, air, x, v, force)) continue;
    for (int i = 0; i < 3; ++i) {
      if (list[r].mask & (1u << i)) f[t[i]] += force;
    }
  }
}

}  // namespace springy
