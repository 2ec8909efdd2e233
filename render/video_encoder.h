// Why: frames become an MP4 the user can play anywhere: H.264 (libx264 via libavcodec),
// yuv420p, BT.709 tagged, moov atom up front (+faststart). FFmpeg's C API is wrapped here so
// that callers see RAII and exceptions, never error codes or exit().
//
// Threading: no GL inside; one VideoEncoder may live on a dedicated encoding thread. All calls
// on one encoder must come from one thread at a time; timings() is safe from any thread.
#pragma once
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "render/row_order.h"

namespace springy::render {

struct VideoSettings {
  int width = 1280;   // even
  int height = 720;   // even
  double fps = 30.0;               // frames per second, any rational (1.4, 29.97): the time base
                                   // is the nearest fraction (av_d2q), so the video plays at it
  int crf = 20;                    // x264 constant rate factor (0..51, lower = better)
  std::string preset = "veryfast"; // x264 preset (ultrafast .. veryslow)
  int threads = 0;                 // encoder threads, 0 = codec default (all cores)
  bool allowFallback = true;       // use FFmpeg's mpeg4 encoder if H.264 is unavailable
  bool forceFallback = false;      // always use mpeg4 (for tests of the fallback path)
};

struct EncodeTimings {
  double convertMs = 0.0;       // last frame: RGBA -> yuv420p (swscale)
  double encodeMs = 0.0;        // last frame: encoder + muxer
  double totalConvertMs = 0.0;
  double totalEncodeMs = 0.0;   // includes finish()
  std::uint64_t frames = 0;
};

class VideoEncoder {
public:
  VideoEncoder();
  ~VideoEncoder();  // closes without throwing; call finish() to get a complete file
  VideoEncoder(const VideoEncoder&) = delete;
  VideoEncoder& operator=(const VideoEncoder&) = delete;

  // Creates exactly `path` (container chosen from the extension, .mp4 expected). Throws
  // RenderError (with FFmpeg's error text and the path) on failure; if the failure comes after
  // the file was created, an empty or partial file may remain at `path`.
  void open(const std::string& path, const VideoSettings& settings);
  void open(const std::string& path, int width, int height, double fps, int crf = 20,
            const std::string& preset = "veryfast");
  bool isOpen() const;

  // One RGBA8 frame, width*height*4 bytes, rows top-down (or bottom-up, as glReadPixels gives
  // them: flipped during the colour conversion at no cost).
  void writeFrame(std::span<const std::uint8_t> rgba, RowOrder order = RowOrder::TopDown);
  // Flushes the encoder, writes the trailer and closes the file; throws RenderError if any write
  // failed (a full disk). After it the encoder is closed.
  void finish();

  std::string codecName() const;  // "libx264" or "mpeg4" (empty before open)
  bool usingFallback() const;     // true when not H.264
  EncodeTimings timings() const;
  std::int64_t framesWritten() const;

  // FFmpeg logs to stderr (x264 prints its settings on every open). false: errors only.
  // Process-wide (av_log_set_level).
  static void setLibraryLogging(bool verbose);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace springy::render
