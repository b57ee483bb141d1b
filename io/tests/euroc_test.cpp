#include "io/euroc.hpp"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <numeric>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "io/euroc_image.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io {
namespace {

std::filesystem::path euroc_root() {
  return test::data_path("euroc_v101");
}

std::string file_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

// The numbers of the first `[...]` list after `key:` in a yaml text, read with strtod: an
// independent reading of the file, not through yaml-cpp.
std::vector<double> yaml_list_by_hand(const std::string& text, const std::string& key) {
  const std::size_t at = text.find(key + ":");
  const std::size_t open = text.find('[', at);
  const std::size_t close = text.find(']', open);
  std::vector<double> values;
  if (at == std::string::npos || open == std::string::npos || close == std::string::npos) {
    return values;
  }
  std::string list = text.substr(open + 1, close - open - 1);
  std::replace(list.begin(), list.end(), ',', ' ');
  const char* p = list.c_str();
  char* end = nullptr;
  for (double v = std::strtod(p, &end); end != p; v = std::strtod(p, &end)) {
    values.push_back(v);
    p = end;
  }
  return values;
}

std::vector<std::int64_t> intervals_ns(const std::vector<std::int64_t>& t) {
  std::vector<std::int64_t> dt;
  for (std::size_t i = 1; i < t.size(); ++i) dt.push_back(t[i] - t[i - 1]);
  return dt;
}

std::int64_t median(std::vector<std::int64_t> v) {
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
  return v[v.size() / 2];
}

// ---- the real EuRoC V1_01 excerpt ---------------------------------------------------------------

TEST(EurocReal, Cam0Has95ImagesAt20HzWithExistingFiles) {
  const EurocFolder folder(euroc_root());
  EXPECT_EQ(folder.cameras(), std::vector<std::string>{"cam0"});
  const auto images = folder.images("cam0");
  ASSERT_EQ(images.size(), 95u);
  EXPECT_EQ(images.front().timestamp.ns, 1403715273262142976);
  EXPECT_EQ(images.back().timestamp.ns, 1403715277962142976);

  std::vector<std::int64_t> t;
  for (const auto& image : images) {
    t.push_back(image.timestamp.ns);
    EXPECT_FALSE(image.exposure.has_value());
    EXPECT_EQ(image.path.filename().string(), std::to_string(image.timestamp.ns) + ".png");
    EXPECT_TRUE(std::filesystem::is_regular_file(image.path)) << image.path;
  }
  // 95 frames at 20 Hz cover 4.75 s: 94 intervals of 50 ms between the first and last stamps.
  EXPECT_NEAR(static_cast<double>(median(intervals_ns(t))), 50e6, 1e3);
  EXPECT_NEAR(static_cast<double>(t.back() - t.front()) * 1e-9, 94 * 0.05, 1e-5);
  EXPECT_NEAR(static_cast<double>(images.size()) / 20.0, 4.75, 1e-12);
}

TEST(EurocReal, Cam0CalibrationMatchesTheYamlFile) {
  const EurocFolder folder(euroc_root());
  const auto calibration = folder.camera_calibration("cam0");
  const std::string yaml = file_text(folder.mav0() / "cam0" / "sensor.yaml");

  EXPECT_EQ(calibration.width, 752);
  EXPECT_EQ(calibration.height, 480);
  EXPECT_DOUBLE_EQ(calibration.rate_hz, 20.0);
  // fu, fv, cu, cv as published with EuRoC.
  EXPECT_DOUBLE_EQ(calibration.intrinsics[0], 458.654);
  EXPECT_DOUBLE_EQ(calibration.intrinsics[1], 457.296);
  EXPECT_DOUBLE_EQ(calibration.intrinsics[2], 367.215);
  EXPECT_DOUBLE_EQ(calibration.intrinsics[3], 248.375);
  EXPECT_EQ(calibration.distortion_model, EurocDistortionModel::kRadialTangential);
  const auto distortion = yaml_list_by_hand(yaml, "distortion_coefficients");
  ASSERT_EQ(distortion.size(), 4u);
  EXPECT_EQ(calibration.distortion_coefficients, distortion);
  EXPECT_DOUBLE_EQ(calibration.distortion_coefficients[0], -0.28340811);
  EXPECT_DOUBLE_EQ(calibration.distortion_coefficients[3], 1.76187114e-05);

  // T_BS, row-major in the file.
  const auto t_bs = yaml_list_by_hand(yaml, "data");
  ASSERT_EQ(t_bs.size(), 16u);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      EXPECT_DOUBLE_EQ(calibration.T_body_sensor(r, c), t_bs[static_cast<std::size_t>(4 * r + c)])
          << r << "," << c;
    }
  }
  EXPECT_DOUBLE_EQ(calibration.T_body_sensor(0, 3), -0.0216401454975);
  EXPECT_DOUBLE_EQ(calibration.T_body_sensor(1, 0), 0.999557249008);
  const Eigen::Matrix3d R = calibration.T_body_sensor.topLeftCorner<3, 3>();
  EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-9);
  EXPECT_NEAR(R.determinant(), 1.0, 1e-9);
  EXPECT_EQ(calibration.T_body_sensor.row(3), Eigen::RowVector4d(0, 0, 0, 1));
  // Known VI-sensor geometry: the camera is ~7 cm from the IMU (body) origin, camera x is almost
  // body y and camera y almost -body x.
  const Eigen::Vector3d p_body_cam = calibration.T_body_sensor.topRightCorner<3, 1>();
  EXPECT_NEAR(p_body_cam.norm(), 0.0688, 1e-3);
  EXPECT_GT(R(1, 0), 0.99);
  EXPECT_LT(R(0, 1), -0.99);
}

