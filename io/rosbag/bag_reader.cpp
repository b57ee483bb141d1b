#include "io/rosbag/bag_reader.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iomanip>
#include <queue>
#include <set>
#include <sstream>
#include <unordered_map>

#include "io/rosbag/bag_records.hpp"
#include "io/rosbag/chunk_compression.hpp"

namespace livod::io::rosbag {
namespace {

// ---- byte sources --------------------------------------------------------------------------

class ByteSource {
 public:
  virtual ~ByteSource() = default;
  [[nodiscard]] virtual std::uint64_t size() const = 0;
  // Reads exactly dst.size() bytes at `offset`; the caller has checked the range.
  virtual void read_at(std::uint64_t offset, std::span<std::byte> dst) const = 0;
};

class FileSource final : public ByteSource {
 public:
  explicit FileSource(const std::filesystem::path& path) : path_(path.string()) {
    fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd_ < 0) throw Error(path_ + ": cannot open: " + std::strerror(errno));
    struct stat st {};
    if (::fstat(fd_, &st) != 0) {
      const int err = errno;
      ::close(fd_);
      throw Error(path_ + ": cannot stat: " + std::strerror(err));
    }
    size_ = static_cast<std::uint64_t>(st.st_size);
  }
  ~FileSource() override { ::close(fd_); }
  FileSource(const FileSource&) = delete;
  FileSource& operator=(const FileSource&) = delete;

  [[nodiscard]] std::uint64_t size() const override { return size_; }

  void read_at(std::uint64_t offset, std::span<std::byte> dst) const override {
    std::size_t done = 0;
    while (done < dst.size()) {
      const ssize_t n =
          ::pread(fd_, dst.data() + done, dst.size() - done, static_cast<off_t>(offset + done));
      if (n < 0) {
        if (errno == EINTR) continue;
        throw Error(path_ + ": read error at offset " + std::to_string(offset + done) + ": " +
                    std::strerror(errno));
      }
      if (n == 0) throw FormatError(path_, offset + done, "unexpected end of file");
      done += static_cast<std::size_t>(n);
    }
  }

 private:
  std::string path_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
};

class MemorySource final : public ByteSource {
 public:
  explicit MemorySource(std::vector<std::byte> bytes) : bytes_(std::move(bytes)) {}
  [[nodiscard]] std::uint64_t size() const override { return bytes_.size(); }
  void read_at(std::uint64_t offset, std::span<std::byte> dst) const override {
    if (!dst.empty()) std::memcpy(dst.data(), bytes_.data() + offset, dst.size());
  }

 private:
  std::vector<std::byte> bytes_;
};

// ---- index structures ----------------------------------------------------------------------

struct IndexEntry {
  std::int64_t time_ns = 0;
  std::uint32_t offset = 0;      // inside the uncompressed chunk
  std::uint32_t conn_index = 0;  // into Impl::connections
};

struct ChunkRecord {
  std::uint64_t position = 0;  // of the chunk record in the file
  std::int64_t start_ns = 0;
  std::int64_t end_ns = 0;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> counts;  // connection index, messages
  std::vector<IndexEntry> scanned;  // recovered bags only: found by scanning the chunk
};

// A record header read from the file; `header` views `bytes`.
struct FileRecord {
  FileRecord() = default;
  FileRecord(FileRecord&&) noexcept =
      default;  // moving keeps `bytes`' buffer, so `header` stays valid
  FileRecord(const FileRecord&) = delete;
  FileRecord& operator=(const FileRecord&) = delete;
  FileRecord& operator=(FileRecord&&) = delete;

  std::uint64_t position = 0;
  std::vector<std::byte> bytes;
  RecordHeader header;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  [[nodiscard]] std::uint64_t end() const { return data_pos + data_len; }
};

// What a chunk record header says about its data.
struct ChunkHeader {
  Compression compression = Compression::kNone;
  std::uint64_t data_pos = 0;
  std::uint32_t data_len = 0;
  std::size_t uncompressed_size = 0;  // declared; exact for none
  bool size_declared = false;
};

std::int64_t to_ns(RosTime t) {
  return t.to_ns();
}

std::string_view as_text(std::span<const std::byte> v) {
  return {reinterpret_cast<const char*>(v.data()), v.size()};
}

}  // namespace

// ---- BagReader::Impl -------------------------------------------------------------------------

struct BagReader::Impl {
  std::unique_ptr<ByteSource> src;
  std::string source;
  Options options;
  std::vector<Connection> connections;
  std::unordered_map<std::uint32_t, std::uint32_t> conn_index_by_id;
  std::vector<ChunkRecord> chunks;
  std::uint64_t first_record_pos = 0;  // after the bag header record
  bool recovered = false;
  std::string index_problem;  // why the index was rebuilt (recovered bags)
  InputLossLog losses;        // damaged stretches skipped while rebuilding the index

  // The message of a FormatError without the leading "<source>: " (losses name the file).
  std::string reason_of(const std::exception& e) const {
    std::string text = e.what();
    if (text.rfind(source + ": ", 0) == 0) text.erase(0, source.size() + 2);
    return text;
  }

  [[noreturn]] void fail(std::uint64_t offset, const std::string& message) const {
    throw FormatError(source, offset, message);
  }

