#include "io/rosbag/bag_writer.hpp"

#include <fstream>
#include <map>

#include "core/error.hpp"
#include "io/rosbag/bag_records.hpp"

namespace livod::io::rosbag {
namespace {

struct IndexOut {
  RosTime time;
  std::uint32_t offset = 0;
};

struct ChunkInfoOut {
  std::uint64_t position = 0;
  RosTime start;
  RosTime end;
  std::map<std::uint32_t, std::uint32_t> counts;  // connection id -> messages
};

bool earlier(RosTime a, RosTime b) {
  return a.to_ns() < b.to_ns();
}

// header_len, header, data_len, data.
void append_record(std::vector<std::byte>& out, const HeaderBuilder& header,
                   std::span<const std::byte> data) {
  header.append_to(out);
  RosWriter w(out);
  w.write_count(data.size());
  w.write_bytes(data);
}

}  // namespace

struct BagWriter::Impl {
  std::string path;
  std::ofstream file;
  Options options;
  std::vector<ConnectionSpec> connections;
  std::vector<bool> connection_written;  // its record is already in a chunk
  std::vector<std::byte> chunk;          // uncompressed records of the open chunk
  std::map<std::uint32_t, std::vector<IndexOut>> chunk_index;
  RosTime chunk_start;
  RosTime chunk_end;
  std::vector<ChunkInfoOut> chunk_infos;
  std::uint64_t file_pos = 0;
  bool closed = false;
  std::vector<std::byte> out;  // scratch for records going to the file
  std::vector<std::byte> compressed;

  void put(std::span<const std::byte> bytes) {
    file.write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
    if (!file) throw Error(path + ": write failed");
    file_pos += bytes.size();
  }

  void append_connection_record(std::vector<std::byte>& dst, std::uint32_t id) const {
    const ConnectionSpec& c = connections[id];
    HeaderBuilder header;
    header.add_u32("conn", id).add_op(BagOp::kConnection).add("topic", c.topic);
    HeaderBuilder fields;
    fields.add("topic", c.topic)
        .add("type", c.type)
        .add("md5sum", c.md5sum)
        .add("message_definition", c.message_definition);
    if (!c.callerid.empty()) fields.add("callerid", c.callerid);
    if (c.latching) fields.add("latching", std::string_view("1"));
    // A connection record's data has the layout of a header: data_len, then the fields.
    header.append_to(dst);
    fields.append_to(dst);
  }

  // The bag header record, padded so that header + data take exactly 4096 bytes.
  void append_bag_header(std::vector<std::byte>& dst, std::uint64_t index_pos) const {
    HeaderBuilder header;
    header.add_u32("chunk_count", static_cast<std::uint32_t>(chunk_infos.size()))
        .add_u32("conn_count", static_cast<std::uint32_t>(connections.size()))
        .add_u64("index_pos", index_pos)
        .add_op(BagOp::kBagHeader);
    const std::vector<std::byte> padding(kBagHeaderPaddedLength - header.size(), std::byte{' '});
    append_record(dst, header, padding);
  }

