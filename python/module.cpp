// springy's Python module, _springy (the package python/springy wraps it; docs/python.md).
//
// A Simulation is a scene loaded as `springy check` loads it, a World stepped frame by frame under
// the stability monitor exactly as `check` steps it (the same advanceTo calls at the same frame
// times, so the same bits), and its state seen from numpy without a copy. Long calls release the
// GIL and look for Ctrl-C between frames. Everything that can be wrong with what Python hands in
// (shapes, NaN, absurd values, unknown keys, bad sizes) is a Python exception naming it; nothing
// here aborts. One call at a time on a simulation (Simulation::Hold).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <csignal>
#include <chrono>
#include <atomic>
#include <cmath>
#include <condition_variable>
#include <functional>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <sstream>
#include <streambuf>
#include <string>
#include <thread>
#include <tuple>
#include <type_traits>
#include <vector>

#include "app/atomic_file.h"
#include "app/frame_pipeline.h"
#include "app/commands.h"
#include "run/records.h"
#include "run/advisor.h"
#include "run/run.h"
#include "app/scene_view.h"
#include "render/error.h"
#include "sim/diagnostics.h"
#include "sim/error.h"
#include "sim/limits.h"
#include "sim/trajectory.h"

namespace py = pybind11;

namespace springy {
namespace {

static_assert(sizeof(Vec3) == 3 * sizeof(double) && std::is_standard_layout_v<Vec3>,
              "the numpy views read the state as rows of three doubles");

PyObject* gUnstable = nullptr;  // springy.Unstable (a RuntimeError)

// Raises springy.Unstable for a failure of the monitor (or a check's criterion), with the body,
// its name, the time, the step and the message as attributes; `record` is check's dict, if any.
[[noreturn]] void raiseUnstable(const Failure& failure, const World& world, py::object record = py::none()) {
  py::object type = py::reinterpret_borrow<py::object>(gUnstable);
  py::object error = type(failure.message);
  const std::vector<BodyInfo>& bodies = world.model().bodies;
  error.attr("body") = failure.body;
  error.attr("body_name") = failure.body < bodies.size() ? bodies[failure.body].name : std::string();
  error.attr("time") = failure.time;
  error.attr("step") = failure.step;
  error.attr("message") = failure.message;
  error.attr("criterion") = failure.criterion;
  error.attr("record") = record;
  PyErr_SetObject(gUnstable, error.ptr());
  throw py::error_already_set();
}

// Raises KeyboardInterrupt (or what a Python signal handler raised) if a signal arrived.
void checkSignals() {
  if (PyErr_CheckSignals() != 0) throw py::error_already_set();
}

// Keeps what is written to std::cerr while a command runs (and passes it on), so that a failed
// command's Python exception carries its message, not only "see stderr".
class CerrTee : public std::streambuf {
 public:
  CerrTee() : original_(std::cerr.rdbuf(this)) {}
  ~CerrTee() override { std::cerr.rdbuf(original_); }
  CerrTee(const CerrTee&) = delete;
  CerrTee& operator=(const CerrTee&) = delete;
  std::string text() {
    std::lock_guard<std::mutex> lock(mutex_);
    return kept_;
  }

 protected:
  int overflow(int c) override {
    if (c == traits_type::eof()) return traits_type::not_eof(c);
    const char ch = static_cast<char>(c);
    return xsputn(&ch, 1) == 1 ? c : traits_type::eof();
  }
  std::streamsize xsputn(const char* s, std::streamsize n) override {
    std::lock_guard<std::mutex> lock(mutex_);
    if (kept_.size() < kMaxKept) kept_.append(s, static_cast<std::size_t>(n));
    return original_->sputn(s, n);
  }
  int sync() override { return original_->pubsync(); }

 private:
  static constexpr std::size_t kMaxKept = 1 << 16;
  std::streambuf* original_;
  std::mutex mutex_;
  std::string kept_;
};

// Discards what is written to std::cerr while it lives (load(..., quiet=True)).
class CerrSilence : public std::streambuf {
 public:
  CerrSilence() : original_(std::cerr.rdbuf(this)) {}
  ~CerrSilence() override { std::cerr.rdbuf(original_); }
  CerrSilence(const CerrSilence&) = delete;
  CerrSilence& operator=(const CerrSilence&) = delete;

 protected:
  int overflow(int c) override { return traits_type::not_eof(c); }
  std::streamsize xsputn(const char*, std::streamsize n) override { return n; }

