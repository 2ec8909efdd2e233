#include "run/advisor.h"

#include <cctype>
#include <chrono>
#include <condition_variable>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <ostream>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "sim/error.h"
#include "sim/harness.h"
#include "sim/interrupt.h"
#include "sim/limits.h"
#include "sim/stability.h"
#include "sim/trajectory.h"
#include "sim/world.h"

namespace springy {
namespace {

constexpr double kSafety = 0.9;  // aim below the estimated limit

// Says on `log` every 5 s that `what` goes on: a survey or a try of a large scene takes minutes,
// and a log should show within seconds that springy is working. From a thread of its own, while
// the caller writes nothing to `log`; stops when it goes.
class StillWorking {
 public:
  StillWorking(std::ostream& log, std::string what)
      : log_(log), what_(std::move(what)), start_(std::chrono::steady_clock::now()), thread_([this] { run(); }) {}
  ~StillWorking() {
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      done_ = true;
    }
    wake_.notify_all();
    thread_.join();
  }
  StillWorking(const StillWorking&) = delete;
  StillWorking& operator=(const StillWorking&) = delete;

 private:
  void run() {
    std::unique_lock<std::mutex> lock(mutex_);
    for (int k = 1; !wake_.wait_for(lock, start_ + std::chrono::seconds(5 * k) - std::chrono::steady_clock::now(),
                                    [this] { return done_; });
         ++k) {
      log_ << what_ << ": " << 5 * k << " s so far\n" << std::flush;
    }
  }
  std::ostream& log_;
  std::string what_;
  std::chrono::steady_clock::time_point start_;
  std::mutex mutex_;
  std::condition_variable wake_;
  bool done_ = false;
  std::thread thread_;  // last: started once the rest is set
};

std::string seconds(double s) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g s", s);
  return buf;
}

std::string number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", x);
  return buf;
}

// Which mode the survey's limit came from, and where it was: the user can look there (a sliver
// triangle, a pinned corner, a stiff spot of the mesh).
std::string limitingMode(const BodyInfo& info, const StabilitySurvey& survey) {
  char buf[256];
  const Vec3& p = survey.position;
  std::snprintf(buf, sizeof buf,
                ", set by its %s (%s %.3g %s) around its vertex %u (of the simulated mesh), then at "
                "(%.3g, %.3g, %.3g) m",
                survey.limit == ModeEstimator::Limit::Damping ? "most damped mode" : "stiffest mode",
                survey.limit == ModeEstimator::Limit::Damping ? "rate" : "omega", survey.rate,
                survey.limit == ModeEstimator::Limit::Damping ? "1/s" : "rad/s", info.meshVertex(survey.vertex), p.x,
                p.y, p.z);
  return buf;
}

