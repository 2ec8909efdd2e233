#include "render/video_encoder.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/imgutils.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <mutex>

#include "render/error.h"
#include "render/image.h"

namespace springy::render {

namespace {
using Clock = std::chrono::steady_clock;
double msSince(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

std::string avError(int err) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(err, buf, sizeof buf);
  return buf;
}
}  // namespace

struct VideoEncoder::Impl {
  std::string path;
  VideoSettings settings;
  AVFormatContext* fmt = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* sws = nullptr;
  bool headerWritten = false;
  bool fileOpen = false;
  bool fallback = false;
  std::string codecName;
  std::int64_t nextPts = 0;
  mutable std::mutex timingMutex;
  EncodeTimings timings;

  ~Impl() { close(); }

  [[noreturn]] void fail(const std::string& what, int err) const {
    throw RenderError("VideoEncoder '" + path + "': " + what + ": " + avError(err));
  }

  void close() {
    if (sws) sws_freeContext(sws), sws = nullptr;
    if (frame) av_frame_free(&frame);
    if (packet) av_packet_free(&packet);
    if (codec) avcodec_free_context(&codec);
    if (fmt) {
      if (fileOpen) avio_closep(&fmt->pb);
      avformat_free_context(fmt);
      fmt = nullptr;
    }
    fileOpen = headerWritten = false;
    stream = nullptr;
  }

  // Sends one frame (nullptr = flush) and writes every packet the encoder hands back.
  void encode(AVFrame* f) {
    int ret = avcodec_send_frame(codec, f);
    if (ret < 0) fail("sending a frame to the encoder failed", ret);
    for (;;) {
      ret = avcodec_receive_packet(codec, packet);
      if (ret == AVERROR(EAGAIN) || ret == AVERROR_EOF) break;
      if (ret < 0) fail("encoding failed", ret);
      packet->duration = 1;  // in codec time base; without it the MP4 is one frame short
      av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      ret = av_interleaved_write_frame(fmt, packet);  // takes the packet's reference
      if (ret < 0) fail("writing a packet failed", ret);
    }
  }

  void open(const std::string& p, const VideoSettings& s) {
    close();
    path = p;
    settings = s;
    nextPts = 0;
    {
      std::lock_guard lock(timingMutex);
      timings = EncodeTimings{};
    }
    checkSettings(p, s);
    // A fraction, not the rounded integer: 1.4 frames/s written as 1 played 40% slow. MPEG-4
    // part 2 allows time base denominators up to 65535.
    const AVRational rate = av_d2q(s.fps, 65535);
    try {
      openOutput();
      const AVCodec* enc = chooseEncoder();
      openCodec(enc, rate);
      allocateFrame();
      createConverter();
      writeHeader();
    } catch (...) {
      close();
      throw;
    }
  }

  // Step of open(): a size the encoder takes (positive and even, for yuv420p) and a sane rate.
  static void checkSettings(const std::string& p, const VideoSettings& s) {
    if (s.width <= 0 || s.height <= 0 || s.width % 2 || s.height % 2)
      throw RenderError("VideoEncoder '" + p + "': width and height must be positive and even, got " +
                        std::to_string(s.width) + "x" + std::to_string(s.height));
    if (!(s.fps >= 0.01 && s.fps <= 1000.0))
      throw RenderError("VideoEncoder '" + p + "': bad frame rate " + std::to_string(s.fps));
  }

  // Step of open(): the container (from the extension, else MP4) and the file, opened first so
  // that an unwritable path fails before any encoder work.
  void openOutput() {
    int ret = avformat_alloc_output_context2(&fmt, nullptr, nullptr, path.c_str());
    if (ret < 0 || !fmt) {
      ret = avformat_alloc_output_context2(&fmt, nullptr, "mp4", path.c_str());
      if (ret < 0 || !fmt) fail("cannot choose an output format", ret);
    }
    if (!(fmt->oformat->flags & AVFMT_NOFILE)) {
      ret = avio_open(&fmt->pb, path.c_str(), AVIO_FLAG_WRITE);
      if (ret < 0) fail("cannot open the output file", ret);
      fileOpen = true;
    }
  }