 private:
  std::streambuf* original_;
};

// Runs a command (runRender, runFrames, runStudy) on another thread with the GIL released; a
// Ctrl-C in Python sets the commands' interrupt flag (they stop within a frame and remove their
// temporary files) and is raised once the command has returned. A non-zero status raises
// springy.Error with what the command said on stderr.
void runCommand(const std::string& what, const std::function<int()>& command) {
  CerrTee tee;
  int status = 0;
  std::exception_ptr thrown;
  bool done = false;
  std::mutex mutex;
  std::condition_variable finished;
  std::thread worker([&] {
    try {
      status = command();
    } catch (...) {
      thrown = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex);
    done = true;
    finished.notify_all();
  });
  bool stopped = false;
  for (;;) {
    {
      py::gil_scoped_release release;
      std::unique_lock<std::mutex> lock(mutex);
      finished.wait_for(lock, std::chrono::milliseconds(50), [&] { return done; });
      if (done) break;
    }
    if (!stopped && PyErr_CheckSignals() != 0) {
      requestInterrupt(SIGINT);  // the Python error stays set until the worker returns
      stopped = true;
    }
  }
  worker.join();
  if (stopped) {
    clearInterrupt();
    throw py::error_already_set();
  }
  if (thrown) std::rethrow_exception(thrown);
  if (status != 0) {
    std::string said = tee.text();
    while (!said.empty() && said.back() == '\n') said.pop_back();
    throw Error(what + " failed (exit status " + std::to_string(status) + ")" + (said.empty() ? "" : ": " + said));
  }
}

// A zero-copy view of `count` rows of three doubles from `data`, kept alive by `owner`,
// read-only: the state must change through the checked setters (Simulation::setState).
py::array rowsView(const Vec3* data, std::size_t count, py::handle owner) {
  py::array_t<double> view({static_cast<py::ssize_t>(count), py::ssize_t{3}},
                           {static_cast<py::ssize_t>(sizeof(Vec3)), static_cast<py::ssize_t>(sizeof(double))},
                           &data->x, owner);
  py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return view;
}

struct Range {
  uint32_t first = 0, count = 0;
};

// What the state's setters take: a coordinate within 1000 km of the origin and a velocity within
// 1000 km/s on each axis. Far beyond any scene (a collider plane is drawn 200 m wide), and the
// doubles still resolve a strut's length there (1e6 m holds 1e-10 m); 1e308 would overflow the
// first force, and the run would step on with infinities until the monitor looks.
constexpr double kMaxCoordinate = 1e6;  // [m]
constexpr double kMaxVelocity = 1e6;    // [m/s]

// The error of a call on a simulation that another call holds (Simulation::Hold).
// `holder` and `call` as Python spells them: "run()", "sim.time".
std::runtime_error busy(const char* holder, const char* call) {
  return std::runtime_error("simulation busy: " + std::string(holder) + " is in progress on another thread (" + call +
                            " refused: one call at a time on a simulation; wait for " + holder +
                            " to return, or load a second simulation)");
}

// Who a setter sets, to name the body and the vertex in its errors: body `body` (its rows are its
// own vertices) or, for -1, the whole state (rows are the model's vertices).
struct Setter {
  const Model& model;
  long body;
  const char* what;  // "positions" or "velocities"

  std::string bodyName(uint32_t b) const { return "body " + std::to_string(b) + " '" + model.bodies[b].name + "'"; }
  // "body 0 'ball': positions", "sim.positions".
  std::string label() const {
    return body == -1 ? std::string("sim.") + what : bodyName(static_cast<uint32_t>(body)) + ": " + what;
  }
  // Entry k of vertex g (a model index): "body 0 'ball': positions[7, 2]", or from the whole
  // state's setter "sim.positions[150, 2] (body 1 'cube', vertex 4)".
  std::string entry(uint32_t g, int k) const {
    const uint32_t b = model.body[g];
    const uint32_t local = g - model.bodies[b].firstVertex;
    const std::string at = ", " + std::to_string(k) + "]";
    if (body == -1) {
      return "sim." + std::string(what) + "[" + std::to_string(g) + at + " (" + bodyName(b) + ", vertex " +
             std::to_string(local) + ")";
    }
    return label() + "[" + std::to_string(local) + at;
  }
  // "body 0 'ball': positions: vertices 3 and 17", or "sim.positions: body 0 'ball', vertices 3 and 17".
  std::string pair(uint32_t i, uint32_t j) const {
    const uint32_t b = model.body[i], first = model.bodies[b].firstVertex;
    const std::string vertices = "vertices " + std::to_string(i - first) + " and " + std::to_string(j - first);
    return body == -1 ? label() + ": " + bodyName(b) + ", " + vertices : label() + ": " + vertices;
  }
};

class Simulation {
 public:
  // The views (rowsView) point into the world's buffers: a check() that starts over keeps the
  // world it replaces, so a view taken before stays readable (Run::keepReplacedWorlds).
  Simulation(const std::string& path, RunOptions options) : run_(path, std::move(options)) { run_.keepReplacedWorlds(); }

