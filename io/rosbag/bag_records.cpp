#include "io/rosbag/bag_records.hpp"

#include <algorithm>
#include <array>

#include "core/error.hpp"

namespace livod::io::rosbag {

RecordHeader RecordHeader::parse(std::span<const std::byte> bytes, std::string_view source,
                                 std::uint64_t base_offset) {
  RecordHeader h;
  h.source_ = source;
  h.base_offset_ = base_offset;
  std::size_t pos = 0;
  while (pos < bytes.size()) {
    if (bytes.size() - pos < 4) {
      throw FormatError(std::string(source), base_offset + pos, "truncated header field length");
    }
    const auto len = detail::load_le<std::uint32_t>(bytes.data() + pos);
    if (len > bytes.size() - pos - 4) {
      throw FormatError(std::string(source), base_offset + pos,
                        "header field length " + std::to_string(len) + " exceeds the header (" +
                            std::to_string(bytes.size() - pos - 4) + " bytes left)");
    }
    const auto field = bytes.subspan(pos + 4, len);
    const std::string_view text(reinterpret_cast<const char*>(field.data()), field.size());
    const auto eq = text.find('=');
    if (eq == std::string_view::npos) {
      throw FormatError(std::string(source), base_offset + pos, "header field without '='");
    }
    h.fields_.emplace_back(text.substr(0, eq), field.subspan(eq + 1));
    pos += 4 + len;
  }
  return h;
}

std::optional<std::span<const std::byte>> RecordHeader::find(std::string_view name) const {
  for (const auto& [n, v] : fields_) {
    if (n == name) return v;
  }
  return std::nullopt;
}

std::span<const std::byte> RecordHeader::required(std::string_view name,
                                                  std::size_t exact_size) const {
  const auto v = find(name);
  if (!v) {
    throw FormatError(std::string(source_), base_offset_,
                      "record header lacks field '" + std::string(name) + "'");
  }
  if (exact_size != 0 && v->size() != exact_size) {
    throw FormatError(std::string(source_), base_offset_,
                      "header field '" + std::string(name) + "' has " + std::to_string(v->size()) +
                          " bytes, expected " + std::to_string(exact_size));
  }
  return *v;
}

std::uint8_t RecordHeader::op() const {
  return static_cast<std::uint8_t>(required("op", 1)[0]);
}

std::uint32_t RecordHeader::u32(std::string_view name) const {
  return detail::load_le<std::uint32_t>(required(name, 4).data());
}

std::uint64_t RecordHeader::u64(std::string_view name) const {
  return detail::load_le<std::uint64_t>(required(name, 8).data());
}

RosTime RecordHeader::time(std::string_view name) const {
  const auto v = required(name, 8);
  return RosTime{detail::load_le<std::uint32_t>(v.data()),
                 detail::load_le<std::uint32_t>(v.data() + 4)};
}

std::string RecordHeader::string(std::string_view name) const {
  const auto v = required(name, 0);
  return std::string(reinterpret_cast<const char*>(v.data()), v.size());
}

HeaderBuilder& HeaderBuilder::add(std::string_view name, std::span<const std::byte> value) {
  fields_.emplace_back(std::string(name), std::vector<std::byte>(value.begin(), value.end()));
  return *this;
}

HeaderBuilder& HeaderBuilder::add(std::string_view name, std::string_view value) {
  return add(name, std::as_bytes(std::span(value.data(), value.size())));
}

HeaderBuilder& HeaderBuilder::add_op(BagOp op) {
  const std::byte b{static_cast<std::uint8_t>(op)};
  return add("op", std::span(&b, 1));
}

HeaderBuilder& HeaderBuilder::add_u32(std::string_view name, std::uint32_t value) {
  std::array<std::byte, 4> b{};
  detail::store_le(value, b.data());
  return add(name, b);
}

HeaderBuilder& HeaderBuilder::add_u64(std::string_view name, std::uint64_t value) {
  std::array<std::byte, 8> b{};
  detail::store_le(value, b.data());
  return add(name, b);
}

HeaderBuilder& HeaderBuilder::add_time(std::string_view name, RosTime value) {
  std::array<std::byte, 8> b{};
  detail::store_le(value.sec, b.data());
  detail::store_le(value.nsec, b.data() + 4);
  return add(name, b);
}

std::size_t HeaderBuilder::size() const {
  std::size_t n = 0;
  for (const auto& [name, value] : fields_) n += 4 + name.size() + 1 + value.size();
  return n;
}

void HeaderBuilder::append_to(std::vector<std::byte>& out) const {
  std::vector<const std::pair<std::string, std::vector<std::byte>>*> sorted;
  sorted.reserve(fields_.size());
  for (const auto& f : fields_) sorted.push_back(&f);
  std::stable_sort(sorted.begin(), sorted.end(),
                   [](const auto* a, const auto* b) { return a->first < b->first; });
  RosWriter w(out);
  w.write_count(size());
  for (const auto* f : sorted) {
    w.write_count(f->first.size() + 1 + f->second.size());
    w.write_bytes(std::as_bytes(std::span(f->first.data(), f->first.size())));
    w.write(static_cast<std::uint8_t>('='));
    w.write_bytes(f->second);
  }
}

}  // namespace livod::io::rosbag
