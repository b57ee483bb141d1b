// Damaged bags: truncated copies (in a temp dir) and corrupted bytes must give a clean
// livod::FormatError with the byte offset or, with Options::recover, a clean partial read, never
// a crash or a runaway allocation.

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <optional>
#include <random>

#include "io/rosbag/bag_reader.hpp"
#include "io/rosbag/bag_writer.hpp"
#include "tests/support/data_dir.hpp"

namespace livod::io::rosbag {
namespace {

struct Recorded {
  std::string topic;
  std::int64_t time_ns;
  std::vector<std::byte> data;
  friend bool operator==(const Recorded&, const Recorded&) = default;
};

std::vector<Recorded> read_all(const BagReader& bag) {
  std::vector<Recorded> out;
  auto cursor = bag.read();
  while (auto m = cursor.next()) {
    out.push_back({m->connection->topic, m->time_ns, {m->data.begin(), m->data.end()}});
  }
  return out;
}

std::vector<std::byte> file_bytes(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::vector<char> chars((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::byte> out(chars.size());
  std::memcpy(out.data(), chars.data(), chars.size());
  return out;
}

void write_file(const std::filesystem::path& p, std::span<const std::byte> bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()),
            static_cast<std::streamsize>(bytes.size()));
}

// A bag written by BagWriter (many small chunks) so that lz4 and uncompressed chunks are covered
// as well as test2.bag's bz2 ones.
std::filesystem::path make_bag(const std::filesystem::path& dir, Compression compression) {
  const auto path = dir / ("made_" + std::string(compression_name(compression)) + ".bag");
  BagWriter::Options options;
  options.compression = compression;
  options.chunk_threshold = 8 * 1024;
  BagWriter bag(path, options);
  const auto imu = bag.add_connection<sensor_msgs::Imu>("/imu");
  const auto packets = bag.add_connection<ouster_ros::PacketMsg>("/packets");
  for (int i = 0; i < 300; ++i) {
    sensor_msgs::Imu m;
    m.header.seq = static_cast<std::uint32_t>(i);
    m.linear_acceleration.z = 9.81 + 0.001 * i;
    bag.write(imu, 1'000'000'000 + i * 10'000'000LL, m);
    if (i % 10 == 0) {
      ouster_ros::PacketMsg p;
      p.buf.assign(1000, static_cast<std::uint8_t>(i));
      bag.write(packets, 1'000'000'000 + i * 10'000'000LL, p);
    }
  }
  bag.close();
  return path;
}

// Truncates a copy of the bag at `cut` and checks both the strict and the recovering reader.
// Returns how many messages the recovering reader got (nullopt when it failed cleanly).
std::optional<std::size_t> check_truncation(const std::filesystem::path& dir,
                                            const std::vector<std::byte>& whole,
                                            const std::vector<Recorded>& full, std::size_t cut) {
  SCOPED_TRACE("truncated at " + std::to_string(cut) + " of " + std::to_string(whole.size()));
  const auto path = dir / "cut.bag";
  write_file(path, std::span(whole).first(cut));
  // Strict: the index (at the end) is gone, so opening must fail cleanly.
  try {
    const BagReader bag(path);
    ADD_FAILURE() << "opened a truncated bag without error";
  } catch (const FormatError& e) {
    EXPECT_LE(e.offset(), whole.size());
  }
  // Recovering: a prefix of the messages (whole chunks before the cut), or a clean error when
  // even the bag header is gone.
  BagReader::Options options;
  options.recover = true;
  try {
    const BagReader bag(path, options);
    EXPECT_TRUE(bag.recovered());
    const auto got = read_all(bag);
    EXPECT_LE(got.size(), full.size());
    EXPECT_TRUE(got.size() <= full.size() && std::equal(got.begin(), got.end(), full.begin()))
        << "not a prefix";
    EXPECT_EQ(bag.message_count(), got.size());
    return got.size();
  } catch (const FormatError& e) {
    EXPECT_LT(cut, 13u + 4104u) << "only a cut inside the bag header may fail: " << e.what();
    return std::nullopt;
  }
}

TEST(RosbagCorruption, TruncatedCopiesFailCleanlyOrReadAPrefix) {
  const auto dir = test::temp_dir("rosbag_truncation");
  std::vector<std::filesystem::path> bags = {test::data_path("rosbag1/test2.bag"),
                                             make_bag(dir, Compression::kLz4),
                                             make_bag(dir, Compression::kNone)};
  for (const auto& source : bags) {
    SCOPED_TRACE(source.string());
    const auto whole = file_bytes(source);
    const auto full = read_all(BagReader(source));
    ASSERT_GT(full.size(), 300u);
    std::vector<std::size_t> cuts = {0, 1, 12, 13, 14, 17, 40, 4116, 4117, 4120, 4200};
    for (std::size_t k = 1; k < 16; ++k) cuts.push_back(whole.size() * k / 16);
    for (std::size_t back = 1; back <= 64; back *= 2) cuts.push_back(whole.size() - back);
    std::size_t partial_reads = 0;
    std::size_t last_count = 0;
    for (std::size_t cut : cuts) {
      const auto n = check_truncation(dir, whole, full, cut);
      if (!n) continue;
      ++partial_reads;
      // The later the cut, the more survives.
      EXPECT_GE(*n, last_count) << "cut " << cut;
      last_count = *n;
    }
    // Every cut after the 4117-byte magic + bag header record gives a partial read.
    EXPECT_EQ(partial_reads,
              static_cast<std::size_t>(std::count_if(cuts.begin(), cuts.end(),
                                                     [](std::size_t c) { return c >= 4117; })));
    // Just before the index section every chunk is complete.
    EXPECT_EQ(last_count, full.size());
  }
}

TEST(RosbagCorruption, UnindexedBagNeedsRecover) {
  // index_pos = 0 is what a bag looks like while it is being recorded.
  auto whole = file_bytes(test::data_path("rosbag1/test2.bag"));
  const std::string needle = "index_pos=";
  const std::string_view text(reinterpret_cast<const char*>(whole.data()), 200);
  const auto at = text.find(needle);
  ASSERT_NE(at, std::string_view::npos);
  std::memset(whole.data() + at + needle.size(), 0, 8);
  try {
    BagReader::from_bytes(whole, "unindexed", {});
    FAIL() << "opened an unindexed bag";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.offset(), 13u);
    EXPECT_NE(std::string(e.what()).find("no index"), std::string::npos) << e.what();
  }
  BagReader::Options options;
  options.recover = true;
  const auto bag = BagReader::from_bytes(whole, "unindexed", options);
  EXPECT_TRUE(bag.recovered());
  EXPECT_EQ(bag.message_count("/imu/data"), 3061u);
  EXPECT_EQ(bag.message_count("/jackal_velocity_controller/odom"), 3060u);
  EXPECT_EQ(read_all(bag), read_all(BagReader(test::data_path("rosbag1/test2.bag"))));
}

TEST(RosbagCorruption, BogusLengthsGiveErrorsWithOffsets) {
  const auto original = file_bytes(test::data_path("rosbag1/test2.bag"));
  auto expect_error_at = [](std::vector<std::byte> bytes, std::uint64_t offset,
                            const std::string& what) {
    try {
      const auto bag = BagReader::from_bytes(std::move(bytes), "damaged", {});
      read_all(bag);
      FAIL() << "no error for " << what;
    } catch (const FormatError& e) {
      EXPECT_EQ(e.offset(), offset) << what << ": " << e.what();
    }
  };
  // Bag header length 0xFFFFFFFF: far beyond the file.
  auto b = original;
  std::memset(b.data() + 13, 0xFF, 4);
  expect_error_at(b, 17, "huge bag header length");
  // Magic damaged.
  b = original;
  b[1] = std::byte{'X'};
  expect_error_at(b, 0, "bad magic");
  // First chunk's declared uncompressed size beyond the limit.
  b = original;
  const std::string_view chunk_text(reinterpret_cast<const char*>(b.data()) + 4117, 64);
  const auto size_at = 4117 + chunk_text.find("size=") + 5;
  std::memset(b.data() + size_at, 0xFF, 4);
  BagReader::Options small;
  small.max_chunk_bytes = 1 << 20;
  try {
    const auto bag = BagReader::from_bytes(b, "damaged", small);
    read_all(bag);
    FAIL() << "no error for a 4 GiB chunk size";
  } catch (const FormatError& e) {
    EXPECT_EQ(e.offset(), 4117u) << e.what();
  }
}

TEST(RosbagCorruption, BadIndexOffsetNamesTheChunk) {
  const auto dir = test::temp_dir("rosbag_bad_index");
  for (Compression compression : {Compression::kLz4, Compression::kNone}) {
    SCOPED_TRACE(std::string(compression_name(compression)));
    auto b = file_bytes(make_bag(dir, compression));
    auto u32_at = [&](std::size_t at) {
      std::uint32_t v = 0;
      std::memcpy(&v, b.data() + at, 4);
      return v;
    };
    // First chunk at 4117, then its first index data record; point its first entry at byte 1 of
    // the chunk data (inside the connection record, not at a message).
    const std::size_t chunk_header_len = u32_at(4117);
    const std::size_t chunk_data_at = 4117 + 8 + chunk_header_len;
    const std::size_t index_at = chunk_data_at + u32_at(4117 + 4 + chunk_header_len);
    const std::size_t entries_at = index_at + 8 + u32_at(index_at);
    const std::uint32_t one = 1;
    std::memcpy(b.data() + entries_at + 8, &one, 4);
    try {
      read_all(BagReader::from_bytes(b, "bad_index", {}));
      FAIL() << "read a message at a bogus index offset";
    } catch (const FormatError& e) {
      // lz4: offsets inside decompressed data are not file offsets, so the chunk's position is
      // reported; none: the record's own file offset.
      EXPECT_EQ(e.offset(), compression == Compression::kLz4 ? 4117u : chunk_data_at + 1)
          << e.what();
    }
  }
}

TEST(RosbagCorruption, RandomByteDamageNeverCrashes) {
  const auto dir = test::temp_dir("rosbag_damage");
  std::vector<std::vector<std::byte>> sources = {file_bytes(test::data_path("rosbag1/test2.bag")),
                                                 file_bytes(make_bag(dir, Compression::kLz4)),
                                                 file_bytes(make_bag(dir, Compression::kNone)),
                                                 file_bytes(make_bag(dir, Compression::kBz2))};
  std::mt19937 rng(1234);
  std::size_t errors = 0;
  std::size_t reads = 0;
  for (const auto& whole : sources) {
    for (int trial = 0; trial < 40; ++trial) {
      auto damaged = whole;
      const int flips = 1 + trial % 4;
      for (int f = 0; f < flips; ++f) {
        const auto at = std::uniform_int_distribution<std::size_t>(0, damaged.size() - 1)(rng);
        damaged[at] = static_cast<std::byte>(std::uniform_int_distribution<int>(0, 255)(rng));
      }
      BagReader::Options options;
      options.recover = trial % 2 == 1;
      options.max_chunk_bytes = 16 << 20;
      try {
        const auto bag = BagReader::from_bytes(std::move(damaged), "damaged", options);
        for (const auto& m : read_all(bag)) EXPECT_LE(m.data.size(), whole.size());
        ++reads;
      } catch (const FormatError&) {
        ++errors;
      }
    }
  }
  // Both outcomes occur: damage in message payloads is invisible, damage in structure is not.
  EXPECT_GT(errors, 0u);
  EXPECT_GT(reads, 0u);
}

}  // namespace
}  // namespace livod::io::rosbag

// ---------------------------------------------------------------------------------------------
// Reading past damage (issue 14): the recovering reader skips what is damaged and says so.

namespace livod::io::rosbag {
namespace {

BagReader::Options recovering() {
  BagReader::Options options;
  options.recover = true;
  return options;
}

std::uint32_t u32_at(const std::vector<std::byte>& b, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, b.data() + at, 4);
  return v;
}

// File offsets of the chunk records of a bag written by make_bag (chunk, then its index records).
std::vector<std::size_t> chunk_offsets(const std::vector<std::byte>& b) {
  std::vector<std::size_t> out;
  std::size_t at = 4117;  // magic + bag header record
  while (at + 8 < b.size()) {
    const std::size_t header_len = u32_at(b, at);
    const std::string_view header(reinterpret_cast<const char*>(b.data()) + at + 4, header_len);
    const std::size_t data_len = u32_at(b, at + 4 + header_len);
    if (header.find(std::string("op=\x05", 4)) != std::string_view::npos) out.push_back(at);
    if (header.find(std::string("op=\x06", 4)) != std::string_view::npos) break;  // index section
    at += 8 + header_len + data_len;
  }
  return out;
}

TEST(RosbagDamage, TruncatedBagIsReindexedAndTheCutChunkIsALoss) {
  const auto dir = test::temp_dir("rosbag_damage_truncated");
  const auto whole = file_bytes(make_bag(dir, Compression::kLz4));
  const auto chunks = chunk_offsets(whole);
  ASSERT_GT(chunks.size(), 5u);
  const std::size_t cut = chunks[4] + 100;  // inside the fifth chunk
  const auto bag = BagReader::from_bytes(
      {whole.begin(), whole.begin() + static_cast<std::ptrdiff_t>(cut)}, "cut.bag", recovering());
  EXPECT_TRUE(bag.recovered());
  EXPECT_NE(bag.index_problem().find("truncated"), std::string::npos) << bag.index_problem();
  EXPECT_EQ(bag.index_problem().find("Options::"), std::string::npos) << bag.index_problem();
  EXPECT_EQ(bag.chunk_count(), 4u);
  ASSERT_EQ(bag.losses().count(), 1u);
  const InputLoss& loss = bag.losses().entries()[0];
  EXPECT_EQ(loss.file, "cut.bag");
  EXPECT_EQ(loss.byte_offset, chunks[4]);
  EXPECT_EQ(loss.bytes, 100u);
  EXPECT_NE(loss.reason.find("the file ends in the damage"), std::string::npos) << loss.reason;
}

TEST(RosbagDamage, ReindexReadsPastADamagedChunk) {
  const auto dir = test::temp_dir("rosbag_damage_middle");
  auto b = file_bytes(make_bag(dir, Compression::kLz4));
  const auto full = read_all(BagReader::from_bytes(b, "intact", {}));
  const auto chunks = chunk_offsets(b);
  ASSERT_GT(chunks.size(), 6u);
  // No index (as while recording) and the third chunk's record header overwritten.
  const std::string_view text(reinterpret_cast<const char*>(b.data()), 200);
  std::memset(b.data() + text.find("index_pos=") + 10, 0, 8);
  std::memset(b.data() + chunks[2], 0xEE, 40);
  const auto bag = BagReader::from_bytes(b, "damaged.bag", recovering());
  EXPECT_TRUE(bag.recovered());
  EXPECT_EQ(bag.chunk_count(), chunks.size() - 1);
  ASSERT_EQ(bag.losses().count(), 1u);
  const InputLoss& loss = bag.losses().entries()[0];
  EXPECT_EQ(loss.byte_offset, chunks[2]);
  EXPECT_EQ(loss.bytes, chunks[3] - chunks[2]);
  ASSERT_TRUE(loss.seconds.has_value());
  EXPECT_GT(*loss.seconds, 0.0);
  const auto got = read_all(bag);
  EXPECT_LT(got.size(), full.size());
  EXPECT_GT(got.size(), full.size() * 3 / 4);
  EXPECT_EQ(got.back(), full.back());  // the chunks after the damage are read
}

TEST(RosbagDamage, IndexedBagSkipsADamagedChunkAndCountsItsMessages) {
  const auto dir = test::temp_dir("rosbag_damage_indexed");
  auto b = file_bytes(make_bag(dir, Compression::kLz4));
  const auto full = read_all(BagReader::from_bytes(b, "intact", {}));
  const auto chunks = chunk_offsets(b);
  // Corrupt the compressed data of the second chunk (its header stays valid).
  const std::size_t header_len = u32_at(b, chunks[1]);
  const std::size_t data_at = chunks[1] + 8 + header_len;
  std::memset(b.data() + data_at, 0xAB, 64);
  const auto bag = BagReader::from_bytes(b, "indexed.bag", recovering());
  EXPECT_FALSE(bag.recovered());
  auto cursor = bag.read();
  std::size_t n = 0;
  while (cursor.next()) ++n;
  ASSERT_EQ(cursor.losses().count(), 1u);
  const InputLoss& loss = cursor.losses().entries()[0];
  EXPECT_EQ(loss.byte_offset, chunks[1]);
  EXPECT_GT(loss.records, 0u);
  EXPECT_EQ(n + loss.records, full.size());
  // The strict reader still throws at the damage.
  EXPECT_THROW(read_all(BagReader::from_bytes(b, "indexed.bag", {})), FormatError);
}

}  // namespace
}  // namespace livod::io::rosbag