// The survey watches one run, with the default adaptive step; a run at a fixed step can take
// another way through an impact and meet stiffer shapes than the survey saw (the bunny of
// scenes/bunny_light.toml with the body material instead of its element keys: the survey's
// tightest mode gave 20 substeps, at which the run fails at t = 1.63 s, as at 40; it passes at
// 80; its default step, 6 substeps, fails too, as do 12 and 24). So `--substeps auto` and the
// default step try their count: the scene runs at it under the stability monitor, as `springy
// check` runs it (the same model, steps and frames), and the count doubles after each failure
// (sim/harness.h searchCount). The estimate is the safe side of an edge that depends on the run
// (bunny_light's survey gives 14 substeps, and 7 pass: docs/stability.md), so `--substeps auto`
// (`searchUp`) also halves a count that passed until a run fails: the count it gives is within a
// factor 2 of the fewest that pass. A larger step passes only if every body that came to rest at
// the first passing count comes to rest at it too (sim/trajectory.h bodyNoLongerAtRest). The
// default step keeps its margin. `what`
// names the choice in messages. Returns what the tries found ("" when the first passed alone).
std::string tryTheSubsteps(const std::string& path, SceneDesc& scene, const char* what, unsigned threads, bool searchUp,
                           std::ostream& log) {
  constexpr int kDoublings = 5;
  std::vector<bool> restsAtFirstPass;
  std::string lastFailure;
  // A failure that stays where it is while the step halves is not the step's (a body through a
  // collider's rim, a crush): after three such tries in a row the search stops and says so,
  // rather than running the scene at ever more substeps (a 3.5 s cloth scene ran 16 minutes).
  std::vector<std::pair<std::string, std::string>> failed;  // (when, the cause without its numbers)
  const auto withoutNumbers = [](const std::string& text) {
    std::string out;
    for (char c : text) {
      if (!std::isdigit(static_cast<unsigned char>(c))) out += c;
    }
    return out;
  };
  const auto run = [&](int substeps) -> std::string {
    log << "springy: " << path << ": trying " << substepsText(substeps) << " over the whole run (" << what << ")...\n"
        << std::flush;
    scene.substeps = substeps;
    PathSettings s;
    s.integrator = scene.integrator;
    s.dt = stepSize(scene);
    s.frame = 1.0 / scene.view.render.fps;
    s.duration = scene.duration;
    s.threads = threads;
    // The model as the run builds it: its resting speed for contacts follows the step.
    const Model model = buildModel(scene);
    const RunPath r = [&] {
      const StillWorking working(log, "springy: " + path + ": trying " + substepsText(substeps));
      return tracePath(model, s);
    }();
    if (interrupted()) throw Error(path + ": " + what + ": interrupted");
    char at[64];
    std::snprintf(at, sizeof at, "after t = %.3g s", r.times.empty() ? 0.0 : r.times.back());
    if (!r.complete) {
      lastFailure = r.failure;
      failed.emplace_back(at, withoutNumbers(r.failure));
      const std::size_t n = failed.size();
      if (n >= 3 && failed[n - 1] == failed[n - 2] && failed[n - 2] == failed[n - 3]) {
        throw Error(path + ": " + what + ": the run fails at the same moment (" + at + ") at " +
                    std::to_string(substeps / 4) + ", " + std::to_string(substeps / 2) + " and " +
                    substepsText(substeps) + ", so a smaller step does not fix it: " + lastFailure);
      }
      return at;
    }
    failed.clear();
    const int moving = bodyNoLongerAtRest(restsAtFirstPass, r);
    return moving < 0 ? std::string() : "body '" + model.bodies[moving].name + "' never comes to rest";
  };
  const CountSearch found = searchCount(scene.substeps, kMaxSubsteps, kDoublings, searchUp, run);
  if (found.count == 0) {
    throw Error(path + ": " + what + ": the run fails even at " + substepsText(found.tries.back().count) + ": " +
                lastFailure);
  }
  scene.substeps = found.count;
  if (found.tries.size() == 1) return "";
  // "; the run failed at 20 (after t = 1.63 s), 40 (after t = 1.7 s) substeps, and passed at 80 substeps"
  std::string said = "; the run ";
  for (std::size_t i = 0; i < found.tries.size();) {
    const bool passed = found.tries[i].failure.empty();
    said += i > 0 ? ", and " : "";
    said += passed ? "passed at " : "failed at ";
    const std::size_t first = i;
    for (; i < found.tries.size() && found.tries[i].failure.empty() == passed; ++i) {
      said += (i > first ? ", " : "") + std::to_string(found.tries[i].count);
      if (!passed) said += " (" + found.tries[i].failure + ")";
    }
    said += i == first + 1 && found.tries[first].count == 1 ? " substep" : " substeps";
  }
  return said;
}
// The survey of the whole run for --substeps auto (sim/stability.h surveyStability), saying every
// 5 s that it goes on. Throws springy::Error when interrupted.
StabilitySurvey surveyTheRun(const std::string& path, const Model& model, const SceneDesc& scene, unsigned threads,
                             std::ostream& log) {
  const StillWorking working(log, "springy: " + path + ": surveying");
  StabilitySurvey survey = surveyStability(model, scene.integrator, scene.duration, 1.0 / scene.view.render.fps,
                                           scene.dt, scene.tolerance, threads);
  if (interrupted()) throw Error(path + ": --substeps auto: the survey: interrupted");
  return survey;
}
}  // namespace

