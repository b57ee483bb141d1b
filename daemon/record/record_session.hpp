#pragma once
// One recording (`livod record -o DIR`, `outputs.record: DIR`, `livod run --record DIR`): which
// sensors can be recorded, the Recorder that writes them, and the files beside the data that make
// the folder replayable (docs/record.md):
//
//   DIR/config.yaml      the configuration with every recorded sensor's source replaced by its
//                        file (source: {replay: {file: <sensor>.pcap}}, .log, .serial) and the
//                        files it names
//                        (Ouster metadata, Velodyne/Hesai calibration) copied beside it, so
//                        `livod replay --config DIR/config.yaml -o OUT` replays the recording.
//                        Written when the recording starts: a killed recorder leaves it too.
//   DIR/<sensor>.pcap    one per LiDAR (recorder.hpp)
//   DIR/<sensor>.log     one per CAN IMU: a candump log
//   DIR/<sensor>.serial  one per serial / USB IMU: a livod serial capture
//   DIR/<sensor>/        one per camera: an EuRoC/ASL folder (data.csv, data/<ns>.png); its
//                        sensor's clock becomes `direct`, time_offset_s 0, decimation 1 (the
//                        folder holds the live frames' mapped times)
//   DIR/recording.txt    written at the end: duration, per file packets, bytes and every loss
//                        (reason, packets, recording time it covers)

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/problems.hpp"
#include "daemon/record/recorder.hpp"

namespace livod::daemon::record {

// What keeps a configuration from being recorded, as configuration problems (not_implemented,
// naming the sensor): every enabled sensor must be a live packet LiDAR over UDP, or a camera or a
// CAN / serial IMU with a device source; a LiDAR's ports must be the ones its
// replay reads (the driver's defaults: a replay source cannot name ports yet); an Ouster needs
// its metadata file.
std::vector<ConfigProblem> record_problems(const LivodConfig& config);

class RecordSession {
 public:
  // Refuses (livod::Error) a folder that already holds a recording (config.yaml), a configuration
  // that was not loaded from a file, or one with record_problems(). Creates the folder, copies
  // the sensors' files, writes config.yaml.
  RecordSession(const LivodConfig& config, std::filesystem::path dir, RecorderOptions options = {});

  [[nodiscard]] Recorder& recorder() { return recorder_; }
  // Before start(): the sensor is not opened (`livod run` opens only what the estimator uses,
  // e.g. no camera with estimator.vio disabled): it is logged and written `enabled: false` into
  // config.yaml, so that the replay does not look for a file the recording does not hold.
  void leave_out(const std::string& sensor, const std::string& reason);
  void start() { recorder_.start(); }
  // Stops the recorder (after the capture threads stopped), writes recording.txt. Returns the
  // losses and errors, one line each. Idempotent.
  std::vector<std::string> finish();

  [[nodiscard]] const std::filesystem::path& dir() const { return dir_; }

 private:
  std::filesystem::path dir_;
  LivodConfig config_;
  std::vector<std::string> left_out_;
  Recorder recorder_;
  HostTime started_;
  bool finished_ = false;
};

// The configuration text of the recording (what RecordSession writes as config.yaml): `source`
// of every recorded sensor replaced by its file, its `metadata` / `calibration` pointing at the
// copies recorded_files() names, other sensors' file references made absolute, `outputs.record`
// and the output files removed (a replay writes into its -o folder). Comments are not kept.
// `not_recorded` sensors are written `enabled: false` (RecordSession::leave_out).
std::string recorded_config_text(const LivodConfig& config,
                                 const std::vector<std::string>& not_recorded = {});

// The files of a recording besides the data: (original, name in DIR) for every recorded sensor's
// metadata and calibration.
std::vector<std::pair<std::filesystem::path, std::string>> recorded_files(
    const LivodConfig& config);

// The folder of one recording of `livod run` under `parent` (outputs.record, --record): a new
// subfolder named after the UTC start time, e.g. parent/20261126T071203Z (-2, -3, ... when it
// exists), so that every start of the service, a restart by systemd included, records into its
// own folder and none is overwritten.
std::filesystem::path new_recording_folder(const std::filesystem::path& parent);

// True for the sensors a recording holds: enabled live packet LiDARs over UDP, cameras, CAN and
// serial IMUs with a device source.
bool is_recorded(const SensorConfig& sensor);
// The recorded sensor's file in the recording's folder: <name>.pcap, <name>.log (candump),
// <name>.serial, <name> (a camera's EuRoC folder).
std::string recorded_file_name(const SensorConfig& sensor);

}  // namespace livod::daemon::record
