#pragma once
// The recorder of `livod record` and `outputs.record` (docs/record.md): raw sensor data to files
// on its own IO thread, never slowing the capture threads or the scheduler down.
//
//   capture thread ──tap (PacketRing: bounded, full ⇒ drop + count)──▶ recorder thread
//                                                                      ─▶ <sensor>.pcap (blocks)
//   CAN IMU capture thread ──tap (SpscRing<CanRecord>)──▶ recorder thread ─▶ <sensor>.log
//   serial IMU capture thread ──tap (PacketRing of reads)──▶ recorder thread ─▶ <sensor>.serial
//   camera capture thread ──tap (FrameRing)──▶ recorder thread: camera clock, PNG ─▶ <sensor>/
//
// Each capture thread copies every datagram into a tap ring owned by the recorder, beside its own
// ring to the scheduler (CaptureThreadConfig::tap). The recorder thread merges a LiDAR's streams
// (lidar, IMU, position ports) in receive-time order into one classic pcap per LiDAR: valid
// Ethernet/IPv4/UDP frames whose record time is the kernel receive time (CLOCK_MONOTONIC moved
// onto UTC by one offset taken when the recorder starts, so the file never jumps with NTP).
// Records are collected into blocks written with one write each (io/block_file.hpp): a block is
// written when it is full or `flush_period` after its first record, so a killed process loses at
// most that much and leaves a file that ends at a record boundary or inside its last record.
//
// Losses are counted per file with the reason and the span of recording time they cover:
//   - buffer full: the tap ring overflowed because the recorder (the disk) fell behind;
//   - write failed: a block could not be written (disk full, I/O error); its records are lost,
//     the file is cut back to its last complete block, and writing is retried every
//     `retry_period` (records arriving meanwhile are lost with the same reason);
//   - truncated: a datagram longer than its slot (it would be a wrong packet in the file).
//
// CAN IMUs are recorded as candump logs (io/candump.hpp: `candump -l` lines, the frame's kernel
// receive time at the format's microsecond resolution, the configured interface's name), serial /
// USB IMUs as livod serial captures (io/serial_capture.hpp: every read as the host read it, with
// its receive time in ns); both with the same blocks, record times (UTC by the one offset) and
// loss accounting as the pcaps, so a replay merges all the recording's files on one timeline.
// An Ouster without a metadata file: the JSON its live source fetched from the sensor is written
// as <sensor>.json (save_metadata(), any thread; written on the recorder thread).
// Cameras are recorded as EuRoC/ASL folders (io/euroc_writer.hpp: lossless PNG per frame,
// data.csv with the exposure): the recorder thread maps each frame through its own CameraClock
// (the same configuration and the same frames as the live source's) and names it by its
// mid-exposure time on the common timeline, on the pcaps' UTC clock; it encodes the PNGs (never a
// capture thread). data.csv is flushed with the same period as the blocks; a frame that cannot be
// written (disk full) is lost and counted, the frames before it stay.
//
// Threads: add_*_stream() and start() on the owning thread (packets a capture thread pushes
// before start() wait in the tap); stop() after the capture threads stopped (it drains the taps);
// stats() and heartbeat() from any thread.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "core/spsc_ring.hpp"
#include "core/time.hpp"
#include "daemon/runtime/heartbeat.hpp"
#include "drivers/camera/camera_clock.hpp"
#include "drivers/camera/frame_ring.hpp"
#include "drivers/capture/packet_ring.hpp"
#include "drivers/imu/imu_decoder.hpp"

