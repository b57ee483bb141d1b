#pragma once
// EuRoC / ASL dataset folders (the layout of the EuRoC MAV datasets and of Kalibr/OpenVINS tools):
//   mav0/cam0/data.csv     #timestamp [ns],filename[,exposure_ns]   images in mav0/cam0/data/
//   mav0/cam0/sensor.yaml  T_BS, rate_hz, resolution, pinhole intrinsics, distortion
//   mav0/imu0/data.csv     #timestamp [ns],w_RS_S_x,y,z [rad s^-1],a_RS_S_x,y,z [m s^-2]
//   mav0/imu0/sensor.yaml  T_BS, rate_hz, noise densities and random walks
//   mav0/state_groundtruth_estimate0/data.csv (optional): timestamp, p_RS_R xyz, q_RS wxyz, ...
// plus TUM trajectories (`t tx ty tz qx qy qz qw`, t in s).
//
// livod extension: the camera csv may carry a third column `exposure_ns` (exposure duration of
// that frame, integer ns), which the simulator writes. Files without it read as plain EuRoC.
//
// Images are not decoded here: records carry the file path, and io/euroc_image.hpp loads a
// cv::Mat, so that OpenCV headers stay out of this widely included header.
//
// Errors: a malformed row or yaml field throws livod::FormatError whose source is "file:line" and
// whose offset is the byte offset of the offending field. Timestamps must strictly increase.

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/time.hpp"

namespace livod::io {

// One row of camN/data.csv; the image itself is loaded lazily from `path`.
struct EurocImageRecord {
  SensorTime timestamp;                 // the dataset clock, ns
  std::filesystem::path path;           // <camN>/data/<filename>
  std::optional<Nanoseconds> exposure;  // livod extension column, when present
};

// One row of imuN/data.csv, in the IMU (sensor) frame S.
struct EurocImuRecord {
  SensorTime timestamp;
  Eigen::Vector3d gyro_rad_s = Eigen::Vector3d::Zero();  // w_RS_S
  Eigen::Vector3d accel_m_s2 = Eigen::Vector3d::Zero();  // a_RS_S (specific force)
};

enum class EurocDistortionModel {
  kRadialTangential,  // "radial-tangential": k1 k2 p1 p2 [k3]
  kEquidistant,       // "equidistant" (Kannala-Brandt): k1 k2 k3 k4
  kNone,              // "none": no coefficients
};

struct EurocCameraCalibration {
  // T_BS: pose of the camera in the body frame, x_body = T_body_sensor * x_cam.
  Eigen::Matrix4d T_body_sensor = Eigen::Matrix4d::Identity();
  double rate_hz = 0.0;
  int width = 0;
  int height = 0;
  // camera_model must be "pinhole": fu, fv, cu, cv in pixels.
  std::array<double, 4> intrinsics{};
  EurocDistortionModel distortion_model = EurocDistortionModel::kNone;
  std::vector<double> distortion_coefficients;
};

struct EurocImuCalibration {
  Eigen::Matrix4d T_body_sensor = Eigen::Matrix4d::Identity();  // T_BS, x_body = T * x_imu
  double rate_hz = 0.0;
  double gyroscope_noise_density = 0.0;      // rad / s / sqrt(Hz)
  double gyroscope_random_walk = 0.0;        // rad / s^2 / sqrt(Hz)
  double accelerometer_noise_density = 0.0;  // m / s^2 / sqrt(Hz)
  double accelerometer_random_walk = 0.0;    // m / s^3 / sqrt(Hz)
};

// A pose of the body in the world (reference) frame: x_world = q * x_body + p.
struct TrajectoryPose {
  SensorTime timestamp;
  Eigen::Vector3d p_world_body = Eigen::Vector3d::Zero();
  Eigen::Quaterniond q_world_body = Eigen::Quaterniond::Identity();
};

// Parsers over file contents; `source` names the file in error messages. Used by the file
// readers below and directly by the fuzz targets.
std::vector<EurocImageRecord> parse_euroc_camera_csv(std::string_view text,
                                                     const std::string& source,
                                                     const std::filesystem::path& image_dir);
std::vector<EurocImuRecord> parse_euroc_imu_csv(std::string_view text, const std::string& source);
std::vector<TrajectoryPose> parse_euroc_groundtruth_csv(std::string_view text,
                                                        const std::string& source);
std::vector<TrajectoryPose> parse_tum_trajectory(std::string_view text, const std::string& source);
EurocCameraCalibration parse_euroc_camera_yaml(std::string_view text, const std::string& source);
EurocImuCalibration parse_euroc_imu_yaml(std::string_view text, const std::string& source);

// File readers. Image paths resolve to <csv folder>/data/<filename>. A missing or unreadable file
// throws livod::Error with its path.
std::vector<EurocImageRecord> read_euroc_camera_csv(const std::filesystem::path& csv);
std::vector<EurocImuRecord> read_euroc_imu_csv(const std::filesystem::path& csv);
std::vector<TrajectoryPose> read_euroc_groundtruth_csv(const std::filesystem::path& csv);
std::vector<TrajectoryPose> read_tum_trajectory(const std::filesystem::path& path);
EurocCameraCalibration read_euroc_camera_yaml(const std::filesystem::path& yaml);
EurocImuCalibration read_euroc_imu_yaml(const std::filesystem::path& yaml);

// A dataset folder: `root` is the folder holding mav0/, or mav0/ itself.
class EurocFolder {
 public:
  // Throws livod::Error if there is no mav0 folder.
  explicit EurocFolder(const std::filesystem::path& root);

  [[nodiscard]] const std::filesystem::path& mav0() const { return mav0_; }
  // Sensor folders present, sorted: "cam0", "cam1" / "imu0".
  [[nodiscard]] std::vector<std::string> cameras() const;
  [[nodiscard]] std::vector<std::string> imus() const;

  [[nodiscard]] std::vector<EurocImageRecord> images(std::string_view camera = "cam0") const;
  [[nodiscard]] EurocCameraCalibration camera_calibration(std::string_view camera = "cam0") const;
  [[nodiscard]] std::vector<EurocImuRecord> imu(std::string_view imu = "imu0") const;
  [[nodiscard]] EurocImuCalibration imu_calibration(std::string_view imu = "imu0") const;
  // mav0/state_groundtruth_estimate0/data.csv, or nullopt when the dataset has none.
  [[nodiscard]] std::optional<std::vector<TrajectoryPose>> groundtruth() const;

 private:
  std::filesystem::path mav0_;
};

}  // namespace livod::io