TEST(EurocReal, Imu0Is200HzFor145SecondsAndReadsGravityWhileStatic) {
  const EurocFolder folder(euroc_root());
  EXPECT_EQ(folder.imus(), std::vector<std::string>{"imu0"});
  const auto imu = folder.imu("imu0");
  ASSERT_EQ(imu.size(), 29120u);
  std::vector<std::int64_t> t;
  for (const auto& s : imu) t.push_back(s.timestamp.ns);
  const double duration = static_cast<double>(t.back() - t.front()) * 1e-9;
  EXPECT_NEAR(duration, 145.6, 0.01);
  EXPECT_NEAR(static_cast<double>(imu.size() - 1) / duration, 200.0, 0.01);
  const auto dt = intervals_ns(t);
  EXPECT_NEAR(static_cast<double>(median(dt)), 5e6, 1e3);
  EXPECT_LT(*std::max_element(dt.begin(), dt.end()), 5'001'000);
  EXPECT_GT(*std::min_element(dt.begin(), dt.end()), 4'999'000);

  // The MAV rests on the ground for the first seconds: mean specific force = gravity.
  Eigen::Vector3d accel_sum = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_sum = Eigen::Vector3d::Zero();
  int n = 0;
  for (const auto& s : imu) {
    if (s.timestamp.ns - t.front() >= 1'000'000'000) break;
    accel_sum += s.accel_m_s2;
    gyro_sum += s.gyro_rad_s;
    ++n;
  }
  ASSERT_EQ(n, 200);
  EXPECT_NEAR((accel_sum / n).norm(), 9.81, 0.1);
  EXPECT_LT((gyro_sum / n).norm(), 0.1);  // only the gyro bias
  // First row, checked against the csv text.
  EXPECT_DOUBLE_EQ(imu.front().gyro_rad_s.x(), -0.0020943951023931952);
  EXPECT_DOUBLE_EQ(imu.front().accel_m_s2.x(), 9.0874956666666655);
  EXPECT_DOUBLE_EQ(imu.front().accel_m_s2.z(), -3.6938381666666662);
}

TEST(EurocReal, Imu0Calibration) {
  const EurocFolder folder(euroc_root());
  const auto calibration = folder.imu_calibration("imu0");
  EXPECT_EQ(calibration.T_body_sensor, Eigen::Matrix4d::Identity());
  EXPECT_DOUBLE_EQ(calibration.rate_hz, 200.0);
  EXPECT_DOUBLE_EQ(calibration.gyroscope_noise_density, 1.6968e-04);
  EXPECT_DOUBLE_EQ(calibration.gyroscope_random_walk, 1.9393e-05);
  EXPECT_DOUBLE_EQ(calibration.accelerometer_noise_density, 2.0e-3);
  EXPECT_DOUBLE_EQ(calibration.accelerometer_random_walk, 3.0e-3);
}

TEST(EurocReal, TumGroundTruthIs200HzWithExactTimestamps) {
  const auto poses = read_tum_trajectory(euroc_root() / "groundtruth_tum.txt");
  ASSERT_EQ(poses.size(), 28712u);
  EXPECT_EQ(poses.front().timestamp.ns, 1403715274302140000);
  EXPECT_EQ(poses.back().timestamp.ns, 1403715417857140000);
  EXPECT_DOUBLE_EQ(poses.front().p_world_body.y(), 2.142470);
  // TUM order is qx qy qz qw.
  const Eigen::Quaterniond expected(0.060514, -0.828459, -0.058956, -0.553641);
  EXPECT_NEAR(poses.front().q_world_body.angularDistance(expected.normalized()), 0.0, 1e-9);
  for (const auto& pose : poses) ASSERT_NEAR(pose.q_world_body.norm(), 1.0, 1e-12);
  const double duration =
      static_cast<double>(poses.back().timestamp.ns - poses.front().timestamp.ns) * 1e-9;
  EXPECT_NEAR(static_cast<double>(poses.size() - 1) / duration, 200.0, 0.1);
  // Vicon ground truth of a flying MAV: positions stay inside the Vicon room (a few metres).
  for (const auto& pose : poses) ASSERT_LT(pose.p_world_body.norm(), 10.0);
  // No EuRoC-style state_groundtruth_estimate0 in this excerpt.
  EXPECT_FALSE(EurocFolder(euroc_root()).groundtruth().has_value());
}

TEST(EurocReal, FirstImageDecodesTo752x480Mono) {
  const auto images = EurocFolder(euroc_root()).images();
  const cv::Mat image = load_euroc_image(images.front());
  EXPECT_EQ(image.cols, 752);
  EXPECT_EQ(image.rows, 480);
  EXPECT_EQ(image.type(), CV_8UC1);
  // A real indoor image, not a blank one.
  double min_value = 0;
  double max_value = 0;
  cv::minMaxLoc(image, &min_value, &max_value);
  EXPECT_GT(max_value - min_value, 100.0);
  const cv::Mat mono = load_euroc_image(images.back(), ImageDecodeMode::kMono8);
  EXPECT_EQ(mono.type(), CV_8UC1);
  EXPECT_EQ(mono.size(), image.size());
}

TEST(EurocReal, MissingFilesAreErrors) {
  EXPECT_THROW(EurocFolder("/nonexistent/livod"), Error);
  EXPECT_THROW(load_dataset_image("/nonexistent/livod/1.png"), Error);
  const EurocFolder folder(euroc_root());
  EXPECT_THROW(folder.images("cam1"), Error);
  // A file that exists but is not an image.
  EXPECT_THROW(load_dataset_image(folder.mav0() / "cam0" / "data.csv"), Error);
}

// ---- csv parsing ----------------------------------------------------------------------------

// Expects `parse` to throw a FormatError whose message names `location` and contains `words`, at
// byte offset `offset`.
template <class F>
void expect_format_error(F&& parse, const std::string& location, std::uint64_t offset,
                         const std::string& words) {
  try {
    parse();
    ADD_FAILURE() << "expected a FormatError at " << location;
  } catch (const FormatError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(location + ":"), std::string::npos) << what;
    EXPECT_NE(what.find(words), std::string::npos) << what;
    EXPECT_EQ(e.offset(), offset) << what;
  }
}

