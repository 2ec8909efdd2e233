#include "sim/implicit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/colliders.h"
#include "sim/forces.h"
#include "sim/force_stages.h"

namespace springy {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

}  // namespace

ImplicitSolver::ImplicitSolver(const Model& model, ImplicitSettings settings) : settings_(settings) {
  n_ = model.vertexCount();
  const Eigen::Index dim = static_cast<Eigen::Index>(3 * n_);
  std::vector<Eigen::Triplet<double>> triplets;
  auto pattern = [&](uint32_t a, uint32_t b) {
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) triplets.emplace_back(3 * a + static_cast<uint32_t>(r), 3 * b + static_cast<uint32_t>(c), 0.0);
    }
  };
  for (uint32_t i = 0; i < n_; ++i) pattern(i, i);
  // Every pair of vertices that share an element of a kind with a Jacobian.
  stages_ = stagesOf(model);
  uint32_t corners[4];
  for (ForceStage stage : stages_) {
    const ForceKind& kind = forceKind(stage);
    if (!kind.jacobian) continue;
    kinds_.push_back({&kind, {}});
    for (std::size_t e = 0, count = kind.elementCount(model); e < count; ++e) {
      kind.elementVertices(model, e, corners);
      for (int a = 0; a < kind.elementSize; ++a) {
        for (int b = 0; b < kind.elementSize; ++b) pattern(corners[a], corners[b]);
      }
    }
  }
  K_.resize(dim, dim);
  K_.setFromTriplets(triplets.begin(), triplets.end());
  K_.makeCompressed();
  D_ = K_;
  A_ = K_;
  diagonal_.resize(n_);
  for (uint32_t i = 0; i < n_; ++i) diagonal_[i] = findBlock(i, i);
  for (KindBlocks& kb : kinds_) {
    const ForceKind& kind = *kb.kind;
    for (std::size_t e = 0, count = kind.elementCount(model); e < count; ++e) {
      kind.elementVertices(model, e, corners);
      for (int a = 0; a < kind.elementSize; ++a) {
        for (int b = 0; b < kind.elementSize; ++b) kb.blocks.push_back(findBlock(corners[a], corners[b]));
      }
    }
  }
  x1_.assign(n_, Vec3{});
  f_.assign(n_, Vec3{});
  v0_.assign(n_, Vec3{});
  vTrial_.assign(n_, Vec3{});
  for (Eigen::VectorXd* vec : {&rhs_, &dv_, &r_, &z_, &p_, &q_, &precond_, &filter_}) vec->setZero(dim);
  for (uint32_t b = 0; b < model.bodies.size(); ++b) {
    if (!(model.bodies[b].gasPressure > 0.0)) continue;
    gasBodies_.push_back(b);
    gasRange_.emplace_back(static_cast<Eigen::Index>(3 * model.bodies[b].firstVertex),
                           static_cast<Eigen::Index>(3 * model.bodies[b].vertexCount));
  }
  gasCoefficient_.assign(gasBodies_.size(), 0.0);
  if (!gasBodies_.empty()) {
    gasGradient_.setZero(dim);
    gasScratch_.assign(n_, Vec3{});
  }
  contacts_.reserve(n_);
  xSaved_.assign(static_cast<std::size_t>(settings_.maxHalvings), std::vector<Vec3>(n_));
  vSaved_.assign(static_cast<std::size_t>(settings_.maxHalvings), std::vector<Vec3>(n_));
  contactNormal_.assign(n_, Vec3{});
  contactSpeed_.assign(n_, 0.0);
}

ImplicitSolver::Block ImplicitSolver::findBlock(uint32_t a, uint32_t b) const {
  Block blk{};
  const int* outer = K_.outerIndexPtr();
  const int* inner = K_.innerIndexPtr();
  for (int c = 0; c < 3; ++c) {
    const int col = static_cast<int>(3 * b) + c;
    const int* it = std::lower_bound(inner + outer[col], inner + outer[col + 1], static_cast<int>(3 * a));
    blk.index[c] = static_cast<int>(it - inner);
  }
  return blk;
}

