#include "drivers/camera/aravis_camera.hpp"

#include <arv.h>

#include <atomic>
#include <cstring>
#include <memory>
#include <mutex>
#include <opencv2/imgproc.hpp>
#include <system_error>
#include <thread>
#include <utility>

#include "core/error.hpp"
#include "core/realtime_offset.hpp"

namespace livod::camera {
namespace {

constexpr std::int64_t kPtpCheckNs = 1'000'000'000;

// Aravis keeps process-wide device lists and interface state: camera discovery and creation from
// several capture threads at once is serialised here (opens are rare; streaming is not affected).
std::mutex& aravis_open_mutex() {
  static std::mutex m;
  return m;
}

std::string take_error(GError*& err) {
  std::string s = err != nullptr && err->message != nullptr ? err->message : "unknown error";
  g_clear_error(&err);
  return s;
}

// How the camera's pixels become the ring format.
enum class Conversion : std::uint8_t {
  kCopy,
  kRgbToBgr,
  kRgbToGrey,
  kBgrToGrey,
  kBayerToBgr,
  kBayerToGrey
};

struct FormatChoice {
  ArvPixelFormat camera;
  Conversion conversion;
  int cv_code;  // OpenCV colour conversion when not a copy
  int camera_cv_type;
};

std::optional<FormatChoice> choose_format(const std::vector<ArvPixelFormat>& available,
                                          PixelFormat to) {
  auto has = [&](ArvPixelFormat f) {
    return std::find(available.begin(), available.end(), f) != available.end();
  };
  struct Bayer {
    ArvPixelFormat f;
    int to_bgr;
  };
  // Aravis / GenICam Bayer names give the colour of the first two pixels; OpenCV's codes name the
  // 2x2 block starting at the second row and column.
  const Bayer bayers[] = {{ARV_PIXEL_FORMAT_BAYER_RG_8, cv::COLOR_BayerBG2BGR},
                          {ARV_PIXEL_FORMAT_BAYER_GR_8, cv::COLOR_BayerGB2BGR},
                          {ARV_PIXEL_FORMAT_BAYER_GB_8, cv::COLOR_BayerGR2BGR},
                          {ARV_PIXEL_FORMAT_BAYER_BG_8, cv::COLOR_BayerRG2BGR}};
  switch (to) {
    case PixelFormat::kMono8:
      if (has(ARV_PIXEL_FORMAT_MONO_8))
        return FormatChoice{ARV_PIXEL_FORMAT_MONO_8, Conversion::kCopy, 0, CV_8UC1};
      if (has(ARV_PIXEL_FORMAT_BGR_8_PACKED)) {
        return FormatChoice{ARV_PIXEL_FORMAT_BGR_8_PACKED, Conversion::kBgrToGrey,
                            cv::COLOR_BGR2GRAY, CV_8UC3};
      }
      if (has(ARV_PIXEL_FORMAT_RGB_8_PACKED)) {
        return FormatChoice{ARV_PIXEL_FORMAT_RGB_8_PACKED, Conversion::kRgbToGrey,
                            cv::COLOR_RGB2GRAY, CV_8UC3};
      }
      for (const auto& b : bayers) {
        if (has(b.f)) return FormatChoice{b.f, Conversion::kBayerToGrey, b.to_bgr, CV_8UC1};
      }
      return std::nullopt;
    case PixelFormat::kMono16:
      if (has(ARV_PIXEL_FORMAT_MONO_16))
        return FormatChoice{ARV_PIXEL_FORMAT_MONO_16, Conversion::kCopy, 0, CV_16UC1};
      return std::nullopt;
    case PixelFormat::kBgr8:
      if (has(ARV_PIXEL_FORMAT_BGR_8_PACKED))
        return FormatChoice{ARV_PIXEL_FORMAT_BGR_8_PACKED, Conversion::kCopy, 0, CV_8UC3};
      if (has(ARV_PIXEL_FORMAT_RGB_8_PACKED)) {
        return FormatChoice{ARV_PIXEL_FORMAT_RGB_8_PACKED, Conversion::kRgbToBgr, cv::COLOR_RGB2BGR,
                            CV_8UC3};
      }
      for (const auto& b : bayers) {
        if (has(b.f)) return FormatChoice{b.f, Conversion::kBayerToBgr, b.to_bgr, CV_8UC1};
      }
      return std::nullopt;
  }
  return std::nullopt;
}

}  // namespace

struct AravisCamera::Impl {
  ArvCamera* camera = nullptr;
  ArvDevice* device = nullptr;  // owned by camera
  ArvStream* stream = nullptr;
  ArvChunkParser* chunks = nullptr;
  gulong lost_handler = 0;
  std::atomic<bool> control_lost{false};
  FormatChoice format{};
  bool auto_exposure = false;
  Nanoseconds exposure{0};
  bool exposure_known = false;
  double gain = std::nan("");
  bool have_frame_id = false;
  std::uint64_t last_frame_id = 0;
  std::int64_t next_exposure_poll_ns = 0;
  std::int64_t next_trigger_ns = 0;
  std::int64_t last_trigger_ns = 0;
  std::int64_t next_realtime_refresh_ns = 0;
  std::int64_t next_ptp_check_ns = 0;
  RealtimeToMonotonic realtime;
  cv::Mat bayer_bgr;  // Bayer -> grey goes through BGR (allocated with the first frame)

