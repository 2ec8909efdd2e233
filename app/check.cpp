// `springy check`: runs scenes headlessly under the stability monitor and reports per body.
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "app/csv.h"
#include "app/export.h"
#include "app/progress.h"
#include "app/runner.h"
#include "sim/error.h"
#include "sim/implicit.h"
#include "sim/vbd.h"
#include "sim/trajectory.h"

namespace springy {
namespace {

void writeTraceHeader(std::ostream& out) {
  out << "scene,time,body,centroid_x,centroid_y,centroid_z,volume,kinetic,gravitational,elastic,total,max_strain,contacts\n";
}

void writeTraceRow(std::ostream& out, const std::string& scene, double t, const std::string& body, const BodyMeasures& m,
                   uint32_t contacts) {
  char numbers[256];
  std::snprintf(numbers, sizeof numbers, ",%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%u\n", m.centroid.x, m.centroid.y,
                m.centroid.z, m.volume, m.kinetic, m.gravitational, m.elastic, m.total(), m.maxStrain, contacts);
  char time[32];
  std::snprintf(time, sizeof time, ",%.6f,", t);
  out << csvField(scene) << time << csvField(body) << numbers;
}

// The run's first lines: the scene, its step and what it runs (force stages, contact, threads).
void printRunHeader(const std::string& path, const SceneDesc& scene, const World& world) {
  if (world.adaptive()) {
    std::printf("%s: %s, %zu bodies, %zu vertices, integrator %s (adaptive), tolerance %g, %g s\n", path.c_str(),
                scene.name.c_str(), scene.bodies.size(), world.model().vertexCount(),
                std::string(integratorName(scene.integrator)).c_str(), scene.tolerance, scene.duration);
  } else {
    std::printf("%s: %s, %zu bodies, %zu vertices, integrator %s, dt %g s (%s), %g s\n", path.c_str(),
                scene.name.c_str(), scene.bodies.size(), world.model().vertexCount(),
                std::string(integratorName(scene.integrator)).c_str(), scene.dt, substepsText(scene.substeps).c_str(),
                scene.duration);
  }
  std::printf("  stages: forces [");
  for (std::size_t i = 0; i < world.forceStages().size(); ++i) {
    std::printf("%s%s", i ? " " : "", std::string(forceStageName(world.forceStages()[i])).c_str());
  }
  std::printf("], collide: %s, contact between bodies: %s, threads: %u\n", world.collides() ? "yes" : "no",
              world.bodyContacts() ? "yes" : "no", world.threads());
  std::fflush(stdout);
}

// One run of a scene under the monitor, frame by frame at the render rate (the states a video
// would show are the ones checked; at least one frame, as `render` draws one: a duration under
// half a frame ran nothing and said ok). `rest` watches the last second's frames; `rows`, when
// given, receives a trace row per frame and body. Returns the first failure; stops early, with
// none, when a signal arrives (the caller asks interrupted()).
std::optional<Failure> runFrames(const std::string& path, const SceneDesc& scene, World& world, Monitor& monitor,
                                 RestWatch& rest, std::ostream* rows, MotionExport* exporter,
                                 const std::function<void(long, const World&, const Monitor&)>& onFrame) {
  const double frame = 1.0 / scene.view.render.fps;
  const long frames = frameCount(scene.duration, frame);
  const double watchFrom = scene.duration - RestWatch::kWindow;
  // A long run shows that it is alive (stderr: a bar on a terminal, a line every 5 s in a log).
  Progress progress(path, frames);
  std::optional<Failure> failure;
  for (long k = 1; k <= frames && !failure; ++k) {
    if (interrupted()) return std::nullopt;
    failure = advanceTo(world, monitor, static_cast<double>(k) * frame);
    progress.update(k, std::to_string(world.stepCount()) + " steps");
    if (world.time() >= watchFrom - 1e-9) rest.add(world.positions());
    if (exporter && !failure) exporter->frame(world, monitor);
    if (onFrame) onFrame(k, world, monitor);
    if (rows) {
      for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
        writeTraceRow(*rows, scene.name, world.time(), world.model().bodies[b].name, monitor.records()[b].last,
                      touchingVertices(world, b));
      }
    }
  }
  progress.finish();
  return failure;
}

}  // namespace

std::vector<std::string> exportOutputs(const std::vector<std::string>& scenes, const std::string& output,
                                       const std::string& format, const std::string& option) {
  namespace fs = std::filesystem;
  const bool directory = isDirectory(output) || (!output.empty() && output.back() == '/') || scenes.size() > 1;
  if (!directory) {
    exportFormatOf(output, option);  // a file: its extension must name a format
    return {output};
  }
  const std::string extension = "." + format;
  exportFormatOf("scene" + extension, option);
  makeDirectories(output, option);
  std::vector<std::string> outputs;
  for (const std::string& scene : scenes) {
    const std::string file = (fs::path(output) / (fs::path(scene).stem().string() + extension)).string();
    for (std::size_t j = 0; j < outputs.size(); ++j) {
      if (outputs[j] == file) throw Error(scenes[j] + " and " + scene + " would both be exported to " + file);
    }
    outputs.push_back(file);
  }
  return outputs;
}