TEST(EurocCsv, CameraCsvWithExposureColumnAndCrLf) {
  const std::string text =
      "#timestamp [ns],filename,exposure_ns\r\n"
      "100,100.png,2000000\r\n"
      "\r\n"
      "150, 150.png , 1500000\r\n";
  const auto images = parse_euroc_camera_csv(text, "cam.csv", "/d");
  ASSERT_EQ(images.size(), 2u);
  EXPECT_EQ(images[0].timestamp.ns, 100);
  EXPECT_EQ(images[0].path, std::filesystem::path("/d/100.png"));
  ASSERT_TRUE(images[0].exposure.has_value());
  EXPECT_EQ(images[0].exposure->count(), 2'000'000);
  EXPECT_EQ(images[1].path, std::filesystem::path("/d/150.png"));
  EXPECT_EQ(images[1].exposure->count(), 1'500'000);
}

TEST(EurocCsv, MalformedCameraRowsNameFileLineAndOffset) {
  const std::string header = "#timestamp [ns],filename\n";  // 25 bytes
  const std::string row1 = "100,100.png\n";                 // line 2, offset 25
  // Line 3 starts at byte 37.
  expect_format_error([&] { parse_euroc_camera_csv(header + row1 + "1x0,a.png\n", "c.csv", "/d"); },
                      "c.csv:3", 37, "not an integer");
  expect_format_error([&] { parse_euroc_camera_csv(header + row1 + "90,a.png\n", "c.csv", "/d"); },
                      "c.csv:3", 37, "does not increase");
  expect_format_error([&] { parse_euroc_camera_csv(header + row1 + "200\n", "c.csv", "/d"); },
                      "c.csv:3", 37, "expected 2 columns");
  expect_format_error(
      [&] { parse_euroc_camera_csv(header + row1 + "200,a.png,5\n", "c.csv", "/d"); }, "c.csv:3",
      37, "expected 2 columns");
  expect_format_error(
      [&] { parse_euroc_camera_csv(header + row1 + "200,a.png,5,6\n", "c.csv", "/d"); }, "c.csv:3",
      49, "too many columns");
  expect_format_error([&] { parse_euroc_camera_csv(header + row1 + "200,\n", "c.csv", "/d"); },
                      "c.csv:3", 41, "filename");
  expect_format_error([&] { parse_euroc_camera_csv("1,a.png,-5\n", "c.csv", "/d"); }, "c.csv:1", 8,
                      "exposure_ns");
  expect_format_error([&] { parse_euroc_camera_csv("1\n", "c.csv", "/d"); }, "c.csv:1", 0,
                      "expected 2 columns");
}

