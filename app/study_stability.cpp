// `springy study stability`: the largest stable step of every integrator on stiff and extreme
// cases against the advisor's bound and the stiffest mode found, and the showcase scenes' whole
// runs against `--substeps auto`'s steps.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>

#include "app/study.h"
#include "scene/scene.h"
#include "sim/cases.h"
#include "sim/error.h"
#include "sim/harness.h"
#include "sim/limits.h"
#include "sim/parallel.h"
#include "sim/stability.h"
#include "sim/trajectory.h"

namespace springy::study {
namespace {

// The showcase scenes (or the scenes named) over their full duration with their own integrator:
// the largest fixed step that passes the whole run under `springy check`'s monitor (bracketed by
// factors of 2 from the survey's proposal, then bisected in log step), against the advisor's
// proposals from its estimate at rest and from the survey of the whole run (`--substeps auto`,
// sim/stability.h).
constexpr double kSafetyFraction = 0.9;  // the advisor's (run/advisor.cpp)

// The survey's tightest mode: which, its rate and the mesh vertex with its largest share.
std::string modeWhere(const Model& model, const StabilitySurvey& survey) {
  const bool damping = survey.limit == ModeEstimator::Limit::Damping;
  return (damping ? "damping " + fmt("%.3g", survey.rate) + " 1/s" : "omega " + fmt("%.3g", survey.rate) + " rad/s") +
         " at vertex " + std::to_string(model.bodies[survey.body].meshVertex(survey.vertex));
}


std::string wholeRunsIntroduction(int halvings) {
  std::ostringstream md;
  md << "Each scene runs its full duration with its own integrator at a fixed step h; passing = the stability "
        "monitor of `springy check` sees nothing at any frame, and every body that comes to rest in the first "
        "passing run (at the proposal, or below it when that fails) comes to rest at h too (over the last second, "
        "as `springy check --end-at-rest`): an instability that saturates below the monitor's energy tolerance "
        "keeps a body moving. Proposed: 0.9 of the advisor's limit, from its estimate at t = 0 (at rest) or "
        "from the survey (`--substeps auto`: the same estimate made every dt along a run with the default "
        "adaptive step, its smallest; the substeps it gives at the scene's dt in brackets). The survey's "
        "tightest mode: the stiffest (omega) or the most damped (its rate), and the mesh vertex with its largest "
        "share. Tried: `--substeps auto` then tries its count, running the scene at it under the monitor as "
        "`springy check` does, doubling it after each failure and halving it (rounded up) after a pass until a "
        "run fails (run/advisor.cpp tryTheSubsteps, sim/harness.h searchCount); here counts of steps per frame, "
        "as `springy check --dt` one frame `--substeps auto` runs (at the scenes' own dt of 2 ms the count "
        "cannot fall below 1, the step not above 2 ms): the step it gives passed, and one at most twice as large "
        "failed. Largest stable step: the tries' passing step and the failing one next above it bracket it, then "
     << halvings
     << " halvings of the bracket's log ratio (assumes every smaller step passes); capped at one frame. The "
        "ratios: a step over the largest stable step (at most 1: it holds; at least 0.5: within a factor 2). "
        "On the bunny of bunny_light with the body material (a "
        "user's mesh given only a mass, tests/data/app/bunny_body.toml) it does not: the survey's run reaches "
        "omega 24,000 rad/s at the landing and proposes 20 substeps (0.1 ms), but RK4 runs at fixed steps meet "
        "stiffer shapes there (95,000 rad/s, around one vertex, along a run at 0.033 ms), fail at 0.1 and "
        "0.05 ms and pass at 0.033 and 0.025 ms; the tries give 80 substeps. The last rows: two scenes of "
        "bodies that meet, under backward Euler, whose step the contact between bodies limits (it acts after the "
        "implicit solve; the advisor takes symplectic Euler's limit for such bodies, sim/stability.h "
        "contactLimitedIntegrator). What sets their step is the bending stiffness (measured on 2026-12-04 with "
        "`springy check --integrator backward_euler --dt h`, the limit bracketed between a passing and a failing "
        "h): four times the bend_period (a sixteenth of the bending stiffness) takes head_on's limit from 0.8-1 "
        "ms to 2.7-4 ms and the column's from 0.8-1 ms to above 4 ms; four times the stretch_period leaves "
        "head_on's where it was and takes the column's to 1.2-1.8 ms; half the approach speed leaves head_on's "
        "where it was. In the column's lasting contact the limit follows the mesh as symplectic Euler's does "
        "(balls of 642 vertices: below 0.6 ms; the advisor proposes 0.18 ms, which passes); in head_on's brief "
        "impact it follows it less (balls of 162 vertices: 1.2-1.5 ms), so there symplectic Euler's limit is "
        "4 times too cautious; no estimate of the impact's own limit is made yet, and the tries make up for it "
        "(`springy check scenes/head_on.toml --integrator backward_euler --substeps auto`: the survey's 11 "
        "substeps of 2 ms, then 6 and 3 pass and 2 fails, so it runs at 3). The bunny_light row is a "
        "bisection's, not a clean edge either: `springy check --dt h --substeps 1 --end-at-rest` with the bunny "
        "1, 3, 10 and 30 mm higher passes all four starts at 0.25, 0.3 and 0.35 ms and fails three at 0.4 ms (at "
        "1.63-1.73 s); its own start passes at 0.4 ms and fails at 0.43 ms. Against 0.35 ms the survey's proposal is "
        "0.42 of the largest stable step, and the tries' 0.29 ms (7 substeps of its 2 ms: 14 and 7 pass, 4 fails) "
        "0.82. The survey's tightest mode is a damping rate of 14000-16000 1/s at 1.6-1.9 s "
        "(a hinge whose triangles have nearly collapsed), found as well along RK4 runs at fixed steps of 0.125 "
        "and 0.25 ms (16000 1/s): at 0.25 ms RK4 runs through that mode above its linear limit (h gamma 4.1 "
        "against 2.8) without a rise the monitor sees; at 0.3 ms, with steps shortened to land on the survey's "
        "times, the same mode (14000 1/s) is followed by the monitor's stop. The linear estimate is the safe "
        "side of an edge that depends on the run."
        " The monitor measures a rise above a body's lowest energy against what the body had left to spend then "
        "(sim/monitor.h, for the integrators whose energy only falls at a stable step, as RK4; before, and still "
        "for the symplectic ones, against its start's scale): the bunny at 3.5 ms, whose instability settles at "
        "some 20 J, under 2 % of that scale (24 J), now fails at t = 0.13 s; at 3 ms it passes the monitor but "
        "keeps a jitter of some 1 J kinetic (0.001 J at 2.5 ms) and never comes to rest, which the rest criterion "
        "above catches. The survey also takes every body's landing step (sim/monitor.h landingStep: putting a "
        "landed vertex back on its support adds m g v h, the bounce takes (1 - e^2) m v^2 / 2, and the step at "
        "which the deepest sink adds the monitor's 2 % beyond that): the cube, restitution 1 and springs whose "
        "own limit is 0.1 s, fails from its landings alone, first at 0.0236 s (its landing step: 0.0233 s); "
        "above that its runs pass or fail by a landing's phase (0.024-0.0275 and 0.031 s pass, 0.029 and 0.0333 "
        "s fail), so its largest stable step is the bisection's, not a clean edge. Nor is the ramp's, through the "
        "rest criterion: its ball comes to rest at 5.56 ms (the tries' first passing run) and not in the runs at "
        "5.8, 6.06, 6.6 and 7.9 ms (at 6.06 ms, `springy check scenes/ramp.toml --dt 0.006058 --substeps 1 "
        "--end-at-rest`: a vertex moves 0.16 m over the last second, against 0.021 m allowed), so the survey's "
        "proposal, 6.09 ms, is above the largest stable step here. When the survey's step was the first run (before "
        "the tries halved), the ball did not rest there "
        "and the criterion did not apply: the largest stable step was 9.2 ms.\n\n"
     << "| scene | integrator | largest stable step | at rest: proposed | / largest | survey: proposed (substeps) | "
        "/ largest | tried: step (per frame) | / largest | survey's tightest: when, body, mode (or landing) | "
        "runs (run time) |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  return md.str();
}

// One scene's whole runs: the advisor's proposals, the tries of `--substeps auto` and the largest
// stable step they bracket.
struct WholeRun {
  std::string name;
  Integrator integrator{};
  double lo = 0, restStep = 0, surveyStep = 0, tried = 0, seconds = 0;
  bool capped = false;
  int substeps = 0, runs = 0;
  CountSearch tries;
  StabilitySurvey survey;
  Model model;
};

WholeRun wholeRun(const std::string& path, std::optional<Integrator> integrator, int halvings) {
  SceneDesc scene = loadScene(path);
  if (integrator) scene.integrator = *integrator;
  WholeRun w;
  w.model = buildModel(scene);
  w.integrator = scene.integrator;
  w.name = fs::path(path).stem().string();
  const double start = threadCpuSeconds();
  const StabilityReport rest = estimateStability(w.model, w.model.restPosition, scene.integrator, scene.duration);
  w.survey = surveyStability(w.model, scene.integrator, scene.duration, 1.0 / scene.view.render.fps, scene.dt,
                             SimulationDesc{}.tolerance);
  const double frame = 1.0 / scene.view.render.fps;
  w.restStep = kSafetyFraction * rest.dtMax;
  w.surveyStep = kSafetyFraction * w.survey.dtMax;
  // The first passing run says which bodies come to rest (sim/trajectory.h bodyNoLongerAtRest).
  std::vector<bool> restsAtReference;
  const auto passes = [&](double h) {
    PathSettings s;
    s.integrator = scene.integrator;
    s.dt = h;
    s.frame = frame;
    s.duration = scene.duration;
    ++w.runs;
    const RunPath run = tracePath(w.model, s);
    if (!run.complete) return false;
    const int moving = bodyNoLongerAtRest(restsAtReference, run);
    if (moving >= 0) {
      std::fprintf(stderr, "springy study stability: %s: step %.4g s: body '%s' does not come to rest\n",
                   w.name.c_str(), h, w.model.bodies[moving].name.c_str());
    }
    return moving < 0;
  };
  // `--substeps auto` with dt one frame: the survey's count of steps per frame, tried as
  // run/advisor.cpp tries it (sim/harness.h searchCount); its passing count and the failing
  // count next to it bracket the largest stable step.
  w.tries = searchCount(safeSubsteps(frame, w.survey.dtMax, kSafetyFraction), kMaxSubsteps, 5, true,
                        [&](int n) { return passes(frame / n) ? std::string() : "fails"; });
  w.tried = w.tries.count > 0 ? frame / w.tries.count : 0.0;
  w.lo = w.tried;
  double hi = frame;
  w.capped = w.tries.count == 1;
  for (const CountTry& t : w.tries.tries) {
    if (!t.failure.empty() && frame / t.count > w.lo) hi = std::min(hi, frame / t.count);
  }
  if (!w.capped && w.lo > 0.0) {
    for (int i = 0; i < halvings; ++i) {
      const double mid = std::sqrt(w.lo * hi);
      (passes(mid) ? w.lo : hi) = mid;
    }
  }
  w.seconds = threadCpuSeconds() - start;
  w.substeps = safeSubsteps(scene.dt, w.survey.dtMax, kSafetyFraction);
  return w;
}

std::string wholeRunRow(const WholeRun& w, std::ostringstream& csv) {
  csv << w.name << "," << integratorName(w.integrator) << "," << fmt("%.4g", w.lo) << "," << (w.capped ? 1 : 0) << ","
      << fmt("%.4g", w.restStep) << "," << fmt("%.4g", w.surveyStep) << "," << w.substeps << "," << w.survey.time
      << "," << fmt("%.4g", w.tried) << "," << w.tries.count << "," << w.runs << "," << fmt("%.1f", w.seconds) << "\n";
  const auto ratio = [&](double h) { return w.capped ? "<= " + fmt("%.2f", h / w.lo) : fmt("%.2f", h / w.lo); };
  std::ostringstream md;
  md << "| " << w.name << " | " << integratorName(w.integrator) << " | " << (w.capped ? ">= " : "")
     << fmt("%.3g", w.lo) << " s | " << fmt("%.3g", w.restStep) << " s | " << ratio(w.restStep) << " | "
     << fmt("%.3g", w.surveyStep) << " s (" << w.substeps << ") | " << ratio(w.surveyStep) << " | "
     << (w.tries.count > 0 ? fmt("%.3g", w.tried) + " s (" + std::to_string(w.tries.count) + ") | " + ratio(w.tried)
                           : std::string("every count tried failed | -"))
     << " | "
     << (w.survey.failure.empty()
             ? "t = " + fmt("%.3g", w.survey.time) + " s, " + w.model.bodies[w.survey.body].name +
                   (w.survey.landing ? " (landing)" : ", " + modeWhere(w.model, w.survey))
             : "survey failed: " + w.survey.failure)
     << " | " << w.runs << " (" << fmt("%.0f", w.seconds) << " s) |\n";
  return md.str();
}

// The showcase scenes with their own integrator; then, unless scenes are named, two scenes of
// bodies that meet under backward Euler, whose step the contact between bodies limits
// (sim/stability.h contactLimitedIntegrator). Side by side on every core.
std::string wholeRuns(const StudyOptions& o, std::ostringstream& csv) {
  const int halvings = o.quick ? 3 : 5;
  csv << "scene,integrator,largest_stable_step,capped,rest_step,survey_step,survey_substeps,survey_time,tried_step,"
         "tried_per_frame,runs,wall_seconds\n";
  std::vector<std::pair<std::string, std::optional<Integrator>>> runsOf;
  for (const std::string& path : scenesOrShowcase(o)) runsOf.emplace_back(path, std::nullopt);
  if (o.scenes.empty()) {
    for (const char* s : {"column", "head_on"}) runsOf.emplace_back(bundledScene(s), Integrator::BackwardEuler);
  }
  std::vector<double> cost;
  for (const auto& [path, integrator] : runsOf) {
    const SceneDesc scene = loadScene(path);
    cost.push_back(static_cast<double>(scene.bodies.size()) * scene.duration * (integrator ? 20 : 1));
  }
  std::vector<WholeRun> runs(runsOf.size());
  runInParallel("springy study stability: whole runs", cost,
                [&](std::size_t i) { runs[i] = wholeRun(runsOf[i].first, runsOf[i].second, halvings); });
  std::string md = wholeRunsIntroduction(halvings);
  for (const WholeRun& w : runs) md += wholeRunRow(w, csv);
  return md;
}

std::string stabilityIntroduction(const StudyOptions& o, double horizon, int iterations) {
  std::ostringstream md;
  md << "# Stability on stiff and extreme cases\n\n"
     << "Generated by `springy study stability" << (o.quick ? " --quick" : "") << " -o " << o.output
     << "` (scripts/study.sh regenerates docs/). Do not edit by hand.\n\n"
     << "- Machine: " << machine() << ".\n"
     << "- Largest stable dt: bisection in log dt (" << iterations
     << " halvings of the bracket's log ratio after bracketing by the tries of `--substeps auto`, below, or where "
        "it proposes no step by factors of 4); stable = over "
     << horizon
     << " simulated s every position and velocity "
        "finite, the body never larger than 10x its rest size, total energy never more than its own scale above "
        "the start (the stability monitor, energy tolerance 100 %). Capped at 0.1 s.\n"
     << "- Bound: 2/omega_max with omega_max the Gershgorin bound of the mass-normalised stiffness at t = 0 "
        "(sim/stability.h); predicted: the advisor's limit for that integrator (damping included; for explicit "
        "Euler the step at which the stiffest mode's energy doubles over the horizon).\n"
     << "- Mode found: the step from the stiffest mode itself (Lanczos on the mass-normalised stiffness, power "
        "iteration on the damping, sim/stability.h ModeEstimator; what `--substeps auto` uses along a run), the "
        "smaller of the mode undamped and a mode as damped with no stiffness.\n"
     << "- Failed first: what the monitor reported just above the limit (nan, blow-up, energy).\n\n";
  md << "- Whole run: what `--substeps auto` proposes for the case, 0.9 of the survey's smallest limit (the stiffest "
        "mode found along the run, sim/stability.h surveyStability, run from the case's released shape, or a "
        "landing's step at the cases' energy tolerance of 100 %), over the "
        "largest stable dt (at most 1: it holds; at least 0.5: within a factor 2). Tried: the step `--substeps "
        "auto` then gives, running the case over its horizon as the bisection does, at steps 0.1 s / n from the "
        "first n whose step is at most the proposal, n doubled after a failure and halved (rounded up) after a "
        "pass until a run fails (sim/harness.h searchCount; the runs it took in brackets): it passed, and a step at "
        "most twice as large failed, which bounds the bisection above. Not every edge is monotone: under backward "
        "Euler at 100 g the survey proposes a landing's step, 0.0443 s, but the tries' first step, 0.0333 s, "
        "fails (the volume), and the largest stable step is taken below it (bracketed instead from the "
        "prediction, by factors of 4, the bisection found 0.0628 s passing: 1.41 here was 0.71).\n\n";
  md << "| case | integrator | largest stable dt | predicted | 2/omega_max | measured / predicted | mode found | "
        "measured / found | whole run: proposed | / largest | tried (runs) | / largest | failed first |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  return md.str();
}

// One case with one integrator: the advisor's prediction, the stiffest mode found, the survey's
// proposal, the tries' step and the largest stable step bisected in their bracket.
struct CaseRow {
  std::string name;
  Integrator integrator{};
  StabilityReport predicted;
  double bound = 0, found = 0, proposed = 0;
  std::string surveyFailure;
  TriedStep tried;
  MeasuredStep measured;
};

CaseRow caseRow(const StabilityCase& c, Integrator integrator, double horizon, int iterations) {
  CaseRow r;
  r.name = c.name;
  r.integrator = integrator;
  r.predicted = estimateStability(c.model, c.positions, integrator, horizon);
  r.bound = 2.0 / r.predicted.bodies[0].omegaMax;
  const double guess = std::isfinite(r.predicted.dtMax) ? r.predicted.dtMax : 0.01;
  const World world(c.model, integrator, guess);
  ModeEstimator modes(world);
  r.found = ModeEstimator::step(integrator, modes.estimate(c.positions, 60), horizon);
  // The whole run as `--substeps auto` sees it: frames of a 50th of the horizon.
  const StabilitySurvey survey = surveyStability(c.model, integrator, horizon, horizon / 50, 0.0,
                                                 SimulationDesc{}.tolerance, 1, &c.positions, kCaseEnergyTolerance);
  r.proposed = kSafetyFraction * survey.dtMax;
  r.surveyFailure = survey.failure.empty() ? "" : failureKind(survey.failure);
  // Then tried as `--substeps auto` tries its count (sim/harness.h searchCount); the largest
  // stable step is bisected in the bracket the tries leave (a step they saw fail bounds it).
  r.tried = std::isfinite(r.proposed) ? triedStep(c.model, integrator, horizon, r.proposed, 0.1, &c.positions, iterations)
                                      : TriedStep{};
  r.measured = r.tried.runs > 0 ? r.tried.largest
                                : largestStableStep(c.model, integrator, horizon, guess, 0.1, &c.positions, iterations);
  return r;
}

std::string caseRowText(const CaseRow& r, std::ostringstream& csv) {
  const BodyStability& b = r.predicted.bodies[0];
  const MeasuredStep& m = r.measured;
  const double predicted = r.predicted.dtMax;
  const std::string failed = m.capped ? "none up to 0.1 s" : m.above.kind;
  csv << r.name << "," << integratorName(r.integrator) << "," << fmt("%.4g", m.dt) << "," << (m.capped ? 1 : 0) << ","
      << fmt("%.4g", predicted) << "," << fmt("%.4g", r.bound) << "," << fmt("%.4g", b.omegaMax) << ","
      << fmt("%.4g", b.gammaMax) << "," << fmt("%.4g", r.found) << "," << fmt("%.4g", r.proposed) << ","
      << r.surveyFailure << "," << fmt("%.4g", r.tried.dt) << "," << r.tried.runs << "," << failed << "\n";
  std::ostringstream md;
  md << "| " << r.name << " | " << integratorName(r.integrator) << " | " << (m.capped ? ">= " : "") << fmt("%.3g", m.dt)
     << " s | " << (std::isfinite(predicted) ? fmt("%.3g", predicted) + " s" : std::string("unconditional")) << " | "
     << fmt("%.3g", r.bound) << " s | "
     << (std::isfinite(predicted) && !m.capped ? fmt("%.2f", m.dt / predicted) : std::string("-")) << " | "
     << (std::isfinite(r.found) ? fmt("%.3g", r.found) + " s" : std::string("unconditional")) << " | "
     << (std::isfinite(r.found) && !m.capped ? fmt("%.2f", m.dt / r.found) : std::string("-")) << " | "
     << (std::isfinite(r.proposed) ? fmt("%.3g", r.proposed) + " s" : std::string("unconditional"))
     << (r.surveyFailure.empty() ? "" : " (survey stopped: " + r.surveyFailure + ")") << " | "
     << (std::isfinite(r.proposed) && !m.capped ? fmt("%.2f", r.proposed / m.dt) : std::string("-")) << " | "
     << (r.tried.runs > 0 && !m.capped ? fmt("%.3g", r.tried.dt) + " s (" + std::to_string(r.tried.runs) + ")"
                                       : std::string("-"))
     << " | " << (r.tried.runs > 0 && !m.capped ? fmt("%.2f", r.tried.dt / m.dt) : std::string("-")) << " | " << failed
     << " |\n";
  return md.str();
}

}  // namespace

int runStability(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out, "stability");
  const double horizon = o.quick ? 0.05 : 0.2;
  const int iterations = o.quick ? 4 : 8;
  std::ostringstream csv, refused, descriptions, csvRuns;
  csv << "case,integrator,measured_dt,capped,predicted_dt,two_over_omega,omega_max,gamma_max,mode_found_dt,"
         "survey_proposed_dt,survey_failure,tried_dt,tried_runs,failed_first\n";
  std::vector<StabilityCase> cases;
  for (const CaseFactory& factory : stabilityCases()) {
    try {
      cases.push_back(factory.make());
    } catch (const Error& e) {
      refused << "- **" << factory.name << "**: refused at load: " << e.what() << "\n";
      continue;
    }
    descriptions << "- **" << cases.back().name << "**: " << cases.back().description << "\n";
  }
  std::vector<std::pair<std::size_t, Integrator>> jobs;
  std::vector<double> cost;
  for (std::size_t c = 0; c < cases.size(); ++c) {
    for (Integrator integrator : kStabilityStudied) {
      jobs.emplace_back(c, integrator);
      cost.push_back(static_cast<double>(cases[c].model.vertexCount()) * stepCost(integrator));
    }
  }
  std::vector<CaseRow> rows(jobs.size());
  runInParallel("springy study stability: cases", cost, [&](std::size_t j) {
    rows[j] = caseRow(cases[jobs[j].first], jobs[j].second, horizon, iterations);
  });
  std::string md = stabilityIntroduction(o, horizon, iterations);
  for (const CaseRow& r : rows) md += caseRowText(r, csv);
  if (!o.quick || !o.scenes.empty()) {  // --quick without --scenes leaves out the showcase scenes' whole runs
    md += "\n## Whole runs: the advisor through impacts\n\n" + wholeRuns(o, csvRuns);
  }
  md += "\n## Cases\n\n" + descriptions.str() + refused.str() +
        "\n## The guarantee\n\nNo case produces a NaN silently: each either runs, or stops with the monitor's "
        "report naming the body, the step and what diverged, or is refused at load because its geometry is "
        "degenerate (tests/test_stability.cpp, `Guarantee.*`). Backward Euler runs every case at dt = 1/60 s; its "
        "contacts are constraints inside the implicit solve (sim/implicit.h).\n";
  writeFile(out / "stability.csv", csv.str());
  if (!csvRuns.str().empty()) writeFile(out / "stability-runs.csv", csvRuns.str());
  writeFile(out / "stability.md", md);
  std::printf("wrote %s\n", (out / "stability.md").string().c_str());
  return 0;
}

}  // namespace springy::study