  void require_in_file(std::uint64_t pos, std::uint64_t len, std::string_view what) const {
    if (pos > src->size() || len > src->size() - pos) {
      fail(pos, std::string(what) + " of " + std::to_string(len) + " bytes runs past the end of " +
                    "the file (" + std::to_string(src->size()) + " bytes)");
    }
  }

  std::vector<std::byte> read_bytes(std::uint64_t pos, std::uint64_t len,
                                    std::string_view what) const {
    require_in_file(pos, len, what);
    std::vector<std::byte> out(static_cast<std::size_t>(len));
    src->read_at(pos, out);
    return out;
  }

  std::uint32_t read_u32(std::uint64_t pos, std::string_view what) const {
    std::array<std::byte, 4> b{};
    require_in_file(pos, 4, what);
    src->read_at(pos, b);
    return detail::load_le<std::uint32_t>(b.data());
  }

  FileRecord read_record(std::uint64_t pos) const {
    FileRecord r;
    r.position = pos;
    const std::uint32_t header_len = read_u32(pos, "record header length");
    r.bytes = read_bytes(pos + 4, header_len, "record header");
    r.header = RecordHeader::parse(r.bytes, source, pos + 4);
    r.data_len = read_u32(pos + 4 + header_len, "record data length");
    r.data_pos = pos + 8 + header_len;
    require_in_file(r.data_pos, r.data_len, "record data");
    return r;
  }

  std::vector<std::byte> read_data(const FileRecord& r) const {
    return read_bytes(r.data_pos, r.data_len, "record data");
  }

  ChunkHeader chunk_header(const FileRecord& r) const {
    if (r.header.op() != static_cast<std::uint8_t>(BagOp::kChunk)) {
      fail(r.position, "expected a chunk record (op 5), found op " + std::to_string(r.header.op()));
    }
    ChunkHeader c;
    const std::string name = r.header.string("compression");
    const auto compression = parse_compression(name);
    if (!compression) fail(r.position, "unsupported chunk compression '" + name + "'");
    c.compression = *compression;
    c.data_pos = r.data_pos;
    c.data_len = r.data_len;
    if (r.header.has("size")) {
      c.uncompressed_size = r.header.u32("size");
      c.size_declared = true;
    } else {
      c.uncompressed_size =
          c.compression == Compression::kNone ? r.data_len : options.max_chunk_bytes;
    }
    if (c.compression == Compression::kNone && c.uncompressed_size != r.data_len) {
      fail(r.position, "uncompressed chunk declares size " + std::to_string(c.uncompressed_size) +
                           " but holds " + std::to_string(r.data_len) + " bytes");
    }
    if (c.uncompressed_size > options.max_chunk_bytes) {
      fail(r.position, "chunk size " + std::to_string(c.uncompressed_size) +
                           " exceeds the limit of " + std::to_string(options.max_chunk_bytes));
    }
    return c;
  }

  // Decompresses a chunk; `out` holds exactly the chunk's records afterwards.
  void load_chunk_data(const FileRecord& r, const ChunkHeader& c,
                       std::vector<std::byte>& out) const {
    const std::vector<std::byte> compressed = read_data(r);
    if (const std::string err =
            decompress_chunk(c.compression, compressed, c.uncompressed_size, out);
        !err.empty()) {
      fail(r.position, "chunk data: " + err);
    }
    if (c.size_declared && out.size() != c.uncompressed_size) {
      fail(r.position, "chunk decompresses to " + std::to_string(out.size()) +
                           " bytes, header says " + std::to_string(c.uncompressed_size));
    }
  }

  Connection parse_connection(const RecordHeader& header, std::span<const std::byte> data,
                              std::uint64_t position, std::uint64_t data_pos) const {
    Connection c;
    c.id = header.u32("conn");
    c.topic = header.string("topic");
    const RecordHeader fields = RecordHeader::parse(data, source, data_pos);
    c.type = fields.string("type");
    c.md5sum = fields.string("md5sum");
    c.message_definition = fields.string("message_definition");
    if (auto v = fields.find("callerid")) c.callerid = std::string(as_text(*v));
    if (auto v = fields.find("latching")) c.latching = as_text(*v) == "1";
    if (c.topic.empty()) fail(position, "connection record with an empty topic");
    return c;
  }

  void add_connection(Connection c, std::uint64_t position) {
    if (conn_index_by_id.contains(c.id)) {
      const Connection& known = connections[conn_index_by_id.at(c.id)];
      if (known.topic != c.topic || known.type != c.type) {
        fail(position, "connection " + std::to_string(c.id) + " redefined with another topic/type");
      }
      return;
    }
    conn_index_by_id.emplace(c.id, static_cast<std::uint32_t>(connections.size()));
    connections.push_back(std::move(c));
  }

  std::uint32_t conn_index(std::uint32_t id, std::uint64_t position) const {
    const auto it = conn_index_by_id.find(id);
    if (it == conn_index_by_id.end()) {
      fail(position, "reference to unknown connection " + std::to_string(id));
    }
    return it->second;
  }

  // Magic + bag header record. Returns index_pos, conn_count, chunk_count.
  struct BagHeader {
    std::uint64_t index_pos = 0;
    std::uint32_t conn_count = 0;
    std::uint32_t chunk_count = 0;
  };

