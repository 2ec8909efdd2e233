// Encodes frames with VideoEncoder, decodes them back with libavformat/libavcodec and checks
// count, size, pixel format, colour tags, timestamps, duration and per-frame PSNR.
#include <gtest/gtest.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>
#include <vector>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "render/error.h"
#include "render/renderer.h"
#include "render/mesh_builders.h"
#include "render/video_encoder.h"

using namespace springy::render;
namespace fs = std::filesystem;

namespace {

constexpr int W = 128, H = 96, FPS = 30, N = 30;

// Moving coloured content: a smooth gradient background and a sliding disc with a soft (3 px,
// anti-aliased-like) edge. Hard saturated edges would measure chroma subsampling, not the codec.
std::vector<std::uint8_t> makeFrame(int k) {
  std::vector<std::uint8_t> f(static_cast<std::size_t>(W * H * 4));
  const float cx = 25.0f + 2.7f * static_cast<float>(k), cy = 45.0f, radius = 16.0f;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t i = static_cast<std::size_t>((y * W + x) * 4);
      const float d = std::hypot(static_cast<float>(x) - cx, static_cast<float>(y) - cy);
      const float a = std::clamp((radius - d) / 3.0f + 0.5f, 0.0f, 1.0f);
      const float bg[3] = {40.0f + static_cast<float>(x), 60.0f + static_cast<float>(y),
                           120.0f + 2.0f * static_cast<float>(k)};
      const float fg[3] = {230.0f, 200.0f, 20.0f};
      for (int c = 0; c < 3; ++c)
        f[i + static_cast<std::size_t>(c)] =
            static_cast<std::uint8_t>(std::lround(bg[c] + (fg[c] - bg[c]) * a));
      f[i + 3] = 255;
    }
  return f;
}

double psnr(const std::vector<std::uint8_t>& a, const std::vector<std::uint8_t>& b) {
  double se = 0.0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); i += 4)
    for (std::size_t c = 0; c < 3; ++c, ++n) {
      const double d = double(a[i + c]) - double(b[i + c]);
      se += d * d;
    }
  const double mse = se / double(n);
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

struct Decoded {
  int width = 0, height = 0;
  AVPixelFormat format = AV_PIX_FMT_NONE;
  AVColorSpace colorspace = AVCOL_SPC_UNSPECIFIED;
  std::vector<std::int64_t> pts;  // stream time base
  std::vector<std::vector<std::uint8_t>> frames;  // RGBA, top-down
  double durationSeconds = 0.0;
  AVRational timeBase{0, 1};
  AVRational frameRate{0, 1};  // the stream's average frame rate
  std::string codec;
};

Decoded decode(const std::string& path) {
  Decoded out;
  AVFormatContext* fmt = nullptr;
  if (avformat_open_input(&fmt, path.c_str(), nullptr, nullptr) < 0) throw std::runtime_error("open");
  if (avformat_find_stream_info(fmt, nullptr) < 0) throw std::runtime_error("stream info");
  const int si = av_find_best_stream(fmt, AVMEDIA_TYPE_VIDEO, -1, -1, nullptr, 0);
  if (si < 0) throw std::runtime_error("no video stream");
  AVStream* st = fmt->streams[si];
  out.timeBase = st->time_base;
  out.frameRate = st->avg_frame_rate;
  out.codec = avcodec_get_name(st->codecpar->codec_id);
  out.colorspace = st->codecpar->color_space;
  if (st->duration > 0) out.durationSeconds = double(st->duration) * av_q2d(st->time_base);
  else out.durationSeconds = double(fmt->duration) / AV_TIME_BASE;
  const AVCodec* dec = avcodec_find_decoder(st->codecpar->codec_id);
  AVCodecContext* ctx = avcodec_alloc_context3(dec);
  avcodec_parameters_to_context(ctx, st->codecpar);
  if (avcodec_open2(ctx, dec, nullptr) < 0) throw std::runtime_error("decoder");
  AVPacket* pkt = av_packet_alloc();
  AVFrame* frame = av_frame_alloc();
  SwsContext* sws = nullptr;
  auto receive = [&]() {
    while (avcodec_receive_frame(ctx, frame) == 0) {
      out.width = frame->width;
      out.height = frame->height;
      out.format = static_cast<AVPixelFormat>(frame->format);
      out.pts.push_back(frame->best_effort_timestamp);
      if (!sws) {
        sws = sws_getContext(frame->width, frame->height, out.format, frame->width, frame->height,
                             AV_PIX_FMT_RGBA, SWS_BILINEAR | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INT,
                             nullptr, nullptr, nullptr);
        const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
        sws_setColorspaceDetails(sws, bt709, 0, bt709, 1, 0, 1 << 16, 1 << 16);
      }
      std::vector<std::uint8_t> rgba(static_cast<std::size_t>(frame->width * frame->height * 4));
      std::uint8_t* dst[1] = {rgba.data()};
      const int dstStride[1] = {frame->width * 4};
      sws_scale(sws, frame->data, frame->linesize, 0, frame->height, dst, dstStride);
      out.frames.push_back(std::move(rgba));
    }
  };
  while (av_read_frame(fmt, pkt) >= 0) {
    if (pkt->stream_index == si) {
      avcodec_send_packet(ctx, pkt);
      receive();
    }
    av_packet_unref(pkt);
  }
  avcodec_send_packet(ctx, nullptr);
  receive();
  sws_freeContext(sws);
  av_frame_free(&frame);
  av_packet_free(&pkt);
  avcodec_free_context(&ctx);
  avformat_close_input(&fmt);
  return out;
}

