// `springy render` and `springy frames`: scenes to MP4 videos and PNG stills.
//
// A video's frames go through the three-thread pipeline of app/frame_pipeline.h, which also
// lists the environment variables `springy render` reads (RenderEnvironment).
#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <functional>
#include <iostream>
#include <thread>

#include "app/atomic_file.h"
#include "app/commands.h"
#include "app/frame_pipeline.h"
#include "app/scene_view.h"
#include "render/error.h"
#include "render/image.h"
#include "render/video_encoder.h"
#include "run/load.h"
#include "sim/error.h"
#include "sim/trajectory.h"

namespace springy {

void applyRenderOverrides(SceneDesc& scene, const RenderOverrides& o) {
  RenderDesc& r = scene.view.render;
  auto size = [](const char* option, int value, int most) {
    if (value < 16 || value > most || value % 2) {
      throw Error(std::string(option) + " " + std::to_string(value) + ": must be even and between 16 and " +
                  std::to_string(most) + " (the video is yuv420p)");
    }
    return value;
  };
  if (o.width) r.width = size("--width", *o.width, 7680);
  if (o.height) r.height = size("--height", *o.height, 4320);
  if (o.fps) {
    if (!(*o.fps >= 1.0 && *o.fps <= 240.0)) {
      char text[64];
      std::snprintf(text, sizeof text, "%g", *o.fps);
      throw Error(std::string("--fps ") + text + ": must be between 1 and 240 frames per second");
    }
    r.fps = *o.fps;
  }
  if (o.crf) {
    if (*o.crf < 0 || *o.crf > 51) throw Error("--crf " + std::to_string(*o.crf) + ": must be between 0 and 51");
    r.crf = *o.crf;
  }
  if (o.preset) r.preset = *o.preset;
  if (o.noOverlay) r.overlay = false;
  if (o.noShadows) r.shadows = false;
  if (o.noAntialias) r.antialias = false;
}

std::function<void(SceneDesc&)> renderEdit(const RenderOverrides& overrides) {
  return [&overrides](SceneDesc& scene) {
    applyRenderOverrides(scene, overrides);
    checkCamera(scene);
  };
}

render::VideoSettings videoSettingsOf(const SceneDesc& scene, const RenderEnvironment& env) {
  render::VideoSettings vs;
  vs.width = scene.view.render.width;
  vs.height = scene.view.render.height;
  vs.fps = scene.view.render.fps;
  vs.crf = scene.view.render.crf;
  vs.preset = scene.view.render.preset;
  // On two cores or fewer one x264 thread: more take the cores from llvmpipe's rasterising
  // threads, and the drawing is the slowest stage (docs/benchmarks.md: 52.0 -> 55.3 frames/s at
  // 720p, 23.6 -> 25.2 at 1080p on 2 cores). With more cores, x264's own choice.
  vs.threads = std::thread::hardware_concurrency() <= 2 ? 1 : 0;
  if (env.x264Threads) vs.threads = *env.x264Threads;
  return vs;
}

namespace {

using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t) { return std::chrono::duration<double, std::milli>(Clock::now() - t).count(); }

bool endsWithMp4(const std::string& name) {
  if (name.size() < 4) return false;
  std::string ext = name.substr(name.size() - 4);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".mp4";
}

std::string stemOf(const std::string& path) { return std::filesystem::path(path).stem().string(); }

// The video each scene is written to, checked before any work. -o names a directory (it exists,
// or ends in '/', or there are several scenes) that gets SCENE.mp4 for each scene, or, for one
// scene, a file that must end in .mp4: anything else (`-o scene.toml`, a typo) would be
// replaced by a video. Throws springy::Error.
std::vector<std::string> videoOutputs(const RenderOptions& options) {
  namespace fs = std::filesystem;
  const std::string& out = options.output;
  std::vector<std::string> outputs;
  const bool several = options.scenes.size() > 1;
  bool directory = !out.empty() && (isDirectory(out) || out.back() == '/');
  if (!out.empty() && !directory) {
    if (several) {
      if (endsWithMp4(out)) {
        throw Error("-o " + out + ": " + std::to_string(options.scenes.size()) +
                    " scenes make one video each: give a directory, not a file name");
      }
      struct stat st {};
      if (::stat(out.c_str(), &st) == 0) {
        throw Error("-o " + out + ": is not a directory (" + std::to_string(options.scenes.size()) +
                    " scenes make one video each)");
      }
      directory = true;
    } else if (!endsWithMp4(out)) {
      throw Error("-o " + out + ": a video's name must end in .mp4 (or name a directory: end it with '/')");
    }
  }
  if (directory) makeDirectories(out, "-o");
  for (const std::string& scene : options.scenes) {
    const std::string name = stemOf(scene) + ".mp4";
    outputs.push_back(out.empty() ? name : directory ? (fs::path(out) / name).string() : out);
    // A name springy made up replaces only a video of springy's; one the user gave, what it names.
    // Never an input, which says so first (a scene's error shows when the scene is run).
    if (out.empty() || directory) {
      std::vector<std::string> inputs;
      try {
        inputs = sceneInputFiles(scene, options.run.sets);
      } catch (const Error&) {  // the scene's own error shows when it is run
      }
      refuseInputs(outputs.back(), inputs);
      refuseUnlessMarked(outputs.back(), render::kSpringyMark, render::kMarkSearchBytes,
                         "render names a scene's video SCENE.mp4 itself (-o FILE.mp4 names the file to replace)");
    }
  }
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (outputs[i] == outputs[j]) {
        throw Error(options.scenes[j] + " and " + options.scenes[i] + " would both be written to " + outputs[i]);
      }
    }
  }
  return outputs;
}

