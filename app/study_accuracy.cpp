// `springy study accuracy`: the work-precision study of every integrator before contact: error at
// a fixed end time against a reference (a closed form, or RK4 at a finer step), run time per
// simulated second, measured convergence order, log-log plots of error against run time.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "app/study.h"
#include "sim/cases.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/interrupt.h"
#include "sim/parallel.h"
#include "sim/shapes.h"

namespace springy::study {
namespace {

struct AccuracyCase {
  std::string name, description;
  Model model;
  std::vector<Vec3> x0;
  double endTime = 1.0;
  std::vector<double> dts;                       // the ladder, each half the one before
  double size = 1.0;                             // body size the error is relative to
  std::function<std::vector<Vec3>()> reference;  // positions at endTime
};

struct Point {
  std::string caseName;
  Integrator integrator;
  double dt;
  double error;          // RMS vertex error / size at endTime
  double wallPerSecond;  // run time per simulated second [s] (its thread's CPU time), median
  bool stable;
};

// The case's state at `end`, stepped on this thread; `seconds`: the run's CPU time on it.
std::vector<Vec3> runTo(const Model& model, const std::vector<Vec3>& x0, Integrator integrator, double dt, double end,
                        double* seconds = nullptr) {
  const double start = threadCpuSeconds();
  World world(model, integrator, dt);
  world.setState(x0, world.velocities());
  const auto steps = static_cast<long>(std::llround(end / dt));
  // Stops at an interrupt (the study then throws): the interrupt flag is one atomic load a step.
  for (long s = 0; s < steps && !interrupted(); ++s) world.step();
  if (seconds) *seconds = threadCpuSeconds() - start;
  return world.positions();
}

std::vector<double> ladder(double first, int count) {
  std::vector<double> d;
  for (int k = 0; k < count; ++k) d.push_back(first / std::pow(2.0, k));
  return d;
}

// The case's reference: RK4 from its start to its end time at its finest step / divisor.
void referenceByRk4(AccuracyCase& c, double divisor) {
  const Model model = c.model;
  const std::vector<Vec3> x0 = c.x0;
  const double dt = c.dts.back() / divisor, end = c.endTime;
  c.reference = [=] { return runTo(model, x0, Integrator::RK4, dt, end); };
}

AccuracyCase strutAccuracy(double damping) {
  // Two masses (1 and 0.5 kg) on one strut (k = 30 N/m), released stretched by 0.1 m, at rest:
  // the relative coordinate y = l - l0 is a damped oscillator mu y'' = -k y - d y'.
  AccuracyCase c;
  const double m0 = 1.0, m1 = 0.5, l0 = 1.0, k = 30.0, d = damping;
  c.name = damping > 0 ? "strut" : "strut (undamped)";
  c.description = "two masses (1, 0.5 kg), one strut k = 30 N/m, d = " + fmt("%g", d) +
                  " N s/m, released stretched 10 %; reference: closed form";
  c.model = strutModel(m0, m1, l0, k, d, false);
  c.model.bodies[0].restSize = l0;
  const double y0 = 0.1, L = l0 + y0;
  // Centre of mass at the origin's side: x0 = -m1/M L, x1 = m0/M L keeps it at 0.
  const double M = m0 + m1;
  c.x0 = {{-m1 / M * L, 0, 0}, {m0 / M * L, 0, 0}};
  c.endTime = 1.0;
  c.dts = ladder(0.005, 6);
  c.size = l0;
  c.reference = [=] {
    const double mu = m0 * m1 / M, zeta = d / (2 * mu), wd = std::sqrt(k / mu - zeta * zeta), t = 1.0;
    const double y = std::exp(-zeta * t) * (y0 * std::cos(wd * t) + zeta * y0 / wd * std::sin(wd * t));
    const double len = l0 + y;
    return std::vector<Vec3>{{-m1 / M * len, 0, 0}, {m0 / M * len, 0, 0}};
  };
  return c;
}

AccuracyCase hingeAccuracy() {
  AccuracyCase c;
  StabilityCase h = hingeCase(0.5, 1.0, 0.5, 1.0);  // P_theta 0.5 s, struts 1 s
  c.name = "hinge";
  c.description =
      "two triangles on one hinge (P_theta = 0.5 s, T_theta = 1 s, struts P = 1 s), released bent "
      "0.5 rad from rest; reference: RK4 at dt/16 of the finest step";
  c.model = h.model;
  c.x0 = h.positions;
  c.endTime = 1.0;
  c.dts = ladder(0.0025, 6);
  c.size = c.model.bodies[0].restSize;
  referenceByRk4(c, 16);
  return c;
}

AccuracyCase gasAccuracy() {
  // A balloon: soft struts, no hinges, an enclosed gas (sim/forces.h) that the squashed shape
  // compresses; the gas's pressure depends on the whole body's volume, so every vertex is
  // coupled to every other.
  AccuracyCase c;
  c.name = "gas";
  c.description =
      "icosphere (162 vertices, radius 1 m, 1 kg), struts P = 0.4 s, T = 1 s, no hinges, gas P_V = "
      "0.2 s, released squashed to 0.8 from rest; reference: RK4 at dt/16 of the finest step";
  BodyDesc desc;
  desc.name = "balloon";
  desc.mesh = makeIcosphere(1.0, 2);
  desc.strutPeriod = 0.4;
  desc.strutDecay = 1.0;
  desc.hingePeriod = 0.0;
  desc.volumePeriod = 0.2;
  c.model.gravity = {};
  addBody(c.model, desc);
  c.x0 = c.model.restPosition;
  for (Vec3& p : c.x0) p.y *= 0.8;
  // Two and a half breathing periods: backward Euler's damping of the mode, omega^2 dt t / 2,
  // is small at the finer steps, where its first order shows.
  c.endTime = 0.5;
  c.dts = ladder(0.005, 6);
  c.size = c.model.bodies[0].restSize;
  referenceByRk4(c, 16);
  return c;
}

// A showcase scene up to its first contact: colliders removed, end time just before the
// lowest vertex could reach the highest collider point (capped at 1 s).
AccuracyCase sceneAccuracy(const std::string& path) {
  const SceneDesc scene = loadScene(path);
  AccuracyCase c;
  c.name = fs::path(path).stem().string();
  Model model = buildModel(scene);
  const double g = length(model.gravity);
  const Vec3 up = g > 0 ? model.gravity / -g : Vec3{0, 1, 0};
  double top = -INFINITY;
  for (const PlaneCollider& p : model.colliders.planes) top = std::max(top, dot(p.point, up));
  for (const TriangleCollider& t : model.colliders.meshes) {
    for (const Vec3& p : t.mesh.positions) top = std::max(top, dot(p, up));
  }
  model.colliders = Colliders{};
  const double h = stepSize(scene);
  const double dt0 = 4 * h;
  // First contact: run the reference step until the lowest free vertex reaches `top`.
  double contact = 1.0;
  {
    World world(model, Integrator::RK4, h);
    while (world.time() < 1.0) {
      world.step();
      double lowest = INFINITY;
      for (std::size_t i = 0; i < world.positions().size(); ++i) {
        if (world.inverseMasses()[i] != 0.0) lowest = std::min(lowest, dot(world.positions()[i], up));
      }
      if (lowest <= top + 0.01 * model.bodies[0].restSize) {
        contact = world.time();
        break;
      }
    }
  }
  c.endTime = std::max(dt0, std::floor(0.95 * contact / dt0) * dt0);
  c.description = scene.name + " (" + std::to_string(model.vertexCount()) + " vertices), until " +
                  fmt("%.3g", c.endTime) + " s (first contact at " + fmt("%.3g", contact) +
                  " s); reference: RK4 at dt/8 of the finest step";
  c.model = model;
  c.x0 = model.restPosition;
  c.dts = ladder(dt0, 5);
  double size = 0;
  for (const BodyInfo& b : model.bodies) size = std::max(size, b.restSize);
  c.size = size;
  referenceByRk4(c, 8);
  return c;
}

double rmsError(const std::vector<Vec3>& x, const std::vector<Vec3>& ref, double size) {
  double sum = 0;
  for (std::size_t i = 0; i < x.size(); ++i) sum += lengthSquared(x[i] - ref[i]);
  return std::sqrt(sum / static_cast<double>(x.size())) / size;
}

// Least-squares slope of log error against log dt over the points in the asymptotic range:
// stable, error below 5 % of the size and above the round-off floor.
double measuredOrder(const std::vector<Point>& points, const std::string& name, Integrator integrator, int* used) {
  // The asymptotic range: the (up to) three finest qualifying steps.
  std::vector<const Point*> use;
  for (const Point& p : points) {
    if (p.caseName != name || p.integrator != integrator || !p.stable || !(p.error < 0.05) || !(p.error > 1e-11))
      continue;
    use.push_back(&p);
  }
  std::sort(use.begin(), use.end(), [](const Point* a, const Point* b) { return a->dt < b->dt; });
  if (use.size() > 3) use.resize(3);
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (const Point* p : use) {
    const double x = std::log(p->dt), y = std::log(p->error);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  if (used) *used = n;
  if (n < 2) return NAN;
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// The cases: a strut (closed form), a hinge, a gas balloon, then the showcase scenes up to their
// first contact (the scenes named, or seven of scenes/ unless --quick). A scene that cannot be
// studied is skipped, with a line in `skipped`.
std::vector<AccuracyCase> accuracyCases(const StudyOptions& o, std::string& skipped) {
  std::vector<AccuracyCase> cases;
  cases.push_back(strutAccuracy(0.5));
  cases.push_back(hingeAccuracy());
  cases.push_back(gasAccuracy());
  std::vector<std::string> scenes = o.scenes;
  if (scenes.empty() && !o.quick) {
    for (const char* s : {"single_sphere", "spheres", "fixed_single_sphere", "cube", "ramp", "bunny_light", "jelly"}) {
      const fs::path p = fs::path(SPRINGY_SCENES_DIR) / (std::string(s) + ".toml");
      if (fs::exists(p)) scenes.push_back(p.string());
    }
  }
  for (const std::string& s : scenes) {
    try {
      cases.push_back(sceneAccuracy(s));
    } catch (const Error& e) {
      std::fprintf(stderr, "springy study accuracy: skipping %s: %s\n", s.c_str(), e.what());
      skipped += "- skipped " + s + ": " + e.what() + "\n";
    }
  }
  return cases;
}

// Every point: each case's reference, then every integrator at every step of the case's ladder
// (`repeats` timed runs each, the median kept), all side by side on every core.
std::vector<Point> measurePoints(const std::vector<AccuracyCase>& cases, int repeats) {
  std::vector<std::vector<Vec3>> references(cases.size());
  std::vector<double> cost;
  for (const AccuracyCase& c : cases) cost.push_back(static_cast<double>(c.model.vertexCount()) * c.endTime / c.dts.back());
  runInParallel("springy study accuracy: references", cost, [&](std::size_t i) { references[i] = cases[i].reference(); });
  struct Job {
    std::size_t c;
    Integrator integrator;
    double dt;
  };
  std::vector<Job> jobs;
  cost.clear();
  for (std::size_t c = 0; c < cases.size(); ++c) {
    for (Integrator integrator : kAll) {
      for (double dt : cases[c].dts) {
        jobs.push_back({c, integrator, dt});
        cost.push_back(static_cast<double>(cases[c].model.vertexCount()) * cases[c].endTime / dt * stepCost(integrator));
      }
    }
  }
  std::vector<Point> points(jobs.size());
  runInParallel("springy study accuracy: runs", cost, [&](std::size_t j) {
    const AccuracyCase& c = cases[jobs[j].c];
    std::vector<double> times;
    std::vector<Vec3> x;
    for (int r = 0; r < repeats; ++r) {
      double seconds = 0;
      x = runTo(c.model, c.x0, jobs[j].integrator, jobs[j].dt, c.endTime, &seconds);
      times.push_back(seconds / c.endTime);
    }
    std::sort(times.begin(), times.end());
    const double err = rmsError(x, references[jobs[j].c], c.size);
    const bool stable = std::isfinite(err) && err < 1.0;
    points[j] = {c.name, jobs[j].integrator, jobs[j].dt, err, times[times.size() / 2], stable};
  });
  return points;
}

// Artificial damping: the undamped strut's energy lost per simulated second, per integrator and step.
struct Loss {
  Integrator integrator;
  double dt, lossPerSecond;
};
std::vector<Loss> artificialDamping(const AccuracyCase& undamped) {
  std::vector<Loss> losses;
  for (Integrator integrator : kAll) {
    for (double dt : undamped.dts) {
      World world(undamped.model, integrator, dt);
      world.setState(undamped.x0, world.velocities());
      const double e0 = measureBody(world, 0).total();
      const auto steps = static_cast<long>(std::llround(1.0 / dt));
      for (long s = 0; s < steps; ++s) world.step();
      losses.push_back({integrator, dt, 1.0 - measureBody(world, 0).total() / e0});
    }
  }
  return losses;
}

std::string pointsCsv(const std::vector<Point>& points) {
  std::ostringstream csv;
  csv << "case,integrator,dt,error,wall_per_sim_second,stable\n";
  for (const Point& p : points) {
    csv << p.caseName << "," << integratorName(p.integrator) << "," << fmt("%.9g", p.dt) << "," << fmt("%.9g", p.error)
        << "," << fmt("%.6g", p.wallPerSecond) << "," << (p.stable ? 1 : 0) << "\n";
  }
  return csv.str();
}

std::string accuracyIntroduction(const StudyOptions& o, int repeats, const std::string& skipped) {
  std::ostringstream md;
  md << "# Accuracy: error against run time\n\n"
     << "Generated by `" << (o.quick ? "springy study accuracy --quick -o " : "springy study accuracy -o ") << o.output
     << "` (scripts/study.sh regenerates docs/). Do not edit by hand.\n\n"
     << "- Machine: " << machine() << ".\n"
     << "- Error: RMS vertex position error at the end time relative to the body's size (bounding-box diagonal "
        "at rest), against the reference named per case. Showcase scenes run without colliders up to just "
        "before their first contact (contact limits every method to low order); whole runs through contact, with "
        "the adaptive steps: [accuracy-contact.md](accuracy-contact.md) (`springy study contact`).\n"
     << "- Run time: per simulated second, the CPU time of the thread that ran it (the runs go side by side on "
        "every core; a run's thread time is what it costs alone, which a run beside it does not inflate as it "
        "inflates wall time), median of "
     << repeats << " runs.\n"
     << "- Order: least-squares slope of log error against log dt over the three finest stable steps with "
        "error between 1e-11 and 5 % (the asymptotic range). Theory: explicit Euler 1, symplectic Euler 1, Verlet 2, "
        "leapfrog 2, RK4 4, backward "
        "Euler 1.\n"
     << "- Showcase scenes: a body released at rest falls rigidly until its first contact (uniform gravity deforms "
        "nothing), so Verlet, leapfrog and RK4 integrate it exactly (error below 1e-11: order n/a) and the first-order "
        "methods show order 1; the hanging sphere (fixed_single_sphere) deforms and shows every order.\n\n"
     << skipped << (skipped.empty() ? "" : "\n");
  return md.str();
}

// A case's section: its table (error / run time per point, measured order) and its plot; its
// measured orders are added to `orders` (accuracy-orders.csv).
std::string caseSection(const fs::path& out, const AccuracyCase& c, const std::vector<Point>& points,
                        std::ostringstream& orders) {
  std::ostringstream md;
  md << "## " << c.name << "\n\n" << c.description << ", end time " << fmt("%.4g", c.endTime) << " s.\n\n";
  md << "| integrator | order (theory) |";
  for (double dt : c.dts) md << " dt " << fmt("%.4g", dt) << " |";
  md << "\n|---|---|";
  for (std::size_t i = 0; i < c.dts.size(); ++i) md << "---|";
  md << "\n";
  for (Integrator integrator : kAll) {
    int used = 0;
    const double order = measuredOrder(points, c.name, integrator, &used);
    orders << c.name << "," << integratorName(integrator) << "," << fmt("%.4f", order) << ","
           << integratorTraits(integrator).order << "," << used << "\n";
    md << "| " << integratorName(integrator) << " | " << (std::isnan(order) ? std::string("n/a") : fmt("%.2f", order))
       << " (" << integratorTraits(integrator).order << ") |";
    for (const Point& p : points) {
      if (p.caseName != c.name || p.integrator != integrator) continue;
      md << " " << (p.stable ? fmt("%.2e", p.error) : std::string("unstable")) << " / "
         << fmt("%.3g", p.wallPerSecond * 1e3) << " ms |";
    }
    md << "\n";
  }
  md << "\nEach cell: error / run time per simulated second.\n\n";
  std::string file = "accuracy-" + c.name;
  std::replace(file.begin(), file.end(), ' ', '_');
  std::vector<PlotSeries> series;
  for (Integrator integrator : kAll) {
    PlotSeries line{std::string(integratorName(integrator)), {}};
    for (const Point& p : points) {
      if (p.caseName == c.name && p.integrator == integrator && p.stable && p.error > 0) {
        line.points.push_back({fmt("%g", p.dt), p.wallPerSecond, p.error});
      }
    }
    series.push_back(line);
  }
  md << errorPlot(out, file, c.name + ": error against run time (labels: dt)", "RMS position error / body size", series);
  return md.str();
}

std::string dampingSection(const AccuracyCase& undamped, const std::vector<Loss>& losses) {
  std::ostringstream md;
  md << "## Artificial damping\n\nThe price of stability: energy lost per simulated second by each integrator on the "
        "undamped strut (k = 30 N/m, the same masses; ideal 0; negative = energy gained).\n\n| integrator |";
  for (double dt : undamped.dts) md << " dt " << fmt("%.4g", dt) << " |";
  md << "\n|---|";
  for (std::size_t i = 0; i < undamped.dts.size(); ++i) md << "---|";
  md << "\n";
  for (Integrator integrator : kAll) {
    md << "| " << integratorName(integrator) << " |";
    for (const Loss& l : losses) {
      if (l.integrator == integrator) md << " " << fmt("%.3g", 100.0 * l.lossPerSecond) << " % |";
    }
    md << "\n";
  }
  return md.str();
}

}  // namespace

int runAccuracy(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out, "accuracy");
  std::string skipped;
  const std::vector<AccuracyCase> cases = accuracyCases(o, skipped);
  const int repeats = std::max(1, o.quick ? 1 : o.repeats);
  const std::vector<Point> points = measurePoints(cases, repeats);
  const AccuracyCase undamped = strutAccuracy(0.0);
  const std::vector<Loss> losses = artificialDamping(undamped);
  writeFile(out / "accuracy.csv", pointsCsv(points));
  std::ostringstream orders;
  orders << "case,integrator,order,theory,points\n";
  std::string md = accuracyIntroduction(o, repeats, skipped);
  for (const AccuracyCase& c : cases) md += caseSection(out, c, points, orders);
  md += dampingSection(undamped, losses);
  md += "\nMeasured orders are also in `accuracy-orders.csv`; every point in `accuracy.csv`.\n";
  writeFile(out / "accuracy-orders.csv", orders.str());
  writeFile(out / "accuracy.md", md);
  std::printf("%s", orders.str().c_str());
  std::printf("wrote %s\n", (out / "accuracy.md").string().c_str());
  return 0;
}

}  // namespace springy::study