void ImplicitSolver::addBlock(Eigen::SparseMatrix<double>& m, const Block& blk, const Matrix3d& values, double scale) {
  double* data = m.valuePtr();
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 3; ++r) data[blk.index[c] + r] += scale * values(r, c);
  }
}

void ImplicitSolver::assemble(const Model& model, const Vec3* x, const Vec3* v, bool definite) {
  std::fill(K_.valuePtr(), K_.valuePtr() + K_.nonZeros(), 0.0);
  std::fill(D_.valuePtr(), D_.valuePtr() + D_.nonZeros(), 0.0);
  // The kinds' diagonal damping, -c m_i (drag; the deformation damping's local part: its
  // rigid-motion part, a rank-6 coupling of the whole body, stays out of the matrix, and Newton
  // converges to the same step).
  for (uint32_t i = 0; i < n_; ++i) {
    const double rate = diagonalDamping(model, stages_, i);
    if (rate > 0.0) addBlock(D_, diagonal_[i], Matrix3d::Identity(), -rate * model.mass[i]);
  }
  // Each element's blocks of df/dx and df/dv, kind by kind in the registry's order.
  Matrix12 jx, jv;
  for (const KindBlocks& kb : kinds_) {
    const ForceKind& kind = *kb.kind;
    const std::size_t size = static_cast<std::size_t>(kind.elementSize);
    for (std::size_t e = 0, count = kind.elementCount(model); e < count; ++e) {
      if (!kind.jacobian(model, e, x, v, definite, jx, jv)) continue;
      const Block* blocks = &kb.blocks[e * size * size];
      for (std::size_t a = 0; a < size; ++a) {
        for (std::size_t b = 0; b < size; ++b) {
          const Block& blk = blocks[a * size + b];
          const auto r = static_cast<Eigen::Index>(3 * a), c = static_cast<Eigen::Index>(3 * b);
          addBlock(K_, blk, jx.block<3, 3>(r, c), 1.0);
          addBlock(D_, blk, jv.block<3, 3>(r, c), 1.0);
        }
      }
    }
  }
}

void ImplicitSolver::assembleGas(const Model& model, const Vec3* x, double dt) {
  for (std::size_t k = 0; k < gasBodies_.size(); ++k) {
    const BodyInfo& info = model.bodies[gasBodies_[k]];
    volumeGradient(model, info, x, gasScratch_.data());
    for (uint32_t i = 0; i < info.vertexCount; ++i) {
      for (int c = 0; c < 3; ++c) gasGradient_(gasRange_[k].first + 3 * static_cast<Eigen::Index>(i) + c) = gasScratch_[i][c];
    }
    const double volume = enclosedVolume(model, gasBodies_[k], x);
    gasCoefficient_[k] = volume > 0.0 ? dt * dt * info.gasPressure * info.restVolume / (volume * volume) : 0.0;
  }
}

void ImplicitSolver::addGasProduct(const Eigen::VectorXd& p, Eigen::VectorXd& q) const {
  for (std::size_t k = 0; k < gasBodies_.size(); ++k) {
    const auto [first, size] = gasRange_[k];
    const auto g = gasGradient_.segment(first, size);
    q.segment(first, size) += (gasCoefficient_[k] * g.dot(p.segment(first, size))) * g;
  }
}

void ImplicitSolver::project(Eigen::VectorXd& vec) const {
  vec.array() *= filter_.array();
  for (uint32_t i : contacts_) {
    const Eigen::Index k = static_cast<Eigen::Index>(3 * i);
    const Vec3& n = contactNormal_[i];
    const double along = vec(k) * n.x + vec(k + 1) * n.y + vec(k + 2) * n.z;
    vec(k) -= along * n.x;
    vec(k + 1) -= along * n.y;
    vec(k + 2) -= along * n.z;
  }
}