TEST(EurocCsv, MalformedImuRows) {
  const std::string good = "1,0,0,0,0,0,9.8\n";  // 16 bytes
  const auto imu = parse_euroc_imu_csv(good + "2, 1e-3 ,-2,3,4,5,6\n", "imu.csv");
  ASSERT_EQ(imu.size(), 2u);
  EXPECT_EQ(imu[1].gyro_rad_s, Eigen::Vector3d(1e-3, -2, 3));
  EXPECT_EQ(imu[1].accel_m_s2, Eigen::Vector3d(4, 5, 6));

  expect_format_error([&] { parse_euroc_imu_csv(good + "2,0,0,0,0,0\n", "imu.csv"); }, "imu.csv:2",
                      16, "expected 7 columns");
  expect_format_error([&] { parse_euroc_imu_csv(good + "2,0,0,nan,0,0,0\n", "imu.csv"); },
                      "imu.csv:2", 22, "w_RS_S_z");
  expect_format_error([&] { parse_euroc_imu_csv(good + "2,0,0,0,0,0,abc\n", "imu.csv"); },
                      "imu.csv:2", 28, "a_RS_S_z");
  expect_format_error([&] { parse_euroc_imu_csv(good + "1,0,0,0,0,0,0\n", "imu.csv"); },
                      "imu.csv:2", 16, "does not increase");
}

TEST(EurocCsv, GroundTruthCsvUsesWxyzOrder) {
  const std::string text =
      "#timestamp, p_RS_R_x [m], p_RS_R_y [m], p_RS_R_z [m], q_RS_w [], q_RS_x [], q_RS_y [], "
      "q_RS_z [], v..., b_w..., b_a...\n"
      "1000,1,2,3,0.7071067811865476,0,0.7071067811865476,0,0,0,0,0,0,0,0,0,0\n";
  const auto poses = parse_euroc_groundtruth_csv(text, "gt.csv");
  ASSERT_EQ(poses.size(), 1u);
  EXPECT_EQ(poses[0].p_world_body, Eigen::Vector3d(1, 2, 3));
  // 90 degrees about y: body x maps to world -z.
  const Eigen::Vector3d x_world = poses[0].q_world_body * Eigen::Vector3d::UnitX();
  EXPECT_NEAR((x_world - Eigen::Vector3d(0, 0, -1)).norm(), 0.0, 1e-12);
  expect_format_error([&] { parse_euroc_groundtruth_csv("5,0,0,0,2,0,0,0\n", "gt.csv"); },
                      "gt.csv:1", 8, "quaternion");
}

