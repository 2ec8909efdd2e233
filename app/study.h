// springy app: the studies' shared parts (`springy study`, app/study_*.cpp).
//
// A study is many runs that do not depend on each other (a case at a step, a scene with an
// integrator): runInParallel gives them to every core, as a sweep's tasks are given, longest
// first, and shows their progress with an ETA. Each run steps its world on one thread and is
// timed by that thread's CPU time (sim/parallel.h threadCpuSeconds), which a run beside it on the
// other core does not inflate, as it inflates wall time; the runs are deterministic, so the
// errors and limits a study finds do not depend on how many run at once.
#pragma once

#include <array>
#include <cstddef>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "app/commands.h"
#include "sim/world.h"

namespace springy::study {

namespace fs = std::filesystem;

// The integrators of the accuracy studies, and of the stability study: with vertex block descent
// (its default sweeps), whose stability is not unconditional unless it converges.
inline constexpr std::array<Integrator, 6> kAll = {Integrator::ExplicitEuler, Integrator::SymplecticEuler,
                                                   Integrator::VelocityVerlet, Integrator::Leapfrog,
                                                   Integrator::RK4, Integrator::BackwardEuler};
inline constexpr std::array<Integrator, 7> kStabilityStudied = {
    Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::VelocityVerlet, Integrator::Leapfrog,
    Integrator::RK4,           Integrator::BackwardEuler,   Integrator::Vbd};

// The force evaluations' worth of work a step of the integrator costs, for ordering runs by
// cost: the table's explicit count, or an implicit step's Newton iterations or sweeps (about 16).
double stepCost(Integrator integrator);

// The machine, as the studies' pages state it: cores, processor, how runs are timed.
std::string machine();

// printf's formatting of one number.
std::string fmt(const char* format, double value);

// Writes text to path atomically, over a file of that name only if springy wrote it (the folder's
// record, app/atomic_file.h writeOwnedFile), and records it.
void writeFile(const fs::path& path, const std::string& text);

// The study's output directory, created when missing; an existing file of that name, or no
// permission, is a springy::Error naming it. Before the run: every file there of a name the study
// `kind` writes (accuracy*, accuracy-contact*, stability*) must be springy's, as the folder's
// record lists it, or springy::Error lists those that are not.
void makeOutputDirectory(const fs::path& out, const std::string& kind);

// A scene shipped in scenes/, by name; the scenes a study names, or else the eight showcase scenes.
std::string bundledScene(const char* name);
std::vector<std::string> scenesOrShowcase(const StudyOptions& options);

// One line of an error-against-run-time plot: its points (label, run time per simulated second,
// error).
struct PlotPoint {
  std::string label;
  double wall, error;
};
struct PlotSeries {
  std::string name;
  std::vector<PlotPoint> points;
};
// Writes FILE.dat and FILE.gp in `out` (log-log error against run time, a line per series, each
// point labelled) and, with gnuplot, FILE.png; returns the Markdown that shows it.
std::string errorPlot(const fs::path& out, const std::string& file, const std::string& title, const std::string& ylabel,
                      const std::vector<PlotSeries>& series);

// Runs job(i) for every i in [0, count) on every core (SPRINGY_THREADS, else the hardware's
// count; each job steps its worlds on one thread), the jobs of largest `cost` first, each job's
// results kept at its index by the job itself. Shows "LABEL: k/count runs, ETA" on stderr. Stops
// taking jobs at an interrupt or a job's exception, which it rethrows once every thread is back;
// throws springy::Error("interrupted") when interrupted.
void runInParallel(const std::string& label, const std::vector<double>& cost,
                   const std::function<void(std::size_t)>& job);

int runAccuracy(const StudyOptions& options);
int runContact(const StudyOptions& options);
int runStability(const StudyOptions& options);

}  // namespace springy::study