void ImplicitSolver::findContacts(const Forces& forces, const std::vector<Vec3>& x0, double t, double dt) {
  contacts_.clear();
  const Model& model = forces.model();
  if (model.colliders.empty()) return;
  forces.evaluate(x0.data(), v0_.data(), t, f_.data());
  const double* invMass = forces.inverseMasses();
  ContactHit hit;
  for (uint32_t i = 0; i < n_; ++i) {
    if (invMass[i] == 0.0) continue;
    const Vec3 predicted = x0[i] + (v0_[i] + f_[i] * (invMass[i] * dt)) * dt;
    if (!model.colliders.firstHit(x0[i], predicted, hit)) continue;
    contacts_.push_back(i);
    contactNormal_[i] = hit.normal;
    contactSpeed_[i] = dot(hit.point - x0[i], hit.normal) / dt;  // lands it on the surface
  }
  stats_.contactConstraints += contacts_.size();
}

double ImplicitSolver::residual(const Forces& forces, const std::vector<Vec3>& x0, const std::vector<Vec3>& v, double t,
                                double dt) {
  const Model& model = forces.model();
  for (std::size_t i = 0; i < n_; ++i) x1_[i] = x0[i] + v[i] * dt;
  forces.evaluate(x1_.data(), v.data(), t + dt, f_.data());
  for (std::size_t i = 0; i < n_; ++i) {
    const Vec3 r = (v[i] - v0_[i]) * model.mass[i] - f_[i] * dt;  // R = M (v - v0) - h f
    for (int c = 0; c < 3; ++c) rhs_(static_cast<Eigen::Index>(3 * i) + c) = -r[c];
  }
  project(rhs_);
  return rhs_.norm();
}

int ImplicitSolver::solveCg(double absoluteFloor) {
  dv_.setZero();
  r_ = rhs_;
  z_ = precond_.cwiseProduct(r_);
  project(z_);
  p_ = z_;
  double rz = r_.dot(z_);
  const double threshold = std::max(settings_.cgTolerance * r_.norm(), absoluteFloor);
  int it = 0;
  for (; it < settings_.maxCg; ++it) {
    if (!(r_.norm() > threshold)) break;
    q_.noalias() = A_ * p_;
    addGasProduct(p_, q_);
    project(q_);
    const double pq = p_.dot(q_);
    if (!(pq > 0.0)) break;  // not positive definite along p (cannot happen with the definite K)
    const double alpha = rz / pq;
    dv_ += alpha * p_;
    r_ -= alpha * q_;
    z_ = precond_.cwiseProduct(r_);
    project(z_);
    const double rzNew = r_.dot(z_);
    p_ = z_ + (rzNew / rz) * p_;
    rz = rzNew;
  }
  return it;
}

bool ImplicitSolver::step(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt) {
  ++stats_.steps;
  // The held vertices' rows filtered out: the pins as they are now (a released pin moves).
  const double* invMass = forces.inverseMasses();
  for (std::size_t i = 0; i < n_; ++i) {
    for (int c = 0; c < 3; ++c) filter_(static_cast<Eigen::Index>(3 * i) + c) = invMass[i] == 0.0 ? 0.0 : 1.0;
  }
  return stepWithin(forces, x, v, t, dt, 0);
}

bool ImplicitSolver::stepWithin(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt,
                                int depth) {
  if (depth < settings_.maxHalvings) {
    xSaved_[static_cast<std::size_t>(depth)] = x;
    vSaved_[static_cast<std::size_t>(depth)] = v;
  }
  if (solve(forces, x, v, t, dt)) return true;
  if (depth >= settings_.maxHalvings) return false;  // the smallest piece: keep its last iterate
  // Newton did not converge (a hinge folding through its wrap, a violent contact): retry the
  // step as two halves from the saved state.
  ++stats_.halvedSteps;
  x = xSaved_[static_cast<std::size_t>(depth)];
  v = vSaved_[static_cast<std::size_t>(depth)];
  return stepWithin(forces, x, v, t, 0.5 * dt, depth + 1) && stepWithin(forces, x, v, t + 0.5 * dt, 0.5 * dt, depth + 1);
}

