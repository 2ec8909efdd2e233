// Small hand-built worlds for the physics tests.
#pragma once

#include <cmath>
#include <vector>

#include "sim/cases.h"
#include "sim/model.h"
#include "sim/world.h"

namespace springy::test {

// The hand-built models live in sim/cases.h, shared with the studies and the benchmarks.
using springy::hingeModel;
using springy::hingePositions;
using springy::strutModel;
using springy::vertexModel;

}  // namespace springy::test