  BagHeader read_bag_header() {
    if (src->size() < kBagMagic.size()) fail(0, "file too short for a ROS bag");
    const auto magic = read_bytes(0, kBagMagic.size(), "magic");
    if (as_text(magic) != kBagMagic) {
      const auto line = as_text(magic);
      if (line.starts_with("#ROS"))
        fail(0, "unsupported bag format version (only 2.0 is supported)");
      fail(0, "not a ROS bag (no '#ROSBAG V2.0' line)");
    }
    const FileRecord r = read_record(kBagMagic.size());
    if (r.header.op() != static_cast<std::uint8_t>(BagOp::kBagHeader)) {
      fail(r.position,
           "first record is not a bag header (op " + std::to_string(r.header.op()) + ")");
    }
    BagHeader h;
    h.index_pos = r.header.u64("index_pos");
    h.conn_count = r.header.u32("conn_count");
    h.chunk_count = r.header.u32("chunk_count");
    first_record_pos = r.end();
    return h;
  }

  void load_index(const BagHeader& h) {
    if (h.index_pos == 0) {
      fail(kBagMagic.size(),
           "bag has no index (index_pos 0: the recording was not closed); it must be "
           "reindexed (rosbag reindex, or read with recovery: livod replay does)");
    }
    // index_pos == size is a bag without connections and chunks.
    if (h.index_pos < first_record_pos || h.index_pos > src->size()) {
      fail(kBagMagic.size(), "index_pos " + std::to_string(h.index_pos) + " is outside the file (" +
                                 std::to_string(src->size()) +
                                 " bytes): the bag is truncated; it must be reindexed (rosbag "
                                 "reindex, or read with recovery: livod replay does)");
    }
    const std::uint64_t remaining = src->size() - h.index_pos;
    if ((static_cast<std::uint64_t>(h.conn_count) + h.chunk_count) * kMinRecordSize > remaining) {
      fail(h.index_pos, "conn_count " + std::to_string(h.conn_count) + " + chunk_count " +
                            std::to_string(h.chunk_count) + " records cannot fit in the " +
                            std::to_string(remaining) + " bytes after index_pos");
    }
    std::uint64_t pos = h.index_pos;
    for (std::uint32_t i = 0; i < h.conn_count; ++i) {
      const FileRecord r = read_record(pos);
      if (r.header.op() != static_cast<std::uint8_t>(BagOp::kConnection)) {
        fail(pos, "expected connection record " + std::to_string(i) + " of " +
                      std::to_string(h.conn_count) + ", found op " + std::to_string(r.header.op()));
      }
      const auto data = read_data(r);
      add_connection(parse_connection(r.header, data, pos, r.data_pos), pos);
      pos = r.end();
    }
    chunks.reserve(h.chunk_count);
    for (std::uint32_t i = 0; i < h.chunk_count; ++i) {
      const FileRecord r = read_record(pos);
      if (r.header.op() != static_cast<std::uint8_t>(BagOp::kChunkInfo)) {
        fail(pos, "expected chunk info record " + std::to_string(i) + " of " +
                      std::to_string(h.chunk_count) + ", found op " +
                      std::to_string(r.header.op()));
      }
      if (r.header.u32("ver") != kIndexVersion) {
        fail(pos, "unsupported chunk info version " + std::to_string(r.header.u32("ver")));
      }
      ChunkRecord c;
      c.position = r.header.u64("chunk_pos");
      c.start_ns = to_ns(r.header.time("start_time"));
      c.end_ns = to_ns(r.header.time("end_time"));
      const std::uint32_t count = r.header.u32("count");
      if (static_cast<std::uint64_t>(count) * kChunkInfoEntrySize != r.data_len) {
        fail(pos, "chunk info count " + std::to_string(count) + " disagrees with its data length " +
                      std::to_string(r.data_len));
      }
      if (c.position < first_record_pos || c.position >= h.index_pos) {
        fail(pos, "chunk_pos " + std::to_string(c.position) + " outside the chunk section");
      }
      if (c.end_ns < c.start_ns) fail(pos, "chunk info end_time before start_time");
      const auto data = read_data(r);
      c.counts.reserve(count);
      for (std::uint32_t k = 0; k < count; ++k) {
        const auto id = detail::load_le<std::uint32_t>(data.data() + k * kChunkInfoEntrySize);
        const auto n = detail::load_le<std::uint32_t>(data.data() + k * kChunkInfoEntrySize + 4);
        c.counts.emplace_back(conn_index(id, pos), n);
      }
      chunks.push_back(std::move(c));
      pos = r.end();
    }
  }