bool ImplicitSolver::solve(const Forces& forces, std::vector<Vec3>& x, std::vector<Vec3>& v, double t, double dt) {
  const Model& model = forces.model();
  for (std::size_t i = 0; i < n_; ++i) v0_[i] = v[i];
  findContacts(forces, x, t, dt);
  // The initial guess v0 already obeys the contacts (each lands on its surface); every Newton
  // update is then filtered, so they hold exactly throughout.
  for (uint32_t i : contacts_) v[i] += contactNormal_[i] * (contactSpeed_[i] - dot(v[i], contactNormal_[i]));
  double rnorm = residual(forces, x, v, t, dt);
  const double r0 = rnorm;
  bool converged = !(r0 > 0.0);
  const double* kv = K_.valuePtr();
  const double* dvals = D_.valuePtr();
  for (int it = 0; it < settings_.maxNewton && !converged; ++it) {
    ++stats_.newtonIterations;
    assemble(model, x1_.data(), v.data(), true);
    // A = M - h D - h^2 K (+ the gas's c g g^T, applied in CG's product)
    double* av = A_.valuePtr();
    for (Eigen::Index k = 0; k < A_.nonZeros(); ++k) av[k] = -dt * dvals[k] - dt * dt * kv[k];
    for (std::size_t i = 0; i < n_; ++i) {
      for (int c = 0; c < 3; ++c) {
        double& diag = av[diagonal_[i].index[c] + c];
        diag += model.mass[i];
        precond_(static_cast<Eigen::Index>(3 * i) + c) = diag;
      }
    }
    if (!gasBodies_.empty()) {
      assembleGas(model, x1_.data(), dt);
      for (std::size_t k = 0; k < gasBodies_.size(); ++k) {
        const auto [first, size] = gasRange_[k];
        precond_.segment(first, size) += gasCoefficient_[k] * gasGradient_.segment(first, size).cwiseAbs2();
      }
    }
    for (Eigen::Index k = 0; k < precond_.size(); ++k) precond_(k) = precond_(k) > 0.0 ? 1.0 / precond_(k) : 0.0;
    stats_.cgIterations += static_cast<uint64_t>(solveCg(0.1 * settings_.newtonTolerance * r0));
    // Backtracking: accept the full Newton step unless it raises the residual.
    double alpha = 1.0, trial = rnorm;
    for (int ls = 0; ls < 6; ++ls) {
      for (std::size_t i = 0; i < n_; ++i) {
        const Eigen::Index k = static_cast<Eigen::Index>(3 * i);
        vTrial_[i] = v[i] + Vec3{dv_(k), dv_(k + 1), dv_(k + 2)} * alpha;
      }
      trial = residual(forces, x, vTrial_, t, dt);
      if (trial < rnorm || ls == 5 || !std::isfinite(trial)) break;
      alpha *= 0.5;
    }
    // The size of the full Newton update (not the damped one the line search took: a tiny
    // alpha is no sign of convergence).
    double update = 0.0, speed = 0.0;
    for (std::size_t i = 0; i < n_; ++i) {
      const Eigen::Index k = static_cast<Eigen::Index>(3 * i);
      update = std::max(update, length(Vec3{dv_(k), dv_(k + 1), dv_(k + 2)}));
      v[i] = vTrial_[i];
      speed = std::max(speed, length(v[i]));
    }
    if (alpha < 1.0) update = std::numeric_limits<double>::infinity();
    rnorm = trial;
    if (!std::isfinite(rnorm)) break;
    // Converged: the residual fell by newtonTolerance, or the update is a negligible velocity
    // (the linearisation with the definite Jacobian converges only linearly in compressed
    // states, where the residual may stall far below any physical significance).
    converged = rnorm <= settings_.newtonTolerance * r0 ||
                update <= settings_.velocityTolerance * (speed + length(model.gravity) * dt);
  }
  if (!converged) ++stats_.unconvergedSteps;
  for (std::size_t i = 0; i < n_; ++i) x[i] += v[i] * dt;
  return converged;
}

}  // namespace springy
