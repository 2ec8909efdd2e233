// springy app: the frames of `springy render`, simulated, drawn and encoded.
//
// Three threads joined by bounded queues of recycled buffers (memory stays bounded, nothing is
// allocated per frame):
//   simulation thread  advances the Run frame by frame (its observers see each frame there) and
//                      copies the positions into a FrameSnapshot (the World is not thread-safe;
//                      only this thread touches it);
//   calling thread     owns the GL context: draws each snapshot and reads the pixels back;
//   encoding thread    hands the pixels to the FrameSink (converts to yuv420p and encodes).
// Each stage works on a different frame, so the wall time approaches the slowest stage rather
// than the sum. The frames are exactly those of the serial order (simulate k, draw k, encode k):
// the simulation is deterministic and the queues are FIFO. RenderEnvironment::serial runs that
// serial order on one thread (the reference the tests compare against).
#pragma once

#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include "app/commands.h"
#include "app/scene_view.h"
#include "render/video_encoder.h"
#include "run/run.h"

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

// The video's encoder settings: the scene's [render] table, and x264's threads.
render::VideoSettings videoSettingsOf(const SceneDesc& scene, const RenderEnvironment& env);

// The scene's [render] table with a command's overrides (applyRenderOverrides), and the camera
// checked (checkCamera): a Run's edit (run/run.h), before any output exists.
std::function<void(SceneDesc&)> renderEdit(const RenderOverrides& overrides);

struct FramePipelineSettings {
  std::string label;     // the progress line's name (the scene's)
  int width = 0;         // frame size in pixels, as the renderer and the sink were set up
  int height = 0;
  bool serial = false;   // one thread, in order (RenderEnvironment::serial)
};

struct FramePipelineResult {
  bool interrupted = false;  // a signal stopped the simulation before the last frame
  double simulateMs = 0.0;   // wall time spent advancing the world, all frames
};

// Where the drawn frames go, in order, on the encoding thread: frame k shows the world at
// k / fps, k = 0 .. run.frames() - 1 (a video of N frames lasts N / fps). `rgba` has bottom-up
// rows, as glReadPixels gives them.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  virtual void write(long k, const std::vector<uint8_t>& rgba) = 0;
};

// The video's frames: the encoder's (open; finish() is left to the caller, who decides whether
// the run is worth keeping).
class EncoderSink : public FrameSink {
 public:
  explicit EncoderSink(render::VideoEncoder& encoder) : encoder_(encoder) {}
  void write(long, const std::vector<uint8_t>& rgba) override { encoder_.writeFrame(rgba, render::RowOrder::BottomUp); }

 private:
  render::VideoEncoder& encoder_;
};

// A frame could not be written by the sink (its message names the file it was writing).
struct EncodeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Runs `run` from its start through its last frame (run.start(), then run.nextFrame() for frames
// 1 .. run.frames(): every frame a check checks is checked), draws frames 0 .. run.frames() - 1
// with `view` (on the calling thread, which owns its GL context) and writes each to `sink`. Shows
// progress on stderr. Stops early at a failure (run.failure(): the frames after it are not
// written) or a signal. Throws what a stage throws, the sink's RenderErrors as EncodeError; the
// threads are joined before anything leaves. `timings`, when given, is read for the progress line.
FramePipelineResult runFramePipeline(Run& run, SceneView& view, FrameSink& sink, const FramePipelineSettings& settings,
                                     const render::VideoEncoder* timings = nullptr);

}  // namespace springy
