#include "app/frame_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "app/atomic_file.h"
#include "app/bounded_queue.h"
#include "app/progress.h"
#include "render/error.h"
#include "sim/error.h"

namespace springy {
namespace {

using Clock = std::chrono::steady_clock;

bool envFlag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::string(v) != "0";
}

struct Frame {
  std::vector<uint8_t> rgba;  // bottom-up rows, as glReadPixels gives them
};

// Joins a thread when leaving scope, also by an exception (after the queues were closed).
struct Joiner {
  std::thread& t;
  ~Joiner() {
    if (t.joinable()) t.join();
  }
};

struct Closer {
  BoundedQueue<FrameSnapshot>& a;
  BoundedQueue<FrameSnapshot>& b;
  BoundedQueue<Frame>& c;
  ~Closer() {
    a.close();
    b.close();
    c.close();
  }
};

}  // namespace

namespace {

// SPRINGY_X264_THREADS: a whole number from 0 (the codec's default) to x264's most, 128
// (X264_THREAD_MAX); anything else is refused, never passed on for the codec to clamp or ignore.
int x264ThreadsOf(const std::string& text) {
  const bool digits = !text.empty() && text.size() <= 3 &&
                      std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || std::stoi(text) > 128) {
    throw Error("SPRINGY_X264_THREADS='" + text +
                "': must be a whole number of encoder threads from 0 (x264's default: every core) to 128; unset it "
                "for springy's choice");
  }
  return std::stoi(text);
}

}  // namespace

RenderEnvironment RenderEnvironment::read() {
  RenderEnvironment env;
  env.serial = envFlag("SPRINGY_RENDER_SERIAL");
  env.profilePasses = envFlag("SPRINGY_RENDER_PROFILE");
  if (const char* aa = std::getenv("SPRINGY_RENDER_AA"); aa && std::string(aa) == "msaa") env.msaa = true;
  if (const char* t = std::getenv("SPRINGY_X264_THREADS")) env.x264Threads = x264ThreadsOf(t);
  return env;
}

namespace {

// The stages' shared parts: the simulation of a frame (timed), and the progress line.
class Stages {
 public:
  Stages(Run& run, SceneView& view, FrameSink& sink, const FramePipelineSettings& settings,
         const render::VideoEncoder* encoder)
      : run_(run), view_(view), sink_(sink), encoder_(encoder), progress_(settings.label, run.frames()),
        bytes_(static_cast<std::size_t>(settings.width) * static_cast<std::size_t>(settings.height) * 4) {}

  // Frame k's simulation: the run's start (k = 0) or its next frame. False when the run stopped
  // (a failure, a signal); `interrupted` says which.
  bool simulate(long k) {
    const auto t0 = Clock::now();
    if (k == 0) {
      run_.start();
    } else if (!interrupted()) {
      run_.nextFrame();
    }
    simNs_ += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
    interrupted_ = interrupted_ || interrupted();
    return !interrupted_ && !run_.failure();
  }
  // Frame k drawn and read back into `rgba`.
  void draw(const FrameSnapshot& snapshot, std::vector<uint8_t>& rgba) {
    view_.draw(snapshot);
    view_.renderer().readPixels(rgba, render::RowOrder::BottomUp);
  }
  void write(long k, const std::vector<uint8_t>& rgba) {
    try {
      sink_.write(k, rgba);
    } catch (const render::RenderError& e) {
      throw EncodeError(e.what());
    }
  }
  void report(long done) {
    const auto& rt = view_.renderer().timings();
    const double simMs = static_cast<double>(simNs_.load()) / 1e6;
    char detail[160];
    int n = std::snprintf(detail, sizeof detail, "sim %.1f, render %.1f frames/s",
                          1000.0 * static_cast<double>(done) / std::max(simMs, 1e-9),
                          1000.0 * static_cast<double>(rt.frames) / std::max(rt.totalRenderMs, 1e-9));
    if (encoder_) {
      const render::EncodeTimings et = encoder_->timings();
      std::snprintf(detail + n, sizeof detail - static_cast<std::size_t>(n), ", encode %.1f frames/s",
                    1000.0 * static_cast<double>(et.frames) / std::max(et.totalEncodeMs + et.totalConvertMs, 1e-9));
    }
    progress_.update(done, detail);
  }
  std::size_t bytes() const { return bytes_; }
  long frames() const { return run_.frames(); }
  World& world() { return run_.world(); }
  FramePipelineResult result() {
    progress_.finish();
    return {interrupted_, static_cast<double>(simNs_.load()) / 1e6};
  }
  std::atomic<bool> interrupted_{false};