std::string substepsText(int count) { return std::to_string(count) + (count == 1 ? " substep" : " substeps"); }

void adviseTimeStep(const std::string& path, SceneDesc& scene, StepChoice choice, unsigned threads, std::ostream& log,
                    bool runIsTry) {
  const Model model = buildModel(scene);
  const StabilityReport r = estimateStability(model, model.restPosition, scene.integrator, scene.duration);
  const BodyStability& b = r.bodies.empty() ? BodyStability{} : r.bodies[r.limitingBody];
  const std::string& body = r.bodies.empty() ? path : model.bodies[r.limitingBody].name;
  // Backward Euler with contact between bodies: the contact stage's limit (sim/stability.h).
  const std::string contactNote =
      !r.bodies.empty() && contactLimitedIntegrator(model, r.limitingBody, scene.integrator) != scene.integrator
          ? std::string(" (") + kContactLimitReason + ")"
          : "";
  if (!(r.dtMax > 0.0) || !std::isfinite(b.omegaMax) || !std::isfinite(b.gammaMax)) {
    throw Error(path + ": body '" + body + "': its stiffest mode has no finite frequency (omega_max " +
                std::to_string(b.omegaMax) + " rad/s, damping rate " + std::to_string(b.gammaMax) +
                " 1/s): its mass, periods or spring constants are out of proportion");
  }
  // Backward Euler without contact between bodies: no limit at rest, but `--substeps auto` still
  // surveys the run for its landings (sim/monitor.h landingStep).
  if (!std::isfinite(r.dtMax) && choice != StepChoice::AutoSubsteps) {
    if (choice == StepChoice::Default) {
      log << "springy: " << path << ": step " << seconds(stepSize(scene)) << " (the scene gives none; "
          << integratorName(scene.integrator) << " is stable at any step on these springs)\n";
    }
    return;
  }
  const int needed = safeSubsteps(scene.dt, r.dtMax, kSafety);
  if (choice == StepChoice::AutoSubsteps) {
    // The estimate at rest does not hold through impacts (bunny_light: 1 substep at rest, and its
    // landing then gains energy): survey the whole run (sim/stability.h) and take its tightest
    // limit, from the stiffest mode found rather than the bound (3-4x looser on the showcase scenes).
    log << "springy: " << path << ": surveying the run for --substeps auto (" << integratorName(kDefaultAdaptive)
        << "; the stiffest mode found every frame and wherever the shape stiffens)...\n"
        << std::flush;
    const StabilitySurvey survey = surveyTheRun(path, model, scene, threads, log);
    if (!survey.failure.empty()) {
      throw Error(path + ": --substeps auto: the survey run (" + std::string(integratorName(kDefaultAdaptive)) +
                  ", tolerance " + number(scene.tolerance) + ") failed, so no step can be advised: " +
                  survey.failure);
    }
    const int surveyed = scene.substeps = safeSubsteps(scene.dt, survey.dtMax, kSafety);
    if (!std::isfinite(survey.dtMax)) {
      log << "springy: " << path << ": --substeps auto: 1 (" << integratorName(scene.integrator)
          << " is stable at any step on these springs, and no landing limits it)\n";
      return;
    }
    const std::string tried = tryTheSubsteps(path, scene, "--substeps auto", threads, true, log);
    log << "springy: " << path << ": --substeps auto: " << scene.substeps << " (step " << seconds(stepSize(scene))
        << "; the survey's estimate of the stable limit for " << integratorName(scene.integrator)
        << " over the whole run " << seconds(survey.dtMax) << " (" << substepsText(surveyed)
        << "), at t = " << number(survey.time) << " s in body '" << model.bodies[survey.body].name << "'"
        << (survey.landing ? std::string(", set by the energy its landing may add")
                           : limitingMode(model.bodies[survey.body], survey))
        << "; at rest " << (std::isfinite(survey.atRest) ? seconds(survey.atRest) : std::string("any step")) << ")"
        << tried << contactNote << "\n";
  } else if (choice == StepChoice::Default) {
    const double margin = impactMargin(scene);
    scene.substeps = safeSubsteps(scene.dt, r.dtMax, margin);
    if (runIsTry) {
      log << "springy: " << path << ": " << substepsText(scene.substeps) << " of dt " << seconds(scene.dt) << " (step "
          << seconds(stepSize(scene)) << "): the scene gives none, so the advisor's: at most " << margin
          << " of the estimated stable limit " << seconds(r.dtMax) << " for " << integratorName(scene.integrator)
          << " (body '" << body << "'), a margin for impacts; this run is its try" << contactNote << "\n";
      return;
    }
    const std::string tried = tryTheSubsteps(path, scene, "the default step", threads, false, log);
    log << "springy: " << path << ": step " << seconds(stepSize(scene)) << " (dt " << seconds(scene.dt) << " / "
        << substepsText(scene.substeps) << "): the scene gives none, so the advisor's: at most " << margin
        << " of the estimated stable limit " << seconds(r.dtMax) << " for " << integratorName(scene.integrator)
        << " (body '" << body << "'), a margin for impacts"
        << (tried.empty() ? std::string() : " (" + tried.substr(2) + ")") << contactNote << "\n";
  } else if (stepSize(scene) > r.dtMax) {
    log << "springy: warning: " << path << ": the step " << seconds(stepSize(scene))
        << " exceeds the estimated stable limit " << seconds(r.dtMax) << " of " << integratorName(scene.integrator)
        << " (body '" << body << "': omega_max <= " << b.omegaMax << " rad/s, damping rate <= " << b.gammaMax
        << " 1/s, 2/omega_max = " << seconds(2.0 / b.omegaMax) << "). Use --substeps auto (" << substepsText(needed)
        << "), a smaller dt, or `springy suggest " << path << "`." << contactNote << "\n";
  }
}

