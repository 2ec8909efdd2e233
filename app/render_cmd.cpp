// `springy render` and `springy frames`: scenes to MP4 videos and PNG stills.
//
// Video pipeline, three threads joined by bounded queues of recycled buffers (memory stays
// bounded, nothing is allocated per frame):
//   simulation thread  advances the World frame by frame and copies the positions into a
//                      FrameSnapshot (the World is not thread-safe; only this thread touches it);
//   main thread        owns the GL context: draws each snapshot and reads the pixels back;
//   encoding thread    converts to yuv420p and encodes.
// Each stage works on a different frame, so the wall time approaches the slowest stage rather
// than the sum. The frames are exactly those of the serial order (simulate k, draw k, encode k):
// the simulation is deterministic and the queues are FIFO. SPRINGY_RENDER_SERIAL=1 runs that
// serial order on one thread (the reference the tests compare against).
// SPRINGY_RENDER_PROFILE=1 also prints the time of each render pass (glFinish after each);
// SPRINGY_RENDER_AA=msaa anti-aliases with 4x MSAA instead of FXAA (for comparisons).
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <iostream>
#include <thread>

#include "app/atomic_file.h"
#include "app/bounded_queue.h"
#include "app/commands.h"
#include "app/progress.h"
#include "app/scene_view.h"
#include "render/image.hpp"
#include "render/video_encoder.hpp"
#include "sim/error.h"