  // Rebuilds connections and per-chunk indexes from the chunks themselves, as `rosbag reindex`
  // does. A damaged record does not end the scan: the next chunk or connection record is searched
  // for (find_record) and the stretch in between is kept as an InputLoss.
  void scan_chunks() {
    connections.clear();
    conn_index_by_id.clear();
    chunks.clear();
    recovered = true;
    std::uint64_t pos = first_record_pos;
    std::vector<std::byte> data;
    std::optional<std::int64_t> last_end_ns;
    // A damaged stretch stays open until a chunk reads again: the records found inside it
    // (connection and message records of a damaged uncompressed chunk) extend it rather than
    // counting as stretches of their own.
    InputLoss open;
    bool is_open = false;
    const auto close = [&](std::optional<std::int64_t> resume_ns) {
      if (!is_open) return;
      if (resume_ns && last_end_ns && *resume_ns >= *last_end_ns) {
        open.seconds = static_cast<double>(*resume_ns - *last_end_ns) * 1e-9;
      }
      losses.add(std::move(open));
      open = InputLoss{};
      is_open = false;
    };
    while (pos < src->size()) {
      try {
        const FileRecord r = read_record(pos);
        const std::uint8_t op = r.header.op();
        if (op == static_cast<std::uint8_t>(BagOp::kChunk)) {
          const ChunkHeader c = chunk_header(r);
          load_chunk_data(r, c, data);
          ChunkRecord chunk = scan_chunk(r.position, data);
          if (!chunk.scanned.empty()) {
            close(chunk.start_ns);
            last_end_ns = chunk.end_ns;
            chunks.push_back(std::move(chunk));
          }
        } else if (op == static_cast<std::uint8_t>(BagOp::kConnection)) {
          add_connection(parse_connection(r.header, read_data(r), pos, r.data_pos), pos);
        } else if (op != static_cast<std::uint8_t>(BagOp::kIndexData) &&
                   op != static_cast<std::uint8_t>(BagOp::kChunkInfo)) {
          fail(pos, "unexpected record (op " + std::to_string(op) + ") in the chunk section");
        }
        pos = r.end();
      } catch (const FormatError& e) {
        const std::optional<std::uint64_t> resume = find_record(pos + 1);
        const std::uint64_t end = resume ? *resume : src->size();
        if (!is_open) {
          is_open = true;
          open.file = source;
          open.byte_offset = pos;
          open.unit = "messages";
          open.reason = reason_of(e);
        }
        open.bytes = end - open.byte_offset.value_or(pos);
        if (!resume) {
          open.reason += " (the file ends in the damage)";
          break;
        }
        pos = *resume;
      }
    }
    close(std::nullopt);
  }

  // The first offset >= `from` where a chunk or connection record starts (its header parses,
  // its data fits the file and a chunk's compression and sizes are valid), or nullopt. Records
  // are found by their op field ("\x04\0\0\0op=\x05" or "...\x07") and the header length before
  // it; rosbag writes at most two short fields before op.
  std::optional<std::uint64_t> find_record(std::uint64_t from) const {
    constexpr std::size_t kWindow = 1 << 16;
    constexpr std::size_t kPattern = 8;
    constexpr std::uint64_t kMaxFieldsBeforeOp = 512;
    const std::byte pattern[7] = {std::byte{4},   std::byte{0},   std::byte{0},  std::byte{0},
                                  std::byte{'o'}, std::byte{'p'}, std::byte{'='}};
    std::uint64_t pos = from;
    std::vector<std::byte> window;
    while (pos + kPattern <= src->size()) {
      const std::size_t n =
          static_cast<std::size_t>(std::min<std::uint64_t>(kWindow, src->size() - pos));
      window.resize(n);
      src->read_at(pos, window);
      for (std::size_t i = 0; i + kPattern <= n; ++i) {
        if (std::memcmp(window.data() + i, pattern, sizeof pattern) != 0) continue;
        const auto op = std::to_integer<std::uint8_t>(window[i + 7]);
        if (op != static_cast<std::uint8_t>(BagOp::kChunk) &&
            op != static_cast<std::uint8_t>(BagOp::kConnection)) {
          continue;
        }
        const std::uint64_t field = pos + i;
        // The record starts at least 4 bytes (its header length) before the field.
        for (std::uint64_t back = 4; back <= kMaxFieldsBeforeOp + 4 && back <= field; ++back) {
          const std::uint64_t start = field - back;
          if (start < from) break;
          if (record_starts_at(start, field)) return start;
        }
      }
      if (n <= kPattern) break;
      pos += n - kPattern + 1;
    }
    return std::nullopt;
  }

  bool record_starts_at(std::uint64_t start, std::uint64_t op_field) const {
    try {
      const std::uint32_t header_len = read_u32(start, "record header length");
      if (op_field + 8 > start + 4 + std::uint64_t{header_len}) return false;
      const FileRecord r = read_record(start);
      if (r.header.op() == static_cast<std::uint8_t>(BagOp::kChunk)) (void)chunk_header(r);
      return true;
    } catch (const FormatError&) {
      return false;
    }
  }

