// Reproduces ouster-sdk's per-field digests (`*_digest.json`) of every capture that has one.
//
// packet_hash: one MD5 per field over all lidar packets in file order. For each packet the SDK
// hashes the column headers (TIMESTAMP u64, ENCODER_COUNT u32, MEASUREMENT_ID u16, STATUS u32,
// FRAME_ID u16, one value per column) and every channel field as a (pixels_per_column,
// columns_per_packet) array in C order, with the field's natural type (RANGE u32, REFLECTIVITY
// and FLAGS u8, SIGNAL and NEAR_IR u16, RAW32_WORDn u32).
// scans: per frame, the staggered (H, W) images of the same fields, TIMESTAMP u64[W],
// STATUS u64[W], MEASUREMENT_ID u16[W] and the frame id as a decimal string. ENCODER_COUNT is
// skipped, as the SDK's own check does (the field is deprecated).

#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>

#include "drivers/ouster/lidar_packet.hpp"
#include "drivers/ouster/metadata.hpp"
#include "drivers/ouster/tests/ouster_test_util.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::drivers::ouster {
namespace {

using Json = nlohmann::json;

// Byte width of each field in the SDK's arrays.
std::size_t field_width(ChannelField f) {
  switch (f) {
    case ChannelField::kRange:
    case ChannelField::kRange2:
    case ChannelField::kRaw32Word1:
    case ChannelField::kRaw32Word2:
    case ChannelField::kRaw32Word3:
    case ChannelField::kRaw32Word4:
      return 4;
    case ChannelField::kSignal:
    case ChannelField::kSignal2:
    case ChannelField::kNearIr:
    case ChannelField::kZoneMask:
      return 2;
    case ChannelField::kFlags:
    case ChannelField::kFlags2:
    case ChannelField::kReflectivity:
    case ChannelField::kReflectivity2:
    case ChannelField::kWindow:
      return 1;
  }
  return 0;
}

constexpr std::array<ChannelField, kChannelFieldCount> kAllFields{
    ChannelField::kRange,      ChannelField::kRange2,       ChannelField::kFlags,
    ChannelField::kFlags2,     ChannelField::kReflectivity, ChannelField::kReflectivity2,
    ChannelField::kSignal,     ChannelField::kSignal2,      ChannelField::kNearIr,
    ChannelField::kWindow,     ChannelField::kZoneMask,     ChannelField::kRaw32Word1,
    ChannelField::kRaw32Word2, ChannelField::kRaw32Word3,   ChannelField::kRaw32Word4};

void append_le(std::vector<std::uint8_t>& out, std::uint64_t v, std::size_t width) {
  for (std::size_t i = 0; i < width; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

struct FrameImage {
  std::uint32_t frame_id = 0;
  std::vector<std::uint64_t> timestamp, status;
  std::vector<std::uint16_t> measurement_id;
  std::map<ChannelField, std::vector<std::uint32_t>> fields;  // H x W, row-major
};

class DigestTest : public ::testing::TestWithParam<std::string> {};

TEST_P(DigestTest, PacketAndFrameHashesMatchOusterSdk) {
  const std::string stem = "ouster/pcaps/" + GetParam();
  std::ifstream digest_file(test::data_path(stem + "_digest.json"));
  const Json digest = Json::parse(digest_file);
  const SensorMetadata meta = load_metadata(test::data_path(stem + ".json"));
  const PacketFormat format = PacketFormat::from_metadata(meta);
  const std::uint32_t rows = format.pixels_per_column;
  const std::uint32_t cols = format.columns_per_packet;
  const std::uint32_t width = format.columns_per_frame;

  std::map<std::string, testutil::Md5> hashes;
  std::vector<FrameImage> frames;
  std::size_t lidar_packets = 0;
  for (const auto& captured : testutil::read_capture(test::data_path(stem + ".pcap"))) {
    if (captured.payload.size() != format.lidar_packet_size) continue;
    LidarPacket p;
    ASSERT_EQ(LidarPacket::parse(captured.payload, format, p), PacketError::kNone);
    ++lidar_packets;
    std::vector<std::uint8_t> ts, enc, mid, status, fid;
    for (std::uint32_t c = 0; c < cols; ++c) {
      append_le(ts, p.column_timestamp_ns(c), 8);
      append_le(enc, p.column_encoder_count(c), 4);
      append_le(mid, p.measurement_id(c), 2);
      append_le(status, p.column_status(c), 4);
      append_le(fid, p.column_frame_id(c), 2);
    }
    hashes["TIMESTAMP"].update(ts.data(), ts.size());
    hashes["ENCODER_COUNT"].update(enc.data(), enc.size());
    hashes["MEASUREMENT_ID"].update(mid.data(), mid.size());
    hashes["STATUS"].update(status.data(), status.size());
    hashes["FRAME_ID"].update(fid.data(), fid.size());
    for (ChannelField f : kAllFields) {
      if (!format.layout->has(f)) continue;
      std::vector<std::uint8_t> bytes;
      for (std::uint32_t px = 0; px < rows; ++px) {
        for (std::uint32_t c = 0; c < cols; ++c)
          append_le(bytes, p.field(c, px, f), field_width(f));
      }
      hashes[std::string(to_string(f))].update(bytes.data(), bytes.size());
    }

    // Staggered frame images, batched by frame id.
    if (frames.empty() || frames.back().frame_id != p.header().frame_id) {
      FrameImage img;
      img.frame_id = p.header().frame_id;
      img.timestamp.assign(width, 0);
      img.status.assign(width, 0);
      img.measurement_id.assign(width, 0);
      for (ChannelField f : kAllFields) {
        if (format.layout->has(f)) img.fields[f].assign(static_cast<std::size_t>(rows) * width, 0);
      }
      frames.push_back(std::move(img));
    }
    FrameImage& img = frames.back();
    for (std::uint32_t c = 0; c < cols; ++c) {
      const std::uint32_t v = p.measurement_id(c);
      img.timestamp[v] = p.column_timestamp_ns(c);
      img.status[v] = p.column_status(c);
      img.measurement_id[v] = static_cast<std::uint16_t>(v);
      for (auto& [f, data] : img.fields) {
        for (std::uint32_t px = 0; px < rows; ++px) data[px * width + v] = p.field(c, px, f);
      }
    }
  }
  ASSERT_GT(lidar_packets, 0U);

  const Json& expected_packets = digest.at("packet_hash");
  for (const auto& [name, value] : expected_packets.items()) {
    SCOPED_TRACE("packet_hash " + name);
    ASSERT_TRUE(hashes.count(name)) << "field not decoded";
    EXPECT_EQ(hashes.at(name).hex(), value.get<std::string>());
  }

  const Json& expected_frames =
      digest.contains("frames") ? digest.at("frames") : digest.at("scans");
  ASSERT_EQ(frames.size(), expected_frames.size());
  for (std::size_t i = 0; i < frames.size(); ++i) {
    const FrameImage& img = frames[i];
    for (const auto& [name, value] : expected_frames[i].items()) {
      SCOPED_TRACE("frame " + std::to_string(i) + " " + name);
      const std::string want = value.get<std::string>();
      testutil::Md5 md5;
      if (name == "FRAME_ID") {
        EXPECT_EQ(std::to_string(img.frame_id), want);
        continue;
      }
      if (name == "ENCODER_COUNT") continue;
      if (name == "TIMESTAMP") {
        md5.update(img.timestamp.data(), img.timestamp.size() * 8);
      } else if (name == "STATUS") {
        md5.update(img.status.data(), img.status.size() * 8);
      } else if (name == "MEASUREMENT_ID") {
        md5.update(img.measurement_id.data(), img.measurement_id.size() * 2);
      } else {
        bool found = false;
        for (const auto& [f, data] : img.fields) {
          if (to_string(f) != name) continue;
          found = true;
          std::vector<std::uint8_t> bytes;
          for (std::uint32_t v : data) append_le(bytes, v, field_width(f));
          md5.update(bytes.data(), bytes.size());
        }
        ASSERT_TRUE(found) << "field not decoded";
      }
      EXPECT_EQ(md5.hex(), want);
    }
  }
}

// Every capture with a digest: LEGACY FW 2.0 and 2.1, RNG19 dual FW 2.2, RNG19 single and RNG15
// FW 2.3.
INSTANTIATE_TEST_SUITE_P(OusterSdkDigests, DigestTest,
                         ::testing::Values("OS-0-32-U1_v2.2.0_1024x10", "OS-1-32-G_v2.1.1_1024x10",
                                           "OS-2-32-U0_v2.0.0_1024x10",
                                           "OS-2-128-U1_v2.3.0_1024x10",
                                           "OS-0-128-U1_v2.3.0_1024x10"));

TEST(OusterDigests, EveryDigestFileIsCovered) {
  std::size_t digests = 0;
  for (const auto& e : std::filesystem::directory_iterator(test::data_path("ouster/pcaps"))) {
    if (e.path().filename().string().ends_with("_digest.json")) ++digests;
  }
  EXPECT_EQ(digests, 5U) << "a new digest file appeared: add it to the list above";
}

}  // namespace
}  // namespace livod::drivers::ouster
