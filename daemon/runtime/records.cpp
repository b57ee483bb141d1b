#include "daemon/runtime/records.hpp"

namespace livod::daemon::runtime {

const char* to_string(PoseStatus s) {
  switch (s) {
    case PoseStatus::kInitialising:
      return "INITIALISING";
    case PoseStatus::kOk:
      return "OK";
    case PoseStatus::kDegenerate:
      return "DEGENERATE";
    case PoseStatus::kImuOnly:
      return "IMU_ONLY";
    case PoseStatus::kSensorStale:
      return "SENSOR_STALE";
  }
  return "?";
}

}  // namespace livod::daemon::runtime