int runCheck(const CheckOptions& options) {
  const std::string who = "springy " + options.command + ": ";  // messages' prefix
  const auto recordError = [&](SceneRecord& record, const Error& e) {
    std::cerr << who << e.what() << "\n";
    record.status = SceneRecord::Status::Error;
    record.message = e.what();
  };
  std::vector<std::string> exports;
  if (options.replay) {
    if (options.scenes.size() != 1 || options.exportOutput.empty()) throw Error("a replay is written for one scene");
    exports = {options.exportOutput};
  } else if (!options.exportOutput.empty()) {
    exports = exportOutputs(options.scenes, options.exportOutput, options.exportFormat, options.exportOption);
  }
  std::unique_ptr<AtomicFile> traceFile;
  std::ofstream trace;
  if (!options.trace.empty()) {
    traceFile = std::make_unique<AtomicFile>(options.trace, options.scenes);  // never over a scene
    trace.open(traceFile->temporaryPath());
    writeTraceHeader(trace);
  }
  // Checked before any run: an unwritable --json or --junit fails at once, and no scene is replaced.
  std::unique_ptr<AtomicFile> jsonFile, junitFile;
  if (!options.json.empty()) jsonFile = std::make_unique<AtomicFile>(options.json, options.scenes);
  if (!options.junit.empty()) junitFile = std::make_unique<AtomicFile>(options.junit, options.scenes);
  std::vector<SceneRecord> records;
  int failures = 0;
  for (std::size_t sceneIndex = 0; sceneIndex < options.scenes.size(); ++sceneIndex) {
    const std::string& path = options.scenes[sceneIndex];
    SceneRecord& record = records.emplace_back();
    record.path = path;
    record.scene = std::filesystem::path(path).stem().string();
    SceneDesc scene;
    bool untried = false;  // the advisor's default step, which this run tries (adviseTimeStep)
    try {
      scene = loadSceneWith(path, options.overrides, true, &untried);
    } catch (const Error& e) {
      recordError(record, e);
      ++failures;
      continue;
    }
    record.scene = scene.name;
    record.integrator = std::string(integratorName(scene.integrator));
    record.dt = scene.dt;
    record.duration = scene.duration;
    MonitorLimits limits;
    limits.minVolume = options.minVolume;
    std::optional<World> worldSlot;
    std::optional<Monitor> monitorSlot;
    std::optional<Failure> failure;
    RestWatch rest;
    std::ostringstream tried;  // the trace rows of a run that is the default step's try, kept until it passes
    auto wallStart = std::chrono::steady_clock::now();
    bool retryFailed = false;
    std::unique_ptr<MotionExport> exporter;
    // One run; a second only when it was the default step's try and went unstable (an untried
    // default step was run twice before: once as the advisor's try, once as the check).
    for (;;) {
      wallStart = std::chrono::steady_clock::now();
      World& world = worldSlot.emplace(makeWorld(scene, options.overrides));
      Monitor& monitor = monitorSlot.emplace(world, limits);
      printRunHeader(path, scene, world);
      tried.str("");
      std::ostream* rows = !trace.is_open() ? nullptr : untried ? static_cast<std::ostream*>(&tried) : &trace;
      rest = RestWatch{};
      try {
        exporter.reset();  // a failed try's output is removed before the next is opened
        if (!exports.empty()) {
          const double frame = 1.0 / scene.view.render.fps;
          exporter = (options.replay ? openReplay : openExport)(exports[sceneIndex], scene, world,
                                                                frameCount(scene.duration, frame), frame, options.scenes);
          exporter->frame(world, monitor);
        }
        failure = runFrames(path, scene, world, monitor, rest, rows, exporter.get(), options.onFrame);
      } catch (const Error& e) {
        recordError(record, e);
        retryFailed = true;
        break;
      }
      if (interrupted()) {
        std::cerr << who << "interrupted\n";
        return interruptedExitStatus();
      }
      if (!failure) break;
      try {
        if (!retryDefaultStep(path, scene, *failure, untried, threadCount(options.overrides), std::cerr)) break;
      } catch (const Error& e) {
        recordError(record, e);
        retryFailed = true;
        break;
      }
    }
    if (retryFailed) {
      ++failures;
      continue;
    }
    record.substeps = scene.substeps;
    World& world = *worldSlot;
    Monitor& monitor = *monitorSlot;
    if (trace.is_open()) trace << tried.str();  // the try passed: its rows are the run's
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wallStart).count();
    record.wall = wall;
    std::printf("  %-16s %9s %8s %8s %10s %10s %9s %10s %10s %10s %10s %s\n", "body", "steps", "sim[s]", "wall[s]",
                "max strain", "max pen[m]", "vol min", "vol end", "kinetic", "grav", "elastic", "rest");
    for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
      const BodyRecord& r = monitor.records()[b];
      const BodyInfo& info = world.model().bodies[b];
      // An open surface (a cloth) encloses no volume: "-".
      char volumeMin[32] = "-", volumeEnd[32] = "-";
      if (info.restVolume > 0.0) {
        std::snprintf(volumeMin, sizeof volumeMin, "%.3f", r.minVolumeRatio);
        std::snprintf(volumeEnd, sizeof volumeEnd, "%.3f", r.last.volume / info.restVolume);
      }
      std::printf("  %-16s %9llu %8.3f %8.3f %10.4f %10.2e %9s %10s %10.4g %10.4g %10.4g %s\n", info.name.c_str(),
                  static_cast<unsigned long long>(world.stepCount()), world.time(), wall, r.maxStrain, r.maxPenetration,
                  volumeMin, volumeEnd, r.last.kinetic, r.last.gravitational, r.last.elastic,
                  rest.atRest(info) ? "yes" : "no");
      record.bodies.push_back(bodyResult(world, monitor, rest, b));
      if (monitor.energyChecked()) {
        std::printf("  %-16s dissipated %.4g J of %.4g J (%.1f%%)\n", "", r.start.total() - r.last.total(),
                    r.energyScale, 100.0 * (r.start.total() - r.last.total()) / r.energyScale);
      }
    }
    if (world.adaptive()) {
      const StepStats& st = world.stepStats();
      std::printf(
          "  adaptive: %llu steps (%llu landing on a frame), %llu rejected (%llu for an impact), step %.3g to "
          "%.3g s, mean %.3g s, %llu force evaluations\n",
          static_cast<unsigned long long>(st.accepted), static_cast<unsigned long long>(st.landed),
          static_cast<unsigned long long>(st.rejected), static_cast<unsigned long long>(st.contactRejected),
          st.smallest, st.largest, world.time() / static_cast<double>(std::max<uint64_t>(st.accepted, 1)),
          static_cast<unsigned long long>(world.forceEvaluations()));
    }
    if (const ImplicitSolver* solver = world.implicitSolver()) {
      const ImplicitStats& st = solver->stats();
      const double steps = static_cast<double>(std::max<uint64_t>(st.steps, 1));
      std::printf("  implicit: %.2f Newton iterations and %.1f CG iterations per step, %llu contacts in the solve, "
                  "%llu steps retried as halves, %llu unconverged\n",
                  static_cast<double>(st.newtonIterations) / steps, static_cast<double>(st.cgIterations) / steps,
                  static_cast<unsigned long long>(st.contactConstraints),
                  static_cast<unsigned long long>(st.halvedSteps), static_cast<unsigned long long>(st.unconvergedSteps));
    }
    if (const VbdSolver* solver = world.vbdSolver()) {
      const VbdStats& st = solver->stats();
      std::printf("  vbd: %d sweeps a step over %zu colours, %llu contacts in the solve (%llu ending on a surface)\n",
                  solver->iterations(), solver->colours(), static_cast<unsigned long long>(st.contactConstraints),
                  static_cast<unsigned long long>(st.activeConstraints));
    }
    if (const BodyContacts* contacts = world.bodyContacts()) {
      const ContactStats& st = contacts->sinceStart();
      const double steps = static_cast<double>(std::max<uint64_t>(st.steps, 1));
      std::printf(
          "  contact: %.2f contacts per step (at most %llu), %.2f impulses per step, %.2f test passes per "
          "step, %llu vertex-steps stopped by the fail-safe; thickness",
          static_cast<double>(st.contacts) / steps, static_cast<unsigned long long>(st.mostContacts),
          static_cast<double>(st.impulses) / steps, static_cast<double>(st.passes) / steps,
          static_cast<unsigned long long>(st.stopped));
      for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
        std::printf(" %s %.3g m%s", world.model().bodies[b].name.c_str(), contacts->thickness(b),
                    b + 1 < world.model().bodies.size() ? "," : "\n");
      }
    }
    if (!failure) failure = endCriteria(world, monitor, rest, options.endVolume, options.endAtRest);
    // A run that failed only a criterion (--end-at-rest, --end-volume) is a valid motion: kept
    // where asked (a report shows it beside the failure).
    if (exporter && (!failure || (failure->criterion && options.exportOnCriterionFailure))) {
      try {
        exporter->commit();
        std::printf("  exported: %s\n", exporter->written().c_str());
      } catch (const Error& e) {
        recordError(record, e);
        ++failures;
        continue;
      }
    } else if (exporter) {
      exporter.reset();
      std::printf("  not exported: the run failed\n");
    }
    if (failure) {
      std::printf("  FAILED: %s\n", failure->message.c_str());
      std::cerr << who << path << ": " << failure->message << "\n";
      record.status = SceneRecord::Status::Failed;
      record.failedBody = failure->body;
      record.message = failure->message;
      ++failures;
    } else {
      std::printf("  ok\n");
    }
  }
  if (traceFile) {
    trace.close();
    if (!trace) throw Error(options.trace + ": writing the trace failed: " + errorText(errno));
    traceFile->commit();
  }
  if (jsonFile) {
    jsonFile->write(recordsJson(records));
    jsonFile->commit();
  }
  if (junitFile) {
    junitFile->write(junitXml(records));
    junitFile->commit();
  }
  if (options.records) *options.records = std::move(records);
  return failures == 0 ? 0 : 1;
}

}  // namespace springy
