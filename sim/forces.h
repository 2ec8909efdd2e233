// springy: external forces (gravity, air drag, wind) and the enclosed gas's pressure, one
// function each over a vertex or face range. Struts and hinges live in strut.h and hinge.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "sim/kind_types.h"
#include "sim/model.h"
#include "sim/parallel.h"

namespace springy {

// f_i = m_i g: gravity is the first stage when present, and starts the sum the other stages add
// to (instead of zeros and an addition: one pass fewer).
void setGravity(const Model& model, std::size_t begin, std::size_t end, Vec3* f);

// f_i += -c m_i (v_i - w): linear drag relative to the air (w = 0 without wind), the seed's
// "plain velocity drag" made independent of mesh resolution by scaling with the vertex mass
// (docs/model.md §6, eq. A9).
void applyDrag(const Model& model, std::size_t begin, std::size_t end, const Vec3& air, const Vec3* v, Vec3* f);

// Wind pressure on the selected faces (all of a range, or a thread's list adding only to the
// corners its masks name): a face turned into the relative wind (w - v_face) . n < 0 is pushed
// along -n with force c A ((w - v_face) . n) n, split equally over its corners.
void applyWindPressure(const Model& model, Elements faces, const Vec3& air, const Vec3* x, const Vec3* v, Vec3* f);

// Enclosed gas (docs/model.md §11, eq. A12-A16; Matyka & Ollila 2004, "Pressure model of soft
// body simulation"):
// an isothermal ideal gas, p V = const, inside a closed body, at the ambient pressure p0 when
// the volume is the rest volume V0. Its pressure over the ambient, p = p0 (V0 / V - 1), pushes
// every face outward; the volume is exact by the divergence theorem, V = 1/6 sum_f x0 . (x1 x x2)
// over the outward faces, and the force on vertex i is p dV/dx_i, where each face contributes
// N / 6 = (x1 - x0) x (x2 - x0) / 6 (a third of its area vector) to each of its corners. The
// volume pass computes each face's N once: its term is x0 . N (the same triple product), and it
// keeps N for the force pass at the same positions, where each vertex sums its faces' N. That
// force is -dE/dx of the gas's energy E = p0 V0 (V / V0 - 1 - ln(V / V0)) (the work the gas
// and the ambient do on the body), whose second derivative at V0 is p0 / V0: the breathing
// stiffness.

// Volume enclosed by a body's faces at positions x (about its first vertex, which keeps the
// terms small and makes the sum independent of where the body is). The faces are summed in
// chunks of kVolumeChunk, and the chunks' sums in order, so that threads can share the work
// and still produce the same number.
double enclosedVolume(const Model& model, uint32_t body, const Vec3* x);
constexpr uint32_t kVolumeChunk = 512;
// Six times the volume of faces [begin, end) of a body about the point o (one chunk's sum),
// sum (x0 - o) . N. With areaVectors, also stores each face's N = (x1 - x0) x (x2 - x0) at
// areaVectors[face] for applyGasPressure.
double sixVolume(const Model& model, uint32_t begin, uint32_t end, const Vec3& o, const Vec3* x,
                 Vec3* areaVectors = nullptr);
// The chunks of a body's faces, and six times the volume of chunk c: enclosedVolume is the
// sum of the chunks in order, over six.
uint32_t volumeChunkCount(const BodyInfo& body);
double chunkSixVolume(const Model& model, uint32_t body, uint32_t chunk, const Vec3* x);
// p0 (V0 / V - 1) [Pa]: +inf for V <= 0 (an inverted body).
double gasOverpressure(const BodyInfo& body, double volume);
// p0 V0 (V / V0 - 1 - ln(V / V0)) [J]: +inf for V <= 0.
double gasEnergy(const BodyInfo& body, double volume);
// The faces around each vertex, in face order (compressed rows: vertex i's are
// faces[start[i]] to faces[start[i + 1] - 1]).
struct VertexFaces {
  std::vector<uint32_t> start, faces;
};
VertexFaces vertexFaces(const Model& model);
// Gas pressure on vertices [begin, end): vertex i of a body with overpressure p (overpressure[b],
// 0 for bodies without gas) receives p / 6 times the sum of the area vectors of its faces
// (areaVectors[face], sixVolume's N at the same positions), summed in face order. Gathered per
// vertex, a thread computes its own vertices' forces and writes nothing else.
void applyGasPressure(const Model& model, const double* overpressure, const VertexFaces& around,
                      const Vec3* areaVectors, std::size_t begin, std::size_t end, Vec3* f);

// Deformation damping (BodyInfo::deformationDamping): f_i = -c m_i (v_i - v - w x (x_i - p)) with
// (v, w) the rigid motion that carries the body's momentum and angular momentum about its
// centre of mass p (Mueller et al. 2007, "Position Based Dynamics", section 3.5, as a force).
// Every deformation mode decays at c / 2 whatever the mesh, and the damping keeps momentum and
// angular momentum and never adds energy: it is -c M times the mass-orthogonal projection of
// the velocities off the rigid motions.
//
// Mass moments of vertices [begin, end) about a point o: the sums a rigid fit needs.
struct MassMoments {
  double mass = 0.0;
  Vec3 first;          // sum m r
  Vec3 momentum;       // sum m v
  Vec3 angular;        // sum m r x v
  double second[6] = {0, 0, 0, 0, 0, 0};  // sum m r r^T: xx, yy, zz, xy, xz, yz
  void add(const MassMoments& o);
};
MassMoments massMoments(const Model& model, std::size_t begin, std::size_t end, const Vec3& o, const Vec3* x,
                        const Vec3* v);
struct RigidMotion {
  Vec3 center, velocity, spin;  // p, v, w
  double rate = 0.0;            // c [1/s]; 0: the body has no deformation damping
  Vec3 at(const Vec3& x) const { return velocity + cross(spin, x - center); }
};
// The rigid motion carrying the moments taken about o (the spin is 0 for a body whose inertia
// is singular, all its mass on a line).
RigidMotion rigidMotion(const MassMoments& moments, const Vec3& o);
// Adds the deformation damping of vertices [begin, end); rigid[b] for each vertex's body b.
void applyDeformationDamping(const Model& model, const RigidMotion* rigid, std::size_t begin, std::size_t end,
                             const Vec3* x, const Vec3* v, Vec3* f);

// The registry's hooks (sim/force_kinds.h) of the kinds in this file that the implicit solvers
// and the advisor take: drag's and the deformation damping's c on the diagonal of df/dv (the
// deformation damping's rigid-motion part, a rank-6 coupling of the whole body, stays out: it
// only lowers the bound, and Newton converges to the same step without it), drag's vbd term
// (-c m (v - w), block c m / h), and the gas's Gershgorin rows: its breathing mode
// omega^2 = (p0 V0 / V^2) sum_j |g_j|^2 / m_j, one eigenvalue of the body, on every row.
double dragDamping(const Model& model, uint32_t vertex);
double deformationDiagonal(const Model& model, uint32_t vertex);
void dragVbdTerm(const VbdCall& call, uint32_t vertex, Vec3& f, Sym3& H);
void gasBoundRows(const Model& model, const Vec3* x, const double* invMass, uint32_t body, RowBound* rows);

}  // namespace springy
