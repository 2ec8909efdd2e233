#include "app/run_outputs.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <system_error>

#include "app/csv.h"
#include "run/advisor.h"
#include "sim/error.h"
#include "sim/implicit.h"
#include "sim/vbd.h"

namespace springy {
namespace {

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

}  // namespace

void writeTraceHeader(std::ostream& out) {
  out << "scene,time,body,centroid_x,centroid_y,centroid_z,volume,kinetic,gravitational,elastic,total,max_strain,contacts\n";
}

void TraceRows::started(const Run&) {
  out_.flush();
  if (!begun_) {
    begin_ = out_.tellp();
    begun_ = true;
    return;
  }
  std::error_code error;
  std::filesystem::resize_file(path_, static_cast<std::uintmax_t>(begin_), error);
  if (error) throw Error(path_ + ": cutting the trace back failed: " + error.message());
  out_.seekp(begin_);
}

void TraceRows::frame(const Run& run) {
  const World& world = run.world();
  for (uint32_t b = 0; b < world.model().bodies.size(); ++b) {
    writeTraceRow(out_, run.scene().name, world.time(), world.model().bodies[b].name, run.monitor().records()[b].last,
                  touchingVertices(world, b));
  }
}

void ExportFrames::started(const Run& run) {
  exporter_.reset();  // a failed try's output is removed before the next is opened
  // The command's inputs and the files this scene was read from (scene/scene.h SceneDesc::inputs).
  std::vector<std::string> inputs = inputs_;
  for (const std::string& file : run.scene().inputs) {
    if (std::find(inputs.begin(), inputs.end(), file) == inputs.end()) inputs.push_back(file);
  }
  exporter_ = open_(path_, run.scene(), run.world(), run.frames(), run.frameTime(), inputs);
  exporter_->frame(run.world(), run.monitor());
}

void ExportFrames::frame(const Run& run) {
  if (!run.failure()) exporter_->frame(run.world(), run.monitor());
}

void RunHeader::started(const Run& run) {
  printRunHeader(run.path(), run.scene(), run.world());
  if (showProgress_) progress_.emplace(run.path(), run.frames());
}

void RunHeader::frame(const Run& run) {
  if (!progress_) return;
  progress_->update(run.frame(), std::to_string(run.world().stepCount()) + " steps");
  if (run.frame() == run.frames() || run.failure()) progress_->finish();
}

namespace {

// What each solver did over the run: the adaptive step's statistics, backward Euler's and vbd's
// iterations, the contacts between bodies.
void printSolverStatistics(const World& world) {
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
}

}  // namespace

void printResults(const Run& run) {
  const World& world = run.world();
  const Monitor& monitor = run.monitor();
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
                static_cast<unsigned long long>(world.stepCount()), world.time(), run.wallSeconds(), r.maxStrain,
                r.maxPenetration, volumeMin, volumeEnd, r.last.kinetic, r.last.gravitational, r.last.elastic,
                run.rest().atRest(info) ? "yes" : "no");
    if (monitor.energyChecked()) {
      std::printf("  %-16s dissipated %.4g J of %.4g J (%.1f%%)\n", "", r.start.total() - r.last.total(),
                  r.energyScale, 100.0 * (r.start.total() - r.last.total()) / r.energyScale);
    }
  }
  printSolverStatistics(world);
}

}  // namespace springy
