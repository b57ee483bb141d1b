#include "daemon/replay/sources.hpp"

#include "core/error.hpp"
#include "daemon/replay/decoder_factory.hpp"
#include "daemon/replay/image_sources.hpp"
#include "daemon/replay/source_kinds.hpp"

namespace livod::daemon::replay {

std::unique_ptr<ReplaySource> make_source(const SensorConfig& sensor,
                                          const ReplaySourceConfig& replay,
                                          const std::vector<std::uint16_t>& ports) {
  const std::string what =
      "sensor '" + sensor.name + "' (" + std::string(enum_name(sensor.driver)) + ") from " +
      std::string(enum_name(replay.format)) + " '" + replay.file.string() + "'";
  try {
    switch (replay.format) {
      case ReplayFormat::pcap:
        if (!is_packet_lidar(sensor.driver)) break;
        return make_pcap_source(replay.file, make_lidar_decoder(sensor), ports);
      case ReplayFormat::candump:
        if (sensor.driver != Driver::can_imu) break;
        return make_candump_source(replay.file, sensor.can, sensor.name);
      case ReplayFormat::rosbag1: {
        // Cameras: image topics (image_sources.hpp).
        if (sensor_kind(sensor.driver) == SensorKind::camera) {
          return make_bag_image_source(replay.file, replay.topic, sensor);
        }
        std::unique_ptr<drivers::LidarDecoder> decoder;
        if (sensor.driver == Driver::ouster && sensor.metadata.empty()) {
          // ouster_ros bags record the metadata on a topic of their own.
          decoder = make_ouster_decoder(sensor, bag_ouster_metadata(replay.file, replay.topic));
        } else if (is_packet_lidar(sensor.driver)) {
          decoder = make_lidar_decoder(sensor);
        }
        return make_bag_source(replay.file, replay.topic, sensor, std::move(decoder));
      }
      case ReplayFormat::euroc:
        // Cameras: an EuRoC/ASL camera folder or a plain image folder (image_sources.hpp).
        if (sensor_kind(sensor.driver) != SensorKind::camera) break;
        return make_image_folder_source(replay.file, sensor);
    }
  } catch (const Error& e) {
    throw Error(what + ": " + e.what());
  }
  throw Error(what + ": this driver cannot be replayed from this format");
}

}  // namespace livod::daemon::replay
