#include "sim/force_kinds.h"

#include <algorithm>
#include <iterator>

namespace springy {
namespace {

bool anyBody(const Model& model, double BodyInfo::*field) {
  return std::any_of(model.bodies.begin(), model.bodies.end(), [&](const BodyInfo& b) { return b.*field > 0.0; });
}

// The registry: one row per force kind, in evaluation order (ForceStage's order).
constexpr ForceKind kKinds[] = {
    {.stage = ForceStage::Gravity,
     .name = "gravity",
     .used = [](const Model& m) { return m.gravity != Vec3{}; },
     .force = [](const StageCall& c) { setGravity(c.model, c.begin, c.end, c.f); }},
    {.stage = ForceStage::Drag,
     .name = "drag",
     .used = [](const Model& m) { return m.drag > 0.0; },
     .force = [](const StageCall& c) { applyDrag(c.model, c.begin, c.end, c.air, c.v, c.f); },
     .diagonalDamping = dragDamping,
     .vbdVertex = dragVbdTerm},
    {.stage = ForceStage::Wind,
     .name = "wind",
     .used = [](const Model& m) { return m.wind && m.wind->pressure > 0.0; },
     .force = [](const StageCall& c) { applyWindPressure(c.model, c.faces, c.air, c.x, c.v, c.f); }},
    {.stage = ForceStage::Struts,
     .name = "struts",
     .used = [](const Model& m) { return !m.struts.empty(); },
     .force = [](const StageCall& c) { applyStruts(c.model.struts.data(), c.struts, c.x, c.v, c.f); },
     .elementSize = 2,
     .elementCount = strutCount,
     .elementVertices = strutVertices,
     .jacobian = strutBlocks,
     .vbdElement = strutVbdTerm,
     .boundRows = strutBoundRows},
    {.stage = ForceStage::Hinges,
     .name = "hinges",
     .used = [](const Model& m) { return !m.hinges.empty(); },
     .force =
         [](const StageCall& c) {
           applyHinges(c.model.hinges.data(), c.data.hingeTerms.data(), c.hinges, c.x, c.v, c.f);
         },
     .elementSize = 4,
     .elementCount = hingeCount,
     .elementVertices = hingeVertices,
     .jacobian = hingeBlocks,
     .vbdElement = hingeVbdTerm,
     .boundRows = hingeBoundRows},
    {.stage = ForceStage::Gas,
     .name = "gas",
     .used = [](const Model& m) { return anyBody(m, &BodyInfo::gasPressure); },
     .force =
         [](const StageCall& c) {
           applyGasPressure(c.model, c.data.overpressure.data(), c.data.facesAround, c.data.areaVectors.data(),
                            c.begin, c.end, c.f);
         },
     .boundRows = gasBoundRows},
    {.stage = ForceStage::Deformation,
     .name = "deformation damping",
     .used = [](const Model& m) { return anyBody(m, &BodyInfo::deformationDamping); },
     .force =
         [](const StageCall& c) {
           applyDeformationDamping(c.model, c.data.rigid.data(), c.begin, c.end, c.x, c.v, c.f);
         },
     .diagonalDamping = deformationDiagonal},
};

constexpr bool registryInStageOrder() {
  for (std::size_t k = 0; k < std::size(kKinds); ++k) {
    if (static_cast<std::size_t>(kKinds[k].stage) != k) return false;
  }
  return true;
}
static_assert(registryInStageOrder(), "kKinds[k] is the kind of ForceStage value k");

}  // namespace

std::span<const ForceKind> forceKinds() { return kKinds; }

std::string_view forceStageName(ForceStage stage) { return forceKind(stage).name; }

std::vector<ForceStage> stagesOf(const Model& model) {
  std::vector<ForceStage> stages;
  for (const ForceKind& kind : kKinds) {
    if (kind.used(model)) stages.push_back(kind.stage);
  }
  return stages;
}

double diagonalDamping(const Model& model, const std::vector<ForceStage>& stages, uint32_t vertex) {
  double rate = 0.0;
  for (ForceStage stage : stages) {
    if (const auto damping = forceKind(stage).diagonalDamping) rate += damping(model, vertex);
  }
  return rate;
}

}  // namespace springy
