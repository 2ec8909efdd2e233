// `springy study accuracy|contact|stability` (app/study_*.cpp): the parts the three share, and
// the command's entry.
#include <algorithm>
#include <atomic>
#include <exception>
#include <fstream>
#include <mutex>
#include <numeric>
#include <sstream>
#include <thread>

#include "app/atomic_file.h"
#include "app/gnuplot.h"
#include "app/progress.h"
#include "app/study.h"
#include "sim/error.h"
#include "sim/interrupt.h"
#include "sim/parallel.h"

namespace springy {
namespace study {
namespace {

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

}  // namespace

double stepCost(Integrator integrator) {
  const IntegratorTraits& t = integratorTraits(integrator);
  return t.implicit ? 16.0 : t.evaluations;
}

std::string machine() {
  std::ostringstream s;
  s << std::thread::hardware_concurrency() << " cores (`nproc`), " << cpuModel()
    << "; Release build, single-threaded simulation; the runs side by side on every core, each timed by the "
       "CPU time of its thread";
  return s.str();
}

std::string fmt(const char* f, double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, f, v);
  return buf;
}

void writeFile(const fs::path& path, const std::string& text) {
  writeOwnedFile(path.string(), text, "springy study writes a file of that name");
}

void makeOutputDirectory(const fs::path& out, const std::string& kind) {
  makeDirectories(out.string(), "-o");
  // Its pages share the folder with others (-o docs): before the run, every file of a name this
  // study writes must be one springy wrote (the folder's record), not the user's.
  const auto writes = [&](const std::string& name) {
    const bool contact = name.rfind("accuracy-contact", 0) == 0;
    return kind == "contact" ? contact : !contact && name.rfind(kind, 0) == 0;
  };
  refuseUnownedIn(out.string(), writes, "springy study " + kind + " writes (" +
                                            (kind == "contact" ? std::string("accuracy-contact") : kind) + "*)");
}

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

std::string errorPlot(const fs::path& out, const std::string& file, const std::string& title, const std::string& ylabel,
                      const std::vector<PlotSeries>& series) {
  std::ostringstream dat, gp;
  for (const PlotSeries& line : series) {
    dat << "# " << line.name << "\n";
    for (const PlotPoint& p : line.points)
      dat << p.label << " " << fmt("%.6g", p.wall) << " " << fmt("%.6g", p.error) << "\n";
    dat << "\n\n";
  }
  writeFile(out / (file + ".dat"), dat.str());
  gp << "set terminal pngcairo size 960,640 font 'DejaVu Sans,10'\n"
     << "set output " << gnuplotText(file + ".png") << "\n"
     << "set logscale xy\nset format x '10^{%L}'\nset format y '10^{%L}'\n"
     << "set xlabel 'run time per simulated second [s]'\nset ylabel " << gnuplotText(ylabel) << "\n"
     << "set title " << gnuplotText(title) << " noenhanced\nset key outside right\nset grid\n"
     << "plot ";
  static const char* kColors[] = {"#d62728", "#ff7f0e", "#2ca02c", "#17becf", "#1f77b4", "#9467bd", "#000000"};
  for (std::size_t idx = 0; idx < series.size(); ++idx) {
    const std::string data = gnuplotText(file + ".dat") + " index " + std::to_string(idx);
    const std::string color = kColors[idx % 7];
    gp << (idx ? ", \\\n     " : "") << data << " using 2:3 with linespoints lw 2 pt 7 lc rgb '" << color
       << "' title " << gnuplotText(series[idx].name) << " noenhanced, \\\n     " << data
       << " using 2:3:1 with labels font ',7' offset 0.6,0.6 tc rgb '" << color << "' notitle";
  }
  gp << "\n";
  writeFile(out / (file + ".gp"), gp.str());
  if (!haveGnuplot()) return "(gnuplot not found: plot skipped; install gnuplot-nox)\n\n";
  const std::string png = (out / (file + ".png")).string();
  refuseUnlessOwned(png, "springy study's gnuplot writes a plot of that name");
  runGnuplot(out / (file + ".gp"));
  recordOwned(png);
  return "![" + title + "](" + file + ".png)\n\n";
}

void runInParallel(const std::string& label, const std::vector<double>& cost,
                   const std::function<void(std::size_t)>& job) {
  std::vector<std::size_t> order(cost.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return cost[a] > cost[b]; });
  const unsigned workers = std::max(1u, std::min<unsigned>(defaultThreadCount(), static_cast<unsigned>(order.size())));
  std::atomic<std::size_t> next{0};
  std::mutex mutex;  // guards done, error and the progress line
  std::size_t done = 0;
  std::exception_ptr error;
  Progress progress(label, static_cast<long>(order.size()), "runs");
  const auto work = [&] {
    for (;;) {
      const std::size_t k = next++;
      if (k >= order.size() || interrupted()) return;
      {
        const std::lock_guard<std::mutex> lock(mutex);
        if (error) return;
      }
      try {
        job(order[k]);
      } catch (...) {
        const std::lock_guard<std::mutex> lock(mutex);
        if (!error) error = std::current_exception();
        return;
      }
      if (interrupted()) return;  // the job stopped short: not a run done
      const std::lock_guard<std::mutex> lock(mutex);
      progress.update(static_cast<long>(++done), std::to_string(workers) + " at a time");
    }
  };
  std::vector<std::thread> threads;
  for (unsigned t = 1; t < workers; ++t) threads.emplace_back(work);
  work();
  for (std::thread& t : threads) t.join();
  progress.finish();
  if (error) std::rethrow_exception(error);
  if (interrupted()) throw Error(label + ": interrupted");
}

}  // namespace study

int runStudy(const StudyOptions& options) {
  if (options.kind == "accuracy") return study::runAccuracy(options);
  if (options.kind == "stability") return study::runStability(options);
  if (options.kind == "contact") return study::runContact(options);
  throw Error("study: unknown kind '" + options.kind + "' (accuracy, contact or stability)");
}

}  // namespace springy
