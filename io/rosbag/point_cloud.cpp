#include "io/rosbag/point_cloud.hpp"

#include <algorithm>
#include <bit>
#include <cstring>

#include "core/error.hpp"

namespace livod::io::rosbag {
namespace {

using sensor_msgs::PointField;

constexpr std::string_view kSource = "sensor_msgs/PointCloud2 message";

template <class T>
T load(const std::uint8_t* p, bool big_endian) {
  using Bits = detail::WireBits<T>;
  Bits bits = 0;
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    const std::size_t shift = big_endian ? 8 * (sizeof(T) - 1 - i) : 8 * i;
    bits |= static_cast<Bits>(static_cast<Bits>(p[i]) << shift);
  }
  return std::bit_cast<T>(bits);
}

// Resolved accessor for one requested field.
struct FieldReader {
  const PointField* field = nullptr;
};

FieldReader find_field(const sensor_msgs::PointCloud2& cloud, const std::string& name) {
  if (name.empty()) return {};
  const auto it = std::find_if(cloud.fields.begin(), cloud.fields.end(),
                               [&](const PointField& f) { return f.name == name; });
  if (it == cloud.fields.end()) {
    std::string names;
    for (const auto& n : field_names(cloud)) names += (names.empty() ? "" : ",") + n;
    throw FormatError(std::string(kSource), 0, "no field '" + name + "' (fields: " + names + ")");
  }
  const std::size_t size = sensor_msgs::point_field_size(it->datatype);
  if (size == 0) {
    throw FormatError(std::string(kSource), 0,
                      "field '" + name + "' has unknown datatype " + std::to_string(it->datatype));
  }
  if (static_cast<std::uint64_t>(it->offset) + size > cloud.point_step) {
    throw FormatError(std::string(kSource), 0,
                      "field '" + name + "' at offset " + std::to_string(it->offset) +
                          " does not fit in point_step " + std::to_string(cloud.point_step));
  }
  return FieldReader{&*it};
}

}  // namespace

std::vector<std::string> field_names(const sensor_msgs::PointCloud2& cloud) {
  std::vector<std::string> names;
  names.reserve(cloud.fields.size());
  for (const auto& f : cloud.fields) names.push_back(f.name);
  return names;
}

double read_point_field(std::span<const std::uint8_t> point, const PointField& field,
                        bool big_endian) {
  const std::uint8_t* p = point.data() + field.offset;
  switch (field.datatype) {
    case PointField::kInt8:
      return static_cast<std::int8_t>(p[0]);
    case PointField::kUint8:
      return p[0];
    case PointField::kInt16:
      return load<std::int16_t>(p, big_endian);
    case PointField::kUint16:
      return load<std::uint16_t>(p, big_endian);
    case PointField::kInt32:
      return load<std::int32_t>(p, big_endian);
    case PointField::kUint32:
      return load<std::uint32_t>(p, big_endian);
    case PointField::kFloat32:
      return load<float>(p, big_endian);
    case PointField::kFloat64:
      return load<double>(p, big_endian);
    default:
      return 0;
  }
}

void extract_points(const sensor_msgs::PointCloud2& cloud, const CloudFields& fields,
                    std::vector<CloudPoint>& out) {
  const FieldReader x = find_field(cloud, fields.x);
  const FieldReader y = find_field(cloud, fields.y);
  const FieldReader z = find_field(cloud, fields.z);
  const FieldReader intensity = find_field(cloud, fields.intensity);
  const FieldReader time = find_field(cloud, fields.time);
  const FieldReader ring = find_field(cloud, fields.ring);
  if (x.field == nullptr || y.field == nullptr || z.field == nullptr) {
    throw FormatError(std::string(kSource), 0, "x, y and z field names are required");
  }
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(cloud.width) * cloud.point_step;
  if (cloud.height > 0 && cloud.width > 0 && cloud.row_step < row_bytes) {
    throw FormatError(std::string(kSource), 0,
                      "row_step " + std::to_string(cloud.row_step) + " < width * point_step " +
                          std::to_string(row_bytes));
  }
  // height * width points must lie inside data (checked by division: the product of two
  // declared u32 sizes may not fit in 64 bits).
  const std::uint64_t size = cloud.data.size();
  const bool empty = cloud.height == 0 || cloud.width == 0;
  if (!empty &&
      (row_bytes > size || (cloud.height > 1 && static_cast<std::uint64_t>(cloud.height - 1) >
                                                    (size - row_bytes) / cloud.row_step))) {
    throw FormatError(std::string(kSource), 0,
                      "data holds " + std::to_string(size) + " bytes, too few for " +
                          std::to_string(cloud.height) + "x" + std::to_string(cloud.width) +
                          " points of row_step " + std::to_string(cloud.row_step));
  }
  out.resize(static_cast<std::size_t>(cloud.height) * cloud.width);
  // A cloud without points returns here: walking the rows of a width-0 cloud would cost up to
  // 2^32 iterations for nothing (a hostile height stalled a replay for seconds per message).
  if (empty) return;
  std::size_t k = 0;
  for (std::uint32_t row = 0; row < cloud.height; ++row) {
    for (std::uint32_t col = 0; col < cloud.width; ++col) {
      const std::span<const std::uint8_t> point(
          cloud.data.data() + static_cast<std::size_t>(row) * cloud.row_step +
              static_cast<std::size_t>(col) * cloud.point_step,
          cloud.point_step);
      CloudPoint& p = out[k++];
      p.x = static_cast<float>(read_point_field(point, *x.field, cloud.is_bigendian));
      p.y = static_cast<float>(read_point_field(point, *y.field, cloud.is_bigendian));
      p.z = static_cast<float>(read_point_field(point, *z.field, cloud.is_bigendian));
      p.intensity =
          intensity.field == nullptr
              ? 0.0f
              : static_cast<float>(read_point_field(point, *intensity.field, cloud.is_bigendian));
      p.time =
          time.field == nullptr ? 0.0 : read_point_field(point, *time.field, cloud.is_bigendian);
      if (ring.field == nullptr) {
        p.ring = static_cast<std::uint16_t>(std::min<std::uint32_t>(row, 0xFFFF));
      } else {
        const double r = read_point_field(point, *ring.field, cloud.is_bigendian);
        p.ring = r >= 0.0 && r <= 65535.0 ? static_cast<std::uint16_t>(r) : 0;  // NaN fails too
      }
    }
  }
}

}  // namespace livod::io::rosbag
