#pragma once
// ROS1 bag (format 2.0) reader, no ROS needed. Opening reads only the bag header and the index
// section (connection records and chunk infos), so topic lists, counts and the time span are
// immediate. A query (topics + inclusive time range) reads the index data records of the chunks
// it needs and yields the messages in time order across chunks, decompressing a chunk (none, bz2,
// lz4) only when one of its messages is due and freeing it once its last one has been returned.
// For uncompressed chunks only the wanted message records are read.
//
// Corrupt or truncated input throws livod::FormatError with the file offset. Every length is
// checked against the file (or the decompressed chunk) before anything is allocated for it.
// With Options::recover the reader reads past damage instead and keeps what it skipped as
// InputLosses: a bag whose index is missing or broken (recording killed, file truncated) gets its
// index rebuilt by scanning the chunks, as `rosbag reindex` does, and a damaged record is passed
// by searching for the next chunk or connection record (BagReader::losses()); with an intact
// index, a chunk that does not read loses its messages (counted from the index) and a message
// record that does not read loses itself (MessageCursor::losses()).
//
//   BagReader bag("run.bag");
//   BagQuery q;
//   q.topics = {"/imu/data"};
//   auto cursor = bag.read(q);
//   while (auto m = cursor.next()) {
//     auto imu = m->as<sensor_msgs::Imu>();
//   }

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/error.hpp"
#include "io/input_loss.hpp"
#include "io/rosbag/ros_messages.hpp"

namespace livod::io::rosbag {

// A connection record: one publisher's topic and type.
struct Connection {
  std::uint32_t id = 0;
  std::string topic;
  std::string type;
  std::string md5sum;
  std::string message_definition;
  std::string callerid;  // empty when the record has none
  bool latching = false;
};

struct BagMessage {
  const Connection* connection = nullptr;  // owned by the reader
  std::int64_t time_ns = 0;                // record time (when the recorder received it)
  std::span<const std::byte> data;         // serialized message; valid until the next next()

  // Deserializes as Msg. Throws livod::Error when the connection's type or md5sum is not Msg's,
  // livod::FormatError when the bytes do not decode.
  template <class Msg>
  [[nodiscard]] Msg as() const {
    check_type(MessageTraits<Msg>::type, MessageTraits<Msg>::md5sum);
    return deserialize<Msg>(data);
  }
  template <class Msg>
  void decode_into(Msg& out) const {
    check_type(MessageTraits<Msg>::type, MessageTraits<Msg>::md5sum);
    deserialize(data, out);
  }

 private:
  void check_type(std::string_view type, std::string_view md5sum) const;
};

struct BagQuery {
  std::vector<std::string> topics;                                   // empty: every topic
  std::int64_t start_ns = std::numeric_limits<std::int64_t>::min();  // inclusive
  std::int64_t end_ns = std::numeric_limits<std::int64_t>::max();    // inclusive
};

struct TopicInfo {
  std::string topic;
  std::string type;    // of the first connection on the topic
  std::string md5sum;  // of the first connection on the topic
  std::uint64_t message_count = 0;
  std::size_t connection_count = 0;
};

class MessageCursor;

class BagReader {
 public:
  struct Options {
    // Largest uncompressed chunk accepted (rosbag writes 768 KiB chunks; a single huge message
    // gets a chunk of its own).
    std::size_t max_chunk_bytes = std::size_t{1} << 30;
    // Read past damage (see above) instead of throwing at the first damaged record.
    bool recover = false;
  };

  explicit BagReader(const std::filesystem::path& path);
  BagReader(const std::filesystem::path& path, Options options);
  // A bag held in memory (tests, fuzzing); `source_name` appears in error messages.
  static BagReader from_bytes(std::vector<std::byte> bytes, std::string source_name,
                              Options options);

  ~BagReader();
  BagReader(BagReader&&) noexcept;
  BagReader& operator=(BagReader&&) noexcept;
  BagReader(const BagReader&) = delete;
  BagReader& operator=(const BagReader&) = delete;

  [[nodiscard]] const std::string& source() const;
  [[nodiscard]] std::uint64_t file_size() const;
  [[nodiscard]] const std::vector<Connection>& connections() const;
  // One entry per topic, sorted by topic name.
  [[nodiscard]] std::vector<TopicInfo> topics() const;
  [[nodiscard]] std::uint64_t message_count() const;
  [[nodiscard]] std::uint64_t message_count(std::string_view topic) const;
  [[nodiscard]] std::size_t chunk_count() const;
  // Earliest / latest message time; nullopt for a bag without messages.
  [[nodiscard]] std::optional<std::int64_t> start_time_ns() const;
  [[nodiscard]] std::optional<std::int64_t> end_time_ns() const;
  // True when the index was rebuilt by scanning (Options::recover on a damaged bag), and why.
  [[nodiscard]] bool recovered() const;
  [[nodiscard]] const std::string& index_problem() const;
  // Stretches skipped while rebuilding the index (empty unless recovered()).
  [[nodiscard]] const InputLossLog& losses() const;
  // Number of chunks per compression name, e.g. {"bz2": 10}. Reads every chunk header.
  [[nodiscard]] std::map<std::string, std::size_t> chunk_compressions() const;

  // Messages matching the query, in time order (ties: file order). The cursor keeps what it
  // needs of the reader alive, so it may outlive this object.
  [[nodiscard]] MessageCursor read(const BagQuery& query = {}) const;

  struct Impl;

 private:
  explicit BagReader(std::shared_ptr<Impl> impl);
  std::shared_ptr<Impl> impl_;
};

class MessageCursor {
 public:
  ~MessageCursor();
  MessageCursor(MessageCursor&&) noexcept;
  MessageCursor& operator=(MessageCursor&&) noexcept;
  MessageCursor(const MessageCursor&) = delete;
  MessageCursor& operator=(const MessageCursor&) = delete;

  // The next message, or nullopt when the query is exhausted. Throws livod::FormatError on a
  // corrupt chunk, index entry or message record.
  std::optional<BagMessage> next();
  // Recovering readers: the chunks and message records this cursor skipped as damaged.
  [[nodiscard]] const InputLossLog& losses() const;

  struct State;

 private:
  friend class BagReader;
  explicit MessageCursor(std::unique_ptr<State> state);
  std::unique_ptr<State> state_;
};

// `rosbag info`-like summary (path, duration, start/end, size, message count, compression, types
// with md5sums, topics with counts and types), for `livod inspect`. Throws like BagReader.
std::string describe_bag(const std::filesystem::path& path);

}  // namespace livod::io::rosbag
