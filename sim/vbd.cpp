// springy: Vertex Block Descent (sim/vbd.h).
#include "sim/vbd.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/force_stages.h"
#include "sim/hinge.h"

namespace springy {
namespace {

// H = L D L^T of a symmetric positive definite 3x3 matrix (no square roots); false if H is not
// definite.
struct Ldl3 {
  double l10, l20, l21, inv0, inv1, inv2;  // L's entries below the diagonal, 1 / D
  bool factor(const Sym3& h) {
    const double d0 = h.a[0];
    if (!(d0 > 0.0)) return false;
    inv0 = 1.0 / d0;
    l10 = h.a[3] * inv0;
    l20 = h.a[4] * inv0;
    const double d1 = h.a[1] - l10 * h.a[3];
    if (!(d1 > 0.0)) return false;
    inv1 = 1.0 / d1;
    l21 = (h.a[5] - l20 * h.a[3]) * inv1;
    const double d2 = h.a[2] - l20 * h.a[4] - l21 * l21 * d1;
    if (!(d2 > 0.0)) return false;
    inv2 = 1.0 / d2;
    return true;
  }
  Vec3 solve(const Vec3& b) const {
    const double z0 = b.x, z1 = b.y - l10 * z0, z2 = b.z - l20 * z0 - l21 * z1;
    Vec3 x;
    x.z = z2 * inv2;
    x.y = z1 * inv1 - l21 * x.z;
    x.x = z0 * inv0 - l10 * x.y - l20 * x.z;
    return x;
  }
};

bool solveSym3(const Sym3& h, const Vec3& b, Vec3& x) {
  Ldl3 f;
  if (!f.factor(h)) return false;
  x = f.solve(b);
  return true;
}

}  // namespace

void VbdSolver::colourVertices(const Model& model) {
  // Colours: greedy in index order over "shares a strut, a hinge or a face", so that a colour's
  // vertices read none of each other's positions (and, for the gas, share no face).
  std::vector<std::vector<uint32_t>> neighbours(n_);
  const auto link = [&](uint32_t a, uint32_t b) {
    if (a == b) return;
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  };
  uint32_t corners[4];
  for (const KindTerms& terms : kinds_) {
    const ForceKind& kind = *terms.kind;
    if (!kind.vbdElement) continue;
    for (std::size_t e = 0, count = kind.elementCount(model); e < count; ++e) {
      kind.elementVertices(model, e, corners);
      for (int a = 0; a < kind.elementSize; ++a) {
        for (int b = a + 1; b < kind.elementSize; ++b) link(corners[a], corners[b]);
      }
    }
  }
  for (const Triangle& f : model.faces) {
    link(f[0], f[1]);
    link(f[1], f[2]);
    link(f[2], f[0]);
  }
  std::vector<int> colourOf(n_, -1);
  int colourCount = 0;
  std::vector<int> seen;  // colour -> the last vertex that saw it taken
  for (uint32_t i = 0; i < n_; ++i) {
    for (uint32_t j : neighbours[i]) {
      const int c = colourOf[j];
      if (c >= 0) {
        if (static_cast<std::size_t>(c) >= seen.size()) seen.resize(c + 1, -1);
        seen[c] = static_cast<int>(i);
      }
    }
    int c = 0;
    while (c < static_cast<int>(seen.size()) && seen[c] == static_cast<int>(i)) ++c;
    colourOf[i] = c;
    colourCount = std::max(colourCount, c + 1);
  }
  colourStart_.assign(colourCount + 1, 0);
  for (uint32_t i = 0; i < n_; ++i) ++colourStart_[colourOf[i] + 1];
  for (int c = 0; c < colourCount; ++c) colourStart_[c + 1] += colourStart_[c];
  colourVertices_.resize(n_);
  std::vector<uint32_t> fill(colourStart_.begin(), colourStart_.end() - 1);
  for (uint32_t i = 0; i < n_; ++i) colourVertices_[fill[colourOf[i]]++] = i;

}

VbdSolver::VbdSolver(const Model& model, int iterations) : model_(&model), iterations_(iterations) {
  n_ = model.vertexCount();
  // Each kind's elements around each vertex, in element order.
  uint32_t corners[4];
  for (ForceStage stage : stagesOf(model)) {
    const ForceKind& kind = forceKind(stage);
    if (!kind.vbdElement && !kind.vbdVertex) continue;
    KindTerms& terms = kinds_.emplace_back(KindTerms{&kind, {}, {}});
    if (!kind.vbdElement) continue;
    const std::size_t count = kind.elementCount(model);
    const auto size = static_cast<uint32_t>(kind.elementSize);
    terms.start.assign(n_ + 1, 0);
    for (std::size_t e = 0; e < count; ++e) {
      kind.elementVertices(model, e, corners);
      for (uint32_t s = 0; s < size; ++s) ++terms.start[corners[s] + 1];
    }
    for (std::size_t i = 0; i < n_; ++i) terms.start[i + 1] += terms.start[i];
    terms.list.resize(terms.start[n_]);
    std::vector<uint32_t> fill(terms.start.begin(), terms.start.end() - 1);
    for (std::size_t e = 0; e < count; ++e) {
      kind.elementVertices(model, e, corners);
      for (uint32_t s = 0; s < size; ++s) terms.list[fill[corners[s]]++] = static_cast<uint32_t>(e) * size + s;
    }
  }
  gasSlot_.assign(model.bodies.size(), -1);
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    if (model.bodies[b].gasPressure > 0.0) {
      gasSlot_[b] = static_cast<int32_t>(gasBodies_.size());
      gasBodies_.push_back(b);
    }
  }
  if (!gasBodies_.empty()) faces_ = vertexFaces(model);