  void flush_chunk() {
    if (chunk.empty()) return;
    ChunkInfoOut info;
    info.position = file_pos;
    info.start = chunk_start;
    info.end = chunk_end;
    compress_chunk(options.compression, chunk, compressed);
    out.clear();
    HeaderBuilder header;
    header.add("compression", compression_name(options.compression))
        .add_op(BagOp::kChunk)
        .add_u32("size", static_cast<std::uint32_t>(chunk.size()));
    append_record(out, header, compressed);
    for (const auto& [conn, entries] : chunk_index) {
      HeaderBuilder index_header;
      index_header.add_u32("conn", conn)
          .add_u32("count", static_cast<std::uint32_t>(entries.size()))
          .add_op(BagOp::kIndexData)
          .add_u32("ver", kIndexVersion);
      std::vector<std::byte> data;
      RosWriter w(data);
      for (const IndexOut& e : entries) {
        w.write_time(e.time);
        w.write(e.offset);
      }
      append_record(out, index_header, data);
      info.counts[conn] = static_cast<std::uint32_t>(entries.size());
    }
    put(out);
    chunk_infos.push_back(std::move(info));
    chunk.clear();
    chunk_index.clear();
  }
};

BagWriter::BagWriter(const std::filesystem::path& path, Options options)
    : impl_(std::make_unique<Impl>()) {
  impl_->path = path.string();
  impl_->options = options;
  impl_->file.open(path, std::ios::binary | std::ios::trunc);
  if (!impl_->file) throw Error(impl_->path + ": cannot create bag file");
  impl_->put(std::as_bytes(std::span(kBagMagic.data(), kBagMagic.size())));
  // Placeholder header of the final size; close() rewrites it with index_pos and the counts.
  impl_->out.clear();
  impl_->append_bag_header(impl_->out, 0);
  impl_->put(impl_->out);
}

BagWriter::~BagWriter() {
  if (impl_ && !impl_->closed) {
    try {
      close();
    } catch (const std::exception&) {
      // Destructors must not throw; callers who care about errors call close() themselves.
    }
  }
}

BagWriter::BagWriter(BagWriter&&) noexcept = default;
BagWriter& BagWriter::operator=(BagWriter&&) noexcept = default;

std::uint32_t BagWriter::add_connection(const ConnectionSpec& spec) {
  if (impl_->closed) throw Error(impl_->path + ": add_connection after close");
  if (spec.topic.empty() || spec.type.empty() || spec.md5sum.empty()) {
    throw Error(impl_->path + ": a connection needs a topic, a type and an md5sum");
  }
  impl_->connections.push_back(spec);
  impl_->connection_written.push_back(false);
  return static_cast<std::uint32_t>(impl_->connections.size() - 1);
}

void BagWriter::check_type(std::uint32_t connection, std::string_view type) const {
  if (connection >= impl_->connections.size()) {
    throw Error(impl_->path + ": unknown connection " + std::to_string(connection));
  }
  if (impl_->connections[connection].type != type) {
    throw Error(impl_->path + ": connection " + std::to_string(connection) + " (" +
                impl_->connections[connection].topic + ") is " +
                impl_->connections[connection].type + ", not " + std::string(type));
  }
}

void BagWriter::write(std::uint32_t connection, std::int64_t time_ns,
                      std::span<const std::byte> message) {
  Impl& b = *impl_;
  if (b.closed) throw Error(b.path + ": write after close");
  if (connection >= b.connections.size()) {
    throw Error(b.path + ": unknown connection " + std::to_string(connection));
  }
  if (time_ns < 1) throw Error(b.path + ": rosbag needs record times >= 1 ns");
  const RosTime t = RosTime::from_ns(time_ns);

  if (b.chunk.empty()) {
    b.chunk_start = t;
    b.chunk_end = t;
  }
  if (!b.connection_written[connection]) {
    b.append_connection_record(b.chunk, connection);
    b.connection_written[connection] = true;
  }
  const auto offset = b.chunk.size();
  HeaderBuilder header;
  header.add_u32("conn", connection).add_op(BagOp::kMessageData).add_time("time", t);
  append_record(b.chunk, header, message);
  if (offset > UINT32_MAX || b.chunk.size() > UINT32_MAX) {
    throw Error(b.path + ": chunk larger than 4 GiB");
  }
  b.chunk_index[connection].push_back(IndexOut{t, static_cast<std::uint32_t>(offset)});
  if (earlier(t, b.chunk_start)) b.chunk_start = t;
  if (earlier(b.chunk_end, t)) b.chunk_end = t;
  if (b.chunk.size() > b.options.chunk_threshold) b.flush_chunk();
}

void BagWriter::close() {
  Impl& b = *impl_;
  if (b.closed) return;
  b.flush_chunk();
  const std::uint64_t index_pos = b.file_pos;
  b.out.clear();
  for (std::uint32_t id = 0; id < b.connections.size(); ++id) {
    b.append_connection_record(b.out, id);
  }
  for (const ChunkInfoOut& info : b.chunk_infos) {
    HeaderBuilder header;
    header.add_u64("chunk_pos", info.position)
        .add_u32("count", static_cast<std::uint32_t>(info.counts.size()))
        .add_time("end_time", info.end)
        .add_op(BagOp::kChunkInfo)
        .add_time("start_time", info.start)
        .add_u32("ver", kIndexVersion);
    std::vector<std::byte> data;
    RosWriter w(data);
    for (const auto& [conn, count] : info.counts) {
      w.write(conn);
      w.write(count);
    }
    append_record(b.out, header, data);
  }
  b.put(b.out);

  b.out.clear();
  b.append_bag_header(b.out, index_pos);
  b.file.seekp(static_cast<std::streamoff>(kBagMagic.size()));
  b.file.write(reinterpret_cast<const char*>(b.out.data()),
               static_cast<std::streamsize>(b.out.size()));
  b.file.close();
  b.closed = true;
  if (!b.file) throw Error(b.path + ": writing the bag header failed");
}

}  // namespace livod::io::rosbag
