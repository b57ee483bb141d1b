// `livod replay` with a camera, end to end on a simulated sequence written with its images:
//  - the folder (pcap + EuRoC camera folder) and the ROS1 bag the simulator exports from it
//    (sensor_msgs/Image) give the same trajectory, pose by pose;
//  - map.pcd is x y z rgb with the colours the images gave the points, --debug-images writes one
//    drawing per processed image, the report counts the visual update;
//  - the same camera as a plain image folder (timestamps.txt) and as CompressedImage (PNG) in a
//    bag replays the same; an unreadable frame is counted and skipped.

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <iomanip>
#include <map>
#include <opencv2/imgcodecs.hpp>

#include "io/euroc.hpp"
#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "tests/replay/sim_replay.hpp"

namespace livod {
namespace {

namespace rb = io::rosbag;

struct Pose {
  Eigen::Vector3d p;
  Eigen::Quaterniond q;
};

std::map<std::int64_t, Pose> read_tum(const std::filesystem::path& path) {
  std::map<std::int64_t, Pose> out;
  std::ifstream in(path);
  std::string stamp;
  double x, y, z, qx, qy, qz, qw;
  while (in >> stamp >> x >> y >> z >> qx >> qy >> qz >> qw) {
    const auto dot = stamp.find('.');
    const std::int64_t ns =
        std::stoll(stamp.substr(0, dot)) * 1'000'000'000LL + std::stoll(stamp.substr(dot + 1));
    out[ns] = Pose{{x, y, z}, Eigen::Quaterniond(qw, qx, qy, qz)};
  }
  return out;
}

struct Difference {
  std::size_t matched = 0;
  double max_dp_m = 0.0;
  double max_dr_deg = 0.0;
};

// Pairs poses within 1 ms.
Difference compare(const std::map<std::int64_t, Pose>& a, const std::map<std::int64_t, Pose>& b) {
  Difference d;
  for (const auto& [t, pa] : a) {
    auto it = b.lower_bound(t - 1'000'000);
    if (it == b.end() || it->first > t + 1'000'000) continue;
    ++d.matched;
    d.max_dp_m = std::max(d.max_dp_m, (pa.p - it->second.p).norm());
    d.max_dr_deg = std::max(d.max_dr_deg, pa.q.angularDistance(it->second.q) * 180.0 / M_PI);
  }
  return d;
}

constexpr const char* kCamera =
    "    camera: {model: pinhole, width: 640, height: 512, intrinsics: [500, 500, 313.205, "
    "261.15], distortion: [-0.07616, 0.123001, -0.00113, 0.000251]}\n"
    "    extrinsic:\n      translation: [0.06, 0, 0.04]\n"
    "      rotation: {matrix: [0, 0, 1, -1, 0, 0, 0, -1, 0]}\n";

// The simulator's bag as dataset_* sensors (header stamps on the host clock: direct mapping).
void write_bag_config(const std::filesystem::path& path, const std::string& bag,
                      const std::string& image_topic) {
  std::ofstream out(path);
  out << "body_frame: imu\nsensors:\n"
      << "  - name: lidar\n    driver: dataset_lidar\n    model: OS1-64\n"
      << "    source: {replay: {file: " << bag << ", topic: /os_cloud_node/points}}\n"
      << "    dataset: {time_field: t, time_unit: ns, stamp: start}\n"
      << "    extrinsic:\n      translation: [-0.006253, 0.011775, -0.007645]\n"
      << "      rotation: {matrix: [1, 0, 0, 0, 1, 0, 0, 0, 1]}\n"
      << "  - name: imu\n    driver: dataset_imu\n"
      << "    source: {replay: {file: " << bag << ", topic: /os_cloud_node/imu}}\n"
      << "  - name: cam0\n    driver: dataset_camera\n"
      << "    source: {replay: {file: " << bag << ", topic: " << image_topic << "}}\n"
      << kCamera;
}

class LivoReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    folder_ = new std::filesystem::path(test::temp_dir("livo-replay-sim"));
    sim::SimRunOptions options;
    options.out_dir = *folder_;
    options.duration_s = 8.0;
    options.write_images = true;
    options.write_bag = true;
    sim::run_scenario(sim::make_scenario("room_handheld_os1_64"), options);
    debug_dir_ = new std::filesystem::path(test::temp_dir("livo-replay-debug"));
    daemon::replay::ReplayOptions ro;
    ro.out_dir = test::temp_dir("livo-replay-folder");
    ro.debug_images_dir = *debug_dir_;
    folder_result_ = new daemon::replay::ReplayResult(
        daemon::replay::run_replay(test::load_clean_config(*folder_ / "config.yaml"), ro));
  }
  static void TearDownTestSuite() {
    delete folder_result_;
    delete debug_dir_;
    delete folder_;
  }