  colourVertices(model);

  for (auto* buffer : {&x0_, &y_, &accel_, &contactPoint_, &contactNormal_}) buffer->assign(n_, Vec3{});
  dVolume_.assign(n_, 0.0);
  constrained_.assign(n_, 0);
  arrival_.assign(n_, 0.0);
  for (auto* buffer : {&volume_, &stiffness_, &overpressure_, &sumA_, &sumB_, &factor_}) buffer->assign(gasBodies_.size(), 0.0);
  if (!gasBodies_.empty()) {
    for (auto* buffer : {&a_, &b_, &gradient_}) buffer->assign(n_, Vec3{});
    ga_.assign(n_, 0.0);
    gb_.assign(n_, 0.0);
    hessian_.assign(n_, Sym3{});
  }
  rigid_.assign(model.bodies.size(), RigidMotion{});
}

void VbdSolver::startAccelerations(const Vec3* x, const Vec3* v, double t) {
  const Model& m = *model_;
  air_ = m.wind ? m.wind->airVelocity(t) : Vec3{};
  // Gravity, wind and the deformation damping at the step's start, serially (in a fixed order).
  std::fill(accel_.begin(), accel_.end(), Vec3{});
  if (m.wind) applyWindPressure(m, Elements::range(0, m.faces.size()), air_, x, v, accel_.data());
  bool damped = false;
  for (uint32_t b = 0; b < m.bodies.size(); ++b) {
    const BodyInfo& info = m.bodies[b];
    rigid_[b] = RigidMotion{};
    if (!(info.deformationDamping > 0.0)) continue;
    const Vec3 o = x[info.firstVertex];
    rigid_[b] = rigidMotion(massMoments(m, info.firstVertex, info.firstVertex + info.vertexCount, o, x, v), o);
    rigid_[b].rate = info.deformationDamping;
    damped = true;
  }
  if (damped) applyDeformationDamping(m, rigid_.data(), 0, n_, x, v, accel_.data());
  for (std::size_t i = 0; i < n_; ++i) accel_[i] = m.gravity + accel_[i] * invMass_[i];
}

void VbdSolver::blockSystem(uint32_t i, const Vec3* x, double h, Vec3& force, Sym3& hessian, Vec3& gradient) const {
  const Model& m = *model_;
  const double mass = m.mass[i], inertia = mass / (h * h), invH = 1.0 / h;
  const Vec3 xi = x[i];
  Vec3 f = (y_[i] - xi) * inertia;
  Sym3 H;
  H.addDiagonal(inertia);
  // Each kind's term, in the registry's order (drag, struts, hinges).
  const VbdCall call{m, x, x0_.data(), invH, air_};
  for (const KindTerms& terms : kinds_) {
    const ForceKind& kind = *terms.kind;
    if (kind.vbdVertex) kind.vbdVertex(call, i, f, H);
    if (!kind.vbdElement) continue;
    const auto size = static_cast<uint32_t>(kind.elementSize);
    for (uint32_t k = terms.start[i]; k < terms.start[i + 1]; ++k) {
      kind.vbdElement(call, terms.list[k] / size, static_cast<int>(terms.list[k] % size), f, H);
    }
  }
  gradient = Vec3{};
  const int32_t slot = gasSlot_[m.body[i]];
  if (slot >= 0) {
    for (uint32_t k = faces_.start[i]; k < faces_.start[i + 1]; ++k) {
      const Triangle& t = m.faces[faces_.faces[k]];
      const int c = t[0] == i ? 0 : (t[1] == i ? 1 : 2);
      gradient += cross(x[t[(c + 1) % 3]] - xi, x[t[(c + 2) % 3]] - xi);
    }
    gradient = gradient * (1.0 / 6.0);
    f += gradient * overpressure_[slot];
  }
  force = f;
  hessian = H;
}