  // One call at a time on a simulation: run, step and check step it with the GIL released, and
  // a call from another thread meanwhile would race with the step. Every call that steps, sets
  // or draws the state holds it for its whole length (between run's frames too); another call
  // on it meanwhile raises RuntimeError naming the call in progress (it does not wait: a Python
  // thread that waited for a run() of minutes would look hung).
  class Hold {
   public:
    Hold(const Simulation& s, const char* call) : s_(s) {
      const char* none = nullptr;
      if (!s.holder_.compare_exchange_strong(none, call)) throw busy(none, call);
    }
    ~Hold() { s_.holder_.store(nullptr); }
    Hold(const Hold&) = delete;
    Hold& operator=(const Hold&) = delete;

   private:
    const Simulation& s_;
  };

  // The state for a call that reads it (`call`: "measures", "time", ...); raises while another
  // call holds the simulation. Nothing can take it between this check and the read: taking it
  // needs the GIL, which the reader holds throughout.
  const World& world(const char* call) const {
    if (const char* holder = holder_.load()) throw busy(holder, call);
    return run_.world();
  }

  const Run& runner() const { return run_; }
  const World& world() const { return run_.world(); }
  const SceneDesc& scene() const { return run_.scene(); }

  // The vertex range of body `body`, or every vertex for -1. Raises IndexError.
  Range range(long body) const {
    if (body == -1) return {0, static_cast<uint32_t>(world().model().vertexCount())};
    const BodyInfo& info = this->body(body);
    return {info.firstVertex, info.vertexCount};
  }

  // Body `body` (not -1). Raises IndexError.
  const BodyInfo& body(long index) const {
    const std::vector<BodyInfo>& bodies = world().model().bodies;
    if (index < 0 || index >= static_cast<long>(bodies.size())) {
      throw py::index_error("body " + std::to_string(index) + ": the scene has " + std::to_string(bodies.size()) +
                            " bodies (indices from 0)");
    }
    return bodies[static_cast<std::size_t>(index)];
  }

  // Advances through every frame time up to `until`, then to `until` itself, as check does: a
  // frame at a time with the GIL released, Ctrl-C looked for between frames.
  void run(double until) {
    Hold hold(*this, "run()");
    refuseFailed();
    if (!std::isfinite(until)) throw py::value_error("run(until=...): the time must be finite");
    const World& w = world();
    if (until < w.time() - 0.5 * w.dt()) {
      throw py::value_error("run(until=" + exactNumber(until) + "): the simulation is already at t = " +
                            exactNumber(w.time()) + " s (it never runs backwards)");
    }
    if (!w.adaptive() && (until - w.time()) / w.dt() > kMaxSteps) {
      throw py::value_error("run(until=" + exactNumber(until) + "): over " + exactNumber(kMaxSteps) + " steps of " +
                            exactNumber(w.dt()) + " s");
    }
    for (;;) {
      const double next = static_cast<double>(run_.frame() + 1) * run_.frameTime();
      const double target = next <= until + 1e-9 * run_.frameTime() ? next : until;
      if (released([&] { return run_.runUntil(target); })) fail();
      checkSignals();
      if (target != next) return;
    }
  }

  // n steps (the adaptive step: n accepted steps), then the monitor's check unless `check` is
  // false (a caller that checks itself, or measures the call's cost).
  void step(long n, bool check) {
    Hold hold(*this, "step()");
    refuseFailed();
    if (n < 0) throw py::value_error("step(n=" + std::to_string(n) + "): n must be 0 or more");
    constexpr long kChunk = 4096;  // steps between looks for Ctrl-C
    for (long done = 0; done < n;) {
      const long chunk = std::min(kChunk, n - done);
      done += chunk;
      if (released([&] { return run_.step(chunk, check && done == n); })) fail();
      if (done < n) checkSignals();
    }
    if (n == 0 && check && released([&] { return run_.step(0, true); })) fail();
  }