bool retryDefaultStep(const std::string& path, SceneDesc& scene, const Failure& failure, bool& untried,
                      unsigned threads, std::ostream& log) {
  if (!untried || failure.criterion) return false;
  untried = false;
  // What the scene did to the body (Failure::cause) is no step's to fix: said at once, rather
  // than tried at ever more substeps; the failure stays the run's (its record, Python's
  // Unstable), as any other that no step fixes.
  if (!failure.cause.empty()) {
    log << "springy: " << path << ": the default step was not tried further: the scene drives the failure ("
        << failure.cause << ")\n";
    return false;
  }
  char after[64];
  std::snprintf(after, sizeof after, "after t = %.3g s", failure.time);
  const int failed = scene.substeps;
  if (failed >= kMaxSubsteps) {
    throw Error(path + ": the default step: the run fails even at " + substepsText(failed) + ": " + after);
  }
  log << "springy: " << path << ": the run failed at " << substepsText(failed) << " (" << after << ")\n";
  scene.substeps = std::min(2 * failed, kMaxSubsteps);
  const std::string tried = tryTheSubsteps(path, scene, "the default step", threads, false, log);
  log << "springy: " << path << ": step " << seconds(stepSize(scene)) << " (dt " << seconds(scene.dt) << " / "
      << substepsText(scene.substeps) << "): the advisor's default step failed at " << substepsText(failed)
      << (tried.empty() ? "; the run passed at " + substepsText(scene.substeps) : tried) << "\n";
  return true;
}
}  // namespace springy
