#pragma once
// Chunk compression of ROS1 bags: "none", "bz2" (libbz2) and "lz4". rosbag's "lz4" is the
// roslz4 stream, which is the standard LZ4 frame format (magic 0x184D2204) with independent
// blocks, no block checksums, no content size and a content checksum; roslz4 rejects any other
// flag combination, so the writer produces exactly that (1 MB blocks, as rosbag uses).

#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace livod::io::rosbag {

enum class Compression { kNone, kBz2, kLz4 };

// The chunk header's "compression" value: "none", "bz2", "lz4".
std::string_view compression_name(Compression compression);
std::optional<Compression> parse_compression(std::string_view name);

// Replaces `out` with the compressed form of `in`.
void compress_chunk(Compression compression, std::span<const std::byte> in,
                    std::vector<std::byte>& out);

// Replaces `out` with the decompressed form of `in`. `out` grows only as output is actually
// produced, so a bogus size in a corrupt file cannot trigger a large allocation by itself, and
// never beyond `max_output` bytes. Returns an empty string on success, otherwise why it failed
// (corrupt or truncated stream, trailing bytes, output larger than max_output).
std::string decompress_chunk(Compression compression, std::span<const std::byte> in,
                             std::size_t max_output, std::vector<std::byte>& out);

}  // namespace livod::io::rosbag
