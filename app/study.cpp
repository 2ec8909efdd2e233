// `springy study accuracy|stability`: the work-precision study of every integrator (error at a
// fixed end time against a reference, wall time per simulated second, measured convergence
// order, log-log plot of error against wall time drawn by gnuplot) and the stability study
// (largest stable dt of every integrator on the stiff and extreme cases against the bound).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "sim/cases.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/harness.h"
#include "sim/hinge.h"
#include "sim/limits.h"
#include "sim/shapes.h"
#include "sim/stability.h"
#include "sim/trajectory.h"

namespace springy {
namespace {

namespace fs = std::filesystem;

constexpr Integrator kAll[] = {
    Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog,
    Integrator::RK4,           Integrator::BackwardEuler};
// The stability study's: with vertex block descent (its default sweeps), whose stability is not
// unconditional unless it converges.
constexpr Integrator kStabilityStudied[] = {
    Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog,
    Integrator::RK4,           Integrator::BackwardEuler,   Integrator::Vbd};

double theoreticalOrder(Integrator i) {
  switch (i) {
    case Integrator::VelocityVerlet:
    case Integrator::Leapfrog: return 2;
    case Integrator::RK4: return 4;
    default: return 1;
  }
}

std::string cpuModel() {
  std::ifstream in("/proc/cpuinfo");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("model name", 0) == 0) {
      const auto colon = line.find(':');
      return colon == std::string::npos ? line : line.substr(colon + 2);
    }
  }
  return "unknown";
}

std::string machine() {
  std::ostringstream s;
  s << std::thread::hardware_concurrency() << " cores (`nproc`), " << cpuModel()
    << "; Release build, single-threaded simulation";
  return s.str();
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

// Writes text to path atomically.
void writeFile(const fs::path& path, const std::string& text) { writeFileAtomically(path.string(), text); }

// ---------------------------------------------------------------------------------------------
// Accuracy.

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
  double wallPerSecond;  // wall time per simulated second [s], median
  bool stable;
};