  ChunkRecord scan_chunk(std::uint64_t chunk_pos, std::span<const std::byte> data) {
    ChunkRecord chunk;
    chunk.position = chunk_pos;
    // Parse into temporaries first so that a damaged chunk adds nothing.
    std::vector<Connection> new_connections;
    std::vector<std::pair<std::uint32_t, IndexEntry>> entries;  // connection id, entry
    constexpr std::string_view where = "uncompressed chunk data";
    std::size_t pos = 0;
    try {
      while (pos < data.size()) {
        if (data.size() - pos < 4) {
          throw FormatError(std::string(where), pos, "truncated record in chunk");
        }
        const auto header_len = detail::load_le<std::uint32_t>(data.data() + pos);
        if (header_len > data.size() - pos - 4 || data.size() - pos - 4 - header_len < 4) {
          throw FormatError(std::string(where), pos, "record header runs past the chunk");
        }
        const RecordHeader h =
            RecordHeader::parse(data.subspan(pos + 4, header_len), where, pos + 4);
        const std::size_t data_len_pos = pos + 4 + header_len;
        const auto data_len = detail::load_le<std::uint32_t>(data.data() + data_len_pos);
        if (data_len > data.size() - data_len_pos - 4) {
          throw FormatError(std::string(where), data_len_pos, "record data runs past the chunk");
        }
        const auto body = data.subspan(data_len_pos + 4, data_len);
        if (h.op() == static_cast<std::uint8_t>(BagOp::kConnection)) {
          new_connections.push_back(parse_connection(h, body, chunk_pos, chunk_pos));
        } else if (h.op() == static_cast<std::uint8_t>(BagOp::kMessageData)) {
          IndexEntry e;
          e.time_ns = to_ns(h.time("time"));
          e.offset = static_cast<std::uint32_t>(pos);
          entries.emplace_back(h.u32("conn"), e);
        }
        pos = data_len_pos + 4 + data_len;
      }
    } catch (const FormatError& e) {
      fail(chunk_pos, e.what());
    }
    for (auto& c : new_connections) add_connection(std::move(c), chunk_pos);
    std::map<std::uint32_t, std::uint32_t> counts;
    for (auto& [id, e] : entries) {
      e.conn_index = conn_index(id, chunk_pos);
      ++counts[e.conn_index];
      if (chunk.scanned.empty() || e.time_ns < chunk.start_ns) chunk.start_ns = e.time_ns;
      if (chunk.scanned.empty() || e.time_ns > chunk.end_ns) chunk.end_ns = e.time_ns;
      chunk.scanned.push_back(e);
    }
    chunk.counts.assign(counts.begin(), counts.end());
    return chunk;
  }

  void open() {
    const BagHeader h = read_bag_header();
    try {
      load_index(h);
    } catch (const FormatError& e) {
      if (!options.recover) throw;
      index_problem = reason_of(e);
      scan_chunks();
    }
  }
};

// ---- MessageCursor ---------------------------------------------------------------------------

namespace {

struct Pending {
  std::int64_t time_ns;
  std::uint64_t chunk_pos;
  std::uint32_t offset;
  std::uint32_t conn_index;
  std::uint32_t slot;
  // std::priority_queue is a max-heap: "greater" puts the earliest (time, file position) on top.
  friend bool operator>(const Pending& a, const Pending& b) {
    if (a.time_ns != b.time_ns) return a.time_ns > b.time_ns;
    if (a.chunk_pos != b.chunk_pos) return a.chunk_pos > b.chunk_pos;
    return a.offset > b.offset;
  }
};

struct ChunkSlot {
  const ChunkRecord* chunk = nullptr;
  ChunkHeader header;
  std::vector<std::byte> data;  // decompressed records (compressed chunks, while needed)
  bool data_loaded = false;
  bool damaged = false;  // recovering: the chunk was found damaged and its messages counted lost
  std::uint32_t pending = 0;
};

}  // namespace

struct MessageCursor::State {
  std::shared_ptr<const BagReader::Impl> bag;
  BagQuery query;
  std::vector<bool> wanted;  // per connection index
  std::vector<ChunkSlot> slots;
  std::size_t next_slot = 0;
  std::priority_queue<Pending, std::vector<Pending>, std::greater<>> heap;
  std::optional<std::uint32_t> last_slot;
  std::vector<std::byte> record;  // message record read from an uncompressed chunk
  InputLossLog losses;            // recovering: damaged chunks and messages skipped

  // Recovering reads skip a damaged chunk or message and keep it as a loss; strict ones throw.
  void lose(std::uint64_t offset, std::uint64_t messages, std::optional<double> seconds,
            const FormatError& e) {
    if (!bag->options.recover) throw e;
    InputLoss loss;
    loss.file = bag->source;
    loss.byte_offset = offset;
    loss.records = messages;
    loss.unit = "messages";
    loss.seconds = seconds;
    loss.reason = bag->reason_of(e);
    losses.add(std::move(loss));
  }

  void load_slot(std::uint32_t slot_index) {
    try {
      load_slot_index(slot_index);
    } catch (const FormatError& e) {
      // Nothing of the chunk is pushed; the index tells how many wanted messages it held.
      ChunkSlot& slot = slots[slot_index];
      slot.damaged = true;
      std::uint64_t messages = 0;
      for (const auto& [conn, n] : slot.chunk->counts) {
        if (wanted[conn]) messages += n;
      }
      slot.pending = 0;  // entries pushed before the damage was found are dropped when popped
      lose(slot.chunk->position, messages,
           static_cast<double>(slot.chunk->end_ns - slot.chunk->start_ns) * 1e-9, e);
    }
  }

  [[nodiscard]] bool in_range(std::int64_t t) const {
    return t >= query.start_ns && t <= query.end_ns;
  }

  void push(std::uint32_t slot_index, const IndexEntry& e) {
    ChunkSlot& slot = slots[slot_index];
    heap.push(Pending{e.time_ns, slot.chunk->position, e.offset, e.conn_index, slot_index});
    ++slot.pending;
  }

