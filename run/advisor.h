// springy run: the time step a run takes when the scene leaves it open, and the advice on one it
// gives. The stability advisor (sim/stability.h) applied to a scene, with tries: a count of
// substeps run over the whole scene under the monitor, as `springy check` runs it.
#pragma once

#include <iosfwd>
#include <string>

#include "scene/scene.h"
#include "sim/monitor.h"

namespace springy {

// Warn: warns when the step exceeds the estimated stable limit. AutoSubsteps (--substeps auto):
// sets scene.substeps to the survey's count, tried over the whole run and doubled or halved until
// it is within a factor 2 of the fewest that pass. Default (neither the scene nor the options gave
// dt or substeps): the estimate at rest with the margin that holds through impacts (impactMargin,
// sim/setup.h), tried and doubled until it passes. Both say what they chose on `log`. The tries run
// on `threads` threads and stop when interrupted() (an Error says so). With `runIsTry` (a Run,
// whose own run is monitored as a try is), the default step is not tried first: the run is its try
// and, if it fails, retryDefaultStep tries on.
enum class StepChoice { Warn, AutoSubsteps, Default };
void adviseTimeStep(const std::string& path, SceneDesc& scene, StepChoice choice, unsigned threads, std::ostream& log,
                    bool runIsTry = false);

// A run that was the default step's try (`untried`) failed: unless the failure is a limit the run
// was given (Failure::criterion), tries twice the count and on, doubling, as adviseTimeStep does,
// sets scene.substeps to the count that passed, says so, clears `untried` and returns true: the
// caller runs the scene again. False when the run was no try or the failure a criterion (the
// caller reports it); throws springy::Error when no count up to kMaxSubsteps passes.
bool retryDefaultStep(const std::string& path, SceneDesc& scene, const Failure& failure, bool& untried,
                      unsigned threads, std::ostream& log);

// "1 substep", "3 substeps": a count of substeps as the messages say it.
std::string substepsText(int count);

}  // namespace springy