  static Difference compare_with_folder(const daemon::replay::ReplayResult& r, const char* what) {
    const auto ref = read_tum(folder_result_->trajectory);
    const auto d = compare(ref, read_tum(r.trajectory));
    std::printf(
        "[livo replay] %s vs folder: %zu of %zu poses matched, max |dp| %.3f mm, max "
        "rotation %.4f deg; images %llu vs %llu, visual updates %llu vs %llu\n",
        what, d.matched, ref.size(), d.max_dp_m * 1e3, d.max_dr_deg,
        static_cast<unsigned long long>(r.summary.counters.images_in),
        static_cast<unsigned long long>(folder_result_->summary.counters.images_in),
        static_cast<unsigned long long>(r.summary.counters.vio_updates),
        static_cast<unsigned long long>(folder_result_->summary.counters.vio_updates));
    EXPECT_GT(ref.size(), 70U);
    EXPECT_GE(d.matched + 1, ref.size());
    EXPECT_EQ(r.summary.counters.images_in, folder_result_->summary.counters.images_in);
    return d;
  }

  static std::filesystem::path* folder_;
  static std::filesystem::path* debug_dir_;
  static daemon::replay::ReplayResult* folder_result_;
};

std::filesystem::path* LivoReplay::folder_ = nullptr;
std::filesystem::path* LivoReplay::debug_dir_ = nullptr;
daemon::replay::ReplayResult* LivoReplay::folder_result_ = nullptr;

TEST_F(LivoReplay, FolderRunsTheVisualUpdate) {
  const auto& s = folder_result_->summary;
  EXPECT_EQ(s.counters.images_in, 80U);
  // Images before the IMU initialisation and the first scan's end are not used; the first pose
  // is that scan's end (the map's first sweep), every later one at an image time.
  EXPECT_EQ(s.counters.image_groups + 1, s.frames);
  EXPECT_GT(s.counters.images_unused, 0U);
  EXPECT_GE(s.counters.image_groups, 75U);
  EXPECT_GE(s.counters.vio_updates, 70U);
  EXPECT_EQ(s.counters.images_rejected, 0U);
  EXPECT_GT(s.vio_patches.p50, 100.0);
  const auto e = test::evaluate(folder_result_->trajectory, *folder_ / "groundtruth.txt");
  std::printf("[livo replay] folder: ATE %.4f m over %zu poses\n", e.ape.rmse, e.gt.size());
  EXPECT_LT(e.ape.rmse, 0.002);
  // The report says what the camera did.
  const std::string timing = test::read_file(folder_result_->timing_text);
  EXPECT_NE(timing.find("visual update: images in 80"), std::string::npos) << timing;
  EXPECT_NE(timing.find("unused (before the first scan's end) " +
                        std::to_string(s.counters.images_unused)),
            std::string::npos)
      << timing;
  EXPECT_NE(test::read_file(folder_result_->timing_json)
                .find("\"image_groups\": " + std::to_string(s.counters.image_groups)),
            std::string::npos);
}

TEST_F(LivoReplay, MapIsColouredFromTheImages) {
  const std::string pcd = test::read_file(folder_result_->map);
  ASSERT_NE(pcd.find("FIELDS x y z rgb\n"), std::string::npos);
  const auto data = pcd.find("DATA binary\n");
  ASSERT_NE(data, std::string::npos);
  const std::size_t n = folder_result_->summary.exported_points;
  ASSERT_GT(n, 1000U);
  ASSERT_EQ(pcd.size() - data - 12, n * 16);
  // The simulator's albedo is grey: every colour is grey (r = g = b), and not all the same.
  std::size_t distinct = 0;
  std::uint32_t first = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint32_t rgb = 0;
    std::memcpy(&rgb, pcd.data() + data + 12 + i * 16 + 12, 4);
    const std::uint32_t r = (rgb >> 16) & 0xFF;
    const std::uint32_t g = (rgb >> 8) & 0xFF;
    const std::uint32_t b = rgb & 0xFF;
    ASSERT_EQ(r, g);
    ASSERT_EQ(g, b);
    if (i == 0) first = rgb;
    distinct += rgb != first ? 1 : 0;
  }
  EXPECT_GT(distinct, n / 2);
}

TEST_F(LivoReplay, DebugImagesAreWrittenPerImage) {
  std::size_t pngs = 0;
  for (const auto& entry : std::filesystem::directory_iterator(*debug_dir_)) {
    pngs += entry.path().extension() == ".png" ? 1 : 0;
  }
  EXPECT_EQ(pngs, folder_result_->summary.counters.image_groups);
  const cv::Mat img = cv::imread(std::filesystem::directory_iterator(*debug_dir_)->path().string(),
                                 cv::IMREAD_COLOR);
  ASSERT_FALSE(img.empty());
  EXPECT_EQ(img.cols, 640);
  EXPECT_EQ(img.rows, 512);
}