namespace springy {
namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

void applyRenderOverrides(SceneDesc& scene, const RenderOverrides& o) {
  RenderDesc& r = scene.render;
  if (o.width) r.width = *o.width;
  if (o.height) r.height = *o.height;
  if (r.width % 2 || r.height % 2 || r.width < 16 || r.height < 16) {
    throw Error("the frame size must be even and at least 16 x 16, got " + std::to_string(r.width) + " x " +
                std::to_string(r.height));
  }
  if (o.fps) r.fps = *o.fps;
  if (!(r.fps >= 1.0 && r.fps <= 240.0)) throw Error("--fps must be between 1 and 240");
  if (o.crf) r.crf = *o.crf;
  if (o.preset) r.preset = *o.preset;
  if (o.noOverlay) r.overlay = false;
  if (o.noShadows) r.shadows = false;
  if (o.noAntialias) r.antialias = false;
}

// Output path for one scene: OUT itself for a single scene and a file name, else OUT/stem.ext.
std::string outputFor(const std::string& scenePath, const std::string& out, std::size_t sceneCount,
                      const std::string& extension) {
  namespace fs = std::filesystem;
  const std::string stem = fs::path(scenePath).stem().string();
  if (out.empty()) return stem + extension;
  const bool isDir = fs::is_directory(out) || out.back() == '/' || sceneCount > 1;
  if (!isDir) return out;
  fs::create_directories(out);
  return (fs::path(out) / (stem + extension)).string();
}

struct Frame {
  std::vector<uint8_t> rgba;  // bottom-up rows, as glReadPixels gives them
};

bool envFlag(const char* name) {
  const char* v = std::getenv(name);
  return v && *v && std::string(v) != "0";
}

// Joins a thread when leaving scope, also by an exception (after the queues were closed).
struct Joiner {
  std::thread& t;
  ~Joiner() {
    if (t.joinable()) t.join();
  }
};

int renderOne(const std::string& path, const std::string& outPath, const RenderOptions& options) {
  SceneDesc scene = loadSceneWith(path, options.overrides);
  applyRenderOverrides(scene, options.render);
  AtomicFile output(outPath);  // an unwritable target fails here, before any simulation
  World world = makeWorld(scene, options.overrides);
  Monitor monitor(world);
  render::RenderSettings rs = renderSettingsOf(scene);
  rs.profilePasses = envFlag("SPRINGY_RENDER_PROFILE");
  if (const char* aa = std::getenv("SPRINGY_RENDER_AA"); aa && std::string(aa) == "msaa")
    rs.antiAliasMethod = render::AntiAliasMethod::Msaa4;
  SceneView view(scene, world, rs);

  render::VideoEncoder::setLibraryLogging(false);
  render::VideoEncoder encoder;
  render::VideoSettings vs;
  vs.width = scene.render.width;
  vs.height = scene.render.height;
  vs.fps = static_cast<int>(std::lround(scene.render.fps));
  vs.crf = scene.render.crf;
  vs.preset = scene.render.preset;
  if (const char* t = std::getenv("SPRINGY_X264_THREADS")) vs.threads = std::atoi(t);
  encoder.open(output.temporaryPath(), vs);

  const long frames = std::max(1L, std::lround(scene.duration * scene.render.fps));
  const std::size_t bytes = static_cast<std::size_t>(scene.render.width) * static_cast<std::size_t>(scene.render.height) * 4;
  const bool serial = envFlag("SPRINGY_RENDER_SERIAL");

  Progress progress(scene.name, frames);
  std::atomic<long long> simNs{0};
  auto simulate = [&](long k) {
    const auto t0 = Clock::now();
    std::optional<Failure> f = advanceTo(world, monitor, static_cast<double>(k) / scene.render.fps);
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

  const auto wallStart = Clock::now();
  std::optional<Failure> failure;
  bool interruptedRun = false;
  if (serial) {
    FrameSnapshot snapshot;
    Frame f{std::vector<uint8_t>(bytes)};
    for (long k = 0; k < frames; ++k) {
      if (interrupted()) {
        interruptedRun = true;
        break;
      }
      failure = simulate(k);
      if (failure) break;
      takeSnapshot(world, snapshot);
      view.draw(snapshot);
      view.renderer().readPixels(f.rgba, render::RowOrder::BottomUp);
      encoder.writeFrame(f.rgba, render::RowOrder::BottomUp);
      report(k + 1);
    }
  } else {
    BoundedQueue<FrameSnapshot> freeSnapshots(3), snapshots(3);
    for (int i = 0; i < 3; ++i) freeSnapshots.push(FrameSnapshot{});
    BoundedQueue<Frame> empty(4), full(3);
    for (int i = 0; i < 4; ++i) empty.push(Frame{std::vector<uint8_t>(bytes)});

    std::exception_ptr simError, encodeError;
    std::atomic<bool> simInterrupted{false};
    std::thread simThread([&] {
      try {
        for (long k = 0; k < frames; ++k) {
          if (interrupted()) {
            simInterrupted = true;
            break;
          }
          if ((failure = simulate(k))) break;
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
    interruptedRun = simInterrupted;
    if (simError) std::rethrow_exception(simError);
    if (encodeError) std::rethrow_exception(encodeError);
  }
  progress.finish();
  if (interruptedRun) {
    std::cerr << "springy render: interrupted; " << output.target() << " not written\n";
    return 130;
  }
  if (failure) {
    std::cerr << "springy render: " << path << ": " << failure->message << "\n"
              << "springy render: stopped; " << output.target() << " not written (no video of an unstable run)\n";
    return 1;
  }
  encoder.finish();
  output.commit();

  const double wall = msSince(wallStart) / 1000.0;
  const auto& rt = view.renderer().timings();
  const render::EncodeTimings et = encoder.timings();
  const auto size = std::filesystem::file_size(outPath);
  const double n = static_cast<double>(frames);
  std::printf("%s -> %s: %ld frames, %.2f s of %dx%d video at %g fps (%s), %.1f MB\n", path.c_str(), outPath.c_str(),
              frames, n / scene.render.fps, scene.render.width, scene.render.height,
              scene.render.fps, encoder.codecName().c_str(), static_cast<double>(size) / 1e6);
  std::printf("  wall %.1f s (%.1f frames/s); per frame: simulate %.1f ms, render %.1f ms, read back %.1f ms, "
              "convert %.1f ms, encode %.1f ms (%s)\n",
              wall, n / wall, static_cast<double>(simNs.load()) / 1e6 / n,
              rt.totalRenderMs / static_cast<double>(rt.frames), rt.totalReadbackMs / static_cast<double>(rt.readbacks),
              et.totalConvertMs / static_cast<double>(et.frames), et.totalEncodeMs / static_cast<double>(et.frames),
              serial ? "one thread, in sequence" : "simulate, render + read back, convert + encode overlap on 3 threads");
  if (rs.profilePasses) {
    std::printf("  render passes per frame (glFinish after each):");
    for (std::size_t p = 0; p < render::kRenderPassCount; ++p)
      std::printf("%s %s %.2f ms", p ? "," : "", render::passName(static_cast<render::RenderPass>(p)),
                  rt.passMs[p] / static_cast<double>(rt.frames));
    std::printf("\n");
  }
  return 0;
}

std::vector<double> parseTimes(const std::string& list) {
  std::vector<double> times;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string item = list.substr(start, comma - start);
    try {
      std::size_t used = 0;
      const double t = std::stod(item, &used);
      if (used != item.size() || !(t >= 0.0)) throw std::invalid_argument(item);
      times.push_back(t);
    } catch (const std::exception&) {
      throw Error("--times: '" + item + "' is not a time in seconds (expected e.g. 0,0.5,1.5)");
    }
    start = comma + 1;
  }
  std::sort(times.begin(), times.end());
  return times;
}

int framesOne(const std::string& path, const FramesOptions& options) {
  namespace fs = std::filesystem;
  SceneDesc scene = loadSceneWith(path, options.overrides);
  applyRenderOverrides(scene, options.render);
  std::vector<double> times = options.times.empty() ? std::vector<double>{} : parseTimes(options.times);
  if (times.empty()) {
    for (int i = 0; i < 8; ++i) times.push_back(scene.duration * i / 7.0);  // eight evenly spaced stills
  }
  fs::create_directories(options.output);
  const std::string stem = fs::path(path).stem().string();
  World world = makeWorld(scene, options.overrides);
  Monitor monitor(world);
  SceneView view(scene, world, renderSettingsOf(scene));
  std::vector<render::Image> stills;
  std::vector<std::string> labels;
  const double frame = 1.0 / scene.render.fps;
  for (double t : times) {
    // Step frame by frame so the monitor sees the run as densely as a video would.
    while (world.time() < t - 0.5 * world.dt()) {
      const double next = std::min(t, world.time() + frame);
      if (std::optional<Failure> failure = advanceTo(world, monitor, next)) {
        std::cerr << "springy frames: " << path << ": " << failure->message << "\n";
        return 1;
      }
      if (interrupted()) return 130;
    }
    view.draw(world);
    render::Image image = view.renderer().readImage();
    char label[64];
    std::snprintf(label, sizeof label, "t = %.2f s", t);
    if (!options.sheetOnly) {
      char name[64];
      std::snprintf(name, sizeof name, "_t%06.2f.png", t);
      const std::string file = (fs::path(options.output) / (stem + name)).string();
      AtomicFile out(file);
      render::writePng(out.temporaryPath(), image);
      out.commit();
      std::printf("%s\n", file.c_str());
    }
    stills.push_back(std::move(image));
    labels.push_back(label);
  }
  if (options.sheet || options.sheetOnly) {
    render::ContactSheetOptions sheet;
    sheet.columns = std::min<int>(4, static_cast<int>(stills.size()));
    const std::string file = (fs::path(options.output) / (stem + "_sheet.png")).string();
    AtomicFile out(file);
    render::writePng(out.temporaryPath(), render::makeContactSheet(stills, labels, sheet));
    out.commit();
    std::printf("%s\n", file.c_str());
  }
  return 0;
}

}  // namespace

int runRender(const RenderOptions& options) {
  int status = 0;
  for (const std::string& path : options.scenes) {
    try {
      const int s = renderOne(path, outputFor(path, options.output, options.scenes.size(), ".mp4"), options);
      if (s == 130) return s;
      status = std::max(status, s);
    } catch (const std::exception& e) {
      std::cerr << "springy render: " << e.what() << "\n";
      status = 1;
    }
  }
  return status;
}

int runFrames(const FramesOptions& options) {
  int status = 0;
  for (const std::string& path : options.scenes) {
    try {
      const int s = framesOne(path, options);
      if (s == 130) return s;
      status = std::max(status, s);
    } catch (const std::exception& e) {
      std::cerr << "springy frames: " << e.what() << "\n";
      status = 1;
    }
  }
  return status;
}

}  // namespace springy