std::vector<Vec3> runTo(const Model& model, const std::vector<Vec3>& x0, Integrator integrator, double dt, double end,
                        double* wall = nullptr) {
  const auto start = std::chrono::steady_clock::now();
  World world(model, integrator, dt);
  world.setState(x0, world.velocities());
  const auto steps = static_cast<long>(std::llround(end / dt));
  for (long s = 0; s < steps; ++s) world.step();
  if (wall) *wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
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
        if (world.model().invMass[i] != 0.0) lowest = std::min(lowest, dot(world.positions()[i], up));
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

// One line of an error-against-run-time plot: its points (label, wall time per simulated second,
// error).
struct PlotPoint {
  std::string label;
  double wall, error;
};
struct PlotSeries {
  std::string name;
  std::vector<PlotPoint> points;
};

// Writes FILE.dat and FILE.gp in `out` (log-log error against wall time, a line per series, each
// point labelled) and, with gnuplot, FILE.png; returns the Markdown that shows it.
std::string errorPlot(const fs::path& out, const std::string& file, const std::string& title, const std::string& ylabel,
                      const std::vector<PlotSeries>& series, bool haveGnuplot) {
  std::ostringstream dat, gp;
  for (const PlotSeries& line : series) {
    dat << "# " << line.name << "\n";
    for (const PlotPoint& p : line.points)
      dat << p.label << " " << fmt("%.6g", p.wall) << " " << fmt("%.6g", p.error) << "\n";
    dat << "\n\n";
  }
  writeFile(out / (file + ".dat"), dat.str());
  gp << "set terminal pngcairo size 960,640 font 'DejaVu Sans,10'\n"
     << "set output '" << (out / (file + ".png")).string() << "'\n"
     << "set logscale xy\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
     << "set xlabel 'wall time per simulated second [s]'\nset ylabel '" << ylabel << "'\n"
     << "set title '" << title << "' noenhanced\nset key outside right\nset grid\n"
     << "plot ";
  static const char* kColors[] = {"#d62728", "#ff7f0e", "#2ca02c", "#17becf", "#1f77b4", "#9467bd", "#000000"};
  for (std::size_t idx = 0; idx < series.size(); ++idx) {
    const std::string data = "'" + (out / (file + ".dat")).string() + "' index " + std::to_string(idx);
    const std::string color = kColors[idx % 7];
    gp << (idx ? ", \\\n     " : "") << data << " using 2:3 with linespoints lw 2 pt 7 lc rgb '" << color << "' title '"
       << series[idx].name << "' noenhanced, \\\n     " << data
       << " using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '" << color << "' notitle";
  }
  gp << "\n";
  writeFile(out / (file + ".gp"), gp.str());
  if (!haveGnuplot) return "(gnuplot not found: plot skipped; install gnuplot-nox)\n\n";
  const std::string cmd = "gnuplot '" + (out / (file + ".gp")).string() + "'";
  if (std::system(cmd.c_str()) != 0) throw Error("gnuplot failed on " + (out / (file + ".gp")).string());
  return "![" + title + "](" + file + ".png)\n\n";
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

// The study's output directory, created when missing; an existing file of that name, or no
// permission, is a springy::Error naming it (std::filesystem's exception went uncaught).
void makeOutputDirectory(const fs::path& out) { makeDirectories(out.string(), "-o"); }

int runAccuracy(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out);
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
  std::string skipped;
  for (const std::string& s : scenes) {
    try {
      cases.push_back(sceneAccuracy(s));
    } catch (const Error& e) {
      std::fprintf(stderr, "springy study accuracy: skipping %s: %s\n", s.c_str(), e.what());
      skipped += "- skipped " + s + ": " + e.what() + "\n";
    }
  }
  const int repeats = std::max(1, o.quick ? 1 : o.repeats);

  std::vector<Point> points;
  for (const AccuracyCase& c : cases) {
    std::fprintf(stderr, "springy study accuracy: %s: reference...\n", c.name.c_str());
    const std::vector<Vec3> ref = c.reference();
    for (Integrator integrator : kAll) {
      for (double dt : c.dts) {
        std::vector<double> walls;
        std::vector<Vec3> x;
        for (int r = 0; r < repeats; ++r) {
          double wall = 0;
          x = runTo(c.model, c.x0, integrator, dt, c.endTime, &wall);
          walls.push_back(wall / c.endTime);
        }
        std::sort(walls.begin(), walls.end());
        const double err = rmsError(x, ref, c.size);
        const bool stable = std::isfinite(err) && err < 1.0;
        points.push_back({c.name, integrator, dt, err, walls[walls.size() / 2], stable});
      }
    }
  }

  // Artificial damping: the undamped strut, energy lost per simulated second.
  const AccuracyCase undamped = strutAccuracy(0.0);
  struct Loss {
    Integrator integrator;
    double dt, lossPerSecond;
  };
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

  // CSV.
  std::ostringstream csv;
  csv << "case,integrator,dt,error,wall_per_sim_second,stable\n";
  for (const Point& p : points) {
    csv << p.caseName << "," << integratorName(p.integrator) << "," << fmt("%.9g", p.dt) << "," << fmt("%.9g", p.error)
        << "," << fmt("%.6g", p.wallPerSecond) << "," << (p.stable ? 1 : 0) << "\n";
  }
  writeFile(out / "accuracy.csv", csv.str());
  std::ostringstream orders;
  orders << "case,integrator,order,theory,points\n";

  // Plots: one per case, error against wall time, one line per integrator, labelled by dt.
  const bool haveGnuplot = std::system("command -v gnuplot > /dev/null 2>&1") == 0;
  std::ostringstream md;
  md << "# Accuracy: error against run time\n\n"
     << "Generated by `" << (o.quick ? "springy study accuracy --quick -o " : "springy study accuracy -o ") << o.output
     << "` (scripts/study.sh regenerates docs/). Do not edit by hand.\n\n"
     << "- Machine: " << machine() << ".\n"
     << "- Error: RMS vertex position error at the end time relative to the body's size (bounding-box diagonal "
        "at rest), against the reference named per case. Showcase scenes run without colliders up to just "
        "before their first contact (contact limits every method to low order); whole runs through contact, with "
        "the adaptive steps: [accuracy-contact.md](accuracy-contact.md) (`springy study contact`).\n"
     << "- Wall time: per simulated second, median of " << repeats << " runs.\n"
     << "- Order: least-squares slope of log error against log dt over the three finest stable steps with "
        "error between 1e-11 and 5 % (the asymptotic range). Theory: explicit Euler 1, symplectic Euler 1, Verlet 2, "
        "leapfrog 2, RK4 4, backward "
        "Euler 1.\n"
     << "- Showcase scenes: a body released at rest falls rigidly until its first contact (uniform gravity deforms "
        "nothing), so Verlet, leapfrog and RK4 integrate it exactly (error below 1e-11: order n/a) and the first-order "
        "methods show order 1; the hanging sphere (fixed_single_sphere) deforms and shows every order.\n\n"
     << skipped << (skipped.empty() ? "" : "\n");
  for (const AccuracyCase& c : cases) {
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
             << theoreticalOrder(integrator) << "," << used << "\n";
      md << "| " << integratorName(integrator) << " | " << (std::isnan(order) ? std::string("n/a") : fmt("%.2f", order))
         << " (" << theoreticalOrder(integrator) << ") |";
      for (const Point& p : points) {
        if (p.caseName != c.name || p.integrator != integrator) continue;
        md << " " << (p.stable ? fmt("%.2e", p.error) : std::string("unstable")) << " / "
           << fmt("%.3g", p.wallPerSecond * 1e3) << " ms |";
      }
      md << "\n";
    }
    md << "\nEach cell: error / wall time per simulated second.\n\n";
    const std::string stem = "accuracy-" + std::string(c.name == "strut" ? "strut" : c.name);
    std::string file = stem;
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
    md << errorPlot(out, file, c.name + ": error against run time (labels: dt)", "RMS position error / body size",
                    series, haveGnuplot);
  }
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
  md << "\nMeasured orders are also in `accuracy-orders.csv`; every point in `accuracy.csv`.\n";
  writeFile(out / "accuracy-orders.csv", orders.str());
  writeFile(out / "accuracy.md", md.str());
  std::printf("%s", orders.str().c_str());
  std::printf("wrote %s\n", (out / "accuracy.md").string().c_str());
  return 0;
}