TEST_F(LivoReplay, SameBytesForAnyThreadCount) {
  // The visual update spreads its per-point and per-patch work (scan projection, reference warps,
  // photometric errors and rows, corner scores, new reference patches) over the worker pool, each
  // item in its own slots, sums in fixed blocks in order: one thread and two give the same
  // trajectory and map, byte for byte (the fixture ran with one thread per core).
  daemon::replay::ReplayOptions ro;
  ro.out_dir = test::temp_dir("livo-replay-serial");
  ro.threads = 1;
  const auto serial =
      daemon::replay::run_replay(test::load_clean_config(*folder_ / "config.yaml"), ro);
  EXPECT_EQ(test::read_file(serial.trajectory), test::read_file(folder_result_->trajectory));
  EXPECT_EQ(test::read_file(serial.map), test::read_file(folder_result_->map));
}

TEST_F(LivoReplay, BagGivesTheFolderTrajectory) {
  const auto config = *folder_ / "bag.yaml";
  write_bag_config(config, "sequence.bag", "/left_camera/image");
  const auto r = test::replay(config, test::temp_dir("livo-replay-bag"));
  const Difference d = compare_with_folder(r, "bag (sensor_msgs/Image)");
  // The bag's stamps are mapped directly, the pcap's through the clock model: sub-millimetre.
  EXPECT_LT(d.max_dp_m, 0.002);
  EXPECT_LT(d.max_dr_deg, 0.05);
}

TEST_F(LivoReplay, CompressedImagesAndPlainFoldersReplayTheSame) {
  // The camera re-recorded as CompressedImage (PNG: lossless) in a bag of its own, and as a
  // plain image folder with timestamps.txt; one PNG made unreadable in the folder.
  const auto records = io::read_euroc_camera_csv(*folder_ / "mav0" / "cam0" / "data.csv");
  ASSERT_EQ(records.size(), 80U);
  const auto plain = *folder_ / "plain";
  std::filesystem::create_directories(plain);
  {
    rb::BagWriter bag(*folder_ / "compressed.bag");
    const auto conn = bag.add_connection<rb::sensor_msgs::CompressedImage>("/cam/compressed");
    std::ofstream stamps(plain / "timestamps.txt");
    stamps << "# time [s] file\n";
    for (std::size_t i = 0; i < records.size(); ++i) {
      std::ifstream png(records[i].path, std::ios::binary);
      rb::sensor_msgs::CompressedImage m;
      m.header.stamp = rb::RosTime::from_ns(records[i].timestamp.ns);
      m.format = "mono8; png compressed";
      m.data.assign(std::istreambuf_iterator<char>(png), {});
      bag.write(conn, records[i].timestamp.ns, m);
      const std::string name = "frame" + std::to_string(1000 + i) + ".png";
      std::filesystem::copy_file(records[i].path, plain / name);
      const std::int64_t ns = records[i].timestamp.ns;
      stamps << ns / 1'000'000'000 << '.' << std::setw(9) << std::setfill('0') << ns % 1'000'000'000
             << ' ' << name << '\n';
    }
    bag.close();
  }
  // Lidar + IMU from the simulator's bag, the camera from the compressed one.
  {
    const auto config = *folder_ / "compressed.yaml";
    write_bag_config(config, "sequence.bag", "/cam/compressed");
    std::string text = test::read_file(config);
    const auto at = text.rfind("file: sequence.bag");
    text.replace(at, std::strlen("file: sequence.bag"), "file: compressed.bag");
    std::ofstream(config) << text;
    const auto r = test::replay(config, test::temp_dir("livo-replay-compressed"));
    const Difference d = compare_with_folder(r, "bag (CompressedImage PNG)");
    EXPECT_LT(d.max_dp_m, 0.002);
  }
  {
    // The folder config with the plain folder instead of the EuRoC one.
    std::string text = test::read_file(*folder_ / "config.yaml");
    const auto at = text.find("file: mav0/cam0");
    ASSERT_NE(at, std::string::npos);
    text.replace(at, std::strlen("file: mav0/cam0"), "file: plain");
    const auto config = *folder_ / "plain.yaml";
    std::ofstream(config) << text;
    const auto r = test::replay(config, test::temp_dir("livo-replay-plain"));
    compare_with_folder(r, "plain folder");
    // Same frames, same times: the same bytes as the EuRoC folder.
    EXPECT_EQ(test::read_file(r.trajectory), test::read_file(folder_result_->trajectory));
    // One unreadable frame: counted, skipped, the rest replays.
    {
      std::ofstream broken(plain / "frame1040.png", std::ios::trunc);
      broken << "not a png";
    }
    const auto r2 = test::replay(config, test::temp_dir("livo-replay-plain-broken"));
    const auto& cam = r2.summary.sensors.back();
    EXPECT_EQ(cam.name, "cam0");
    EXPECT_NE(cam.counters.find("unreadable 1"), std::string::npos) << cam.counters;
    EXPECT_EQ(cam.images, 79U);
  }
}

}  // namespace
}  // namespace livod