  void load_slot_index(std::uint32_t slot_index) {
    const BagReader::Impl& b = *bag;
    ChunkSlot& slot = slots[slot_index];
    const ChunkRecord& chunk = *slot.chunk;
    const FileRecord r = b.read_record(chunk.position);
    slot.header = b.chunk_header(r);
    if (b.recovered) {
      for (const IndexEntry& e : chunk.scanned) {
        if (wanted[e.conn_index] && in_range(e.time_ns)) push(slot_index, e);
      }
      return;
    }
    // The chunk's index data records follow it, one per connection in the chunk.
    std::uint64_t pos = r.end();
    for (std::size_t i = 0; i < chunk.counts.size(); ++i) {
      const FileRecord ir = b.read_record(pos);
      if (ir.header.op() != static_cast<std::uint8_t>(BagOp::kIndexData)) {
        b.fail(pos, "expected index data record after chunk at " + std::to_string(chunk.position) +
                        ", found op " + std::to_string(ir.header.op()));
      }
      if (ir.header.u32("ver") != kIndexVersion) {
        b.fail(pos, "unsupported index data version " + std::to_string(ir.header.u32("ver")));
      }
      const std::uint32_t conn = b.conn_index(ir.header.u32("conn"), pos);
      const std::uint32_t count = ir.header.u32("count");
      const auto declared = std::find_if(chunk.counts.begin(), chunk.counts.end(),
                                         [&](const auto& c) { return c.first == conn; });
      if (declared == chunk.counts.end() || declared->second != count) {
        b.fail(pos, "index data for connection " + std::to_string(ir.header.u32("conn")) +
                        " disagrees with the chunk info");
      }
      if (static_cast<std::uint64_t>(count) * kIndexEntrySize != ir.data_len) {
        b.fail(pos, "index data count " + std::to_string(count) + " disagrees with its length " +
                        std::to_string(ir.data_len));
      }
      if (wanted[conn]) {
        const auto data = b.read_data(ir);
        for (std::uint32_t k = 0; k < count; ++k) {
          const std::byte* p = data.data() + k * kIndexEntrySize;
          IndexEntry e;
          e.time_ns = to_ns(
              RosTime{detail::load_le<std::uint32_t>(p), detail::load_le<std::uint32_t>(p + 4)});
          e.offset = detail::load_le<std::uint32_t>(p + 8);
          e.conn_index = conn;
          if (e.time_ns < chunk.start_ns || e.time_ns > chunk.end_ns) {
            b.fail(ir.data_pos + k * kIndexEntrySize,
                   "index entry time outside its chunk's time range");
          }
          if (e.offset >= slot.header.uncompressed_size) {
            b.fail(ir.data_pos + k * kIndexEntrySize,
                   "index entry offset " + std::to_string(e.offset) + " beyond the chunk");
          }
          if (in_range(e.time_ns)) push(slot_index, e);
        }
      }
      pos = ir.end();
    }
  }

  // The message record at `p`: header fields and the message bytes.
  BagMessage read_message(const Pending& p) {
    const BagReader::Impl& b = *bag;
    ChunkSlot& slot = slots[p.slot];
    const Connection& conn = b.connections[p.conn_index];
    std::span<const std::byte> body;
    if (slot.header.compression == Compression::kNone) {
      // Read just this record from the file.
      const std::uint64_t rec = slot.header.data_pos + p.offset;
      const std::uint64_t chunk_end = slot.header.data_pos + slot.header.data_len;
      const std::uint64_t available = chunk_end - rec;  // rec < chunk_end: offset was checked
      if (available < kMinRecordSize) b.fail(rec, "message record runs past its chunk");
      const std::uint32_t header_len = b.read_u32(rec, "message record header length");
      if (header_len > available - kMinRecordSize) {
        b.fail(rec, "message record header runs past its chunk");
      }
      const std::uint32_t data_len = b.read_u32(rec + 4 + header_len, "message data length");
      if (data_len > available - kMinRecordSize - header_len) {
        b.fail(rec, "message data runs past its chunk");
      }
      record.resize(kMinRecordSize + header_len + data_len);
      b.src->read_at(rec, record);
      body = parse_message_record(record, b.source, rec, conn.id, p.time_ns);
    } else {
      if (!slot.data_loaded) {
        const FileRecord r = b.read_record(slot.chunk->position);
        b.load_chunk_data(r, slot.header, slot.data);
        slot.data_loaded = true;
      }
      // Offsets inside decompressed data are not file offsets: report the chunk's position.
      try {
        body = parse_message_record(std::span<const std::byte>(slot.data).subspan(p.offset),
                                    "uncompressed chunk data", p.offset, conn.id, p.time_ns);
      } catch (const FormatError& e) {
        b.fail(slot.chunk->position, e.what());
      }
    }
    BagMessage m;
    m.connection = &conn;
    m.time_ns = p.time_ns;
    m.data = body;
    return m;
  }

  // Checks the message data record at the start of `bytes` against its index entry and returns
  // the serialized message.
  static std::span<const std::byte> parse_message_record(std::span<const std::byte> bytes,
                                                         std::string_view source,
                                                         std::uint64_t base, std::uint32_t conn_id,
                                                         std::int64_t time_ns) {
    const auto fail = [&](const std::string& message) {
      throw FormatError(std::string(source), base, message);
    };
    if (bytes.size() < kMinRecordSize) fail("truncated message record");
    const auto header_len = detail::load_le<std::uint32_t>(bytes.data());
    if (header_len > bytes.size() - kMinRecordSize) {
      fail("message record header runs past its chunk");
    }
    const RecordHeader h = RecordHeader::parse(bytes.subspan(4, header_len), source, base + 4);
    if (h.op() != static_cast<std::uint8_t>(BagOp::kMessageData)) {
      fail("index points at op " + std::to_string(h.op()) + ", not a message data record");
    }
    const auto data_len = detail::load_le<std::uint32_t>(bytes.data() + 4 + header_len);
    if (data_len > bytes.size() - kMinRecordSize - header_len) {
      fail("message data runs past its chunk");
    }
    if (h.u32("conn") != conn_id) {
      fail("message record connection " + std::to_string(h.u32("conn")) +
           " disagrees with the index (" + std::to_string(conn_id) + ")");
    }
    if (to_ns(h.time("time")) != time_ns) fail("message record time disagrees with the index");
    return bytes.subspan(kMinRecordSize + header_len, data_len);
  }