// ---------------------------------------------------------------------------------------------
// The scenes a study names, or else the eight showcase scenes.
std::string bundledScene(const char* name) {
  return (fs::path(SPRINGY_SCENES_DIR) / (std::string(name) + ".toml")).string();
}

std::vector<std::string> scenesOrShowcase(const StudyOptions& o) {
  if (!o.scenes.empty()) return o.scenes;
  std::vector<std::string> scenes;
  for (const char* s :
       {"single_sphere", "spheres", "fixed_single_sphere", "cube", "ramp", "jelly", "bunny", "bunny_light"}) {
    scenes.push_back(bundledScene(s));
  }
  return scenes;
}

// ---------------------------------------------------------------------------------------------
// Through contact: whole runs of scenes, error against a fine reference (sim/trajectory.h).

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

int runContact(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out);
  const std::vector<std::string> scenes = scenesOrShowcase(o);
  // Fixed steps divide the frame (every run samples the same instants): the frame over n0 x 2^k
  // with n0 from the original's 2 ms step; the references 4 and 8 times finer than the finest.
  const int rungs = o.quick ? 3 : 5;
  const std::vector<double> tolerances =
      o.quick ? std::vector<double>{1e-3, 1e-4} : std::vector<double>{1e-3, 1e-4, 1e-5, 1e-6, 1e-7};
  constexpr Integrator kFixed[] = {Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog,
                                   Integrator::RK4};
  constexpr Integrator kAdaptive[] = {Integrator::BogackiShampine, Integrator::AdaptiveVerlet};
  const bool haveGnuplot = std::system("command -v gnuplot > /dev/null 2>&1") == 0;
  std::ostringstream md, csv, body;
  csv << "scene,method,dt,tolerance,complete,centroid_rms,end_position,lowest_volume,wall_per_sim_second,evaluations,"
         "steps,rejected,energy_lost\n";
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
        "the step), and its wall time over the adaptive run's (above 1: the adaptive step is cheaper for that "
        "accuracy).\n\n";
  // Written again after every scene: a long study shows what it has so far.
  const auto writeAll = [&] {
    writeFile(out / "accuracy-contact.csv", csv.str());
    writeFile(out / "accuracy-contact.md", md.str() + body.str());
  };
  for (const std::string& path : scenes) {
    const SceneDesc scene = loadScene(path);
    const Model model = buildModel(scene);
    const std::string name = fs::path(path).stem().string();
    PathSettings base;
    base.frame = 1.0 / scene.view.render.fps;
    const double full = o.maxDuration > 0 ? std::min(scene.duration, o.maxDuration) : scene.duration;
    base.duration = base.frame * std::max(1.0, std::floor(full / base.frame + 1e-9));
    const double n0 = std::ceil(base.frame / 0.002 - 1e-9);
    const double finest = base.frame / (n0 * std::pow(2.0, rungs - 1));
    const auto run = [&](Integrator integrator, double dt, double tolerance) {
      PathSettings s = base;
      s.integrator = integrator;
      s.dt = dt;
      s.tolerance = tolerance;
      std::fprintf(stderr, "springy study contact: %s: %s %s %.4g...\n", name.c_str(),
                   std::string(integratorName(integrator)).c_str(), tolerance > 0 ? "tolerance" : "dt",
                   tolerance > 0 ? tolerance : dt);
      return tracePath(model, s);
    };
    const RunPath reference = run(Integrator::RK4, finest / 8, 0);
    const RunPath check = run(Integrator::RK4, finest / 4, 0);
    body << "## " << name << "\n\n";
    if (!reference.complete || !check.complete) {
      body << "No reference: RK4 at dt " << fmt("%.3g", finest / 8)
           << " s failed: " << (reference.complete ? check.failure : reference.failure) << "\n\n";
      continue;
    }
    const PathError agreement = pathError(model, reference, check);
    std::vector<ContactPoint> points;
    for (Integrator integrator : kFixed) {
      for (int k = 0; k < rungs; ++k) {
        const double dt = base.frame / (n0 * std::pow(2.0, k));
        ContactPoint p{std::string(integratorName(integrator)), dt, 0, run(integrator, dt, 0), {}};
        if (p.path.complete) p.error = pathError(model, reference, p.path);
        points.push_back(std::move(p));
      }
    }
    for (Integrator adaptive : kAdaptive) {
      for (double tolerance : tolerances) {
        ContactPoint p{std::string(integratorName(adaptive)),
                       base.frame / n0,
                       tolerance,
                       run(adaptive, base.frame / n0, tolerance),
                       {}};
        if (p.path.complete) p.error = pathError(model, reference, p.path);
        points.push_back(std::move(p));
      }
    }
    // Vertex block descent (implicit, its default sweeps): from a frame down to the ladder's coarsest step.
    for (double m = 1; m <= n0; m *= 2) {
      ContactPoint p{std::string(integratorName(Integrator::Vbd)), base.frame / m, 0, run(Integrator::Vbd, base.frame / m, 0), {}};
      if (p.path.complete) p.error = pathError(model, reference, p.path);
      points.push_back(std::move(p));
    }
    const auto perSecond = [&](const ContactPoint& p) { return p.path.wallSeconds / base.duration; };
    for (const ContactPoint& p : points) {
      csv << name << "," << p.method << "," << fmt("%.6g", p.dt) << "," << fmt("%.3g", p.tolerance) << ","
          << (p.path.complete ? 1 : 0) << "," << fmt("%.6g", p.error.centroidRms) << ","
          << fmt("%.6g", p.error.endPosition) << "," << fmt("%.6g", p.error.lowestVolume) << ","
          << fmt("%.6g", perSecond(p)) << "," << p.path.evaluations << "," << p.path.steps << ","
          << p.path.stepStats.rejected << "," << fmt("%.6g", p.error.energyLost) << "\n";
    }
    body << scene.name << ": " << model.vertexCount() << " vertices in " << model.bodies.size() << " "
         << (model.bodies.size() == 1 ? "body" : "bodies") << ", " << fmt("%.4g", base.duration) << " s"
         << (base.duration < scene.duration - 1e-9 ? " of " + fmt("%.4g", scene.duration) + " s"
                                                   : std::string(" (all of it)"))
         << ". Reference: RK4 at dt " << fmt("%.3g", finest / 8) << " s; RK4 at twice that step differs from it by "
         << fmt("%.2e", agreement.centroidRms) << " (centroid RMS), " << fmt("%.2e", agreement.endPosition)
         << " (end position), " << fmt("%.2e", agreement.lowestVolume) << " (lowest volume).\n\n";
    body << "| integrator | order through contact |";
    for (int k = 0; k < rungs; ++k) body << " dt " << fmt("%.3g", base.frame / (n0 * std::pow(2.0, k))) << " |";
    body << "\n|---|---|";
    for (int k = 0; k < rungs; ++k) body << "---|";
    body << "\n";
    for (Integrator integrator : kFixed) {
      const std::string method(integratorName(integrator));
      const double order = contactOrder(points, method);
      body << "| " << method << " | " << (std::isnan(order) ? std::string("n/a") : fmt("%.2f", order)) << " |";
      for (const ContactPoint& p : points) {
        if (p.method != method) continue;
        body << " " << (p.path.complete ? fmt("%.2e", p.error.centroidRms) : describeFailure(p.path)) << " / "
             << fmt("%.3g", perSecond(p) * 1e3) << " ms |";
      }
      body << "\n";
    }
    body << "\nEach cell: centroid RMS error / wall time per simulated second (a failed run: what stopped it, and its "
            "time until then).\n\n"
         << "| implicit, or the coarsest explicit | dt | centroid RMS | end position | lowest volume | energy lost beyond "
            "the reference | wall per sim. s |\n|---|---|---|---|---|---|---|\n";
    for (const ContactPoint& p : points) {
      const bool implicit = p.method == integratorName(Integrator::Vbd);
      const bool coarsest = p.tolerance == 0.0 && !implicit && std::fabs(p.dt - base.frame / n0) < 1e-12 &&
                            (p.method == integratorName(Integrator::SymplecticEuler) ||
                             p.method == integratorName(Integrator::RK4));
      if (!implicit && !coarsest) continue;
      body << "| " << p.method << (implicit ? " (" + std::to_string(SimulationDesc{}.iterations) + " sweeps)" : "")
           << " | " << fmt("%.3g", p.dt) << " | ";
      if (!p.path.complete) {
        body << describeFailure(p.path) << " at t = " << fmt("%.3g", p.path.times.back()) << " s | | | | "
             << fmt("%.3g", perSecond(p) * 1e3) << " ms |\n";
        continue;
      }
      body << fmt("%.2e", p.error.centroidRms) << " | " << fmt("%.2e", p.error.endPosition) << " | "
           << fmt("%.2e", p.error.lowestVolume) << " | " << fmt("%.3g", p.error.energyLost) << " J ("
           << fmt("%.1f", 100.0 * p.error.energyLostShare) << "%) | " << fmt("%.3g", perSecond(p) * 1e3) << " ms |\n";
    }
    body << "\nEnergy lost beyond the reference: the run's total energy at the last frame below the reference's, and "
            "that as a share of the reference's largest kinetic energy (the motion's energy): the numerical damping.\n\n"
         << "| adaptive | tolerance | centroid RMS | end position | lowest volume | wall per sim. s | steps (rejected) "
            "| "
            "step from-to [s] | fixed step for the same error costs |\n|---|---|---|---|---|---|---|---|---|\n";
    const auto isFixed = [](const ContactPoint& p) { return p.tolerance == 0.0; };
    for (const ContactPoint& p : points) {
      if (isFixed(p)) continue;
      body << "| " << p.method << " | " << fmt("%.0e", p.tolerance) << " | ";
      if (!p.path.complete) {
        body << describeFailure(p.path) << " | | | " << fmt("%.3g", perSecond(p) * 1e3) << " ms | | | |\n";
        continue;
      }
      // The cheapest fixed-step run at least as accurate, whose accuracy holds under refinement:
      // how much longer it takes.
      const auto holds = [&](const ContactPoint& q) {
        return std::none_of(points.begin(), points.end(), [&](const ContactPoint& finer) {
          return finer.method == q.method && isFixed(finer) && finer.dt < q.dt && finer.path.complete &&
                 finer.error.centroidRms > q.error.centroidRms;
        });
      };
      const ContactPoint* rival = nullptr;
      for (const ContactPoint& q : points) {
        if (!isFixed(q) || !q.path.complete || q.error.centroidRms > p.error.centroidRms || !holds(q)) continue;
        if (!rival || perSecond(q) < perSecond(*rival)) rival = &q;
      }
      const StepStats& st = p.path.stepStats;
      body << fmt("%.2e", p.error.centroidRms) << " | " << fmt("%.2e", p.error.endPosition) << " | "
           << fmt("%.2e", p.error.lowestVolume) << " | " << fmt("%.3g", perSecond(p) * 1e3) << " ms | " << st.accepted
           << " (" << st.rejected << ") | " << fmt("%.2g", st.smallest) << "-" << fmt("%.2g", st.largest) << " | "
           << (rival ? fmt("%.2f", perSecond(*rival) / perSecond(p)) + "x (" + rival->method + ", dt " +
                           fmt("%.3g", rival->dt) + ")"
                     : std::string("none of the ladder is as accurate"))
           << " |\n";
    }
    body << "\n";
    std::vector<PlotSeries> series;
    for (Integrator integrator : kFixed) series.push_back({std::string(integratorName(integrator)), {}});
    for (Integrator integrator : kAdaptive) series.push_back({std::string(integratorName(integrator)), {}});
    series.push_back({std::string(integratorName(Integrator::Vbd)), {}});
    for (const ContactPoint& p : points) {
      if (!p.path.complete || !(p.error.centroidRms > 0)) continue;
      for (PlotSeries& line : series) {
        if (line.name != p.method) continue;
        line.points.push_back(
            {isFixed(p) ? fmt("%.3g", p.dt) : fmt("%.0e", p.tolerance), perSecond(p), p.error.centroidRms});
      }
    }
    body << errorPlot(out, "accuracy-contact-" + name, name + " through contact (labels: dt; adaptive: tolerance)",
                      "centroid RMS error / body size", series, haveGnuplot);
    writeAll();
  }
  writeAll();
  std::printf("wrote %s\n", (out / "accuracy-contact.md").string().c_str());
  return 0;
}