 private:
  Run& run_;
  SceneView& view_;
  FrameSink& sink_;
  const render::VideoEncoder* encoder_;
  Progress progress_;
  std::size_t bytes_;
  std::atomic<long long> simNs_{0};
};

// The reference order, on one thread: simulate k, draw k, write k.
FramePipelineResult runSerial(Stages& stages) {
  FrameSnapshot snapshot;
  std::vector<uint8_t> rgba(stages.bytes());
  for (long k = 0; k < stages.frames(); ++k) {
    if (!stages.simulate(k)) break;
    takeSnapshot(stages.world(), snapshot);
    stages.draw(snapshot, rgba);
    stages.write(k, rgba);
    stages.report(k + 1);
  }
  stages.simulate(stages.frames());  // the last frame is checked too
  return stages.result();
}

FramePipelineResult runThreaded(Stages& stages) {
  BoundedQueue<FrameSnapshot> freeSnapshots(3), snapshots(3);
  for (int i = 0; i < 3; ++i) freeSnapshots.push(FrameSnapshot{});
  BoundedQueue<Frame> empty(4), full(3);
  for (int i = 0; i < 4; ++i) empty.push(Frame{std::vector<uint8_t>(stages.bytes())});
  std::exception_ptr simError, encodeError;
  // Simulation: frame k's snapshot into `snapshots`, and the last frame checked.
  std::thread simThread([&] {
    try {
      for (long k = 0; k <= stages.frames(); ++k) {
        if (!stages.simulate(k) || k == stages.frames()) break;
        FrameSnapshot s;
        if (!freeSnapshots.pop(s)) break;  // the renderer stopped
        takeSnapshot(stages.world(), s);
        if (!snapshots.push(std::move(s))) break;
      }
    } catch (...) {
      simError = std::current_exception();
    }
    snapshots.close();  // the renderer drains what is left, then stops
  });
  // Writing: the `full` frames, in order, then back to `empty`.
  std::thread encodeThread([&] {
    Frame f;
    try {
      for (long k = 0; full.pop(f); ++k) {
        stages.write(k, f.rgba);
        empty.push(std::move(f));
      }
    } catch (...) {
      encodeError = std::current_exception();
      empty.close();  // unblock the renderer
    }
  });
  {
    // Declared after the threads: on the way out (also by an exception) the queues are closed
    // first, so both threads finish, then they are joined.
    Joiner joinSim{simThread}, joinEncode{encodeThread};
    Closer closer{freeSnapshots, snapshots, full};
    // Drawing, on this thread: each snapshot drawn and read back into an `empty` frame.
    FrameSnapshot s;
    long done = 0;
    while (snapshots.pop(s)) {
      Frame f;
      if (!empty.pop(f)) break;  // the writer failed
      stages.draw(s, f.rgba);
      freeSnapshots.push(std::move(s));
      if (!full.push(std::move(f))) break;
      stages.report(++done);
    }
  }
  if (simError) std::rethrow_exception(simError);
  if (encodeError) std::rethrow_exception(encodeError);
  return stages.result();
}

}  // namespace

FramePipelineResult runFramePipeline(Run& run, SceneView& view, FrameSink& sink, const FramePipelineSettings& settings,
                                     const render::VideoEncoder* timings) {
  Stages stages(run, view, sink, settings, timings);
  return settings.serial ? runSerial(stages) : runThreaded(stages);
}

}  // namespace springy