  // Step of open(): H.264, or MPEG-4 part 2 where it is missing (if allowed) or forced.
  const AVCodec* chooseEncoder() {
    const AVCodec* enc = settings.forceFallback ? nullptr : avcodec_find_encoder(AV_CODEC_ID_H264);
    fallback = enc == nullptr;
    if (fallback) {
      if (!settings.allowFallback && !settings.forceFallback)
        throw RenderError("VideoEncoder '" + path + "': no H.264 encoder (libx264) available");
      enc = avcodec_find_encoder(AV_CODEC_ID_MPEG4);
      if (!enc) throw RenderError("VideoEncoder '" + path + "': neither H.264 nor MPEG-4 encoder available");
    }
    codecName = enc->name;
    return enc;
  }

  // Step of open(): the stream and the encoder at the frame rate, yuv420p, BT.709 tagged, a
  // keyframe every two seconds; x264 at the preset and CRF, or mpeg4 at a matching quantiser.
  void openCodec(const AVCodec* enc, AVRational rate) {
    const VideoSettings& s = settings;
    stream = avformat_new_stream(fmt, nullptr);
    if (!stream) throw RenderError("VideoEncoder '" + path + "': cannot create a stream");
    codec = avcodec_alloc_context3(enc);
    if (!codec) throw RenderError("VideoEncoder '" + path + "': cannot allocate the codec context");
    codec->codec_id = enc->id;
    codec->width = s.width;
    codec->height = s.height;
    codec->time_base = av_inv_q(rate);
    codec->framerate = rate;
    codec->pix_fmt = AV_PIX_FMT_YUV420P;
    codec->gop_size = std::max(1, static_cast<int>(std::lround(s.fps * 2.0)));
    if (s.threads < 0) throw RenderError("VideoEncoder '" + path + "': " + std::to_string(s.threads) + " threads");
    codec->thread_count = s.threads;
    codec->color_primaries = AVCOL_PRI_BT709;
    codec->color_trc = AVCOL_TRC_BT709;
    codec->colorspace = AVCOL_SPC_BT709;
    codec->color_range = AVCOL_RANGE_MPEG;
    stream->time_base = codec->time_base;
    stream->avg_frame_rate = rate;
    if (fmt->oformat->flags & AVFMT_GLOBALHEADER) codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    AVDictionary* opts = nullptr;
    if (!fallback) {
      av_dict_set(&opts, "preset", s.preset.c_str(), 0);
      av_dict_set(&opts, "crf", std::to_string(std::clamp(s.crf, 0, 51)).c_str(), 0);
    } else {
      // mpeg4 has no CRF: a fixed quantiser roughly matching the requested quality.
      codec->flags |= AV_CODEC_FLAG_QSCALE;
      codec->global_quality = FF_QP2LAMBDA * std::clamp(s.crf / 8, 2, 31);
      codec->max_b_frames = 0;
    }
    int ret = avcodec_open2(codec, enc, &opts);
    av_dict_free(&opts);
    if (ret < 0) fail(std::string("cannot open encoder ") + enc->name, ret);
    ret = avcodec_parameters_from_context(stream->codecpar, codec);
    if (ret < 0) fail("cannot copy codec parameters", ret);
  }

  // Step of open(): the frame the colour conversion writes into (tagged as the stream) and the
  // packet the encoder hands back.
  void allocateFrame() {
    frame = av_frame_alloc();
    packet = av_packet_alloc();
    if (!frame || !packet) throw RenderError("VideoEncoder '" + path + "': out of memory");
    frame->format = codec->pix_fmt;
    frame->width = settings.width;
    frame->height = settings.height;
    frame->color_primaries = AVCOL_PRI_BT709;
    frame->color_trc = AVCOL_TRC_BT709;
    frame->colorspace = AVCOL_SPC_BT709;
    frame->color_range = AVCOL_RANGE_MPEG;
    const int ret = av_frame_get_buffer(frame, 0);
    if (ret < 0) fail("cannot allocate a frame", ret);
  }

  // Step of open(): the RGBA -> yuv420p converter. RGBA input is full range; output
  // limited-range BT.709, matching the stream tags.
  void createConverter() {
    const int w = settings.width, h = settings.height;
    sws = sws_getContext(w, h, AV_PIX_FMT_RGBA, w, h, AV_PIX_FMT_YUV420P,
                         SWS_BILINEAR | SWS_ACCURATE_RND | SWS_FULL_CHR_H_INP, nullptr, nullptr, nullptr);
    if (!sws) throw RenderError("VideoEncoder '" + path + "': cannot create the colour converter");
    const int* bt709 = sws_getCoefficients(SWS_CS_ITU709);
    sws_setColorspaceDetails(sws, bt709, 1, bt709, 0, 0, 1 << 16, 1 << 16);
  }