// ---------------------------------------------------------------------------------------------
// Stability.

// The showcase scenes (or the scenes named) over their full duration with their own integrator:
// the largest fixed step that passes the whole run under `springy check`'s monitor (bracketed by
// factors of 2 from the survey's proposal, then bisected in log step), against the advisor's
// proposals from its estimate at rest and from the survey of the whole run (`--substeps auto`,
// sim/stability.h).
constexpr double kSafetyFraction = 0.9;  // the advisor's (app/suggest.cpp)

// The survey's tightest mode: which, its rate and the mesh vertex with its largest share.
std::string modeWhere(const Model& model, const StabilitySurvey& survey) {
  const bool damping = survey.limit == ModeEstimator::Limit::Damping;
  return (damping ? "damping " + fmt("%.3g", survey.rate) + " 1/s" : "omega " + fmt("%.3g", survey.rate) + " rad/s") +
         " at vertex " + std::to_string(model.bodies[survey.body].meshVertex(survey.vertex));
}

std::string wholeRuns(const StudyOptions& o, std::ostringstream& csv) {
  const int halvings = o.quick ? 3 : 5;
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
        "run fails (app/suggest.cpp tryTheSubsteps, sim/harness.h searchCount); here counts of steps per frame, "
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
        "runs (wall) |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  csv << "scene,integrator,largest_stable_step,capped,rest_step,survey_step,survey_substeps,survey_time,tried_step,"
         "tried_per_frame,runs,wall_seconds\n";
  // The showcase scenes with their own integrator; then, unless scenes are named, two scenes of
  // bodies that meet under backward Euler, whose step the contact between bodies limits
  // (sim/stability.h contactLimitedIntegrator).
  std::vector<std::pair<std::string, std::optional<Integrator>>> runsOf;
  for (const std::string& path : scenesOrShowcase(o)) runsOf.emplace_back(path, std::nullopt);
  if (o.scenes.empty()) {
    for (const char* s : {"column", "head_on"}) runsOf.emplace_back(bundledScene(s), Integrator::BackwardEuler);
  }
  for (const auto& [path, integrator] : runsOf) {
    SceneDesc scene = loadScene(path);
    if (integrator) scene.integrator = *integrator;
    const Model model = buildModel(scene);
    const std::string name = fs::path(path).stem().string();
    const auto start = std::chrono::steady_clock::now();
    std::fprintf(stderr, "springy study stability: %s: survey...\n", name.c_str());
    const StabilityReport rest = estimateStability(model, model.restPosition, scene.integrator, scene.duration);
    const StabilitySurvey survey =
        surveyStability(model, scene.integrator, scene.duration, 1.0 / scene.view.render.fps, scene.dt,
                        SimulationDesc{}.tolerance);
    const double frame = 1.0 / scene.view.render.fps;
    const double restStep = kSafetyFraction * rest.dtMax, surveyStep = kSafetyFraction * survey.dtMax;
    int runs = 0;
    // The first passing run says which bodies come to rest (sim/trajectory.h bodyNoLongerAtRest).
    std::vector<bool> restsAtReference;
    const auto passes = [&](double h) {
      PathSettings s;
      s.integrator = scene.integrator;
      s.dt = h;
      s.frame = frame;
      s.duration = scene.duration;
      std::fprintf(stderr, "springy study stability: %s: step %.4g s...\n", name.c_str(), h);
      ++runs;
      const RunPath run = tracePath(model, s);
      if (!run.complete) return false;
      const int moving = bodyNoLongerAtRest(restsAtReference, run);
      if (moving >= 0) {
        std::fprintf(stderr, "springy study stability: %s: step %.4g s: body '%s' does not come to rest\n",
                     name.c_str(), h, model.bodies[moving].name.c_str());
      }
      return moving < 0;
    };
    // `--substeps auto` with dt one frame: the survey's count of steps per frame, tried as
    // app/suggest.cpp tries it (sim/harness.h searchCount); its passing count and the failing
    // count next to it bracket the largest stable step.
    const CountSearch tries = searchCount(safeSubsteps(frame, survey.dtMax, kSafetyFraction), kMaxSubsteps, 5, true,
                                          [&](int n) { return passes(frame / n) ? std::string() : "fails"; });
    const double tried = tries.count > 0 ? frame / tries.count : 0.0;
    double lo = tried, hi = frame;
    bool capped = tries.count == 1;
    for (const CountTry& t : tries.tries) {
      if (!t.failure.empty() && frame / t.count > lo) hi = std::min(hi, frame / t.count);
    }
    if (!capped && lo > 0.0) {
      for (int i = 0; i < halvings; ++i) {
        const double mid = std::sqrt(lo * hi);
        (passes(mid) ? lo : hi) = mid;
      }
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const int substeps = safeSubsteps(scene.dt, survey.dtMax, kSafetyFraction);
    csv << name << "," << integratorName(scene.integrator) << "," << fmt("%.4g", lo) << "," << (capped ? 1 : 0) << ","
        << fmt("%.4g", restStep) << "," << fmt("%.4g", surveyStep) << "," << substeps << "," << survey.time << ","
        << fmt("%.4g", tried) << "," << tries.count << "," << runs << "," << fmt("%.1f", wall) << "\n";
    const auto ratio = [&](double h) { return capped ? "<= " + fmt("%.2f", h / lo) : fmt("%.2f", h / lo); };
    md << "| " << name << " | " << integratorName(scene.integrator) << " | " << (capped ? ">= " : "") << fmt("%.3g", lo)
       << " s | " << fmt("%.3g", restStep) << " s | " << ratio(restStep) << " | " << fmt("%.3g", surveyStep) << " s ("
       << substeps << ") | " << ratio(surveyStep) << " | "
       << (tries.count > 0 ? fmt("%.3g", tried) + " s (" + std::to_string(tries.count) + ") | " + ratio(tried)
                           : std::string("every count tried failed | -"))
       << " | "
       << (survey.failure.empty() ? "t = " + fmt("%.3g", survey.time) + " s, " + model.bodies[survey.body].name +
                                        (survey.landing ? " (landing)" : ", " + modeWhere(model, survey))
                                  : "survey failed: " + survey.failure)
       << " | " << runs << " (" << fmt("%.0f", wall) << " s) |\n";
  }
  return md.str();
}

int runStability(const StudyOptions& o) {
  const fs::path out = o.output;
  makeOutputDirectory(out);
  const double horizon = o.quick ? 0.05 : 0.2;
  const int iterations = o.quick ? 4 : 8;
  std::ostringstream csv, md;
  csv << "case,integrator,measured_dt,capped,predicted_dt,two_over_omega,omega_max,gamma_max,mode_found_dt,"
         "survey_proposed_dt,survey_failure,tried_dt,tried_runs,failed_first\n";
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
  std::ostringstream refused, descriptions, csvRuns;
  for (const CaseFactory& factory : stabilityCases()) {
    StabilityCase c;
    try {
      c = factory.make();
    } catch (const Error& e) {
      refused << "- **" << factory.name << "**: refused at load: " << e.what() << "\n";
      continue;
    }
    descriptions << "- **" << c.name << "**: " << c.description << "\n";
    std::fprintf(stderr, "springy study stability: %s\n", c.name.c_str());
    for (Integrator integrator : kStabilityStudied) {
      const StabilityReport pred = estimateStability(c.model, c.positions, integrator, horizon);
      const BodyStability& b = pred.bodies[0];
      const double bound = 2.0 / b.omegaMax;
      const double guess = std::isfinite(pred.dtMax) ? pred.dtMax : 0.01;
      const World world(c.model, integrator, guess);
      ModeEstimator modes(world);
      const double found = ModeEstimator::step(integrator, modes.estimate(c.positions, 60), horizon);
      // The whole run as `--substeps auto` sees it: frames of a 50th of the horizon.
      const StabilitySurvey survey = surveyStability(c.model, integrator, horizon, horizon / 50, 0.0,
                                                     SimulationDesc{}.tolerance, 1, &c.positions,
                                                     kCaseEnergyTolerance);
      const double proposed = kSafetyFraction * survey.dtMax;
      std::string surveyFailure = survey.failure.empty() ? "" : failureKind(survey.failure);
      // Then tried as `--substeps auto` tries its count (sim/harness.h searchCount); the largest
      // stable step is bisected in the bracket the tries leave (a step they saw fail bounds it).
      const TriedStep tried = std::isfinite(proposed)
                                  ? triedStep(c.model, integrator, horizon, proposed, 0.1, &c.positions, iterations)
                                  : TriedStep{};
      const MeasuredStep m =
          tried.runs > 0 ? tried.largest
                         : largestStableStep(c.model, integrator, horizon, guess, 0.1, &c.positions, iterations);
      std::string failed = m.capped ? "none up to 0.1 s" : m.above.kind;
      csv << c.name << "," << integratorName(integrator) << "," << fmt("%.4g", m.dt) << "," << (m.capped ? 1 : 0) << ","
          << fmt("%.4g", pred.dtMax) << "," << fmt("%.4g", bound) << "," << fmt("%.4g", b.omegaMax) << ","
          << fmt("%.4g", b.gammaMax) << "," << fmt("%.4g", found) << "," << fmt("%.4g", proposed) << ","
          << surveyFailure << "," << fmt("%.4g", tried.dt) << "," << tried.runs << "," << failed << "\n";
      md << "| " << c.name << " | " << integratorName(integrator) << " | " << (m.capped ? ">= " : "")
         << fmt("%.3g", m.dt) << " s | "
         << (std::isfinite(pred.dtMax) ? fmt("%.3g", pred.dtMax) + " s" : std::string("unconditional")) << " | "
         << fmt("%.3g", bound) << " s | "
         << (std::isfinite(pred.dtMax) && !m.capped ? fmt("%.2f", m.dt / pred.dtMax) : std::string("-")) << " | "
         << (std::isfinite(found) ? fmt("%.3g", found) + " s" : std::string("unconditional")) << " | "
         << (std::isfinite(found) && !m.capped ? fmt("%.2f", m.dt / found) : std::string("-")) << " | "
         << (std::isfinite(proposed) ? fmt("%.3g", proposed) + " s" : std::string("unconditional"))
         << (surveyFailure.empty() ? "" : " (survey stopped: " + surveyFailure + ")") << " | "
         << (std::isfinite(proposed) && !m.capped ? fmt("%.2f", proposed / m.dt) : std::string("-")) << " | "
         << (tried.runs > 0 && !m.capped ? fmt("%.3g", tried.dt) + " s (" + std::to_string(tried.runs) + ")"
                                         : std::string("-"))
         << " | " << (tried.runs > 0 && !m.capped ? fmt("%.2f", tried.dt / m.dt) : std::string("-")) << " | " << failed
         << " |\n";
    }
  }
  if (!o.quick || !o.scenes.empty()) {  // --quick without --scenes leaves out the showcase scenes' whole runs
    md << "\n## Whole runs: the advisor through impacts\n\n" << wholeRuns(o, csvRuns);
  }
  md << "\n## Cases\n\n"
     << descriptions.str() << refused.str()
     << "\n## The guarantee\n\nNo case produces a NaN silently: each either runs, or stops with the monitor's "
        "report naming the body, the step and what diverged, or is refused at load because its geometry is "
        "degenerate (tests/test_stability.cpp, `Guarantee.*`). Backward Euler runs every case at dt = 1/60 s; its "
        "contacts are constraints inside the implicit solve (sim/implicit.h).\n";
  writeFile(out / "stability.csv", csv.str());
  if (!csvRuns.str().empty()) writeFile(out / "stability-runs.csv", csvRuns.str());
  writeFile(out / "stability.md", md.str());
  std::printf("wrote %s\n", (out / "stability.md").string().c_str());
  return 0;
}

}  // namespace

int runStudy(const StudyOptions& options) {
  if (options.kind == "accuracy") return runAccuracy(options);
  if (options.kind == "stability") return runStability(options);
  if (options.kind == "contact") return runContact(options);
  throw Error("study: unknown kind '" + options.kind + "' (accuracy, contact or stability)");
}

}  // namespace springy
