// `springy study contact`: whole runs of scenes through contact, each integrator's centroid path
// against a fine RK4 reference (sim/trajectory.h), error against run time, the adaptive steps'
// tolerances, vertex block descent's numerical damping.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/study.h"
#include "scene/scene.h"
#include "sim/trajectory.h"

namespace springy::study {
namespace {

constexpr std::array<Integrator, 4> kFixed = {Integrator::SymplecticEuler, Integrator::VelocityVerlet,
                                              Integrator::Leapfrog, Integrator::RK4};
constexpr std::array<Integrator, 2> kAdaptive = {Integrator::BogackiShampine, Integrator::AdaptiveVerlet};

struct ContactPoint {
  std::string method;  // the integrator's name
  double dt = 0, tolerance = 0;
  RunPath path;
  PathError error;
};

std::string describeFailure(const RunPath& p) {
  return p.failure.find("energy") != std::string::npos   ? "energy rose"
         : p.failure.find("NaN") != std::string::npos    ? "NaN"
         : p.failure.find("volume") != std::string::npos ? "collapsed"
                                                         : "failed";
}

// Least-squares slope of log error against log dt over the finest three complete steps.
double contactOrder(const std::vector<ContactPoint>& points, const std::string& method) {
  std::vector<const ContactPoint*> use;
  for (const ContactPoint& p : points) {
    if (p.method == method && p.path.complete && p.error.centroidRms > 0) use.push_back(&p);
  }
  std::sort(use.begin(), use.end(), [](const ContactPoint* a, const ContactPoint* b) { return a->dt < b->dt; });
  if (use.size() > 3) use.resize(3);
  if (use.size() < 2) return NAN;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(use.size());
  for (const ContactPoint* p : use) {
    const double x = std::log(p->dt), y = std::log(p->error.centroidRms);
    sx += x, sy += y, sxx += x * x, sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// One scene's runs: the reference (RK4 at an eighth of the finest step), its check (at a quarter),
// and the points: every fixed-step integrator down the ladder, the adaptive ones at each
// tolerance, vbd from a frame down to the ladder's coarsest step.
struct SceneRuns {
  std::string name;
  SceneDesc scene;
  Model model;
  PathSettings base;
  double n0 = 1, finest = 0;
  int rungs = 0;
  RunPath reference, check;
  std::vector<ContactPoint> points;
  double perSecond(const ContactPoint& p) const { return p.path.stepSeconds / base.duration; }
};

// The scene's runs, side by side on every core; the errors against the reference.
SceneRuns runScene(const std::string& path, const StudyOptions& o, const std::vector<double>& tolerances) {
  SceneRuns s;
  s.scene = loadScene(path);
  s.model = buildModel(s.scene);
  s.name = fs::path(path).stem().string();
  // Fixed steps divide the frame (every run samples the same instants): the frame over n0 x 2^k
  // with n0 from the original's 2 ms step; the references 4 and 8 times finer than the finest.
  s.rungs = o.quick ? 3 : 5;
  s.base.frame = 1.0 / s.scene.view.render.fps;
  const double full = o.maxDuration > 0 ? std::min(s.scene.duration, o.maxDuration) : s.scene.duration;
  s.base.duration = s.base.frame * std::max(1.0, std::floor(full / s.base.frame + 1e-9));
  s.n0 = std::ceil(s.base.frame / 0.002 - 1e-9);
  s.finest = s.base.frame / (s.n0 * std::pow(2.0, s.rungs - 1));
  std::vector<ContactPoint> runs;
  runs.push_back({"reference", s.finest / 8, 0, {}, {}});
  runs.push_back({"check", s.finest / 4, 0, {}, {}});
  for (Integrator integrator : kFixed) {
    for (int k = 0; k < s.rungs; ++k) {
      runs.push_back({std::string(integratorName(integrator)), s.base.frame / (s.n0 * std::pow(2.0, k)), 0, {}, {}});
    }
  }
  for (Integrator adaptive : kAdaptive) {
    for (double tolerance : tolerances) runs.push_back({std::string(integratorName(adaptive)), s.base.frame / s.n0, tolerance, {}, {}});
  }
  for (double m = 1; m <= s.n0; m *= 2) {
    runs.push_back({std::string(integratorName(Integrator::Vbd)), s.base.frame / m, 0, {}, {}});
  }
  std::vector<double> cost;
  for (const ContactPoint& r : runs) {
    Integrator integrator = Integrator::RK4;
    parseIntegrator(r.method, integrator);
    cost.push_back(r.tolerance > 0 ? 1.0 / r.tolerance : stepCost(integrator) / r.dt);
  }
  runInParallel("springy study contact: " + s.name, cost, [&](std::size_t i) {
    ContactPoint& r = runs[i];
    PathSettings settings = s.base;
    settings.integrator = Integrator::RK4;
    if (i > 1) parseIntegrator(r.method, settings.integrator);
    settings.dt = r.dt;
    settings.tolerance = r.tolerance;
    r.path = tracePath(s.model, settings);
  });
  s.reference = std::move(runs[0].path);
  s.check = std::move(runs[1].path);
  if (!s.reference.complete || !s.check.complete) return s;
  s.points.assign(std::make_move_iterator(runs.begin() + 2), std::make_move_iterator(runs.end()));
  for (ContactPoint& p : s.points) {
    if (p.path.complete) p.error = pathError(s.model, s.reference, p.path);
  }
  return s;
}

std::string contactIntroduction(const StudyOptions& o) {
  std::ostringstream md;
  md << "# Accuracy through contact: whole runs\n\n"
     << "Generated by `springy study contact" << (o.quick ? " --quick" : "")
     << (o.maxDuration > 0 ? " --max-duration " + fmt("%g", o.maxDuration) : std::string()) << " -o " << o.output
     << "` (scripts/study.sh regenerates docs/). Do not edit by hand.\n\n"
     << "- Machine: " << machine() << "; one run per point.\n"
     << "- Each scene runs with its colliders and contacts, from the start over the duration given, sampled at its "
        "video frames. Error: per body, the RMS over frames of the distance between its centroid and the "
        "reference's, relative to its size (bounding-box diagonal at rest); the largest over bodies. Also the last "
        "frame's centroid distance and the lowest volume's relative difference.\n"
     << "- Fixed steps divide the frame (frame / (n0 2^k), n0 from the original's 2 ms), so every run is compared at "
        "the same instants; the adaptive steps (bs32: Bogacki-Shampine 3(2); verlet_adaptive: velocity Verlet with "
        "its error from the change of acceleration; `--tolerance`) land on every frame.\n"
     << "- Reference: RK4 at an eighth of the finest step; its check, RK4 at a quarter, must differ from it far "
        "less than the errors reported (each scene names the difference).\n"
     << "- Order through contact: slope of log error against log dt over the three finest steps; contact "
        "resolved once per step (at its end; Verlet's after the drift, before the forces there) makes every "
        "method about first order.\n"
     << "- The last column: the cheapest fixed-step run of the ladder whose error is no larger and stays so when "
        "the step is refined (no finer step of its scheme is less accurate: an error that grows again under "
        "refinement was that step's luck, its path crossing the reference's, not an accuracy a user can choose by "
        "the step), and its run time over the adaptive run's (above 1: the adaptive step is cheaper for that "
        "accuracy).\n\n";
  return md.str();
}

// The fixed steps' table: error and run time per step, the order through contact.
std::string fixedTable(const SceneRuns& s) {
  std::ostringstream body;
  body << "| integrator | order through contact |";
  for (int k = 0; k < s.rungs; ++k) body << " dt " << fmt("%.3g", s.base.frame / (s.n0 * std::pow(2.0, k))) << " |";
  body << "\n|---|---|";
  for (int k = 0; k < s.rungs; ++k) body << "---|";
  body << "\n";
  for (Integrator integrator : kFixed) {
    const std::string method(integratorName(integrator));
    const double order = contactOrder(s.points, method);
    body << "| " << method << " | " << (std::isnan(order) ? std::string("n/a") : fmt("%.2f", order)) << " |";
    for (const ContactPoint& p : s.points) {
      if (p.method != method || p.tolerance > 0) continue;
      body << " " << (p.path.complete ? fmt("%.2e", p.error.centroidRms) : describeFailure(p.path)) << " / "
           << fmt("%.3g", s.perSecond(p) * 1e3) << " ms |";
    }
    body << "\n";
  }
  body << "\nEach cell: centroid RMS error / run time per simulated second (a failed run: what stopped it, and its "
          "time until then).\n\n";
  return body.str();
}

// vbd at each step beside the coarsest explicit runs: errors and the energy lost beyond the reference.
std::string implicitTable(const SceneRuns& s) {
  std::ostringstream body;
  body << "| implicit, or the coarsest explicit | dt | centroid RMS | end position | lowest volume | energy lost beyond "
          "the reference | run time per sim. s |\n|---|---|---|---|---|---|---|\n";
  for (const ContactPoint& p : s.points) {
    const bool implicit = p.method == integratorName(Integrator::Vbd);
    const bool coarsest = p.tolerance == 0.0 && !implicit && std::fabs(p.dt - s.base.frame / s.n0) < 1e-12 &&
                          (p.method == integratorName(Integrator::SymplecticEuler) ||
                           p.method == integratorName(Integrator::RK4));
    if (!implicit && !coarsest) continue;
    body << "| " << p.method << (implicit ? " (" + std::to_string(SimulationDesc{}.iterations) + " sweeps)" : "")
         << " | " << fmt("%.3g", p.dt) << " | ";
    if (!p.path.complete) {
      body << describeFailure(p.path) << " at t = " << fmt("%.3g", p.path.times.back()) << " s | | | | "
           << fmt("%.3g", s.perSecond(p) * 1e3) << " ms |\n";
      continue;
    }
    body << fmt("%.2e", p.error.centroidRms) << " | " << fmt("%.2e", p.error.endPosition) << " | "
         << fmt("%.2e", p.error.lowestVolume) << " | " << fmt("%.3g", p.error.energyLost) << " J ("
         << fmt("%.1f", 100.0 * p.error.energyLostShare) << "%) | " << fmt("%.3g", s.perSecond(p) * 1e3) << " ms |\n";
  }
  body << "\nEnergy lost beyond the reference: the run's total energy at the last frame below the reference's, and "
          "that as a share of the reference's largest kinetic energy (the motion's energy): the numerical damping.\n\n";
  return body.str();
}

// A run at a step given (vbd's too), not an adaptive one.
bool isFixed(const ContactPoint& p) { return p.tolerance == 0.0; }

// The cheapest fixed-step run at least as accurate as `p`, whose accuracy holds under refinement
// (no finer step of its scheme is less accurate), or null.
const ContactPoint* cheapestAsAccurate(const SceneRuns& s, const ContactPoint& p) {
  const auto holds = [&](const ContactPoint& q) {
    return std::none_of(s.points.begin(), s.points.end(), [&](const ContactPoint& finer) {
      return finer.method == q.method && isFixed(finer) && finer.dt < q.dt && finer.path.complete &&
             finer.error.centroidRms > q.error.centroidRms;
    });
  };
  const ContactPoint* rival = nullptr;
  for (const ContactPoint& q : s.points) {
    if (!isFixed(q) || !q.path.complete || q.error.centroidRms > p.error.centroidRms || !holds(q)) continue;
    if (!rival || s.perSecond(q) < s.perSecond(*rival)) rival = &q;
  }
  return rival;
}

// The adaptive steps' table: each tolerance's error, steps, and what a fixed step as accurate costs.
std::string adaptiveTable(const SceneRuns& s) {
  std::ostringstream body;
  body << "| adaptive | tolerance | centroid RMS | end position | lowest volume | run time per sim. s | steps (rejected) "
          "| step from-to [s] | fixed step for the same error costs |\n|---|---|---|---|---|---|---|---|---|\n";
  for (const ContactPoint& p : s.points) {
    if (p.tolerance == 0.0) continue;
    body << "| " << p.method << " | " << fmt("%.0e", p.tolerance) << " | ";
    if (!p.path.complete) {
      body << describeFailure(p.path) << " | | | " << fmt("%.3g", s.perSecond(p) * 1e3) << " ms | | | |\n";
      continue;
    }
    const ContactPoint* rival = cheapestAsAccurate(s, p);
    const StepStats& st = p.path.stepStats;
    body << fmt("%.2e", p.error.centroidRms) << " | " << fmt("%.2e", p.error.endPosition) << " | "
         << fmt("%.2e", p.error.lowestVolume) << " | " << fmt("%.3g", s.perSecond(p) * 1e3) << " ms | " << st.accepted
         << " (" << st.rejected << ") | " << fmt("%.2g", st.smallest) << "-" << fmt("%.2g", st.largest) << " | "
         << (rival ? fmt("%.2f", s.perSecond(*rival) / s.perSecond(p)) + "x (" + rival->method + ", dt " +
                         fmt("%.3g", rival->dt) + ")"
                   : std::string("none of the ladder is as accurate"))
         << " |\n";
  }
  body << "\n";
  return body.str();
}

// The scene's section: what it is, the reference's agreement, the three tables and the plot; its
// rows of the csv.
std::string sceneSection(const fs::path& out, const SceneRuns& s, std::ostringstream& csv) {
  std::ostringstream body;
  body << "## " << s.name << "\n\n";
  if (!s.reference.complete || !s.check.complete) {
    body << "No reference: RK4 at dt " << fmt("%.3g", s.finest / 8)
         << " s failed: " << (s.reference.complete ? s.check.failure : s.reference.failure) << "\n\n";
    return body.str();
  }
  for (const ContactPoint& p : s.points) {
    csv << s.name << "," << p.method << "," << fmt("%.6g", p.dt) << "," << fmt("%.3g", p.tolerance) << ","
        << (p.path.complete ? 1 : 0) << "," << fmt("%.6g", p.error.centroidRms) << ","
        << fmt("%.6g", p.error.endPosition) << "," << fmt("%.6g", p.error.lowestVolume) << ","
        << fmt("%.6g", s.perSecond(p)) << "," << p.path.evaluations << "," << p.path.steps << ","
        << p.path.stepStats.rejected << "," << fmt("%.6g", p.error.energyLost) << "\n";
  }
  const PathError agreement = pathError(s.model, s.reference, s.check);
  body << s.scene.name << ": " << s.model.vertexCount() << " vertices in " << s.model.bodies.size() << " "
       << (s.model.bodies.size() == 1 ? "body" : "bodies") << ", " << fmt("%.4g", s.base.duration) << " s"
       << (s.base.duration < s.scene.duration - 1e-9 ? " of " + fmt("%.4g", s.scene.duration) + " s"
                                                     : std::string(" (all of it)"))
       << ". Reference: RK4 at dt " << fmt("%.3g", s.finest / 8) << " s; RK4 at twice that step differs from it by "
       << fmt("%.2e", agreement.centroidRms) << " (centroid RMS), " << fmt("%.2e", agreement.endPosition)
       << " (end position), " << fmt("%.2e", agreement.lowestVolume) << " (lowest volume).\n\n";
  body << fixedTable(s) << implicitTable(s) << adaptiveTable(s);
  std::vector<PlotSeries> series;
  for (Integrator integrator : kFixed) series.push_back({std::string(integratorName(integrator)), {}});
  for (Integrator integrator : kAdaptive) series.push_back({std::string(integratorName(integrator)), {}});
  series.push_back({std::string(integratorName(Integrator::Vbd)), {}});
  for (const ContactPoint& p : s.points) {
    if (!p.path.complete || !(p.error.centroidRms > 0)) continue;
    for (PlotSeries& line : series) {
      if (line.name != p.method) continue;
      line.points.push_back(
          {p.tolerance == 0.0 ? fmt("%.3g", p.dt) : fmt("%.0e", p.tolerance), s.perSecond(p), p.error.centroidRms});
    }
  }
  body << errorPlot(out, "accuracy-contact-" + s.name, s.name + " through contact (labels: dt; adaptive: tolerance)",
                    "centroid RMS error / body size", series);
  return body.str();
}

}  // namespace

int runContact(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out, "contact");
  const std::vector<double> tolerances =
      o.quick ? std::vector<double>{1e-3, 1e-4} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7};
  const std::string md = contactIntroduction(o);
  std::ostringstream csv;
  std::string body;
  csv << "scene,method,dt,tolerance,complete,centroid_rms,end_position,lowest_volume,wall_per_sim_second,evaluations,"
         "steps,rejected,energy_lost\n";
  for (const std::string& path : scenesOrShowcase(o)) {
    body += sceneSection(out, runScene(path, o, tolerances), csv);
    // Written again after every scene: a long study shows what it has so far.
    writeFile(out / "accuracy-contact.csv", csv.str());
    writeFile(out / "accuracy-contact.md", md + body);
  }
  writeFile(out / "accuracy-contact.csv", csv.str());
  writeFile(out / "accuracy-contact.md", md + body);
  std::printf("wrote %s\n", (out / "accuracy-contact.md").string().c_str());
  return 0;
}

}  // namespace springy::study
