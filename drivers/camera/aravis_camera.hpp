#pragma once
// GigE Vision and USB3 Vision cameras through libaravis 0.8 (sensor-protocols.md 6.2). USB3
// Vision devices go through Aravis's libusb transport; GigE Vision through its GVSP stream thread.
//
//   open: arv_camera_new(camera_id | first camera) -> pixel format (Mono8 / Mono16 / BGR8, or the
//         camera's RGB8 / Bayer8 converted) -> region width x height -> frame rate -> exposure
//         (auto off) and gain -> trigger (free run, Software, or a hardware line: rising edge,
//         FrameStart) -> GigE packet size (negotiated with arv_camera_gv_auto_packet_size, or the
//         configured one) -> chunk data ExposureTime when the camera has chunks -> PTP
//         (PtpEnable or GevIEEE1588) when asked -> stream with `buffers` pre-allocated buffers
//         -> start acquisition
//   each frame: arv_stream_timeout_pop_buffer -> status (anything but SUCCESS, e.g. missing
//         packets, is counted `incomplete` and dropped) -> frame id gaps -> copy into the ring slot
//         (the one copy; Bayer/RGB converted on the way) -> push the buffer back
//
// Time: the buffer's device timestamp (ns: GigE ticks converted with the tick frequency, USB3
// Vision ns) is the sensor time, the camera clock (CameraClockKind::kDevice, mapped free-running)
// or PTP time when PTP is enabled (kPtp). Which instant it marks is vendor-specific (most cameras:
// start of exposure; `instant` configures it). host_rx is Aravis's system timestamp (CLOCK_REALTIME
// when the leader packet or transfer arrived), converted to CLOCK_MONOTONIC at once.
//
// Exposure per frame: the ChunkExposureTime of the frame when the camera sends chunk data, else
// the ExposureTime feature, read back after each change and every `exposure_poll` while auto
// exposure is on.
//
// Loss: Aravis's control-lost signal (GigE heartbeat failures, USB removal) or silence for the
// source's stale_after; the source closes the camera and opens it again by its id.

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "drivers/camera/camera_backend.hpp"

namespace livod::camera {

enum class TriggerMode : std::uint8_t { kFreeRun, kSoftware, kHardware };

struct AravisCameraConfig {
  std::string camera_id;  // Aravis device id ("Vendor-Model-Serial", "Fake_1"); empty = first
  int width = 0;
  int height = 0;
  PixelFormat format = PixelFormat::kMono8;
  std::optional<double> frame_rate_hz;  // free run: the camera's rate; software trigger: livod's
  std::optional<Nanoseconds> exposure;  // fixed exposure (auto off); unset = leave it
  std::optional<double> gain;           // camera units (usually dB); unset = leave it
  TriggerMode trigger = TriggerMode::kFreeRun;
  std::string trigger_source = "Line1";  // hardware trigger input line
  int buffers = 8;
  int packet_size = 0;         // GigE: bytes per GVSP packet; 0 = negotiate (auto)
  bool packet_resend = true;   // GigE: ask the camera to resend missing packets
  bool chunk_exposure = true;  // use ChunkExposureTime when the camera has chunk data
  bool ptp = false;            // enable PTP (IEEE 1588); an error if the camera has none
  StampInstant instant = StampInstant::kStartOfExposure;
  Nanoseconds exposure_poll{std::chrono::seconds(1)};
};

// Counters beyond the common ones (any thread).
struct AravisStatus {
  int packet_size = 0;         // negotiated GigE packet size (0: USB3 Vision / not yet)
  double frame_rate_hz = 0.0;  // free run: AcquisitionFrameRate read back after setting it
  bool chunks = false;         // per-frame exposure from chunk data
  bool ptp = false;            // PTP enabled
  std::string ptp_status;      // the camera's PtpStatus / GevIEEE1588Status at the last check
  std::uint64_t stream_failures = 0;   // Aravis stream statistics
  std::uint64_t stream_underruns = 0;  // no free buffer when a frame came (should stay 0)
  std::string serial;                  // of the opened camera (DeviceSerialNumber)
  std::string model;                   // vendor and model name
};

class AravisCamera final : public CameraBackend {
 public:
  explicit AravisCamera(AravisCameraConfig config);
  ~AravisCamera() override;

  void open() override;
  void close() noexcept override;
  Result next_frame(std::chrono::milliseconds timeout, FrameSink& sink) override;
  bool service() override;
  [[nodiscard]] std::string describe() const override;
  [[nodiscard]] std::string loss_reason() const override { return loss_reason_; }

  [[nodiscard]] AravisStatus status() const;  // any thread

  // Enables Aravis's in-process fake camera interface ("Fake_1"), for tests and benchmarks.
  static void enable_fake_interface();

 private:
  struct Impl;
  void read_back(std::int64_t now);  // exposure and gain features

  AravisCameraConfig config_;
  std::unique_ptr<Impl> impl_;
  std::string loss_reason_;
};

}  // namespace livod::camera
