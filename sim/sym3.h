// springy: a symmetric 3x3 matrix, the per-vertex block of vertex block descent (sim/vbd.h)
// that each force kind adds its term to (sim/force_kinds.h).
#pragma once

#include "sim/model.h"

namespace springy {

// A symmetric 3x3 matrix: xx, yy, zz, xy, xz, yz.
struct Sym3 {
  double a[6] = {0, 0, 0, 0, 0, 0};
  void addDiagonal(double s) {
    a[0] += s;
    a[1] += s;
    a[2] += s;
  }
  void addOuter(const Vec3& u, double s) {  // += s u u^T
    a[0] += s * u.x * u.x;
    a[1] += s * u.y * u.y;
    a[2] += s * u.z * u.z;
    a[3] += s * u.x * u.y;
    a[4] += s * u.x * u.z;
    a[5] += s * u.y * u.z;
  }
};

}  // namespace springy