  std::optional<BagMessage> next() {
    if (last_slot) {
      ChunkSlot& s = slots[*last_slot];
      if (s.pending == 0) {
        s.data.clear();
        s.data.shrink_to_fit();
        s.data_loaded = false;
      }
      last_slot.reset();
    }
    // Chunks are visited by start time: any message earlier than (or tied with) the heap top
    // lives in a chunk that starts no later than it, so load those before popping.
    while (true) {
      while (next_slot < slots.size() &&
             (heap.empty() || slots[next_slot].chunk->start_ns <= heap.top().time_ns)) {
        load_slot(static_cast<std::uint32_t>(next_slot++));
      }
      if (heap.empty()) return std::nullopt;
      const Pending p = heap.top();
      heap.pop();
      ChunkSlot& slot = slots[p.slot];
      if (slot.damaged) continue;  // counted in the chunk's loss
      try {
        BagMessage m = read_message(p);
        --slot.pending;
        last_slot = p.slot;
        return m;
      } catch (const FormatError& e) {
        if (slot.header.compression != Compression::kNone && !slot.data_loaded) {
          // The chunk does not decompress: every message still due from it is lost.
          slot.damaged = true;
          lose(slot.chunk->position, slot.pending, std::nullopt, e);
          slot.pending = 0;
        } else {
          --slot.pending;
          lose(slot.header.compression == Compression::kNone ? slot.header.data_pos + p.offset
                                                             : slot.chunk->position,
               1, std::nullopt, e);
          last_slot = p.slot;
        }
      }
    }
  }
};

MessageCursor::MessageCursor(std::unique_ptr<State> state) : state_(std::move(state)) {}
MessageCursor::~MessageCursor() = default;
MessageCursor::MessageCursor(MessageCursor&&) noexcept = default;
MessageCursor& MessageCursor::operator=(MessageCursor&&) noexcept = default;

std::optional<BagMessage> MessageCursor::next() {
  return state_->next();
}

const InputLossLog& MessageCursor::losses() const {
  return state_->losses;
}

// ---- BagMessage ------------------------------------------------------------------------------

void BagMessage::check_type(std::string_view type, std::string_view md5sum) const {
  if (connection == nullptr) throw Error("BagMessage without a connection");
  if (connection->type != type || (connection->md5sum != md5sum && connection->md5sum != "*")) {
    throw Error("topic " + connection->topic + " carries " + connection->type + " (md5 " +
                connection->md5sum + "), not " + std::string(type) + " (md5 " +
                std::string(md5sum) + ")");
  }
}

// ---- BagReader -------------------------------------------------------------------------------

BagReader::BagReader(std::shared_ptr<Impl> impl) : impl_(std::move(impl)) {}

BagReader::BagReader(const std::filesystem::path& path) : BagReader(path, Options{}) {}

BagReader::BagReader(const std::filesystem::path& path, Options options) {
  auto impl = std::make_shared<Impl>();
  impl->src = std::make_unique<FileSource>(path);
  impl->source = path.string();
  impl->options = options;
  impl->open();
  impl_ = std::move(impl);
}

BagReader BagReader::from_bytes(std::vector<std::byte> bytes, std::string source_name,
                                Options options) {
  auto impl = std::make_shared<Impl>();
  impl->src = std::make_unique<MemorySource>(std::move(bytes));
  impl->source = std::move(source_name);
  impl->options = options;
  impl->open();
  return BagReader(std::move(impl));
}

BagReader::~BagReader() = default;
BagReader::BagReader(BagReader&&) noexcept = default;
BagReader& BagReader::operator=(BagReader&&) noexcept = default;

const std::string& BagReader::source() const {
  return impl_->source;
}
std::uint64_t BagReader::file_size() const {
  return impl_->src->size();
}
const std::vector<Connection>& BagReader::connections() const {
  return impl_->connections;
}
std::size_t BagReader::chunk_count() const {
  return impl_->chunks.size();
}
bool BagReader::recovered() const {
  return impl_->recovered;
}
const std::string& BagReader::index_problem() const {
  return impl_->index_problem;
}
const InputLossLog& BagReader::losses() const {
  return impl_->losses;
}

std::vector<TopicInfo> BagReader::topics() const {
  std::map<std::string, TopicInfo> by_topic;
  for (const Connection& c : impl_->connections) {
    auto [it, inserted] = by_topic.try_emplace(c.topic);
    if (inserted) {
      it->second.topic = c.topic;
      it->second.type = c.type;
      it->second.md5sum = c.md5sum;
    }
    ++it->second.connection_count;
  }
  for (const ChunkRecord& chunk : impl_->chunks) {
    for (const auto& [conn, n] : chunk.counts) {
      by_topic[impl_->connections[conn].topic].message_count += n;
    }
  }
  std::vector<TopicInfo> out;
  out.reserve(by_topic.size());
  for (auto& [topic, info] : by_topic) out.push_back(std::move(info));
  return out;
}

