#include "run/options.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <algorithm>

#include "sim/error.h"
#include "sim/limits.h"
#include "sim/parallel.h"
#include "sim/world.h"

namespace springy {
namespace {

// A number as typed: all of the text (strtod's syntax). Throws "FLAG: expected WHAT, got 'TEXT'".
double number(const std::string& flag, const std::string& text, const std::string& what = "a number") {
  char* end = nullptr;
  const double value = text.empty() ? 0.0 : std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || std::isspace(static_cast<unsigned char>(text[0]))) {
    throw Error(flag + ": expected " + what + ", got '" + text + "'");
  }
  return value;
}

// A whole number as typed (digits only, at most 12). Throws "FLAG: expected WHAT, got 'TEXT'".
long whole(const std::string& flag, const std::string& text, const std::string& what = "a whole number") {
  const bool digits = !text.empty() && text.size() <= 12 && text.find_first_not_of("0123456789") == std::string::npos;
  if (!digits) throw Error(flag + ": expected " + what + ", got '" + text + "'");
  return std::strtol(text.c_str(), nullptr, 10);
}

bool boolean(const std::string& flag, const std::string& text) {
  if (text == "true" || text == "1" || text.empty()) return true;
  if (text == "false" || text == "0") return false;
  throw Error(flag + ": expected true or false, got '" + text + "'");
}

// Narrows a whole number that checkRunOptions then judges: one past the range when it is far out.
template <class T>
T clampedTo(long value) {
  return static_cast<T>(std::clamp<long>(value, 0, 1L << 30));
}

std::vector<RunOption> makeTable() {
  using Group = RunOption::Group;
  std::vector<RunOption> t;
  t.push_back({"integrator", "--integrator", "NAME", "Override the scene's integrator: " + integratorNames(),
               Group::Run, false, [](RunOptions& o, const std::string& text) { o.integrator = text; }});
  t.push_back({"dt", "--dt", "SECONDS",
               "Override the scene's time step [s] (the adaptive integrator's first step)", Group::Run, false,
               [](RunOptions& o, const std::string& text) { o.dt = number("--dt", text); }});
  t.push_back({"tolerance", "--tolerance", "FRACTION",
               "Choose each step by a tolerance: an adaptive integrator (verlet_adaptive unless --integrator bs32), "
               "each step's error at most this fraction of each body's size (e.g. 1e-4)",
               Group::Run, false,
               [](RunOptions& o, const std::string& text) { o.tolerance = number("--tolerance", text); }});
  t.push_back({"iterations", "--iterations", "N",
               "vbd's sweeps over the vertices per step, 1 to " + std::to_string(kMaxIterations) +
                   "; vbd only (default: the scene's [scene] iterations, else 8)",
               Group::Run, false, [](RunOptions& o, const std::string& text) {
                 o.iterations = clampedTo<int>(whole("--iterations", text));
               }});
  t.push_back({"substeps", "--substeps", "N|auto", "Steps of dt/N per dt, or 'auto': the stability advisor's safe number",
               Group::Run, false, [](RunOptions& o, const std::string& text) {
                 if (text == "auto") {
                   o.autoSubsteps = true;
                   o.substeps.reset();
                   return;
                 }
                 o.substeps = clampedTo<int>(whole("--substeps", text, "a whole number or 'auto'"));
                 o.autoSubsteps = false;
               }});
  t.push_back({"duration", "--duration", "SECONDS", "Override the simulated duration [s]", Group::Run, false,
               [](RunOptions& o, const std::string& text) { o.duration = number("--duration", text); }});
  t.push_back({"threads", "--threads", "N",
               "Simulation threads, 1 to 256 (default: $SPRINGY_THREADS, else all cores; models under " +
                   std::to_string(World::kMinVerticesPerThread) +
                   " vertices per thread use fewer). Results are identical for every count.",
               Group::Run, false,
               [](RunOptions& o, const std::string& text) { o.threads = clampedTo<unsigned>(whole("--threads", text)); }});
  t.push_back({"set", "--set", "KEY=VALUE",
               "Set a scene key before the scene is read (repeatable): KEY a dotted path (environment.drag, "
               "scene.duration, body.mass for every body, body.0.mass for the first), VALUE a TOML value (0.5, "
               "\"rk4\", true, [0, 2, 0])",
               Group::Run, true, [](RunOptions& o, const std::string& text) {
                 if (text.find('=') == std::string::npos) throw Error("--set " + text + ": expected KEY=VALUE");
                 o.sets.push_back(text);
               }});
  t.push_back({"min_volume", "--min-volume", "FRACTION", "Fail if a body's volume falls below this fraction of rest",
               Group::Criteria, false,
               [](RunOptions& o, const std::string& text) { o.minVolume = number("--min-volume", text); }});
  t.push_back({"end_volume", "--end-volume", "FRACTION",
               "Fail if a body ends below this fraction of its rest volume", Group::Criteria, false,
               [](RunOptions& o, const std::string& text) { o.endVolume = number("--end-volume", text); }});
  t.push_back({"end_at_rest", "--end-at-rest", "",
               "Fail unless every body is at rest: over the last second no vertex moves more than 0.2% of its "
               "body's size",
               Group::Criteria, false,
               [](RunOptions& o, const std::string& text) { o.endAtRest = boolean("--end-at-rest", text); }});
  return t;
}

}  // namespace

