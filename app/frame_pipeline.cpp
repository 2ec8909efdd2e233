#include "app/frame_pipeline.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <thread>
#include <vector>

#include "app/atomic_file.h"
#include "app/bounded_queue.h"
#include "app/progress.h"
#include "app/runner.h"
#include "render/error.h"

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

}  // namespace

RenderEnvironment RenderEnvironment::read() {
  RenderEnvironment env;
  env.serial = envFlag("SPRINGY_RENDER_SERIAL");
  env.profilePasses = envFlag("SPRINGY_RENDER_PROFILE");
  if (const char* aa = std::getenv("SPRINGY_RENDER_AA"); aa && std::string(aa) == "msaa") env.msaa = true;
  if (const char* t = std::getenv("SPRINGY_X264_THREADS")) env.x264Threads = std::atoi(t);
  return env;
}

FramePipelineResult runFramePipeline(World& world, Monitor& monitor, SceneView& view, render::VideoEncoder& encoder,
                                     const FramePipelineSettings& settings) {
  const long frames = settings.frames;
  const std::size_t bytes =
      static_cast<std::size_t>(settings.width) * static_cast<std::size_t>(settings.height) * 4;

  Progress progress(settings.label, frames);
  std::atomic<long long> simNs{0};
  auto simulate = [&](long k) {
    const auto t0 = Clock::now();
    std::optional<Failure> f = advanceTo(world, monitor, static_cast<double>(k) / settings.fps);
    simNs += std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now() - t0).count();
    return f;
  };
  auto report = [&](long done) {
    const auto& rt = view.renderer().timings();
    const render::EncodeTimings et = encoder.timings();
    const double simMs = static_cast<double>(simNs.load()) / 1e6;
    char detail[160];
    std::snprintf(detail, sizeof detail, "sim %.1f, render %.1f, encode %.1f frames/s",
                  1000.0 * static_cast<double>(done) / std::max(simMs, 1e-9),
                  1000.0 * static_cast<double>(rt.frames) / std::max(rt.totalRenderMs, 1e-9),
                  1000.0 * static_cast<double>(et.frames) / std::max(et.totalEncodeMs + et.totalConvertMs, 1e-9));
    progress.update(done, detail);
  };

  FramePipelineResult result;
  if (settings.serial) {
    FrameSnapshot snapshot;
    Frame f{std::vector<uint8_t>(bytes)};
    for (long k = 0; k < frames; ++k) {
      if (interrupted()) {
        result.interrupted = true;
        break;
      }
      result.failure = simulate(k);
      if (result.failure) break;
      takeSnapshot(world, snapshot);
      view.draw(snapshot);
      view.renderer().readPixels(f.rgba, render::RowOrder::BottomUp);
      try {
        encoder.writeFrame(f.rgba, render::RowOrder::BottomUp);
      } catch (const render::RenderError& e) {
        throw EncodeError(e.what());
      }
      report(k + 1);
    }
  } else {
    BoundedQueue<FrameSnapshot> freeSnapshots(3), snapshots(3);
    for (int i = 0; i < 3; ++i) freeSnapshots.push(FrameSnapshot{});
    BoundedQueue<Frame> empty(4), full(3);
    for (int i = 0; i < 4; ++i) empty.push(Frame{std::vector<uint8_t>(bytes)});

    std::exception_ptr simError, encodeError;
    std::atomic<bool> simInterrupted{false};
    // Simulation: frame k's snapshot into `snapshots`.
    std::thread simThread([&] {
      try {
        for (long k = 0; k < frames; ++k) {
          if (interrupted()) {
            simInterrupted = true;
            break;
          }
          if ((result.failure = simulate(k))) break;
          FrameSnapshot s;
          if (!freeSnapshots.pop(s)) break;  // the renderer stopped
          takeSnapshot(world, s);
          if (!snapshots.push(std::move(s))) break;
        }
      } catch (...) {
        simError = std::current_exception();
      }
      snapshots.close();  // the renderer drains what is left, then stops
    });
    // Encoding: the `full` frames, in order, then back to `empty`.
    std::thread encodeThread([&] {
      Frame f;
      try {
        while (full.pop(f)) {
          encoder.writeFrame(f.rgba, render::RowOrder::BottomUp);
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
      struct Closer {
        BoundedQueue<FrameSnapshot>& a;
        BoundedQueue<FrameSnapshot>& b;
        BoundedQueue<Frame>& c;
        ~Closer() {
          a.close();
          b.close();
          c.close();
        }
      } closer{freeSnapshots, snapshots, full};
      // Drawing, on this thread: each snapshot drawn and read back into an `empty` frame.
      FrameSnapshot s;
      long done = 0;
      while (snapshots.pop(s)) {
        view.draw(s);
        freeSnapshots.push(std::move(s));
        Frame f;
        if (!empty.pop(f)) break;  // the encoder failed
        view.renderer().readPixels(f.rgba, render::RowOrder::BottomUp);
        if (!full.push(std::move(f))) break;
        report(++done);
      }
    }
    result.interrupted = simInterrupted;
    if (simError) std::rethrow_exception(simError);
    if (encodeError) {
      try {
        std::rethrow_exception(encodeError);
      } catch (const render::RenderError& e) {
        throw EncodeError(e.what());
      }
    }
  }
  progress.finish();
  result.simulateMs = static_cast<double>(simNs.load()) / 1e6;
  return result;
}

}  // namespace springy
