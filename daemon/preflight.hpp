#pragma once
// What `load_config` cannot check because it opens no file beyond the YAML: the files the
// configuration names, read and parsed as the run reads them. check-config and replay call the
// same function, so a configuration that check-config passes is not refused by the run:
//   - every enabled packet LiDAR's decoder is built from its metadata / calibration (Ouster
//     metadata parsed, its model cross-checked against the configured one);
//   - with `open_recordings`, every recording the replay would use is opened exactly as the
//     replay opens it (pcap/bag/candump headers, bag topics and their types, the metadata an
//     Ouster bag carries).
// Problems carry the sensor's YAML path and line.

#include <filesystem>
#include <vector>

#include "daemon/config/config.hpp"
#include "daemon/config/load_config.hpp"
#include "daemon/config/problems.hpp"

namespace livod::daemon {

std::vector<ConfigProblem> check_config_files(const LivodConfig& config, bool open_recordings);

// load_config, then (when the YAML itself has no error) check_config_files: what `run` and
// `replay` check before anything starts.
ConfigResult load_checked_config(const std::filesystem::path& path, bool open_recordings);

}  // namespace livod::daemon
