#include "sim/integrators.h"

#include <iterator>

namespace springy {
namespace {

using I = Integrator;
// name, order, evaluations, implicit, adaptive, iterations, moving colliders, soft attachments, energy swings
constexpr IntegratorTraits kTable[] = {
    {I::ExplicitEuler, "explicit_euler", 1, 1, false, false, false, true, true, false},
    {I::SymplecticEuler, "symplectic_euler", 1, 1, false, false, false, true, true, true},
    {I::VelocityVerlet, "verlet", 2, 1, false, false, false, true, true, true},
    {I::Leapfrog, "leapfrog", 2, 2, false, false, false, true, true, true},
    {I::RK4, "rk4", 4, 4, false, false, false, true, true, false},
    {I::BackwardEuler, "backward_euler", 1, 0, true, false, false, false, false, false},
    {I::BogackiShampine, "bs32", 3, 3, false, true, false, true, true, false},
    {I::AdaptiveVerlet, "verlet_adaptive", 2, 1, false, true, false, true, true, true},
    {I::Vbd, "vbd", 1, 0, true, false, true, false, false, false},
};

constexpr bool tableInEnumOrder() {
  for (std::size_t k = 0; k < std::size(kTable); ++k) {
    if (static_cast<std::size_t>(kTable[k].integrator) != k) return false;
  }
  return true;
}
static_assert(tableInEnumOrder(), "kTable[k] is the integrator of Integrator value k");

}  // namespace

const IntegratorTraits& integratorTraits(Integrator integrator) { return kTable[static_cast<std::size_t>(integrator)]; }

bool parseIntegrator(std::string_view name, Integrator& out) {
  for (const IntegratorTraits& t : kTable) {
    if (t.name == name) {
      out = t.integrator;
      return true;
    }
  }
  return false;
}

std::string integratorNames() {
  std::string s;
  for (const IntegratorTraits& t : kTable) s += (s.empty() ? "" : ", ") + std::string(t.name);
  return s;
}

std::string integratorRefuses(Integrator integrator, bool movingColliders, bool softAttachments) {
  const IntegratorTraits& t = integratorTraits(integrator);
  if (movingColliders && !t.movingColliders) return "colliders that move";
  if (softAttachments && !t.softAttachments) return "soft attachments ([[attach]] with a period)";
  return {};
}

}  // namespace springy
