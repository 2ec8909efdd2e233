#include "sim/implicit.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sim/colliders.h"
#include "sim/forces.h"
#include "sim/hinge.h"
#include "sim/force_stages.h"

namespace springy {
namespace {

using Eigen::Matrix3d;
using Eigen::Vector3d;

Vector3d ev(const Vec3& a) { return {a.x, a.y, a.z}; }

Matrix3d skew(const Vector3d& a) {
  Matrix3d s;
  s << 0, -a.z(), a.y(), a.z(), 0, -a.x(), -a.y(), a.x(), 0;
  return s;  // s b = a x b
}

// Derivatives of G(h, a) = -(h x a) / s, s = |a|^2 - (a.h)^2, with respect to a and h.
void wingDerivatives(const Vector3d& h, const Vector3d& a, Matrix3d& dGda, Matrix3d& dGdh) {
  const Vector3d q = h.cross(a);
  const double ah = a.dot(h);
  const double s = a.squaredNorm() - ah * ah;
  const Vector3d r = a - ah * h;
  dGda = -skew(h) / s + (2.0 / (s * s)) * q * r.transpose();
  dGdh = -skew(a) * (-1.0 / s) - (2.0 * ah / (s * s)) * q * a.transpose();
}

}  // namespace

bool strutJacobian(const Strut& st, const Vec3* x, const Vec3* v, Matrix3d& dfdx, Matrix3d& dfdv, bool definite) {
  const Vec3 xij = x[st.j] - x[st.i];
  const double l = length(xij);
  if (!(l > 0.0)) return false;
  const Vector3d u = ev(xij / l);
  const Matrix3d uu = u * u.transpose();
  const Matrix3d P = Matrix3d::Identity() - uu;
  const double transverse = 1.0 - st.restLength / l;
  dfdx = st.stiffness * uu + st.stiffness * (definite ? std::max(0.0, transverse) : transverse) * P;
  if (!definite) {
    const Vector3d vij = ev(v[st.j] - v[st.i]);
    dfdx += (st.damping / l) * (u * (P * vij).transpose() + vij.dot(u) * P);
  }
  dfdv = st.damping * uu;
  return true;
}

bool dihedralHessian(const Vec3& x0, const Vec3& x1, const Vec3& x2, const Vec3& x3, Matrix12& H) {
  HingeGeometry geo;
  if (!hingeGeometry(x0, x1, x2, x3, geo)) return false;
  const Vector3d e = ev(x1 - x0);
  const double l = e.norm();
  const Vector3d h = e / l;
  const Matrix3d Pl = (Matrix3d::Identity() - h * h.transpose()) / l;  // d h / d x1
  const Vector3d a = ev(x2 - x0), b = ev(x3 - x0);
  Matrix3d Gaa, Gha, Gab, Ghb;
  wingDerivatives(h, a, Gaa, Gha);
  wingDerivatives(h, b, Gab, Ghb);
  const Matrix3d Jea = Gha * Pl, Jeb = Ghb * Pl;  // through the edge direction
  H.setZero();
  auto blk = [&](int i, int j) { return H.block<3, 3>(3 * i, 3 * j); };
  // g2 = G(h, a)
  blk(2, 2) = Gaa;
  blk(2, 1) = Jea;
  blk(2, 0) = -Gaa - Jea;
  // g3 = -G(h, b)
  blk(3, 3) = -Gab;
  blk(3, 1) = -Jeb;
  blk(3, 0) = Gab + Jeb;
  // g1 = -(d02 g2 + d03 g3) / l
  const Vector3d g1 = ev(geo.grad[1]), g2 = ev(geo.grad[2]), g3 = ev(geo.grad[3]);
  const double d02 = a.dot(h), d03 = b.dot(h);
  // Row gradients of d02, d03 and l with respect to x0..x3.
  Eigen::Matrix<double, 1, 3> dd02[4], dd03[4], dl[4];
  const Eigen::Matrix<double, 1, 3> ht = h.transpose(), zero = Eigen::Matrix<double, 1, 3>::Zero();
  dd02[2] = ht;
  dd02[3] = zero;
  dd02[1] = a.transpose() * Pl;
  dd02[0] = -ht - dd02[1];
  dd03[2] = zero;
  dd03[3] = ht;
  dd03[1] = b.transpose() * Pl;
  dd03[0] = -ht - dd03[1];
  dl[0] = -ht;
  dl[1] = ht;
  dl[2] = dl[3] = zero;
  for (int k = 0; k < 4; ++k) {
    const Matrix3d dg2 = blk(2, k), dg3 = blk(3, k);
    blk(1, k) = -(g2 * dd02[k] + d02 * dg2 + g3 * dd03[k] + d03 * dg3) / l - (g1 / l) * dl[k];
  }
  // g0 = -(g1 + g2 + g3)
  for (int k = 0; k < 4; ++k) blk(0, k) = -(Matrix3d(blk(1, k)) + Matrix3d(blk(2, k)) + Matrix3d(blk(3, k)));
  return true;
}

bool hingeJacobian(const Hinge& hg, const Vec3* x, const Vec3* v, Matrix12& dfdx, Matrix12& dfdv, bool definite) {
  const Vec3 &x0 = x[hg.v[0]], &x1 = x[hg.v[1]], &x2 = x[hg.v[2]], &x3 = x[hg.v[3]];
  HingeGeometry geo;
  // The solver's (definite) Jacobian bounds the lever the gradient divides by, so it stays
  // finite in a crushed face; there it only approximates the faded force's derivative (hinge.h),
  // which costs Newton iterations, not accuracy: the residual uses the force itself. The exact
  // Jacobian uses the exact gradient.
  if (!hingeGeometry(x0, x1, x2, x3, geo, definite ? hg.minLever[0] : 0.0, definite ? hg.minLever[1] : 0.0)) {
    return false;
  }
  Eigen::Matrix<double, 12, 1> g, vel;
  for (int i = 0; i < 4; ++i) {
    g.segment<3>(3 * i) = ev(geo.grad[i]);
    vel.segment<3>(3 * i) = ev(v[hg.v[i]]);
  }
  dfdv = -hg.damping * g * g.transpose();
  if (definite) {
    dfdx = -hg.stiffness * g * g.transpose();
    return true;
  }
  Matrix12 H;
  if (!dihedralHessian(x0, x1, x2, x3, H)) return false;
  const double rate = g.dot(vel);
  const double torque = hg.stiffness * angleDifference(geo.theta, hg.restAngle) + hg.damping * rate;
  // d torque / d x_k = k g_k^T + d sum_j v_j^T H_jk
  const Eigen::Matrix<double, 1, 12> dtorque = hg.stiffness * g.transpose() + hg.damping * (vel.transpose() * H);
  dfdx = -g * dtorque - torque * H;
  return true;
}

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
  for (const Strut& s : model.struts) {
    pattern(s.i, s.j);
    pattern(s.j, s.i);
  }
  for (const Hinge& h : model.hinges) {
    for (uint32_t a : h.v) {
      for (uint32_t b : h.v) pattern(a, b);
    }
  }
  K_.resize(dim, dim);
  K_.setFromTriplets(triplets.begin(), triplets.end());
  K_.makeCompressed();
  D_ = K_;
  A_ = K_;
  diagonal_.resize(n_);
  for (uint32_t i = 0; i < n_; ++i) diagonal_[i] = findBlock(i, i);
  for (const Strut& s : model.struts) {
    strutBlocks_.push_back(findBlock(s.i, s.j));
    strutBlocks_.push_back(findBlock(s.j, s.i));
  }
  for (const Hinge& h : model.hinges) {
    for (uint32_t a : h.v) {
      for (uint32_t b : h.v) hingeBlocks_.push_back(findBlock(a, b));
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
  for (std::size_t i = 0; i < n_; ++i) {
    for (int c = 0; c < 3; ++c) filter_(static_cast<Eigen::Index>(3 * i) + c) = model.invMass[i] == 0.0 ? 0.0 : 1.0;
  }
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
  // Drag and the deformation damping's diagonal part -c m_i (its rigid-motion part, a rank-6
  // coupling of the whole body, stays out of the matrix: Newton converges to the same step).
  for (std::size_t i = 0; i < n_; ++i) {
    const double rate = model.drag + model.bodies[model.body[i]].deformationDamping;
    if (rate > 0.0) addBlock(D_, diagonal_[i], Matrix3d::Identity(), -rate * model.mass[i]);
  }
  Matrix3d kx, kv;
  for (std::size_t s = 0; s < model.struts.size(); ++s) {
    const Strut& st = model.struts[s];
    if (!strutJacobian(st, x, v, kx, kv, definite)) continue;
    addBlock(K_, diagonal_[st.i], kx, -1.0);
    addBlock(K_, diagonal_[st.j], kx, -1.0);
    addBlock(K_, strutBlocks_[2 * s], kx, 1.0);
    addBlock(K_, strutBlocks_[2 * s + 1], kx, 1.0);
    addBlock(D_, diagonal_[st.i], kv, -1.0);
    addBlock(D_, diagonal_[st.j], kv, -1.0);
    addBlock(D_, strutBlocks_[2 * s], kv, 1.0);
    addBlock(D_, strutBlocks_[2 * s + 1], kv, 1.0);
  }
  Matrix12 hx, hv;
  for (std::size_t k = 0; k < model.hinges.size(); ++k) {
    if (!hingeJacobian(model.hinges[k], x, v, hx, hv, definite)) continue;
    for (int a = 0; a < 4; ++a) {
      for (int b = 0; b < 4; ++b) {
        const Block& blk = hingeBlocks_[16 * k + static_cast<std::size_t>(4 * a + b)];
        addBlock(K_, blk, hx.block<3, 3>(3 * a, 3 * b), 1.0);
        addBlock(D_, blk, hv.block<3, 3>(3 * a, 3 * b), 1.0);
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
  ContactHit hit;
  for (uint32_t i = 0; i < n_; ++i) {
    if (model.invMass[i] == 0.0) continue;
    const Vec3 predicted = x0[i] + (v0_[i] + f_[i] * (model.invMass[i] * dt)) * dt;
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