Vec3 VbdSolver::constrain(uint32_t i, const Vec3& xi, const Sym3& hessian, Vec3 dx) const {
  if (!constrained_[i]) return dx;
  const Vec3& n = contactNormal_[i];
  const double s = dot(xi + dx - contactPoint_[i], n);
  if (!(s < 0.0)) return dx;
  // The block's quadratic minimised on the surface: dx + lambda H^-1 n, with x + dx on it.
  Vec3 w;
  if (solveSym3(hessian, n, w) && dot(n, w) > 0.0) return dx + w * (-s / dot(n, w));
  return dx - n * s;
}

void VbdSolver::arrive(uint32_t i, Vec3& x, Vec3& v) const {
  if (!constrained_[i] || !std::isfinite(arrival_[i])) return;
  const Vec3& n = contactNormal_[i];
  const double s = dot(x - contactPoint_[i], n);
  v += n * (arrival_[i] - dot(v, n));
  x -= n * (s + 1e-9);
}

void VbdSolver::findArrivals(const Vec3* x, double h) {
  const Model& m = *model_;
  for (uint32_t i = 0; i < n_; ++i) {
    arrival_[i] = std::numeric_limits<double>::quiet_NaN();
    if (!constrained_[i] || invMass_[i] == 0.0) continue;
    const Vec3& n = contactNormal_[i];
    if (dot(x[i] - contactPoint_[i], n) > 1e-9) continue;  // the springs took it off the surface
    // The force the surface holds it against at the end of the solve (its block's residual:
    // inertia, gravity and the springs pressing it on) is the contact's: its impulse over the
    // step, f . n h / m, is the normal velocity the surface took.
    Vec3 f, g;
    Sym3 H;
    blockSystem(i, x, h, f, H, g);
    const double pressing = dot(f, n);
    if (!(pressing < 0.0)) continue;
    arrival_[i] = dot(x[i] - x0_[i], n) / h + pressing * h / m.mass[i];
  }
}

void VbdSolver::predict(Vec3* x, const Vec3* v, double dt) {
  const Model& m = *model_;
  ContactHit hit;
  const bool colliders = !m.colliders.empty();
  for (uint32_t i = 0; i < n_; ++i) {
    if (invMass_[i] == 0.0) {
      y_[i] = x[i];
      continue;
    }
    y_[i] = x[i] + (v[i] + accel_[i] * dt) * dt;
    constrained_[i] = 0;
    x[i] = y_[i];
    if (colliders && m.colliders.firstHit(x0_[i], y_[i], hit)) {
      constrained_[i] = 1;
      contactPoint_[i] = hit.point;
      contactNormal_[i] = hit.normal;
      ++stats_.contactConstraints;
      const double s = dot(x[i] - hit.point, hit.normal);
      if (s < 0.0) x[i] -= hit.normal * s;  // the guess starts on the surface
    }
  }
}

void VbdSolver::updateGas(std::size_t k) {
  const BodyInfo& info = model_->bodies[gasBodies_[k]];
  stiffness_[k] = volume_[k] > 0.0 ? info.gasPressure * info.restVolume / (volume_[k] * volume_[k]) : 0.0;
  overpressure_[k] = gasOverpressure(info, volume_[k]);
}

void VbdSolver::sweepColour(const Forces& forces, const uint32_t* list, std::size_t count, Vec3* x, double dt) {
  forces.parallelFor(count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = list[k];
      if (invMass_[i] == 0.0) continue;
      Vec3 f, g, d;
      Sym3 H;
      blockSystem(i, x, dt, f, H, g);
      if (!solveSym3(H, f, d)) continue;  // cannot happen: H >= m / h^2 I
      x[i] += constrain(i, x[i], H, d);
    }
  });
}