class VideoTest : public ::testing::Test {
protected:
  fs::path dir = fs::temp_directory_path() / ("springy_video_test_" + std::to_string(getpid()));
  void SetUp() override {
    fs::create_directories(dir);
    VideoEncoder::setLibraryLogging(false);
  }
  void TearDown() override { fs::remove_all(dir); }

  void roundTrip(bool fallback, double minPsnr) {
    const std::string path = (dir / (fallback ? "mpeg4.mp4" : "h264.mp4")).string();
    VideoSettings s;
    s.width = W;
    s.height = H;
    s.fps = FPS;
    s.crf = 18;
    s.preset = "veryfast";
    s.forceFallback = fallback;
    std::vector<std::vector<std::uint8_t>> inputs;
    {
      VideoEncoder enc;
      enc.open(path, s);
      EXPECT_EQ(enc.usingFallback(), fallback);
      EXPECT_EQ(enc.codecName(), fallback ? "mpeg4" : "libx264");
      for (int k = 0; k < N; ++k) {
        inputs.push_back(makeFrame(k));
        enc.writeFrame(inputs.back());
      }
      enc.finish();
      EXPECT_FALSE(enc.isOpen());
      const EncodeTimings t = enc.timings();
      EXPECT_EQ(t.frames, std::uint64_t{N});
      EXPECT_GT(t.totalConvertMs, 0.0);
      EXPECT_GT(t.totalEncodeMs, 0.0);
    }
    const Decoded d = decode(path);
    EXPECT_EQ(d.codec, fallback ? "mpeg4" : "h264");
    ASSERT_EQ(d.frames.size(), std::size_t{N});
    EXPECT_EQ(d.width, W);
    EXPECT_EQ(d.height, H);
    EXPECT_EQ(d.format, AV_PIX_FMT_YUV420P);
    EXPECT_EQ(d.colorspace, AVCOL_SPC_BT709);
    for (std::size_t i = 1; i < d.pts.size(); ++i) EXPECT_GT(d.pts[i], d.pts[i - 1]) << "frame " << i;
    EXPECT_NEAR(d.durationSeconds, double(N) / FPS, 1.0 / FPS + 1e-6);
    for (int k = 0; k < N; ++k) {
      const double p = psnr(inputs[std::size_t(k)], d.frames[std::size_t(k)]);
      EXPECT_GT(p, minPsnr) << "frame " << k;
      if (std::getenv("SPRINGY_VIDEO_VERBOSE")) std::printf("frame %d psnr %.2f\n", k, p);
    }
  }
};

}  // namespace

TEST_F(VideoTest, H264RoundTrip) { roundTrip(false, 30.0); }

TEST_F(VideoTest, Mpeg4FallbackRoundTrip) { roundTrip(true, 30.0); }

// A fractional rate is kept as a fraction (av_d2q): 1.4 frames/s was written as 1, and 7 frames
// played for 7 s instead of 5.
TEST_F(VideoTest, FractionalFrameRatePlaysAtThatRate) {
  for (const double fps : {1.4, 29.97}) {
    const std::string path = (dir / "fractional.mp4").string();
    const int n = 7;
    {
      VideoEncoder enc;
      enc.open(path, W, H, fps);
      for (int k = 0; k < n; ++k) enc.writeFrame(makeFrame(k));
      enc.finish();
    }
    const Decoded d = decode(path);
    ASSERT_EQ(d.frames.size(), std::size_t{n});
    EXPECT_NEAR(av_q2d(d.frameRate), fps, 1e-9) << fps;
    EXPECT_NEAR(d.durationSeconds, n / fps, 1e-3) << fps;
    for (std::size_t i = 0; i < d.pts.size(); ++i)
      EXPECT_NEAR(double(d.pts[i]) * av_q2d(d.timeBase), double(i) / fps, 1e-3) << fps << " frame " << i;
  }
}

// The same through `springy render --fps 1.4`: 5 s of scene are 7 frames lasting 5 s.
TEST_F(VideoTest, RenderWithAFractionalFpsKeepsTheDuration) {
  const std::string out = (dir / "fps.mp4").string();
  const std::string cmd = std::string(SPRINGY_BINARY) + " render " + SPRINGY_SOURCE_DIR +
                          "/tests/data/app/tiny.toml --duration 5 --fps 1.4 -o " + out + " > " + out + ".log 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const Decoded d = decode(out);
  EXPECT_EQ(d.frames.size(), 7u);
  EXPECT_NEAR(av_q2d(d.frameRate), 1.4, 1e-9);
  EXPECT_NEAR(d.durationSeconds, 5.0, 1e-3);
}