  // Published for status() (any thread).
  mutable std::mutex status_mutex;
  AravisStatus status;

  struct Reaper {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done;
  };
  std::vector<Reaper> reapers;  // releasing closed cameras (see close())

  // Joins the reapers that have finished (all of them with `all`).
  void join_reapers(bool all) {
    for (auto it = reapers.begin(); it != reapers.end();) {
      if (all || it->done->load()) {
        it->thread.join();
        it = reapers.erase(it);
      } else {
        ++it;
      }
    }
  }

  ~Impl() { join_reapers(true); }

  static void on_control_lost(ArvDevice* /*device*/, gpointer self) {
    static_cast<Impl*>(self)->control_lost.store(true, std::memory_order_relaxed);
  }
};

AravisCamera::AravisCamera(AravisCameraConfig config)
    : config_(std::move(config)), impl_(std::make_unique<Impl>()) {
  if (config_.buffers < 2) config_.buffers = 2;
}

AravisCamera::~AravisCamera() {
  close();
}

void AravisCamera::enable_fake_interface() {
  const std::lock_guard lock(aravis_open_mutex());
  arv_enable_interface("Fake");
}

std::string AravisCamera::describe() const {
  return "Aravis camera " +
         (config_.camera_id.empty() ? std::string("(first found)") : "'" + config_.camera_id + "'");
}

AravisStatus AravisCamera::status() const {
  const std::lock_guard lock(impl_->status_mutex);
  return impl_->status;
}

void AravisCamera::open() {
  Impl& m = *impl_;
  loss_reason_.clear();
  GError* err = nullptr;
  const std::string what = describe();
  auto fail = [&](const std::string& msg) {
    close();
    throw Error(what + ": " + msg);
  };
  {
    const std::lock_guard lock(aravis_open_mutex());
    arv_update_device_list();
    m.camera =
        arv_camera_new(config_.camera_id.empty() ? nullptr : config_.camera_id.c_str(), &err);
    if (m.camera == nullptr) {
      std::string seen;
      for (unsigned i = 0; i < arv_get_n_devices(); ++i) {
        seen += (seen.empty() ? "" : ", ") + std::string(arv_get_device_id(i));
      }
      const std::string why = take_error(err);
      throw Error(what + " not found (" + why +
                  "; cameras visible: " + (seen.empty() ? std::string("none") : seen) + ")");
    }
  }
  m.device = arv_camera_get_device(m.camera);
  m.control_lost.store(false);
  m.lost_handler =
      g_signal_connect(m.device, "control-lost", G_CALLBACK(&Impl::on_control_lost), &m);
  const char* serial = arv_camera_get_device_serial_number(m.camera, nullptr);
  const char* model = arv_camera_get_model_name(m.camera, nullptr);
  const char* vendor = arv_camera_get_vendor_name(m.camera, nullptr);

  // Pixel format.
  guint n = 0;
  gint64* formats = arv_camera_dup_available_pixel_formats(m.camera, &n, &err);
  std::vector<ArvPixelFormat> available;
  for (guint i = 0; formats != nullptr && i < n; ++i)
    available.push_back(static_cast<ArvPixelFormat>(formats[i]));
  g_free(formats);
  g_clear_error(&err);
  const auto choice = choose_format(available, config_.format);
  if (!choice)
    fail(std::string("offers no pixel format livod converts to ") + to_string(config_.format));
  m.format = *choice;
  arv_camera_set_pixel_format(m.camera, choice->camera, &err);
  if (err != nullptr) fail("cannot set the pixel format (" + take_error(err) + ")");

  // Region: the configured size, keeping the camera's offsets when they leave room for it.
  gint x = 0, y = 0, w = 0, h = 0;
  arv_camera_get_region(m.camera, &x, &y, &w, &h, &err);
  g_clear_error(&err);
  gint sensor_w = 0, sensor_h = 0;
  arv_camera_get_sensor_size(m.camera, &sensor_w, &sensor_h, &err);
  g_clear_error(&err);
  if (sensor_w > 0 && x + config_.width > sensor_w) x = 0;
  if (sensor_h > 0 && y + config_.height > sensor_h) y = 0;
  arv_camera_set_region(m.camera, x, y, config_.width, config_.height, &err);
  g_clear_error(&err);
  arv_camera_get_region(m.camera, &x, &y, &w, &h, &err);
  g_clear_error(&err);
  if (w != config_.width || h != config_.height) {
    fail("delivers " + std::to_string(w) + "x" + std::to_string(h) + ", not the configured " +
         std::to_string(config_.width) + "x" + std::to_string(config_.height));
  }

  // Trigger and frame rate.
  double frame_rate = 0.0;
  if (config_.trigger == TriggerMode::kFreeRun) {
    arv_camera_clear_triggers(m.camera, &err);
    g_clear_error(&err);
    if (config_.frame_rate_hz) {
      arv_camera_set_frame_rate(m.camera, *config_.frame_rate_hz, &err);
      if (err != nullptr) fail("cannot set the frame rate (" + take_error(err) + ")");
    }
    frame_rate = arv_camera_get_frame_rate(m.camera, &err);
    g_clear_error(&err);
  } else {
    const char* source =
        config_.trigger == TriggerMode::kSoftware ? "Software" : config_.trigger_source.c_str();
    if (config_.trigger == TriggerMode::kSoftware &&
        !arv_camera_is_software_trigger_supported(m.camera, nullptr)) {
      fail("has no software trigger");
    }
    arv_camera_set_trigger(m.camera, source, &err);
    if (err != nullptr)
      fail(std::string("cannot set trigger source ") + source + " (" + take_error(err) + ")");
  }

  // Exposure and gain.
  if (config_.exposure) {
    if (arv_camera_is_exposure_auto_available(m.camera, nullptr)) {
      arv_camera_set_exposure_time_auto(m.camera, ARV_AUTO_OFF, &err);
      g_clear_error(&err);
    }
    arv_camera_set_exposure_time(m.camera, static_cast<double>(config_.exposure->count()) * 1e-3,
                                 &err);
    if (err != nullptr) fail("cannot set the exposure (" + take_error(err) + ")");
  }
  if (config_.gain) {
    if (arv_camera_is_gain_auto_available(m.camera, nullptr)) {
      arv_camera_set_gain_auto(m.camera, ARV_AUTO_OFF, &err);
      g_clear_error(&err);
    }
    arv_camera_set_gain(m.camera, *config_.gain, &err);
    if (err != nullptr) fail("cannot set the gain (" + take_error(err) + ")");
  }
  m.auto_exposure = arv_camera_is_exposure_auto_available(m.camera, nullptr) &&
                    arv_camera_get_exposure_time_auto(m.camera, nullptr) != ARV_AUTO_OFF;

  // GigE packet size.
  int packet_size = 0;
  if (arv_camera_is_gv_device(m.camera)) {
    if (config_.packet_size > 0) {
      arv_camera_gv_set_packet_size(m.camera, config_.packet_size, &err);
      if (err != nullptr)
        fail("cannot set packet size " + std::to_string(config_.packet_size) + " (" +
             take_error(err) + ")");
      packet_size = static_cast<int>(arv_camera_gv_get_packet_size(m.camera, nullptr));
    } else {
      packet_size = static_cast<int>(arv_camera_gv_auto_packet_size(m.camera, &err));
      if (err != nullptr) fail("packet size negotiation failed (" + take_error(err) + ")");
    }
  }

  // Per-frame exposure from chunk data.
  bool chunks = false;
  if (config_.chunk_exposure && arv_camera_are_chunks_available(m.camera, nullptr)) {
    arv_camera_set_chunks(m.camera, "ExposureTime", &err);
    if (err == nullptr) {
      m.chunks = arv_camera_create_chunk_parser(m.camera);
      chunks = m.chunks != nullptr;
    }
    g_clear_error(&err);
  }

  // PTP.
  std::string ptp_status;
  if (config_.ptp) {
    const char* feature = nullptr;
    for (const char* f : {"PtpEnable", "GevIEEE1588"}) {
      if (arv_camera_is_feature_available(m.camera, f, nullptr)) {
        feature = f;
        break;
      }
    }
    if (feature == nullptr) fail("has no PTP (neither PtpEnable nor GevIEEE1588); set ptp: false");
    arv_camera_set_boolean(m.camera, feature, TRUE, &err);
    if (err != nullptr)
      fail(std::string("cannot enable ") + feature + " (" + take_error(err) + ")");
  }

  // Stream and buffers.
  m.stream = arv_camera_create_stream(m.camera, nullptr, nullptr, &err);
  if (m.stream == nullptr) fail("cannot create the stream (" + take_error(err) + ")");
  if (ARV_IS_GV_STREAM(m.stream)) {
    g_object_set(m.stream, "packet-resend",
                 config_.packet_resend ? ARV_GV_STREAM_PACKET_RESEND_ALWAYS
                                       : ARV_GV_STREAM_PACKET_RESEND_NEVER,
                 nullptr);
  }
  const guint payload = arv_camera_get_payload(m.camera, &err);
  if (err != nullptr || payload == 0)
    fail("cannot read the payload size (" + take_error(err) + ")");
  for (int i = 0; i < config_.buffers; ++i)
    arv_stream_push_buffer(m.stream, arv_buffer_new_allocate(payload));
  arv_camera_start_acquisition(m.camera, &err);
  if (err != nullptr) fail("cannot start acquisition (" + take_error(err) + ")");

  m.have_frame_id = false;
  m.realtime.refresh();
  const std::int64_t now = host_now().ns;
  m.next_trigger_ns = now;
  m.exposure_known = false;
  read_back(now);  // the first frames already carry the exposure
  m.next_ptp_check_ns = 0;
  {
    const std::lock_guard lock(m.status_mutex);
    m.status.packet_size = packet_size;
    m.status.frame_rate_hz = frame_rate;
    m.status.chunks = chunks;
    m.status.ptp = config_.ptp;
    m.status.ptp_status = ptp_status;
    m.status.serial = serial != nullptr ? serial : "";
    m.status.model =
        std::string(vendor != nullptr ? vendor : "") + " " + (model != nullptr ? model : "");
  }
}

void AravisCamera::close() noexcept {
  Impl& m = *impl_;
  if (m.device != nullptr && m.lost_handler != 0)
    g_signal_handler_disconnect(m.device, m.lost_handler);
  m.lost_handler = 0;
  m.device = nullptr;
  if (m.camera == nullptr && m.stream == nullptr) return;
  // Stopping and releasing a GigE camera that is gone blocks for seconds in GVCP timeouts (stop
  // command, stream channel, control release: ~12 s with Aravis 0.8's defaults). That must not
  // delay the reconnection, so the objects are released on a reaper thread; the destructor joins
  // the reapers. A healthy camera is released within milliseconds the same way.
  ArvCamera* camera = std::exchange(m.camera, nullptr);
  ArvStream* stream = std::exchange(m.stream, nullptr);
  ArvChunkParser* chunks = std::exchange(m.chunks, nullptr);
  const bool stop = !m.control_lost.load(std::memory_order_relaxed);
  m.join_reapers(false);
  try {
    auto done = std::make_shared<std::atomic<bool>>(false);
    std::thread t([camera, stream, chunks, stop, done] {
      if (camera != nullptr && stop) arv_camera_stop_acquisition(camera, nullptr);
      if (stream != nullptr) g_object_unref(stream);
      if (chunks != nullptr) g_object_unref(chunks);
      if (camera != nullptr) {
        const std::lock_guard lock(aravis_open_mutex());
        g_object_unref(camera);
      }
      done->store(true);
    });
    m.reapers.push_back({std::move(t), std::move(done)});
  } catch (const std::system_error&) {
    // No thread available: release here (blocking).
    if (camera != nullptr && stop) arv_camera_stop_acquisition(camera, nullptr);
    if (stream != nullptr) g_object_unref(stream);
    if (chunks != nullptr) g_object_unref(chunks);
    if (camera != nullptr) g_object_unref(camera);
  }
}

void AravisCamera::read_back(std::int64_t now) {
  Impl& m = *impl_;
  GError* err = nullptr;
  const double us = arv_camera_get_exposure_time(m.camera, &err);
  if (err == nullptr && us > 0.0) {
    m.exposure = Nanoseconds(static_cast<std::int64_t>(us * 1e3 + 0.5));
    m.exposure_known = true;
    stats_.set_exposure(m.exposure);
  }
  g_clear_error(&err);
  if (arv_camera_is_gain_available(m.camera, nullptr)) {
    const double g = arv_camera_get_gain(m.camera, &err);
    if (err == nullptr) {
      m.gain = g;
      stats_.set_gain(g);
    }
    g_clear_error(&err);
  }
  m.next_exposure_poll_ns = now + config_.exposure_poll.count();
}

bool AravisCamera::service() {
  Impl& m = *impl_;
  if (m.control_lost.load(std::memory_order_relaxed)) {
    loss_reason_ = describe() + ": control lost (camera gone or unreachable)";
    return false;
  }
  GError* err = nullptr;
  const std::int64_t now = host_now().ns;
  if (auto c = mailbox_.take()) {
    if (c->exposure) {
      if (arv_camera_is_exposure_auto_available(m.camera, nullptr)) {
        arv_camera_set_exposure_time_auto(m.camera, ARV_AUTO_OFF, nullptr);
      }
      arv_camera_set_exposure_time(m.camera, static_cast<double>(c->exposure->count()) * 1e-3,
                                   &err);
      if (err != nullptr) stats_.add_control_error();
      g_clear_error(&err);
      m.auto_exposure = false;
    }
    if (c->gain) {
      arv_camera_set_gain(m.camera, *c->gain, &err);
      if (err != nullptr) stats_.add_control_error();
      g_clear_error(&err);
    }
    m.next_exposure_poll_ns = 0;  // read back now
  }
  if (now >= m.next_exposure_poll_ns &&
      (m.auto_exposure || !m.exposure_known || m.next_exposure_poll_ns == 0)) {
    read_back(now);
  }
  if (config_.trigger == TriggerMode::kSoftware && config_.frame_rate_hz &&
      now >= m.next_trigger_ns) {
    arv_camera_software_trigger(m.camera, &err);
    if (err == nullptr) {
      stats_.add_trigger();
    } else {
      stats_.add_control_error();
    }
    m.last_trigger_ns = now;
    g_clear_error(&err);
    const auto period = static_cast<std::int64_t>(1e9 / *config_.frame_rate_hz);
    m.next_trigger_ns += period;
    if (m.next_trigger_ns < now) m.next_trigger_ns = now + period;  // fell behind: no burst
  }
  if (now >= m.next_realtime_refresh_ns) {
    m.realtime.refresh();
    m.next_realtime_refresh_ns = now + kRealtimeOffsetRefreshNs;
    guint64 completed = 0, failures = 0, underruns = 0;
    arv_stream_get_statistics(m.stream, &completed, &failures, &underruns);
    const std::lock_guard lock(m.status_mutex);
    m.status.stream_failures = failures;
    m.status.stream_underruns = underruns;
  }
  if (config_.ptp && now >= m.next_ptp_check_ns) {
    std::string status;
    for (const char* f : {"PtpStatus", "GevIEEE1588Status"}) {
      if (arv_camera_is_feature_available(m.camera, f, nullptr)) {
        const char* s = arv_camera_get_string(m.camera, f, &err);
        if (err == nullptr && s != nullptr) status = s;
        g_clear_error(&err);
        break;
      }
    }
    m.next_ptp_check_ns = now + kPtpCheckNs;
    const std::lock_guard lock(m.status_mutex);
    m.status.ptp_status = status;
  }
  return true;
}

CameraBackend::Result AravisCamera::next_frame(std::chrono::milliseconds timeout, FrameSink& sink) {
  Impl& m = *impl_;
  ArvBuffer* buffer =
      arv_stream_timeout_pop_buffer(m.stream, static_cast<guint64>(timeout.count()) * 1000);
  if (buffer == nullptr) {
    if (m.control_lost.load(std::memory_order_relaxed)) {
      loss_reason_ = describe() + ": control lost (camera gone or unreachable)";
      return Result::kLost;
    }
    return Result::kIdle;
  }
  const std::int64_t system_ns = static_cast<std::int64_t>(arv_buffer_get_system_timestamp(buffer));
  const HostTime rx = system_ns > 0 ? m.realtime.to_host(system_ns) : host_now();
  size_t size = 0;
  arv_buffer_get_data(buffer, &size);
  stats_.add_frame(size, rx.ns);
  const std::uint64_t frame_id = arv_buffer_get_frame_id(buffer);
  if (m.have_frame_id && frame_id > m.last_frame_id + 1) {
    stats_.add_gaps(frame_id - m.last_frame_id - 1);
  } else if (m.have_frame_id && frame_id < m.last_frame_id && m.last_frame_id > 0xF000 &&
             frame_id < 0x1000) {
    // GigE Vision 1.x block ids are 16 bits, 1..65535 (0 is never used).
    stats_.add_gaps(0xFFFF - m.last_frame_id + frame_id - 1);
  }
  m.have_frame_id = true;
  m.last_frame_id = frame_id;

  Result result = Result::kFrame;
  const ArvBufferPayloadType payload = arv_buffer_get_payload_type(buffer);
  if (arv_buffer_get_status(buffer) != ARV_BUFFER_STATUS_SUCCESS ||
      (payload != ARV_BUFFER_PAYLOAD_TYPE_IMAGE && payload != ARV_BUFFER_PAYLOAD_TYPE_CHUNK_DATA)) {
    stats_.add_incomplete();
    result = Result::kDropped;
  } else {
    const int w = arv_buffer_get_image_width(buffer);
    const int h = arv_buffer_get_image_height(buffer);
    size_t image_size = 0;
    const void* image = arv_buffer_get_image_data(buffer, &image_size);
    gint x_pad = 0, y_pad = 0;
    arv_buffer_get_image_padding(buffer, &x_pad, &y_pad);
    const int in_bpp = m.format.camera_cv_type == CV_8UC3    ? 3
                       : m.format.camera_cv_type == CV_16UC1 ? 2
                                                             : 1;
    const std::size_t stride =
        static_cast<std::size_t>(w) * in_bpp + static_cast<std::size_t>(std::max(x_pad, 0));
    if (w != config_.width || h != config_.height || image == nullptr ||
        image_size < stride * static_cast<std::size_t>(h)) {
      stats_.add_convert_error();
      result = Result::kDropped;
    } else if (cv::Mat slot = sink.acquire(w, h); !slot.empty()) {
      const cv::Mat src(h, w, m.format.camera_cv_type, const_cast<void*>(image), stride);
      switch (m.format.conversion) {
        case Conversion::kCopy:
          src.copyTo(slot);
          break;
        case Conversion::kBayerToGrey:
          // Demosaicing to grey goes through BGR: a scratch image allocated with the first frame.
          cv::cvtColor(src, m.bayer_bgr, m.format.cv_code);
          cv::cvtColor(m.bayer_bgr, slot, cv::COLOR_BGR2GRAY);
          break;
        default:
          cv::cvtColor(src, slot, m.format.cv_code);
          break;
      }
      FrameInfo info;
      info.sequence = frame_id;
      info.sensor_time = SensorTime(static_cast<std::int64_t>(arv_buffer_get_timestamp(buffer)));
      info.host_rx = rx;
      info.instant = config_.instant;
      info.clock = config_.ptp ? CameraClockKind::kPtp : CameraClockKind::kDevice;
      info.exposure = m.exposure_known ? m.exposure : Nanoseconds(0);
      info.exposure_source =
          m.exposure_known ? ExposureSource::kReadback : ExposureSource::kUnknown;
      if (m.chunks != nullptr) {
        GError* err = nullptr;
        const double us =
            arv_chunk_parser_get_float_value(m.chunks, buffer, "ChunkExposureTime", &err);
        if (err == nullptr && us > 0.0) {
          info.exposure = Nanoseconds(static_cast<std::int64_t>(us * 1e3 + 0.5));
          info.exposure_source = ExposureSource::kFrameData;
        }
        g_clear_error(&err);
      }
      info.gain = m.gain;
      info.trigger_host_ns = config_.trigger == TriggerMode::kSoftware ? m.last_trigger_ns : 0;
      info.width = w;
      info.height = h;
      info.format = config_.format;
      info.stride = slot.step[0];
      sink.commit(info);
    }
  }
  arv_stream_push_buffer(m.stream, buffer);
  return result;
}

}  // namespace livod::camera