const char* signalName(int signal) {
  switch (signal) {
    case SIGINT: return "SIGINT";
    case SIGTERM: return "SIGTERM";
    case SIGHUP: return "SIGHUP";
    default: return "a signal";
  }
}

// The encoder's errors name the temporary file; the user knows the target.
[[noreturn]] void videoFailed(const AtomicFile& output, const std::exception& e) {
  throw Error(output.target() + ": writing the video failed: " + e.what() + " (" + output.target() +
              " left as it was)");
}

// The closing summary: the video, then the time per frame of each stage.
void printSummary(const std::string& path, const std::string& outPath, const SceneDesc& scene, long frames,
                  double wallSeconds, const FramePipelineResult& run, const render::RenderTimings& rt,
                  const render::VideoEncoder& encoder, const RenderEnvironment& env) {
  const render::EncodeTimings et = encoder.timings();
  struct stat st {};
  const double size = ::stat(outPath.c_str(), &st) == 0 ? static_cast<double>(st.st_size) : 0.0;
  const double n = static_cast<double>(frames);
  std::printf("%s -> %s: %ld frames, %.2f s of %dx%d video at %g fps (%s), %.1f MB\n", path.c_str(), outPath.c_str(),
              frames, n / scene.view.render.fps, scene.view.render.width, scene.view.render.height,
              scene.view.render.fps, encoder.codecName().c_str(), size / 1e6);
  std::printf("  wall %.1f s (%.1f frames/s); per frame: simulate %.1f ms, render %.1f ms, read back %.1f ms, "
              "convert %.1f ms, encode %.1f ms (%s)\n",
              wallSeconds, n / wallSeconds, run.simulateMs / n,
              rt.totalRenderMs / static_cast<double>(rt.frames), rt.totalReadbackMs / static_cast<double>(rt.readbacks),
              et.totalConvertMs / static_cast<double>(et.frames), et.totalEncodeMs / static_cast<double>(et.frames),
              env.serial ? "one thread, in sequence"
                         : "simulate, render + read back, convert + encode overlap on 3 threads");
  if (env.profilePasses) {
    std::printf("  render passes per frame (glFinish after each):");
    for (std::size_t p = 0; p < render::kRenderPassCount; ++p)
      std::printf("%s %s %.2f ms", p ? "," : "", render::passName(static_cast<render::RenderPass>(p)),
                  rt.passMs[p] / static_cast<double>(rt.frames));
    std::printf("\n");
  }
}

int renderOne(const std::string& path, const std::string& outPath, const RenderOptions& options,
              const RenderEnvironment& env) {
  // A scene that gives no step: the drawn run is the try of the advisor's default step.
  Run run(path, options.run, renderEdit(options.render));
  const SceneDesc& scene = run.scene();
  // An unwritable target fails here, before any simulation; no scene (or a file one reads) is
  // ever written over.
  AtomicFile output(outPath, sceneInputFiles(options.scenes, options.run.sets));
  render::RenderSettings rs = renderSettingsOf(scene);
  rs.profilePasses = env.profilePasses;
  if (env.msaa) rs.antiAliasMethod = render::AntiAliasMethod::Msaa4;
  for (;;) {
    SceneView view(scene, run.world(), rs);
    render::VideoEncoder::setLibraryLogging(false);
    render::VideoEncoder encoder;
    try {
      encoder.open(output.temporaryPath(), videoSettingsOf(scene, env));
    } catch (const render::RenderError& e) {
      videoFailed(output, e);
    }
    FramePipelineSettings pipeline{scene.name, scene.view.render.width, scene.view.render.height, env.serial};
    const auto wallStart = Clock::now();
    EncoderSink sink(encoder);
    FramePipelineResult result;
    try {
      result = runFramePipeline(run, view, sink, pipeline, &encoder);
    } catch (const EncodeError& e) {
      videoFailed(output, e);
    }
    if (result.interrupted || interrupted()) {  // also a signal after the last frame was simulated
      std::cerr << "springy render: interrupted by " << signalName(interruptSignal()) << "; " << output.target()
                << " not written\n";
      return interruptedExitStatus();
    }
    if (run.failure() && run.retry()) continue;  // drawn again, into the same temporary file, at the step that passed
    if (run.failure()) {
      std::cerr << "springy render: " << path << ": " << run.failure()->message << "\n"
                << "springy render: stopped; " << output.target() << " not written (no video of an unstable run)\n";
      return 1;
    }
    try {
      encoder.finish();
    } catch (const render::RenderError& e) {
      videoFailed(output, e);
    }
    output.commit();
    printSummary(path, outPath, scene, run.frames(), msSince(wallStart) / 1000.0, result, view.renderer().timings(),
                 encoder, env);
    return 0;
  }
}

