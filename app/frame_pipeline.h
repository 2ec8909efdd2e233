// springy app: the frames of `springy render`, simulated, drawn and encoded.
//
// Three threads joined by bounded queues of recycled buffers (memory stays bounded, nothing is
// allocated per frame):
//   simulation thread  advances the World frame by frame and copies the positions into a
//                      FrameSnapshot (the World is not thread-safe; only this thread touches it);
//   calling thread     owns the GL context: draws each snapshot and reads the pixels back;
//   encoding thread    converts to yuv420p and encodes.
// Each stage works on a different frame, so the wall time approaches the slowest stage rather
// than the sum. The frames are exactly those of the serial order (simulate k, draw k, encode k):
// the simulation is deterministic and the queues are FIFO. RenderEnvironment::serial runs that
// serial order on one thread (the reference the tests compare against).
#pragma once

#include <optional>
#include <stdexcept>
#include <string>

#include "app/scene_view.h"
#include "render/video_encoder.h"
#include "sim/monitor.h"

namespace springy {

// The environment variables `springy render` reads, each read once (RenderEnvironment::read)
// and nowhere else. For tests, profiling and comparisons; none is needed for normal use.
//   SPRINGY_RENDER_SERIAL=1   simulate, draw and encode one frame after the other on one thread:
//                             the reference order the pipelined video must equal byte for byte
//                             (tests/render/test_render_video.cpp).
//   SPRINGY_RENDER_PROFILE=1  time each render pass (a glFinish after each, so a little slower)
//                             and print the time per pass per frame in the closing summary.
//   SPRINGY_RENDER_AA=msaa    anti-alias with 4x MSAA instead of FXAA (for comparisons).
//   SPRINGY_X264_THREADS=N    x264's encoder threads (0: the codec's default, every core;
//                             unset: 1 on a machine of 2 cores or fewer, else 0).
// A flag counts as set when it is non-empty and not "0".
struct RenderEnvironment {
  bool serial = false;             // SPRINGY_RENDER_SERIAL
  bool profilePasses = false;      // SPRINGY_RENDER_PROFILE
  bool msaa = false;               // SPRINGY_RENDER_AA=msaa
  std::optional<int> x264Threads;  // SPRINGY_X264_THREADS, when set
  static RenderEnvironment read();
};

struct FramePipelineSettings {
  std::string label;     // the progress line's name (the scene's)
  long frames = 0;       // frame k shows the world at time k / fps
  double fps = 30.0;
  int width = 0;         // frame size in pixels, as the renderer and the encoder were set up
  int height = 0;
  bool serial = false;   // one thread, in order (RenderEnvironment::serial)
};

struct FramePipelineResult {
  std::optional<Failure> failure;  // the monitor stopped the run (frames after it not encoded)
  bool interrupted = false;        // a signal stopped the simulation before the last frame
  double simulateMs = 0.0;         // wall time spent advancing the world, all frames
};

// A frame could not be written by the encoder (its message names the file it was writing).
struct EncodeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Simulates settings.frames frames of `world` under `monitor`, draws each with `view` (on the
// calling thread, which owns its GL context) and writes it to `encoder` (open; finish() is left
// to the caller, who decides whether the run is worth keeping). Shows progress on stderr.
// Stops early at a failure or a signal (see the result). Throws what a stage throws, the
// encoder's RenderErrors as EncodeError; the threads are joined before anything leaves.
FramePipelineResult runFramePipeline(World& world, Monitor& monitor, SceneView& view, render::VideoEncoder& encoder,
                                     const FramePipelineSettings& settings);

}  // namespace springy
