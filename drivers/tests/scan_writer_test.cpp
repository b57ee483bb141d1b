// CSV and PCD output of scans, read back.

#include "drivers/scan_writer.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers {
namespace {

LidarScan make_scan(std::int64_t start_ns, float base) {
  LidarScan scan;
  scan.start.sensor = SensorTime(start_ns);
  scan.push_back(base + 1.5f, -2.25f, 0.125f, 17.0f, 3, 0, 0);
  scan.push_back(base - 4.0f, 0.5f, -1.0f, 250.0f, 15, 1, 1'500'000);
  scan.push_back(9.0f, 9.0f, 9.0f, 1.0f, 0, 0, 2'000'000, false);  // invalid: not written
  return scan;
}

std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ScanWriter, FormatFollowsTheExtension) {
  EXPECT_EQ(scan_format_for("a.csv"), ScanFileFormat::kCsv);
  EXPECT_EQ(scan_format_for("a.PCD"), ScanFileFormat::kPcdBinary);
  EXPECT_EQ(scan_format_for("a.pcd", true), ScanFileFormat::kPcdAscii);
  EXPECT_FALSE(scan_format_for("a.ply"));
  EXPECT_THROW(ScanWriter("/nonexistent-dir/x.csv", ScanFileFormat::kCsv), Error);
}

TEST(ScanWriter, CsvHasOneRowPerValidPointWithAbsoluteTimes) {
  const auto path = livod::test::temp_dir("scan_writer_csv") / "out.csv";
  {
    ScanWriter w(path, ScanFileFormat::kCsv);
    w.write(make_scan(1'000'000'000'000, 0.0f));
    w.write(make_scan(1'000'100'000'000, 10.0f));
    w.close();
    EXPECT_EQ(w.scans_written(), 2U);
    EXPECT_EQ(w.points_written(), 4U);
  }
  EXPECT_EQ(read_file(path),
            "frame,x,y,z,intensity,t_ns,ring,return\n"
            "0,1.500000,-2.250000,0.125000,17,1000000000000,3,0\n"
            "0,-4.000000,0.500000,-1.000000,250,1000001500000,15,1\n"
            "1,11.500000,-2.250000,0.125000,17,1000100000000,3,0\n"
            "1,6.000000,0.500000,-1.000000,250,1000101500000,15,1\n");
}

TEST(ScanWriter, BinaryPcdRoundTrips) {
  const auto path = livod::test::temp_dir("scan_writer_pcd") / "out.pcd";
  {
    ScanWriter w(path, ScanFileFormat::kPcdBinary);
    w.write(make_scan(2'000'000'000, 0.0f));
    w.write(make_scan(2'100'000'000, 10.0f));
  }  // the destructor closes
  const std::string text = read_file(path);
  const std::size_t data = text.find("DATA binary\n");
  ASSERT_NE(data, std::string::npos);
  std::istringstream header(text.substr(0, data));
  std::string line;
  std::size_t width = 0;
  std::size_t points = 0;
  while (std::getline(header, line)) {
    std::istringstream fields(line);
    std::string key;
    fields >> key;
    if (key == "WIDTH") fields >> width;
    if (key == "POINTS") fields >> points;
    if (key == "FIELDS") {
      EXPECT_EQ(line, "FIELDS x y z intensity t ring");
    }
    if (key == "SIZE") {
      EXPECT_EQ(line, "SIZE 4 4 4 4 8 2");
    }
    if (key == "TYPE") {
      EXPECT_EQ(line, "TYPE F F F F F U");
    }
  }
  EXPECT_EQ(width, 4U);
  EXPECT_EQ(points, 4U);
  constexpr std::size_t kRecord = 4 + 4 + 4 + 4 + 8 + 2;
  const std::size_t body = data + std::strlen("DATA binary\n");
  ASSERT_EQ(text.size() - body, 4 * kRecord);
  const char* r = text.data() + body + 3 * kRecord;  // second scan, second point
  float x = 0, intensity = 0;
  double t = 0;
  std::uint16_t ring = 0;
  std::memcpy(&x, r, 4);
  std::memcpy(&intensity, r + 12, 4);
  std::memcpy(&t, r + 16, 8);
  std::memcpy(&ring, r + 24, 2);
  EXPECT_EQ(x, 6.0f);
  EXPECT_EQ(intensity, 250.0f);
  EXPECT_DOUBLE_EQ(t, 2.1015);
  EXPECT_EQ(ring, 15);
}

TEST(ScanWriter, AsciiPcd) {
  const auto path = livod::test::temp_dir("scan_writer_ascii") / "out.pcd";
  {
    ScanWriter w(path, ScanFileFormat::kPcdAscii);
    w.write(make_scan(3'000'000'000, 0.0f));
  }
  const std::string text = read_file(path);
  const std::size_t data = text.find("DATA ascii\n");
  ASSERT_NE(data, std::string::npos);
  EXPECT_EQ(text.substr(data + 11),
            "1.500000 -2.250000 0.125000 17 3.000000000 3\n"
            "-4.000000 0.500000 -1.000000 250 3.001500000 15\n");
}

}  // namespace
}  // namespace livod::drivers