// The times of --times, sorted. Each must be finite and within [0, duration]: a time past the end
// (1e9, inf) would simulate for ever.
std::vector<double> parseTimes(const std::string& list, double duration) {
  std::vector<double> times;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    const std::string item = list.substr(start, comma - start);
    double t = 0.0;
    try {
      std::size_t used = 0;
      t = std::stod(item, &used);
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error("--times: '" + item + "' is not a time in seconds (expected e.g. 0,0.5,1.5)");
    }
    if (!std::isfinite(t)) throw Error("--times: '" + item + "' is not a finite time in seconds");
    if (t < 0.0 || t > duration) {
      char limit[64];
      std::snprintf(limit, sizeof limit, "%g", duration);
      throw Error("--times: '" + item + "' is not within the scene's duration, 0 to " + limit +
                  " s (--duration changes it)");
    }
    times.push_back(t);
    start = comma + 1;
  }
  std::sort(times.begin(), times.end());
  return times;
}

// "t = 1.50 s" / "_t001.50": two decimals, or as many more as it takes to tell the times apart,
// so that two stills never get the same file name (one would overwrite the other). The same
// time twice is an error.
int timeDecimals(const std::vector<double>& times) {
  constexpr int kMost = 9;
  for (int decimals = 2; decimals <= kMost; ++decimals) {
    bool distinct = true;
    char a[64], b[64];
    for (std::size_t i = 1; i < times.size() && distinct; ++i) {
      std::snprintf(a, sizeof a, "%.*f", decimals, times[i - 1]);
      std::snprintf(b, sizeof b, "%.*f", decimals, times[i]);
      distinct = std::string(a) != b;
    }
    if (distinct) return decimals;
  }
  for (std::size_t i = 1; i < times.size(); ++i) {
    char a[64], b[64];
    std::snprintf(a, sizeof a, "%.*f", kMost, times[i - 1]);
    std::snprintf(b, sizeof b, "%.*f", kMost, times[i]);
    if (std::string(a) == b) {
      char t0[32], t1[32];
      std::snprintf(t0, sizeof t0, "%.17g", times[i - 1]);
      std::snprintf(t1, sizeof t1, "%.17g", times[i]);
      throw Error(times[i - 1] == times[i] ? "--times: " + std::string(t0) + " is given twice"
                                           : "--times: " + std::string(t0) + " and " + t1 +
                                                 " are too close to tell apart in the stills' file names");
    }
  }
  return kMost;
}

// The still at time t, and the contact sheet, of the scene `stem` in `folder`.
std::string stillFile(const std::string& folder, const std::string& stem, double t, int decimals) {
  char name[64];
  std::snprintf(name, sizeof name, "_t%0*.*f.png", decimals + 4, decimals, t);
  return (std::filesystem::path(folder) / (stem + name)).string();
}
std::string sheetFile(const std::string& folder, const std::string& stem) {
  return (std::filesystem::path(folder) / (stem + "_sheet.png")).string();
}

// Before the run: the stills' names are springy's, so each replaces only a still of springy's.
void refuseOthersStills(const FramesOptions& options, const std::vector<double>& times, int decimals,
                        const std::string& stem) {
  const std::vector<std::string> inputs = sceneInputFiles(options.scenes, options.run.sets);
  const auto refuse = [&](const std::string& file) {
    refuseInputs(file, inputs);  // an input says so first
    refuseUnlessMarked(file, render::kSpringyMark, render::kMarkSearchBytes,
                       "frames names the stills SCENE_tTIME.png itself");
  };
  if (!options.sheetOnly) {
    for (double t : times) refuse(stillFile(options.output, stem, t, decimals));
  }
  if (options.sheet || options.sheetOnly) refuse(sheetFile(options.output, stem));
}