const std::vector<RunOption>& runOptionTable() {
  static const std::vector<RunOption> table = makeTable();
  return table;
}

const RunOption* findRunOption(std::string_view nameOrFlag) {
  for (const RunOption& option : runOptionTable()) {
    if (option.name == nameOrFlag || option.flag == nameOrFlag) return &option;
  }
  return nullptr;
}

void setRunOption(RunOptions& options, std::string_view name, const std::string& text) {
  const RunOption* option = findRunOption(name);
  if (!option) {
    std::string names;
    for (const RunOption& o : runOptionTable()) names += (names.empty() ? "" : ", ") + o.name;
    throw Error("'" + std::string(name) + "' is not a run option; they are: " + names);
  }
  option->set(options, text);
  checkRunOptions(options);
}

void checkRunOptions(const RunOptions& o) {
  Integrator parsed{};
  if (o.integrator && !parseIntegrator(*o.integrator, parsed)) {
    throw Error("--integrator: '" + *o.integrator + "' is not one of: " + integratorNames());
  }
  if (o.dt && (!(*o.dt > 0.0) || !std::isfinite(*o.dt))) throw Error("--dt must be a positive finite number of seconds");
  if (o.duration && (!(*o.duration > 0.0) || !std::isfinite(*o.duration))) {
    throw Error("--duration must be a positive finite number of seconds");
  }
  if (o.tolerance && !(*o.tolerance >= 1e-12 && *o.tolerance <= 0.5)) {
    throw Error("--tolerance must be a number from 1e-12 to 0.5 (a fraction of each body's size)");
  }
  if (o.iterations && (*o.iterations < 1 || *o.iterations > kMaxIterations)) {
    throw Error("--iterations must be between 1 and " + std::to_string(kMaxIterations) + " (vbd's sweeps a step)");
  }
  if (o.substeps && (*o.substeps < 1 || *o.substeps > kMaxSubsteps)) {
    throw Error("--substeps must be between 1 and " + std::to_string(kMaxSubsteps) + " (or auto)");
  }
  if (o.threads && (*o.threads < 1 || *o.threads > kMaxThreads)) {
    throw Error("--threads must be between 1 and " + std::to_string(kMaxThreads));
  }
  const auto fraction = [](const char* flag, double value) {
    if (!(value >= 0.0 && value <= 1.0)) {
      throw Error(std::string(flag) + " must be a fraction from 0 to 1 (of the rest volume), not " + std::to_string(value));
    }
  };
  fraction("--min-volume", o.minVolume);
  fraction("--end-volume", o.endVolume);
}

unsigned threadCount(const RunOptions& options) { return options.threads ? *options.threads : defaultThreadCount(); }

std::string studyKind(const std::string& text) {
  std::string kinds;
  for (const char* kind : {"accuracy", "contact", "stability"}) {
    if (text == kind) return text;
    kinds += (kinds.empty() ? "" : ", ") + std::string(kind);
  }
  throw Error("study: '" + text + "' is not a study; the studies are: " + kinds);
}

int studyRepeats(const std::string& text) {
  const long repeats = whole("--repeats", text);
  if (repeats < 1 || repeats > kMaxStudyRepeats) {
    throw Error("--repeats must be between 1 and " + std::to_string(kMaxStudyRepeats) + " (timed runs per point)");
  }
  return static_cast<int>(repeats);
}

double studyMaxDuration(const std::string& text) {
  // The words of --duration's check: nan and inf are no durations (CLI11's PositiveNumber let nan through).
  const double seconds = number("--max-duration", text);
  if (!(seconds > 0.0) || !std::isfinite(seconds)) {
    throw Error("--max-duration must be a positive finite number of seconds");
  }
  return seconds;
}

}  // namespace springy