std::uint64_t BagReader::message_count() const {
  std::uint64_t n = 0;
  for (const ChunkRecord& chunk : impl_->chunks) {
    for (const auto& c : chunk.counts) n += c.second;
  }
  return n;
}

std::uint64_t BagReader::message_count(std::string_view topic) const {
  std::uint64_t n = 0;
  for (const ChunkRecord& chunk : impl_->chunks) {
    for (const auto& [conn, count] : chunk.counts) {
      if (impl_->connections[conn].topic == topic) n += count;
    }
  }
  return n;
}

std::optional<std::int64_t> BagReader::start_time_ns() const {
  std::optional<std::int64_t> t;
  for (const ChunkRecord& chunk : impl_->chunks) {
    if (!t || chunk.start_ns < *t) t = chunk.start_ns;
  }
  return t;
}

std::optional<std::int64_t> BagReader::end_time_ns() const {
  std::optional<std::int64_t> t;
  for (const ChunkRecord& chunk : impl_->chunks) {
    if (!t || chunk.end_ns > *t) t = chunk.end_ns;
  }
  return t;
}

std::map<std::string, std::size_t> BagReader::chunk_compressions() const {
  std::map<std::string, std::size_t> out;
  for (const ChunkRecord& chunk : impl_->chunks) {
    const FileRecord r = impl_->read_record(chunk.position);
    ++out[std::string(compression_name(impl_->chunk_header(r).compression))];
  }
  return out;
}

MessageCursor BagReader::read(const BagQuery& query) const {
  auto state = std::make_unique<MessageCursor::State>();
  state->bag = impl_;
  state->query = query;
  state->wanted.assign(impl_->connections.size(), query.topics.empty());
  if (!query.topics.empty()) {
    const std::set<std::string_view> topics(query.topics.begin(), query.topics.end());
    for (std::size_t i = 0; i < impl_->connections.size(); ++i) {
      state->wanted[i] = topics.contains(impl_->connections[i].topic);
    }
  }
  for (const ChunkRecord& chunk : impl_->chunks) {
    if (chunk.end_ns < query.start_ns || chunk.start_ns > query.end_ns) continue;
    const bool has_wanted =
        std::any_of(chunk.counts.begin(), chunk.counts.end(),
                    [&](const auto& c) { return c.second > 0 && state->wanted[c.first]; });
    if (!has_wanted) continue;
    ChunkSlot slot;
    slot.chunk = &chunk;
    state->slots.push_back(std::move(slot));
  }
  std::stable_sort(state->slots.begin(), state->slots.end(),
                   [](const ChunkSlot& a, const ChunkSlot& b) {
                     if (a.chunk->start_ns != b.chunk->start_ns) {
                       return a.chunk->start_ns < b.chunk->start_ns;
                     }
                     return a.chunk->position < b.chunk->position;
                   });
  return MessageCursor(std::move(state));
}

// ---- describe_bag ----------------------------------------------------------------------------

namespace {

std::string format_time(std::int64_t ns) {
  std::ostringstream s;
  s << ns / 1'000'000'000 << '.' << std::setw(9) << std::setfill('0') << ns % 1'000'000'000;
  return s.str();
}

}  // namespace

std::string describe_bag(const std::filesystem::path& path) {
  const BagReader bag(path);
  std::ostringstream s;
  s << "path:        " << path.string() << "\n";
  s << "version:     2.0\n";
  const auto start = bag.start_time_ns();
  const auto end = bag.end_time_ns();
  if (start && end) {
    s << "duration:    " << std::fixed << std::setprecision(3)
      << static_cast<double>(*end - *start) * 1e-9 << " s\n";
    s << "start:       " << format_time(*start) << "\n";
    s << "end:         " << format_time(*end) << "\n";
  }
  s << "size:        " << bag.file_size() << " bytes\n";
  s << "messages:    " << bag.message_count() << "\n";
  s << "compression:";
  const auto compressions = bag.chunk_compressions();
  if (compressions.empty()) s << " none";
  for (const auto& [name, n] : compressions) {
    s << " " << name << " [" << n << "/" << bag.chunk_count() << " chunks]";
  }
  s << "\n";
  const auto topics = bag.topics();
  std::map<std::string, std::string> types;
  for (const Connection& c : bag.connections()) types.emplace(c.type, c.md5sum);
  std::size_t type_width = 0;
  std::size_t topic_width = 0;
  for (const auto& [type, md5] : types) type_width = std::max(type_width, type.size());
  for (const TopicInfo& t : topics) topic_width = std::max(topic_width, t.topic.size());
  const char* label = "types:       ";
  for (const auto& [type, md5] : types) {
    s << label << std::left << std::setw(static_cast<int>(type_width)) << type << " [" << md5
      << "]\n";
    label = "             ";
  }
  label = "topics:      ";
  for (const TopicInfo& t : topics) {
    s << label << std::left << std::setw(static_cast<int>(topic_width)) << t.topic << " "
      << std::right << std::setw(8) << t.message_count << " msgs : " << t.type;
    if (t.connection_count > 1) s << " (" << t.connection_count << " connections)";
    s << "\n";
    label = "             ";
  }
  return s.str();
}

}  // namespace livod::io::rosbag