// One pass of framesOne over the times: its exit status, or nothing when the run was the default
// step's try, it failed, and a step that passes was found (the stills are then drawn again, over
// the same files).
std::optional<int> framesRun(Run& run, const FramesOptions& options, const std::vector<double>& times,
                             int decimals, const std::string& stem) {
  SceneView view(run.scene(), run.world(), renderSettingsOf(run.scene()));
  std::vector<render::Image> stills;
  std::vector<std::string> labels;
  auto stopped = [&](const std::string& what) {
    std::cerr << "springy frames: interrupted by " << signalName(interruptSignal()) << "; " << what
              << " not written\n";
    return interruptedExitStatus();
  };
  // Writes a PNG through the one checked writer: a full disk is an error, never a truncated file,
  // and never over a file a scene reads.
  const std::vector<std::string> inputs = sceneInputFiles(options.scenes, options.run.sets);
  auto write = [&](const std::string& file, const render::Image& image) {
    AtomicFile out(file, inputs);
    out.write(render::encodePng(image));
    out.commit();
    std::printf("%s\n", file.c_str());
  };
  for (double t : times) {
    char label[64];
    std::snprintf(label, sizeof label, "t = %.*f s", decimals, t);
    const std::string file = stillFile(options.output, stem, t, decimals);
    // Frame by frame, so the monitor sees the run as a video would, then to the still's time.
    if (run.runUntil(t)) {
      if (run.retry()) return std::nullopt;
      std::cerr << "springy frames: " << run.path() << ": " << run.failure()->message << "\n";
      return 1;
    }
    if (interrupted()) return stopped(options.sheetOnly ? "the contact sheet" : file);
    view.draw(run.world());
    render::Image image = view.renderer().readImage();
    if (!options.sheetOnly) write(file, image);
    stills.push_back(std::move(image));
    labels.push_back(label);
  }
  if (options.sheet || options.sheetOnly) {
    const std::string file = sheetFile(options.output, stem);
    if (interrupted()) return stopped(file);
    write(file, render::makeContactSheet(stills, labels, sheetOptions(stills.size())));
  }
  return 0;
}

int framesOne(const std::string& path, const FramesOptions& options) {
  Run run(path, options.run, renderEdit(options.render));
  std::vector<double> times = options.times.empty() ? std::vector<double>{} : parseTimes(options.times, run.scene().duration);
  if (times.empty()) times = sheetTimes(run.scene().duration);
  const int decimals = timeDecimals(times);
  makeDirectories(options.output, "-o");
  const std::string stem = stemOf(path);
  refuseOthersStills(options, times, decimals, stem);
  for (;;) {  // again only after the default step's try failed and a longer step passed
    if (const std::optional<int> status = framesRun(run, options, times, decimals, stem)) return *status;
  }
}

}  // namespace

int runRender(const RenderOptions& options) {
  std::vector<std::string> outputs;
  RenderEnvironment env;
  try {
    outputs = videoOutputs(options);
    env = RenderEnvironment::read();
  } catch (const std::exception& e) {
    std::cerr << "springy render: " << e.what() << "\n";
    return 1;
  }
  int status = 0;
  for (std::size_t i = 0; i < options.scenes.size(); ++i) {
    const std::string& path = options.scenes[i];
    try {
      status = std::max(status, renderOne(path, outputs[i], options, env));
    } catch (const std::exception& e) {
      std::cerr << "springy render: " << e.what() << "\n";
      status = std::max(status, 1);
    }
    if (interrupted()) return interruptedExitStatus();
  }
  return status;
}

int runFrames(const FramesOptions& options) {
  // Scenes with the same name would write the same stills.
  for (std::size_t i = 0; i < options.scenes.size(); ++i) {
    for (std::size_t j = 0; j < i; ++j) {
      if (stemOf(options.scenes[i]) == stemOf(options.scenes[j])) {
        std::cerr << "springy frames: " << options.scenes[j] << " and " << options.scenes[i]
                  << " would both be written to " << options.output << "/" << stemOf(options.scenes[i])
                  << "_*.png\n";
        return 1;
      }
    }
  }
  int status = 0;
  for (const std::string& path : options.scenes) {
    try {
      status = std::max(status, framesOne(path, options));
    } catch (const std::exception& e) {
      std::cerr << "springy frames: " << e.what() << "\n";
      status = std::max(status, 1);
    }
    if (interrupted()) return interruptedExitStatus();
  }
  return status;
}

}  // namespace springy
