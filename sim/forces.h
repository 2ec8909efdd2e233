// springy: external forces (gravity, air drag, wind), one function each over a vertex or
// face range. Struts and hinges live in strut.h and hinge.h.
#pragma once

#include <cstddef>

#include "sim/model.h"
#include "sim/parallel.h"

namespace springy {

// f_i += m_i g
void applyGravity(const Model& model, std::size_t begin, std::size_t end, Vec3* f);

// f_i += -c m_i (v_i - w): linear drag relative to the air (w = 0 without wind), seed 3.2's
// "plain velocity drag" made independent of mesh resolution by scaling with the vertex mass.
void applyDrag(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* v, Vec3* f);

// Wind pressure on faces [begin, end): a face turned into the relative wind (w - v_face) . n < 0
// is pushed along -n with force c A ((w - v_face) . n) n, split equally over its corners.
void applyWindPressure(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* x,
                       const Vec3* v, Vec3* f);
// The same for the listed faces, adding only to the corners whose bit is set in the mask.
void applyWindPressureOwned(const Model& model, const ElementRef* list, std::size_t count, const Vec3& air,
                       const Vec3* x, const Vec3* v, Vec3* f);

}  // namespace springy
