#include "io/rosbag/chunk_compression.hpp"

#include <bzlib.h>
#include <lz4frame.h>

#include <algorithm>
#include <climits>
#include <cstring>
#include <memory>

#include "core/error.hpp"

namespace livod::io::rosbag {
namespace {

// rosbag's BZ2Stream settings: 900 kB blocks, default work factor.
constexpr int kBz2BlockSize100k = 9;
constexpr int kBz2WorkFactor = 30;
// First output allocation; later growth doubles, bounded by max_output.
constexpr std::size_t kMinInitialOutput = 64 * 1024;
constexpr std::size_t kInitialExpansion = 4;

// Grows `out` for more output; false when it is already max_output long.
bool grow(std::vector<std::byte>& out, std::size_t max_output) {
  if (out.size() >= max_output) return false;
  const std::size_t doubled = out.size() > max_output / 2 ? max_output : out.size() * 2;
  out.resize(std::min(std::max(doubled, kMinInitialOutput), max_output));
  return true;
}

std::size_t initial_output_size(std::size_t in_size, std::size_t max_output) {
  const std::size_t guess =
      in_size > SIZE_MAX / kInitialExpansion ? SIZE_MAX : in_size * kInitialExpansion;
  return std::min(max_output, std::max(guess, kMinInitialOutput));
}

std::string decompress_bz2(std::span<const std::byte> in, std::size_t max_output,
                           std::vector<std::byte>& out) {
  if (in.size() > UINT_MAX) return "bz2 input larger than 4 GiB";
  bz_stream strm{};
  if (BZ2_bzDecompressInit(&strm, 0, 0) != BZ_OK) return "bz2 init failed";
  struct Closer {
    bz_stream* s;
    ~Closer() { BZ2_bzDecompressEnd(s); }
  } closer{&strm};

  out.resize(initial_output_size(in.size(), max_output));
  strm.next_in = const_cast<char*>(reinterpret_cast<const char*>(in.data()));
  strm.avail_in = static_cast<unsigned>(in.size());
  std::size_t produced = 0;
  for (;;) {
    if (produced == out.size() && !grow(out, max_output)) {
      // Output is full: the stream must end here without producing anything more.
      char probe = 0;
      strm.next_out = &probe;
      strm.avail_out = 1;
      const int ret = BZ2_bzDecompress(&strm);
      if (ret == BZ_STREAM_END && strm.avail_out == 1) break;
      if (ret != BZ_OK && ret != BZ_STREAM_END)
        return "corrupt bz2 stream (code " + std::to_string(ret) + ")";
      if (strm.avail_out == 0) {
        return "bz2 data decompresses to more than " + std::to_string(max_output) + " bytes";
      }
      if (strm.avail_in == 0) return "truncated bz2 stream";
      continue;
    }
    const std::size_t room = std::min<std::size_t>(out.size() - produced, UINT_MAX);
    strm.next_out = reinterpret_cast<char*>(out.data() + produced);
    strm.avail_out = static_cast<unsigned>(room);
    const unsigned in_before = strm.avail_in;
    const int ret = BZ2_bzDecompress(&strm);
    const std::size_t got = room - strm.avail_out;
    produced += got;
    if (ret == BZ_STREAM_END) break;
    if (ret != BZ_OK) return "corrupt bz2 stream (code " + std::to_string(ret) + ")";
    if (got == 0 && strm.avail_in == in_before) return "truncated bz2 stream";
  }
  if (strm.avail_in != 0) {
    return std::to_string(strm.avail_in) + " trailing bytes after the bz2 stream";
  }
  out.resize(produced);
  return {};
}

std::string decompress_lz4(std::span<const std::byte> in, std::size_t max_output,
                           std::vector<std::byte>& out) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) return "lz4 init failed";
  const std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(
      raw, &LZ4F_freeDecompressionContext);

