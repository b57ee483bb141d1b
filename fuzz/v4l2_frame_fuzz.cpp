// libFuzzer target: the V4L2 backend on fuzzed buffers. The input picks a wire format, a ring
// format, buffer flags, sequence numbers and the buffer bytes (MJPEG included); the real
// V4l2Camera dequeues them from a RecordedV4l2Device and converts them into a frame ring.
// Invariants: no crash, every delivered buffer is counted once (converted, dropped as corrupt, or
// a conversion error), frames in the ring have the negotiated size.

#include <linux/videodev2.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>

#include "drivers/camera/frame_ring.hpp"
#include "drivers/camera/v4l2_camera.hpp"
#include "drivers/camera/v4l2_recorded.hpp"

namespace {

using namespace livod::camera;

class Sink final : public FrameSink {
 public:
  Sink(int w, int h, PixelFormat f) : ring(2, static_cast<std::size_t>(w) * h * 3), format(f) {}
  cv::Mat acquire(int width, int height) override {
    const auto slot = ring.begin_write();
    if (slot.empty()) return {};
    return cv::Mat(height, width, cv_type(format), slot.data());
  }
  void commit(const FrameInfo& info) override {
    ring.commit(info);
    ++committed;
    if (ring.front() != nullptr) ring.pop();
  }
  FrameRing ring;
  PixelFormat format;
  std::uint64_t committed = 0;
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  constexpr std::uint32_t kFormats[] = {V4L2_PIX_FMT_GREY,  V4L2_PIX_FMT_Y16,   V4L2_PIX_FMT_YUYV,
                                        V4L2_PIX_FMT_MJPEG, V4L2_PIX_FMT_BGR24, V4L2_PIX_FMT_RGB24};
  const std::uint32_t wire = kFormats[data[0] % 6];
  const PixelFormat out = wire == V4L2_PIX_FMT_Y16 ? PixelFormat::kMono16
                          : (data[1] & 1)          ? PixelFormat::kBgr8
                                                   : PixelFormat::kMono8;
  const int w = 8 + 2 * (data[2] % 8);
  const int h = 4 + data[3] % 8;
  V4l2Recording rec;
  rec.formats = {wire};
  rec.width = w;
  rec.height = h;
  // Frames: [flags byte][sequence byte][length: 2 bytes LE, 0xFFFF = the full image][bytes...].
  std::size_t pos = 4;
  std::uint32_t seq = 0;
  while (pos + 4 <= size && rec.frames.size() < 8) {
    RecordedBuffer b;
    const std::uint8_t f = data[pos];
    b.flags = (f & 1 ? V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC : 0) |
              (f & 2 ? V4L2_BUF_FLAG_TSTAMP_SRC_SOE : 0) | (f & 4 ? V4L2_BUF_FLAG_ERROR : 0) |
              (f & 8 ? V4L2_BUF_FLAG_TIMESTAMP_COPY : 0);
    seq += data[pos + 1];
    b.sequence = seq;
    b.timestamp_ns = 1'000'000'000 + static_cast<std::int64_t>(rec.frames.size()) * 1'000'000;
    const std::size_t full = static_cast<std::size_t>(w) * h *
                             (wire == V4L2_PIX_FMT_GREY                                  ? 1
                              : wire == V4L2_PIX_FMT_BGR24 || wire == V4L2_PIX_FMT_RGB24 ? 3
                                                                                         : 2);
    const std::size_t len = data[pos + 2] | (static_cast<std::size_t>(data[pos + 3]) << 8);
    std::size_t n = len == 0xFFFF ? full : len;
    pos += 4;
    n = std::min(n, size - pos);
    b.bytes.assign(data + pos, data + pos + n);
    pos += n;
    rec.frames.push_back(std::move(b));
  }
  auto dev = std::make_shared<RecordedV4l2Device>(rec);
  V4l2CameraConfig cfg;
  cfg.path = rec.path;
  cfg.width = w;
  cfg.height = h;
  cfg.format = out;
  V4l2Camera cam(cfg, dev);
  cam.open();
  Sink sink(w, h, out);
  for (std::size_t i = 0; i < rec.frames.size(); ++i) {
    cam.next_frame(std::chrono::milliseconds(0), sink);
  }
  const auto c = cam.counters();
  if (c.frames != rec.frames.size()) std::abort();
  if (sink.committed + c.incomplete + c.convert_errors != c.frames) std::abort();
  cam.close();
  return 0;
}