  // Step of open(): the file header, with the index (moov atom) to be moved up front at the end
  // (+faststart), so that the video plays while it downloads.
  void writeHeader() {
    AVDictionary* muxOpts = nullptr;
    av_dict_set(&muxOpts, "movflags", "+faststart", 0);
    av_dict_set(&fmt->metadata, "comment", std::string(kSpringyMark).c_str(), 0);  // render/image.h
    const int ret = avformat_write_header(fmt, &muxOpts);
    av_dict_free(&muxOpts);
    if (ret < 0) fail("cannot write the file header", ret);
    headerWritten = true;
  }

  void writeFrame(std::span<const std::uint8_t> rgba, RowOrder order) {
    if (!codec) throw RenderError("VideoEncoder::writeFrame: encoder is not open");
    const std::size_t expected =
        static_cast<std::size_t>(settings.width) * static_cast<std::size_t>(settings.height) * 4;
    if (rgba.size() != expected)
      throw RenderError("VideoEncoder '" + path + "': frame has " + std::to_string(rgba.size()) +
                        " bytes, expected " + std::to_string(expected));
    const auto t0 = Clock::now();
    int ret = av_frame_make_writable(frame);  // the encoder may still hold the previous buffer
    if (ret < 0) fail("cannot make the frame writable", ret);
    // Bottom-up rows: start at the last row and step backwards (a negative stride).
    const std::ptrdiff_t row = static_cast<std::ptrdiff_t>(settings.width) * 4;
    const std::uint8_t* src[1] = {order == RowOrder::TopDown
                                      ? rgba.data()
                                      : rgba.data() + row * (settings.height - 1)};
    const int srcStride[1] = {order == RowOrder::TopDown ? settings.width * 4 : -settings.width * 4};
    sws_scale(sws, src, srcStride, 0, settings.height, frame->data, frame->linesize);
    frame->pts = nextPts++;
    const double convert = msSince(t0);
    const auto t1 = Clock::now();
    encode(frame);
    const double enc = msSince(t1);
    std::lock_guard lock(timingMutex);
    timings.convertMs = convert;
    timings.encodeMs = enc;
    timings.totalConvertMs += convert;
    timings.totalEncodeMs += enc;
    ++timings.frames;
  }

  void finish() {
    if (!codec) throw RenderError("VideoEncoder::finish: encoder is not open");
    const auto t0 = Clock::now();
    try {
      encode(nullptr);
      int ret = av_write_trailer(fmt);
      if (ret < 0) fail("cannot write the trailer", ret);
      // Closing flushes the last buffered bytes: its result is the last write's (a full disk).
      if (fileOpen) {
        fileOpen = false;
        ret = avio_closep(&fmt->pb);
        if (ret < 0) fail("cannot write the file", ret);
      }
    } catch (...) {
      close();
      throw;
    }
    close();
    std::lock_guard lock(timingMutex);
    timings.totalEncodeMs += msSince(t0);
  }
};

void VideoEncoder::setLibraryLogging(bool verbose) {
  av_log_set_level(verbose ? AV_LOG_INFO : AV_LOG_ERROR);
}

VideoEncoder::VideoEncoder() : impl_(std::make_unique<Impl>()) {}
VideoEncoder::~VideoEncoder() = default;

void VideoEncoder::open(const std::string& path, const VideoSettings& settings) {
  impl_->open(path, settings);
}
void VideoEncoder::open(const std::string& path, int width, int height, double fps, int crf,
                        const std::string& preset) {
  VideoSettings s;
  s.width = width;
  s.height = height;
  s.fps = fps;
  s.crf = crf;
  s.preset = preset;
  impl_->open(path, s);
}
bool VideoEncoder::isOpen() const { return impl_->codec != nullptr; }
void VideoEncoder::writeFrame(std::span<const std::uint8_t> rgba, RowOrder order) {
  impl_->writeFrame(rgba, order);
}
void VideoEncoder::finish() { impl_->finish(); }
std::string VideoEncoder::codecName() const { return impl_->codecName; }
bool VideoEncoder::usingFallback() const { return impl_->fallback; }
EncodeTimings VideoEncoder::timings() const {
  std::lock_guard lock(impl_->timingMutex);
  return impl_->timings;
}
std::int64_t VideoEncoder::framesWritten() const { return impl_->nextPts; }

}  // namespace springy::render