  out.resize(initial_output_size(in.size(), max_output));
  std::size_t consumed = 0;
  std::size_t produced = 0;
  for (;;) {
    if (produced == out.size() && !grow(out, max_output)) {
      std::byte probe{};
      std::size_t probe_size = 1;
      std::size_t src_size = in.size() - consumed;
      const std::size_t ret =
          LZ4F_decompress(ctx.get(), &probe, &probe_size, in.data() + consumed, &src_size, nullptr);
      if (LZ4F_isError(ret)) return std::string("corrupt lz4 frame: ") + LZ4F_getErrorName(ret);
      consumed += src_size;
      if (probe_size != 0) {
        return "lz4 data decompresses to more than " + std::to_string(max_output) + " bytes";
      }
      if (ret == 0) break;
      if (src_size == 0) return "truncated lz4 frame";
      continue;
    }
    std::size_t dst_size = out.size() - produced;
    std::size_t src_size = in.size() - consumed;
    const std::size_t ret = LZ4F_decompress(ctx.get(), out.data() + produced, &dst_size,
                                            in.data() + consumed, &src_size, nullptr);
    if (LZ4F_isError(ret)) return std::string("corrupt lz4 frame: ") + LZ4F_getErrorName(ret);
    consumed += src_size;
    produced += dst_size;
    if (ret == 0) break;  // frame complete (content checksum verified)
    if (src_size == 0 && dst_size == 0) return "truncated lz4 frame";
  }
  if (consumed != in.size()) {
    return std::to_string(in.size() - consumed) + " trailing bytes after the lz4 frame";
  }
  out.resize(produced);
  return {};
}

}  // namespace

std::string_view compression_name(Compression compression) {
  switch (compression) {
    case Compression::kNone:
      return "none";
    case Compression::kBz2:
      return "bz2";
    case Compression::kLz4:
      return "lz4";
  }
  return "none";
}

std::optional<Compression> parse_compression(std::string_view name) {
  if (name == "none") return Compression::kNone;
  if (name == "bz2") return Compression::kBz2;
  if (name == "lz4") return Compression::kLz4;
  return std::nullopt;
}

void compress_chunk(Compression compression, std::span<const std::byte> in,
                    std::vector<std::byte>& out) {
  switch (compression) {
    case Compression::kNone:
      out.assign(in.begin(), in.end());
      return;
    case Compression::kBz2: {
      if (in.size() > UINT_MAX / 2) throw Error("bz2: chunk too large");
      // libbz2's documented worst case: 1% larger plus 600 bytes.
      unsigned out_size = static_cast<unsigned>(in.size() + in.size() / 100 + 600);
      out.resize(out_size);
      const int ret = BZ2_bzBuffToBuffCompress(
          reinterpret_cast<char*>(out.data()), &out_size,
          const_cast<char*>(reinterpret_cast<const char*>(in.data())),
          static_cast<unsigned>(in.size()), kBz2BlockSize100k, 0, kBz2WorkFactor);
      if (ret != BZ_OK) throw Error("bz2 compression failed (code " + std::to_string(ret) + ")");
      out.resize(out_size);
      return;
    }
    case Compression::kLz4: {
      LZ4F_preferences_t prefs{};
      prefs.frameInfo.blockSizeID = LZ4F_max1MB;
      prefs.frameInfo.blockMode = LZ4F_blockIndependent;
      prefs.frameInfo.contentChecksumFlag = LZ4F_contentChecksumEnabled;
      prefs.frameInfo.frameType = LZ4F_frame;
      prefs.frameInfo.contentSize = 0;  // roslz4 rejects frames that carry the content size
      prefs.frameInfo.blockChecksumFlag = LZ4F_noBlockChecksum;
      out.resize(LZ4F_compressFrameBound(in.size(), &prefs));
      const std::size_t n =
          LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), &prefs);
      if (LZ4F_isError(n))
        throw Error(std::string("lz4 compression failed: ") + LZ4F_getErrorName(n));
      out.resize(n);
      return;
    }
  }
}

std::string decompress_chunk(Compression compression, std::span<const std::byte> in,
                             std::size_t max_output, std::vector<std::byte>& out) {
  switch (compression) {
    case Compression::kNone:
      if (in.size() > max_output) {
        return "chunk larger than " + std::to_string(max_output) + " bytes";
      }
      out.assign(in.begin(), in.end());
      return {};
    case Compression::kBz2:
      return decompress_bz2(in, max_output, out);
    case Compression::kLz4:
      return decompress_lz4(in, max_output, out);
  }
  return "unknown compression";
}

}  // namespace livod::io::rosbag