void VbdSolver::sweepColourWithGas(const Forces& forces, const uint32_t* list, std::size_t count, Vec3* x, double dt) {
  const Model& m = *model_;
  forces.parallelFor(count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = list[k];
      if (invMass_[i] == 0.0) continue;
      Vec3 f;
      blockSystem(i, x, dt, f, hessian_[i], gradient_[i]);
      Ldl3 factor;
      if (factor.factor(hessian_[i])) {
        a_[i] = factor.solve(f);
        b_[i] = factor.solve(gradient_[i]);
      } else {  // cannot happen: H >= m / h^2 I
        a_[i] = b_[i] = Vec3{};
      }
      ga_[i] = dot(gradient_[i], a_[i]);
      gb_[i] = dot(gradient_[i], b_[i]);
    }
  });
  // In colour order, on one thread: the same sums on any thread count.
  std::fill(sumA_.begin(), sumA_.end(), 0.0);
  std::fill(sumB_.begin(), sumB_.end(), 0.0);
  for (std::size_t k = 0; k < count; ++k) {
    const uint32_t i = list[k];
    const int32_t slot = gasSlot_[m.body[i]];
    if (slot < 0 || invMass_[i] == 0.0) continue;
    sumA_[slot] += ga_[i];
    sumB_[slot] += gb_[i];
  }
  for (std::size_t g = 0; g < gasBodies_.size(); ++g) {
    factor_[g] = stiffness_[g] * sumA_[g] / (1.0 + stiffness_[g] * sumB_[g]);
  }
  forces.parallelFor(count, [&](std::size_t begin, std::size_t end) {
    for (std::size_t k = begin; k < end; ++k) {
      const uint32_t i = list[k];
      if (invMass_[i] == 0.0) continue;
      const int32_t slot = gasSlot_[m.body[i]];
      Vec3 d = slot >= 0 ? a_[i] - b_[i] * factor_[slot] : a_[i];
      d = constrain(i, x[i], hessian_[i], d);
      x[i] += d;
      dVolume_[i] = dot(gradient_[i], d);
    }
  });
  for (std::size_t k = 0; k < count; ++k) {
    const uint32_t i = list[k];
    const int32_t slot = gasSlot_[m.body[i]];
    if (slot >= 0 && invMass_[i] != 0.0) volume_[slot] += dVolume_[i];
  }
  for (std::size_t g = 0; g < gasBodies_.size(); ++g) updateGas(g);
}

void VbdSolver::step(const Forces& forces, std::vector<Vec3>& xs, std::vector<Vec3>& vs, double t, double dt) {
  const Model& m = *model_;
  Vec3 *x = xs.data(), *v = vs.data();
  ++stats_.steps;
  h_ = dt;
  invMass_ = forces.inverseMasses();
  startAccelerations(x, v, t);
  std::copy(xs.begin(), xs.end(), x0_.begin());
  predict(x, v, dt);
  for (std::size_t k = 0; k < gasBodies_.size(); ++k) {
    volume_[k] = enclosedVolume(m, gasBodies_[k], x);
    updateGas(k);
  }
  for (int it = 0; it < iterations_; ++it) {
    ++stats_.sweeps;
    for (std::size_t c = 0; c + 1 < colourStart_.size(); ++c) {
      std::size_t count;
      const uint32_t* list = colour(c, count);
      // With a gas the colour's vertices are coupled through the volume they share: the block
      // system is D + c G G^T (D the colour's 3x3 blocks, G its volume gradients, c = p0 V0 / V^2),
      // solved exactly by Sherman-Morrison: dx_i = a_i - b_i c (G . a) / (1 + c G . b), with
      // a_i = D_i^-1 f_i and b_i = D_i^-1 g_i (solving each vertex alone overshoots the volume
      // by about the colour's size times and diverges).
      if (gasBodies_.empty()) {
        sweepColour(forces, list, count, x, dt);
      } else {
        sweepColourWithGas(forces, list, count, x, dt);
      }
    }
  }
  if (!m.colliders.empty()) findArrivals(x, dt);
  const double invDt = 1.0 / dt;
  for (uint32_t i = 0; i < n_; ++i) {
    if (invMass_[i] == 0.0) continue;
    v[i] = (x[i] - x0_[i]) * invDt;
    if (constrained_[i] && std::fabs(dot(x[i] - contactPoint_[i], contactNormal_[i])) < 1e-12) ++stats_.activeConstraints;
  }
}

}  // namespace springy