TEST(EurocCsv, TumTimestampsAreExactInNanoseconds) {
  const auto poses = parse_tum_trajectory(
      "# t x y z qx qy qz qw\n"
      "1403715274.30214 0 0 0 0 0 0 1\n"
      "1403715274.3021400005\t0 0 0 0 0 0 1\n"
      "1.4037152745e9 0 0 0 0 0 0 1\n"
      "1403715275 0 0 0 0 0 0 1\n",
      "t.txt");
  ASSERT_EQ(poses.size(), 4u);
  EXPECT_EQ(poses[0].timestamp.ns, 1403715274302140000);
  EXPECT_EQ(poses[1].timestamp.ns, 1403715274302140001);  // rounded half up
  EXPECT_EQ(poses[2].timestamp.ns, 1403715274500000000);
  EXPECT_EQ(poses[3].timestamp.ns, 1403715275000000000);
  expect_format_error([&] { parse_tum_trajectory("1.5.2 0 0 0 0 0 0 1\n", "t.txt"); }, "t.txt:1", 0,
                      "not a time");
  expect_format_error([&] { parse_tum_trajectory("99999999999 0 0 0 0 0 0 1\n", "t.txt"); },
                      "t.txt:1", 0, "not a time");
  expect_format_error([&] { parse_tum_trajectory("1 0 0 0 0 0 0\n", "t.txt"); }, "t.txt:1", 0,
                      "expected 8 columns");
}

// ---- yaml parsing ---------------------------------------------------------------------------

std::string camera_yaml(const std::string& replace_key = "", const std::string& with = "") {
  std::string text = file_text(euroc_root() / "mav0" / "cam0" / "sensor.yaml");
  if (!replace_key.empty()) {
    const std::size_t at = text.find(replace_key + ":");
    const std::size_t end = text.find('\n', at);
    text.replace(at, end - at, with);
  }
  return text;
}

TEST(EurocYaml, CameraYamlErrorsNameTheField) {
  EXPECT_NO_THROW(parse_euroc_camera_yaml(camera_yaml(), "s.yaml"));
  auto expect_error = [](const std::string& text, const std::string& words) {
    try {
      parse_euroc_camera_yaml(text, "s.yaml");
      ADD_FAILURE() << "expected a FormatError mentioning " << words;
    } catch (const FormatError& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("s.yaml:"), std::string::npos) << e.what();
    }
  };
  expect_error(camera_yaml("intrinsics", "intrinsics: [458.654, 457.296, 367.215]"), "intrinsics");
  expect_error(camera_yaml("intrinsics", "intrinsicz: 1"), "missing key 'intrinsics'");
  expect_error(camera_yaml("camera_model", "camera_model: omni"), "camera_model");
  expect_error(camera_yaml("distortion_model", "distortion_model: fisheye62"), "distortion_model");
  expect_error(camera_yaml("rate_hz", "rate_hz: fast"), "rate_hz");
  expect_error(camera_yaml("resolution", "resolution: [752.5, 480]"), "resolution");
  expect_error(camera_yaml("distortion_coefficients", "distortion_coefficients: [1, 2]"),
               "distortion_coefficients");
  expect_error("rate_hz: [1, 2\n", "yaml syntax error");
  expect_error("- 1\n- 2\n", "not a mapping");

  // A T_BS whose rotation is a reflection (det -1) is not a camera pose.
  std::string reflected = camera_yaml();
  const std::size_t at = reflected.find("0.999660727178");
  reflected.replace(at, 14, "-0.999660727178");
  expect_error(reflected, "rigid transform");
}

TEST(EurocYaml, ErrorsCarryTheYamlLine) {
  // rate_hz is on line 16 of the EuRoC cam0 sensor.yaml.
  const std::string text = camera_yaml("rate_hz", "rate_hz: fast");
  ASSERT_EQ(
      std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(text.find("fast")), '\n'),
      15);
  try {
    parse_euroc_camera_yaml(text, "s.yaml");
    FAIL() << "expected a FormatError";
  } catch (const FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("s.yaml:16:"), std::string::npos) << e.what();
    EXPECT_EQ(e.offset(), text.find("fast"));
  }
}

}  // namespace
}  // namespace livod::io