TEST_F(VideoTest, FaststartPutsMoovBeforeMdat) {
  const std::string path = (dir / "fs.mp4").string();
  VideoEncoder enc;
  enc.open(path, W, H, FPS);
  for (int k = 0; k < 5; ++k) enc.writeFrame(makeFrame(k));
  enc.finish();
  std::ifstream in(path, std::ios::binary);
  const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto moov = bytes.find("moov"), mdat = bytes.find("mdat");
  ASSERT_NE(moov, std::string::npos);
  ASSERT_NE(mdat, std::string::npos);
  EXPECT_LT(moov, mdat);
}

TEST_F(VideoTest, UnwritablePathThrowsNamingIt) {
  const std::string path = (dir / "no-such-dir" / "out.mp4").string();
  VideoEncoder enc;
  try {
    enc.open(path, W, H, FPS);
    FAIL() << "expected RenderError";
  } catch (const RenderError& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
  EXPECT_FALSE(enc.isOpen());
  EXPECT_FALSE(fs::exists(path));
}

TEST_F(VideoTest, BadArgumentsThrow) {
  VideoEncoder enc;
  EXPECT_THROW(enc.open((dir / "odd.mp4").string(), 127, 96, FPS), RenderError);
  EXPECT_THROW(enc.writeFrame(makeFrame(0)), RenderError);  // not open
  enc.open((dir / "ok.mp4").string(), W, H, FPS);
  EXPECT_THROW(enc.writeFrame(std::vector<std::uint8_t>(10)), RenderError);
  enc.finish();
}

// The app's pattern: render on the main thread, encode on a dedicated thread.
TEST_F(VideoTest, RendererFramesEncodedOnAnotherThread) {
  RenderSettings rs;
  rs.width = W;
  rs.height = H;
  Renderer r(rs);
  r.addGround({0, 0, 0}, {0, 1, 0}, 20.0f);
  const MeshData box = makeBox({0, 0.5f, 0}, glm::vec3(0.5f));
  const MeshId id = r.addDynamicMesh(box.vertexCount(), box.indices, Material{});
  r.setCamera(frameBounds({-1, 0, -1}, {1, 2, 1}, r.aspect()));

  std::mutex mutex;
  std::condition_variable cv;
  std::deque<std::vector<std::uint8_t>> queue;
  bool done = false;
  const std::string path = (dir / "threaded.mp4").string();
  std::string error;
  std::thread encoder([&] {
    try {
      VideoEncoder enc;
      enc.open(path, W, H, FPS);
      for (;;) {
        std::unique_lock lock(mutex);
        cv.wait(lock, [&] { return done || !queue.empty(); });
        if (queue.empty()) break;
        std::vector<std::uint8_t> f = std::move(queue.front());
        queue.pop_front();
        lock.unlock();
        enc.writeFrame(f);
      }
      enc.finish();
    } catch (const std::exception& e) {
      error = e.what();
    }
  });
  for (int k = 0; k < 12; ++k) {
    std::vector<float> pos = box.positions;
    for (std::size_t i = 0; i < pos.size(); i += 3) pos[i] += 0.1f * static_cast<float>(k);
    r.updateDynamicMesh(id, pos);
    r.render();
    std::vector<std::uint8_t> rgba;
    r.readPixels(rgba);
    {
      std::lock_guard lock(mutex);
      queue.push_back(std::move(rgba));
    }
    cv.notify_one();
  }
  {
    std::lock_guard lock(mutex);
    done = true;
  }
  cv.notify_one();
  encoder.join();
  ASSERT_EQ(error, "");
  const Decoded d = decode(path);
  EXPECT_EQ(d.frames.size(), 12u);
}

// `springy render` runs simulation, drawing and encoding on three threads. The frames must be
// exactly those of the serial order (SPRINGY_RENDER_SERIAL=1: simulate, draw, encode one frame
// at a time on one thread): same count, same pixels, same order. x264 is deterministic for
// identical input, so identical input frames decode to identical pictures.
TEST_F(VideoTest, PipelinedRenderMatchesTheSerialReference) {
  const std::string scene = std::string(SPRINGY_SOURCE_DIR) + "/scenes/single_sphere.toml";
  auto render = [&](const std::string& name, bool serial) {
    const std::string out = (dir / name).string();
    const std::string cmd = std::string(serial ? "SPRINGY_RENDER_SERIAL=1 " : "SPRINGY_RENDER_SERIAL=0 ") +
                            SPRINGY_BINARY + " render " + scene +
                            " --duration 1.5 --width 256 --height 144 -o " + out + " > " + out + ".log 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    return decode(out);
  };
  const Decoded serial = render("serial.mp4", true), piped = render("piped.mp4", false);
  ASSERT_EQ(serial.frames.size(), 45u);  // 1.5 s at 30 frames/s
  ASSERT_EQ(piped.frames.size(), serial.frames.size());
  for (std::size_t k = 0; k < serial.frames.size(); ++k)
    ASSERT_TRUE(piped.frames[k] == serial.frames[k]) << "frame " << k << " differs";
  // The ball falls: the frames really change over time (so "in order" means something).
  EXPECT_FALSE(serial.frames.front() == serial.frames.back());
}