namespace livod::daemon::record {

struct RecorderOptions {
  std::filesystem::path dir;                       // created if missing
  std::size_t block_bytes = std::size_t{1} << 20;  // one write(2) per block
  Nanoseconds flush_period{200'000'000};           // a partly filled block waits at most this long
  // Packets younger than this wait for the LiDAR's other streams, so that a file's records are in
  // receive-time order across its ports (a capture thread may push a little late).
  Nanoseconds hold_back{50'000'000};
  Nanoseconds sync_period{2'000'000'000};   // fdatasync: survives a power loss up to here
  Nanoseconds retry_period{1'000'000'000};  // after a failed write, the next attempt
  // Tap ring memory per stream: capacity = this / slot size, within [256, 16384] packets.
  std::size_t stream_buffer_bytes = std::size_t{16} << 20;
};

// One UDP stream of a LiDAR to record into `<sensor>.pcap`.
struct PacketStreamSpec {
  std::string sensor;              // the file is <sensor>.pcap
  std::string stream;              // "lidar", "imu", "position"
  std::size_t slot_bytes = 65536;  // the largest datagram of the port (the capture ring's slot)
  std::uint32_t dst_ip = 0;        // written as the frames' destination (host order; 0 unknown)
};

// The kinds of file a recording holds.
enum class RecordedFormat : std::uint8_t { pcap, candump, serial };

// A CAN IMU to record into `<sensor>.log` (a candump log).
struct CanStreamSpec {
  std::string sensor;
  std::string interface;  // written in every line ("can0")
};

// A serial / USB IMU to record into `<sensor>.serial` (a livod serial capture).
struct SerialStreamSpec {
  std::string sensor;
  std::size_t slot_bytes = 4096;  // the capture thread's largest read
};

// A camera to record into the EuRoC folder `<sensor>/` (data.csv, data/<ns>.png).
struct CameraStreamSpec {
  std::string sensor;
  std::size_t frame_bytes = 0;      // the capture ring's slot: width x height x bytes per pixel
  camera::CameraClockConfig clock;  // the live source's (devices::camera_clock_config)
};

struct LossSpan {
  std::string reason;         // "buffer full (disk too slow)", "write failed: No space left ..."
  std::int64_t first_ns = 0;  // recording time (the pcap's clock, UTC ns) of the first loss
  std::int64_t last_ns = 0;   // ... and of the last one in this span
  std::uint64_t packets = 0;
  std::uint64_t bytes = 0;  // payload bytes (0 for buffer overflows: never seen)
};

struct FileStats {
  std::string sensor;
  std::filesystem::path file;
  std::vector<std::string> streams;
  std::string unit = "packets";     // what `packets` counts: "packets", "frames", "reads"
  std::uint64_t packets = 0;        // datagrams (CAN frames, serial reads) written
  std::uint64_t payload_bytes = 0;  // their UDP payload (CAN data, serial) bytes
  std::uint64_t file_bytes = 0;     // the file's size
  std::int64_t first_ns = 0;        // first and last record time written (UTC ns); 0: none
  std::int64_t last_ns = 0;
  std::uint64_t lost_buffer_full = 0;
  std::uint64_t lost_write_failed = 0;
  std::uint64_t lost_truncated = 0;
  std::uint64_t lost_invalid = 0;  // a record the file's format cannot hold (never seen live)
  std::vector<LossSpan> losses;    // in time order; consecutive losses of one reason merged
  std::string last_error;          // the last write error ("No space left on device"), or empty
  std::vector<std::string> notes;  // e.g. the sensor metadata saved beside the file
  [[nodiscard]] std::uint64_t lost() const {
    return lost_buffer_full + lost_write_failed + lost_truncated + lost_invalid;
  }
};

class Recorder {
 public:
  // Creates the folder. Throws livod::Error if it cannot.
  explicit Recorder(RecorderOptions options);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  // Before start(): opens <sensor>.pcap on the sensor's first stream (writes its header; throws
  // livod::Error naming the file) and returns the tap ring the stream's capture thread pushes
  // into. The ring lives as long as the recorder.
  drivers::capture::PacketRing& add_packet_stream(const PacketStreamSpec& spec);
  // Before start(): opens <sensor>.log (throws livod::Error naming the file, or for a second
  // stream of the sensor) and returns the tap its CAN capture thread pushes into.
  SpscRing<imu::CanRecord>& add_can_stream(const CanStreamSpec& spec);
  // Before start(): opens <sensor>.serial and writes its header; returns the tap of its reads.
  drivers::capture::PacketRing& add_serial_stream(const SerialStreamSpec& spec);
  // Before start(): creates the folder <sensor>/ with data/ and data.csv; returns the tap of its
  // frames (memory: up to stream_buffer_bytes, 4 to 64 frames).
  camera::FrameRing& add_camera_stream(const CameraStreamSpec& spec);

  // Before start(): the Ouster `sensor` has no metadata file; its metadata, fetched from the
  // sensor, is to be saved as <sensor>.json (save_metadata). stop() reports it if it never came.
  void expect_metadata(const std::string& sensor);
  // Any thread (the metadata fetcher's): queues the JSON for the recorder thread, which writes the
  // first as <sensor>.json and any later different one (a re-initialised sensor) as
  // <sensor>.reinit-<n>.json, noting it in the pcap's stats. Never blocks on the disk.
  void save_metadata(const std::string& sensor, std::string json);

  void start();
  // Drains every tap (call once the capture threads stopped), writes the last blocks, syncs and
  // closes the files, joins the thread. Returns what went wrong (losses, errors), one line each.
  // Idempotent.
  std::vector<std::string> stop();

  // Any thread: a snapshot (refreshed by the recorder thread once per turn).
  [[nodiscard]] std::vector<FileStats> stats() const;
  [[nodiscard]] const runtime::Heartbeat& heartbeat() const { return heartbeat_; }
  [[nodiscard]] const std::filesystem::path& dir() const { return options_.dir; }
  [[nodiscard]] bool started() const { return started_; }
  // UTC = monotonic + this (the offset every record time uses).
  [[nodiscard]] std::int64_t realtime_offset_ns() const { return realtime_offset_ns_; }

 private:
  struct File;
  struct CameraFolder;
  bool turn_cameras(HostTime now, bool final);
  bool write_metadata();
  File& new_file(const std::string& sensor, const std::string& extension, RecordedFormat format);
  void run(const std::stop_token& stop);
  bool turn(HostTime now, bool final);
  void publish_stats();

  RecorderOptions options_;
  std::int64_t realtime_offset_ns_ = 0;
  std::vector<std::unique_ptr<File>> files_;
  std::vector<std::unique_ptr<CameraFolder>> cameras_;
  runtime::Heartbeat heartbeat_;
  struct Metadata {
    std::string sensor;
    std::string last_json;  // the newest written
    int written = 0;
  };
  std::vector<Metadata> metadata_;  // recorder thread (after start())
  std::mutex metadata_mutex_;
  std::vector<std::pair<std::string, std::string>> metadata_queue_;  // guarded: (sensor, json)
  mutable std::mutex stats_mutex_;
  std::vector<FileStats> stats_;
  bool started_ = false;
  bool stopped_ = false;
  std::jthread thread_;  // last
};

// One line per file for logs and reports: "os1.pcap: 12345 packets, 15.2 MB, 0 lost".
std::string format_file_stats(const FileStats& s);

}  // namespace livod::daemon::record