  // Runs on to the end of the scene (check's last frame) and returns check's record as JSON (the
  // same fields as `check --json`). A failure of the monitor raises Unstable (with the record); a
  // criterion (min_volume, end_volume, end_at_rest) that fails gives status "failed". A scene
  // that gives no step, run from its start, tries longer steps as check does (Run::complete).
  // The criteria come as load()'s keywords do, as text through the run options' table
  // (run/options.h), so a bad one raises springy.Error with the command line's words.
  std::string check(const std::map<std::string, std::string>& criteria) {
    Hold hold(*this, "check()");
    refuseFailed();
    RunOptions given;
    for (const auto& [name, text] : criteria) {
      const RunOption* row = findRunOption(name);
      if (!row || row->name != name || row->group != RunOption::Group::Criteria) {
        throw py::type_error("check(): '" + name + "' is not one of check's criteria");
      }
      setRunOption(given, name, text);
    }
    const auto has = [&](const char* name) { return criteria.count(name) != 0; };
    run_.setCriteria(has("min_volume") ? std::optional<double>(given.minVolume) : std::nullopt,
                     has("end_volume") ? std::optional<double>(given.endVolume) : std::nullopt,
                     has("end_at_rest") ? std::optional<bool>(given.endAtRest) : std::nullopt);
    const std::optional<Failure> failure = released([&] { return run_.complete(); });
    checkSignals();
    if (failure && !failure->criterion) fail(toJson(run_.record()).dump());
    return toJson(run_.record()).dump();
  }

  // Replaces the positions or the velocities of a range, checked (shape, type, every value finite
  // and in bounds, no strut's ends on one point; the error names the body and the vertex). The
  // integrator's caches and the contact history start again, and so does the monitor's watch
  // (energy put in by hand is no instability); a failure is forgotten: stepping goes on from here.
  void setRows(py::handle value, long body, bool positions) {
    Hold hold(*this, positions ? "setting positions" : "setting velocities");
    const Setter to{world().model(), body, positions ? "positions" : "velocities"};
    const Range r = range(body);
    const auto rows = checkedRows(value, to.label(), r.count);
    const auto in = rows.unchecked<2>();
    std::vector<Vec3> x = world().positions(), v = world().velocities();
    std::vector<Vec3>& target = positions ? x : v;
    for (uint32_t i = 0; i < r.count; ++i) target[r.first + i] = Vec3(in(i, 0), in(i, 1), in(i, 2));
    if (positions) checkBounds(x, r, to, kMaxCoordinate, "a coordinate must be within 1e6 m of the origin");
    if (!positions) checkBounds(v, r, to, kMaxVelocity, "a velocity must be within 1e6 m/s on each axis");
    if (positions) checkStruts(x, r, to);
    run_.setState(std::move(x), std::move(v));
  }

  // The frame at this instant as `springy frames` draws it: HxWx3 uint8, rows top-down.
  py::array render(std::optional<int> width, std::optional<int> height, bool overlay, bool shadows, bool antialias) {
    Hold hold(*this, "render()");
    RenderOverrides o;
    o.width = width;
    o.height = height;
    o.noOverlay = !overlay;
    o.noShadows = !shadows;
    o.noAntialias = !antialias;
    // The view (its GL context, meshes and scene copy) is made again only when what it draws changes.
    const auto key = std::make_tuple(width, height, overlay, shadows, antialias, scene().substeps);
    if (!view_ || key != viewKey_) {
      SceneDesc drawn = scene();
      applyRenderOverrides(drawn, o);  // throws for a bad size before the old view is dropped
      view_.reset();
      viewScene_ = std::move(drawn);
      view_ = std::make_unique<SceneView>(viewScene_, world(), renderSettingsOf(viewScene_));
      viewKey_ = key;
    }
    view_->draw(world());
    const render::Image image = view_->renderer().readImage();
    py::array_t<uint8_t> out({image.height, image.width, 3});
    uint8_t* rgb = out.mutable_data();
    const std::size_t pixels = static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height);
    for (std::size_t i = 0; i < pixels; ++i) {
      for (std::size_t c = 0; c < 3; ++c) rgb[3 * i + c] = image.rgba[4 * i + c];
    }
    return out;
  }

 private:
  // `value` as rows of three finite doubles, `count` of them; raises naming `name`.
  static py::array_t<double, py::array::c_style | py::array::forcecast> checkedRows(py::handle value,
                                                                                    const std::string& name,
                                                                                    uint32_t count) {
    py::array given = py::array::ensure(value);
    if (!given) {
      throw py::type_error(name + ": expected an array of numbers, not " +
                           std::string(py::str(py::type::of(value).attr("__name__"))));
    }
    if (given.ndim() != 2 || given.shape(0) != count || given.shape(1) != 3) {
      std::string shape = "(";
      for (py::ssize_t i = 0; i < given.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(given.shape(i));
      shape += given.ndim() == 1 ? ",)" : ")";
      throw py::value_error(name + ": expected shape (" + std::to_string(count) + ", 3), got " + shape);
    }
    const char kind = given.dtype().kind();
    if (kind != 'f' && kind != 'i' && kind != 'u') {
      throw py::type_error(name + ": expected real numbers, got dtype " + std::string(py::str(given.dtype())));
    }
    const auto rows = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
    if (!rows) throw py::error_already_set();
    return rows;
  }

  // Every value of vertices r of `rows` finite and within `bound` (`rule` says so); checked in the
  // state's vectors, where each entry's vertex names its body.
  static void checkBounds(const std::vector<Vec3>& rows, Range r, const Setter& to, double bound, const char* rule) {
    for (uint32_t i = r.first; i < r.first + r.count; ++i) {
      for (int k = 0; k < 3; ++k) {
        const double value = rows[i][k];
        if (!std::isfinite(value)) {
          throw py::value_error(to.entry(i, k) + " is " + exactNumber(value) + ": every value must be finite");
        }
        if (std::abs(value) > bound) {
          throw py::value_error(to.entry(i, k) + " is " + exactNumber(value) + ": " + rule);
        }
      }
    }
  }

  // No strut among vertices r with both ends on one point: it would have no direction and push
  // nothing apart (sim/strut.cpp skips it), so a body set onto a point (all zeros) would stay one.
  static void checkStruts(const std::vector<Vec3>& x, Range r, const Setter& to) {
    for (const Strut& strut : to.model.struts) {
      if (strut.i < r.first || strut.i - r.first >= r.count || length(x[strut.j] - x[strut.i]) > 0.0) continue;
      const Vec3& p = x[strut.i];
      throw py::value_error(to.pair(strut.i, strut.j) + ", joined by a strut, are both at (" + exactNumber(p.x) + ", " +
                            exactNumber(p.y) + ", " + exactNumber(p.z) +
                            "): a strut's ends must be apart (a body cannot be set onto a point)");
    }
  }

  // Stepping a simulation that failed raises its failure again: its state is what the monitor
  // refused. Setting the state (setRows) forgets the failure; so does loading the scene again.
  void refuseFailed() const {
    if (run_.failure()) raise(*run_.failure(), world());
  }

  // Runs fn with the GIL released (the caller holds the simulation: Hold).
  template <class F>
  static std::invoke_result_t<F&> released(F&& fn) {
    py::gil_scoped_release release;
    return fn();
  }

  // Raises the run's failure as springy.Unstable (with check's record, when given).
  [[noreturn]] void fail(const std::string& recordJson = "") {
    Failure said = *run_.failure();
    if (run_.untried() && !said.criterion) {
      said.message += " (the scene gives no step, and springy's default, " + substepsText(scene().substeps) +
                      ", was not tried: sim.check() tries longer ones from the start, or load the scene with "
                      "substeps=" + std::to_string(2 * scene().substeps) + ")";
    }
    raise(said, world(), recordJson.empty() ? py::none() : py::module_::import("json").attr("loads")(recordJson));
  }
  [[noreturn]] static void raise(const Failure& failure, const World& world, py::object record = py::none()) {
    raiseUnstable(failure, world, std::move(record));
  }

  Run run_;
  // The call that holds the simulation ("run", "step", ...), or null (Hold). Taken and given back
  // with the GIL held; atomic since the stepping thread reads nothing of it without the GIL, but
  // cheap enough to leave no doubt.
  mutable std::atomic<const char*> holder_{nullptr};
  SceneDesc viewScene_;   // the scene as drawn (its [render] with the overrides)
  std::unique_ptr<SceneView> view_;
  std::tuple<std::optional<int>, std::optional<int>, bool, bool, bool, int> viewKey_;  // render()'s arguments
};

// A view of one of the per-vertex vectors, a body's rows or (body -1) every vertex's.
enum class Rows { Positions, Velocities, Rest };
py::array bodyRows(py::object self, long body, Rows which) {
  const Simulation& s = self.cast<const Simulation&>();
  const Range r = s.range(body);
  const World& w = s.world(which == Rows::Positions    ? "positions"
                           : which == Rows::Velocities ? "velocities"
                                                       : "rest_positions");
  const std::vector<Vec3>& rows = which == Rows::Positions    ? w.positions()
                                  : which == Rows::Velocities ? w.velocities()
                                                              : w.model().restPosition;
  return rowsView(rows.data() + r.first, r.count, self);
}

py::dict measuresDict(const BodyMeasures& m) {
  py::dict d;
  d["centroid"] = py::make_tuple(m.centroid.x, m.centroid.y, m.centroid.z);
  d["momentum"] = py::make_tuple(m.momentum.x, m.momentum.y, m.momentum.z);
  d["angular_momentum"] = py::make_tuple(m.angularMomentum.x, m.angularMomentum.y, m.angularMomentum.z);
  d["kinetic"] = m.kinetic;
  d["gravitational"] = m.gravitational;
  d["elastic"] = m.elastic;
  d["total"] = m.total();
  d["volume"] = m.volume;
  d["size"] = m.size;
  d["max_strain"] = m.maxStrain;
  d["penetration"] = m.penetration;
  d["rms_speed"] = m.rmsSpeed;
  d["finite"] = m.finite;
  return d;
}

// Run options from Python's keywords (their values as the command line's text: springy.load
// passes str(value)), through the table the command line reads (run/options.h): the same checks
// and messages.
RunOptions runOptionsOf(const std::vector<std::string>& sets, const std::map<std::string, std::string>& given) {
  RunOptions o;
  for (const std::string& s : sets) setRunOption(o, "set", s);
  for (const auto& [name, text] : given) {
    const RunOption* option = findRunOption(name);
    if (!option || name == "set" || option->flag == name) {
      std::string names;
      for (const RunOption& row : runOptionTable()) names += (names.empty() ? "" : ", ") + row.name;
      throw py::type_error("'" + name + "' is not an option of a run; they are: " + names);
    }
    setRunOption(o, name, text);
  }
  return o;
}

RenderOverrides renderOverridesOf(std::optional<int> width, std::optional<int> height, std::optional<double> fps,
                                  bool overlay, bool shadows, bool antialias) {
  RenderOverrides r;
  r.width = width;
  r.height = height;
  r.fps = fps;
  r.noOverlay = !overlay;
  r.noShadows = !shadows;
  r.noAntialias = !antialias;
  return r;
}

// Registers springy's exceptions: Error (a ValueError), RenderError and Unstable (RuntimeErrors).
void defineErrors(py::module_& m) {
  py::register_exception<Error>(m, "Error", PyExc_ValueError);
  py::register_exception<render::RenderError>(m, "RenderError", PyExc_RuntimeError);
  gUnstable = PyErr_NewExceptionWithDoc(
      "springy.Unstable",
      "The stability monitor stopped the run (a blow-up, a body behind a collider, a limit given): "
      "attributes body, body_name, time, step, message, criterion, record.",
      PyExc_RuntimeError, nullptr);
  m.add_object("Unstable", py::handle(gUnstable));
}

// Simulation's construction and its calls that run, check and render it.
void defineSimulationRuns(py::class_<Simulation>& cls) {
  cls.def(py::init([](const std::string& path, const std::vector<std::string>& sets,
                      const std::map<std::string, std::string>& options, bool quiet) {
            RunOptions o = runOptionsOf(sets, options);
            py::gil_scoped_release release;  // the advisor may survey the step
            std::optional<CerrSilence> silence;
            if (quiet) silence.emplace();
            return std::make_unique<Simulation>(path, std::move(o));
          }),
          py::arg("path"), py::arg("sets"), py::arg("options"), py::arg("quiet"))
      .def("run", &Simulation::run, py::arg("until"))
      .def("step", &Simulation::step, py::arg("n") = 1, py::arg("check") = true)
      .def("check", &Simulation::check, py::arg("criteria"))
      .def("render", &Simulation::render, py::arg("width"), py::arg("height"), py::arg("overlay"),
           py::arg("shadows"), py::arg("antialias"));
}

// Simulation's read-only properties: its clock, its settings and its state's hash.
void defineSimulationProperties(py::class_<Simulation>& cls) {
  // What the steps change is read through world(name): refused while another call holds the
  // simulation. The scene's name, duration, fps, threads and bodies never change.
  cls.def_property_readonly("time", [](const Simulation& s) { return s.world("sim.time").time(); })
      .def_property_readonly("dt", [](const Simulation& s) { return s.world("sim.dt").dt(); })
      .def_property_readonly("steps", [](const Simulation& s) { return s.world("sim.steps").stepCount(); })
      .def_property_readonly("force_evaluations",
                             [](const Simulation& s) { return s.world("sim.force_evaluations").forceEvaluations(); })
      .def_property_readonly("integrator",
                             [](const Simulation& s) {
                               return std::string(integratorName(s.world("sim.integrator").integrator()));
                             })
      .def_property_readonly("substeps",
                             [](const Simulation& s) {
                               s.world("sim.substeps");  // check() may choose more
                               return s.scene().substeps;
                             })
      .def_property_readonly("duration", [](const Simulation& s) { return s.scene().duration; })
      .def_property_readonly("fps", [](const Simulation& s) { return s.scene().view.render.fps; })
      .def_property_readonly("threads", [](const Simulation& s) { return s.world().threads(); })
      .def_property_readonly("name", [](const Simulation& s) { return s.scene().name; })
      .def_property_readonly("step_untried",
                             [](const Simulation& s) {
                               s.world("sim.step_untried");
                               return s.runner().untried();
                             })
      .def_property_readonly("state_hash", [](const Simulation& s) { return stateHash(s.world("sim.state_hash")); })
      .def_property_readonly("body_count", [](const Simulation& s) { return s.world().model().bodies.size(); });
}

// Simulation's bodies: their facts, their state as numpy views (and its setters), faces and measures.
void defineSimulationBodies(py::class_<Simulation>& cls) {
  cls.def("body_info",
          [](const Simulation& s, long body) {
            const BodyInfo& b = s.body(body);
            py::dict d;
            d["name"] = b.name;
            d["first_vertex"] = b.firstVertex;
            d["vertex_count"] = b.vertexCount;
            d["mass"] = b.mass;
            d["rest_volume"] = b.restVolume;
            d["rest_size"] = b.restSize;
            d["open"] = b.open;
            return d;
          })
      .def("positions", [](py::object self, long body) { return bodyRows(self, body, Rows::Positions); },
           py::arg("body") = -1)
      .def("velocities", [](py::object self, long body) { return bodyRows(self, body, Rows::Velocities); },
           py::arg("body") = -1)
      .def("rest_positions", [](py::object self, long body) { return bodyRows(self, body, Rows::Rest); },
           py::arg("body") = -1)
      .def(
          "masses",
          [](py::object self, long body) {
            const Simulation& s = self.cast<const Simulation&>();
            const Range r = s.range(body);
            py::array_t<double> view({static_cast<py::ssize_t>(r.count)}, {static_cast<py::ssize_t>(sizeof(double))},
                                     s.world().model().mass.data() + r.first, self);
            py::detail::array_proxy(view.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
            return view;
          },
          py::arg("body") = -1)
      .def("set_positions", [](Simulation& s, py::handle a, long body) { s.setRows(a, body, true); },
           py::arg("value"), py::arg("body") = -1)
      .def("set_velocities", [](Simulation& s, py::handle a, long body) { s.setRows(a, body, false); },
           py::arg("value"), py::arg("body") = -1)
      .def("faces",
           [](const Simulation& s, long body) {
             const Model& model = s.world().model();
             const BodyInfo& b = s.body(body);
             py::array_t<uint32_t> out({static_cast<py::ssize_t>(b.faceCount), py::ssize_t{3}});
             auto o = out.mutable_unchecked<2>();
             for (uint32_t f = 0; f < b.faceCount; ++f) {
               for (int k = 0; k < 3; ++k) o(f, k) = model.faces[b.firstFace + f][static_cast<std::size_t>(k)] - b.firstVertex;
             }
             return out;
           })
      .def("mesh_order",
           [](const Simulation& s, long body) {
             const BodyInfo& b = s.body(body);
             py::array_t<uint32_t> out(static_cast<py::ssize_t>(b.modelVertex.size()));
             auto o = out.mutable_unchecked<1>();
             for (std::size_t k = 0; k < b.modelVertex.size(); ++k) {
               o(static_cast<py::ssize_t>(k)) = b.modelVertex[k] - b.firstVertex;
             }
             return out;
           })
      .def("measures", [](const Simulation& s, long body) {
        s.body(body);
        const World& world = s.world("measures()");
        py::dict d = measuresDict(measureBody(world, static_cast<uint32_t>(body)));
        d["contacts"] = touchingVertices(world, static_cast<uint32_t>(body));
        return d;
      });
}

// The Simulation class (springy.load's result).
void defineSimulation(py::module_& m) {
  py::class_<Simulation> cls(m, "Simulation");
  defineSimulationRuns(cls);
  defineSimulationProperties(cls);
  defineSimulationBodies(cls);
}

// The commands that draw or study: render_video, frames and study, as the command line runs them.
void defineCommands(py::module_& m) {
  m.def(
      "render_video",
      [](const std::vector<std::string>& scenes, const std::string& output, const std::vector<std::string>& sets,
         const std::map<std::string, std::string>& options, std::optional<int> width, std::optional<int> height,
         std::optional<double> fps, std::optional<int> crf, bool overlay, bool shadows, bool antialias) {
        RenderOptions o;
        o.scenes = scenes;
        o.output = output;
        o.run = runOptionsOf(sets, options);
        o.render = renderOverridesOf(width, height, fps, overlay, shadows, antialias);
        o.render.crf = crf;
        runCommand("springy render", [&] { return runRender(o); });
      },
      py::arg("scenes"), py::arg("output"), py::arg("sets"), py::arg("options"), py::arg("width"), py::arg("height"),
      py::arg("fps"), py::arg("crf"), py::arg("overlay"), py::arg("shadows"), py::arg("antialias"));
  m.def(
      "frames",
      [](const std::vector<std::string>& scenes, const std::string& output, const std::string& times, bool sheet,
         bool sheetOnly, const std::vector<std::string>& sets, const std::map<std::string, std::string>& options,
         std::optional<int> width, std::optional<int> height, bool overlay, bool shadows, bool antialias) {
        FramesOptions o;
        o.scenes = scenes;
        o.output = output;
        o.times = times;
        o.sheet = sheet;
        o.sheetOnly = sheetOnly;
        o.run = runOptionsOf(sets, options);
        o.render = renderOverridesOf(width, height, std::nullopt, overlay, shadows, antialias);
        runCommand("springy frames", [&] { return runFrames(o); });
      },
      py::arg("scenes"), py::arg("output"), py::arg("times"), py::arg("sheet"), py::arg("sheet_only"),
      py::arg("sets"), py::arg("options"), py::arg("width"), py::arg("height"), py::arg("overlay"),
      py::arg("shadows"), py::arg("antialias"));
  m.def(
      "study",
      [](const std::string& kind, const std::string& output, const std::vector<std::string>& scenes, bool quick,
         const std::string& repeats, std::optional<std::string> maxDuration) {
        // KIND, --repeats and --max-duration from their text, as the command line reads them (run/options.h).
        StudyOptions o;
        o.kind = studyKind(kind);
        o.output = output;
        o.scenes = scenes;
        o.quick = quick;
        o.repeats = studyRepeats(repeats);
        if (maxDuration) o.maxDuration = studyMaxDuration(*maxDuration);
        runCommand("springy study " + kind, [&] { return runStudy(o); });
      },
      py::arg("kind"), py::arg("output"), py::arg("scenes"), py::arg("quick"), py::arg("repeats"),
      py::arg("max_duration"));
}

// The tables Python reads: the integrators' names and the run options.
void defineTables(py::module_& m) {
  m.def("integrators", [] { return integratorNames(); });
  // The run options' table (run/options.h): what load() and the commands take, as the command line does.
  m.def("run_options", [] {
    py::list rows;
    for (const RunOption& o : runOptionTable()) {
      py::dict row;
      row["name"] = o.name;
      row["flag"] = o.flag;
      row["value"] = o.value;
      row["help"] = o.help;
      row["criterion"] = o.group == RunOption::Group::Criteria;
      row["repeatable"] = o.repeatable;
      rows.append(row);
    }
    return rows;
  });
}

}  // namespace
}  // namespace springy

PYBIND11_MODULE(_springy, m) {
  using namespace springy;
  m.doc() = "springy's C++ core (use the springy package: docs/python.md)";
  defineErrors(m);
  defineSimulation(m);
  defineCommands(m);
  defineTables(m);
}
