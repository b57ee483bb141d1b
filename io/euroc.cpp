#include "io/euroc.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>
#include <system_error>
#include <utility>

#include "core/error.hpp"
#include "core/text.hpp"

namespace livod::io {
namespace {

// Sensor yaml files are a few hundred bytes; anything much larger is not one.
constexpr std::uintmax_t kMaxYamlBytes = 1 << 20;
// Fields of a ground-truth row: EuRoC has 17 (time, p, q, v, b_w, b_a); allow a few more.
constexpr std::size_t kMaxGroundtruthColumns = 32;
// T_BS must be a rigid transform; calibration files print ~6-12 digits.
constexpr double kRotationTolerance = 1e-3;
constexpr double kQuaternionNormTolerance = 1e-3;
// Seconds in a TUM time stamp are capped so that the value in ns fits an int64 (year 2255).
constexpr std::int64_t kMaxTumSeconds = 9'000'000'000;
constexpr std::int64_t kNanosecondsPerSecond = 1'000'000'000;
constexpr int kMaxImageSide = 1 << 16;

std::string read_file_text(const std::filesystem::path& path, std::uintmax_t max_bytes) {
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (ec) throw Error(path.string() + ": cannot read: " + ec.message());
  if (size > max_bytes) {
    throw Error(path.string() + ": " + std::to_string(size) + " bytes is more than the " +
                std::to_string(max_bytes) + " allowed for this kind of file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path.string() + ": cannot open");
  std::string text(static_cast<std::size_t>(size), '\0');
  in.read(text.data(), static_cast<std::streamsize>(size));
  if (static_cast<std::uintmax_t>(in.gcount()) != size) {
    throw Error(path.string() + ": read error (file changed while reading?)");
  }
  return text;
}

std::string read_csv_text(const std::filesystem::path& path) {
  // Text files are read whole; the limit only guards against pointing the reader at a device or
  // a huge unrelated file by mistake.
  constexpr std::uintmax_t kMaxCsvBytes = std::uintmax_t{4} << 30;
  return read_file_text(path, kMaxCsvBytes);
}

bool is_blank(char c) {
  return c == ' ' || c == '\t' || c == '\r';
}

struct Field {
  std::string_view text;
  std::uint64_t offset = 0;  // byte offset in the file
};

struct Line {
  std::string_view text;  // without the line break
  std::uint64_t number = 0;
  std::uint64_t offset = 0;
};

// Splits text into lines, skipping blank lines and '#' comments (EuRoC's header line is one).
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}

  bool next(Line& line) {
    while (position_ < text_.size()) {
      const std::size_t end = std::min(text_.find('\n', position_), text_.size());
      line.text = text_.substr(position_, end - position_);
      line.offset = position_;
      line.number = ++number_;
      position_ = end + 1;
      const std::string_view content = trim_whitespace(line.text);
      if (content.empty() || content.front() == '#') continue;
      return true;
    }
    return false;
  }

 private:
  std::string_view text_;
  std::size_t position_ = 0;
  std::uint64_t number_ = 0;
};

[[noreturn]] void fail_at(const std::string& source, const Line& line, std::uint64_t offset,
                          const std::string& message) {
  throw FormatError(source + ":" + std::to_string(line.number), offset, message);
}

// Splits a row at `delimiter` (or at runs of blanks when delimiter is ' '), trimming each field.
// At most max_fields fields are accepted; a longer row is an error, so a pathological row cannot
// grow the field list without bound.
void split_row(const std::string& source, const Line& line, char delimiter, std::size_t max_fields,
               std::vector<Field>& fields) {
  fields.clear();
  const std::string_view text = line.text;
  std::size_t i = 0;
  auto push = [&](std::size_t begin, std::size_t end) {
    if (fields.size() == max_fields) {
      fail_at(source, line, line.offset + begin,
              "too many columns (at most " + std::to_string(max_fields) + " expected)");
    }
    std::string_view raw = text.substr(begin, end - begin);
    std::size_t lead = 0;
    while (lead < raw.size() && is_blank(raw[lead])) ++lead;
    fields.push_back(Field{trim_whitespace(raw), line.offset + begin + lead});
  };
  if (delimiter == ' ') {
    while (i < text.size()) {
      while (i < text.size() && is_blank(text[i])) ++i;
      if (i == text.size()) break;
      const std::size_t begin = i;
      while (i < text.size() && !is_blank(text[i])) ++i;
      push(begin, i);
    }
    return;
  }
  std::size_t begin = 0;
  for (; i <= text.size(); ++i) {
    if (i == text.size() || text[i] == delimiter) {
      push(begin, i);
      begin = i + 1;
    }
  }
}

std::int64_t parse_int(const std::string& source, const Line& line, const Field& field,
                       const char* what) {
  std::int64_t value = 0;
  const char* first = field.text.data();
  const char* last = first + field.text.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (field.text.empty() || ec != std::errc() || ptr != last) {
    fail_at(source, line, field.offset,
            std::string(what) + ": '" + std::string(field.text) + "' is not an integer");
  }
  return value;
}

std::optional<double> to_double(std::string_view text) {
  double value = 0.0;
  const char* first = text.data();
  const char* last = first + text.size();
  const auto [ptr, ec] = std::from_chars(first, last, value);
  if (text.empty() || ec != std::errc() || ptr != last || !std::isfinite(value)) {
    return std::nullopt;
  }
  return value;
}

double parse_double(const std::string& source, const Line& line, const Field& field,
                    const char* what) {
  const auto value = to_double(field.text);
  if (!value) {
    fail_at(source, line, field.offset,
            std::string(what) + ": '" + std::string(field.text) + "' is not a finite number");
  }
  return *value;
}

// Decimal seconds to ns without going through a double, so that "1403715274.30214" becomes
// exactly 1403715274302140000 (a double only holds ~16 digits). Exponent forms fall back to
// double arithmetic.
std::optional<std::int64_t> seconds_text_to_ns(std::string_view text) {
  if (text.find_first_of("eE") != std::string_view::npos) {
    const auto seconds = to_double(text);
    if (!seconds || std::fabs(*seconds) > static_cast<double>(kMaxTumSeconds)) return std::nullopt;
    return static_cast<std::int64_t>(std::llround(*seconds * 1e9));
  }
  std::size_t i = 0;
  const bool negative = !text.empty() && text[0] == '-';
  if (negative) ++i;
  std::int64_t seconds = 0;
  std::size_t digits = 0;
  for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++digits) {
    seconds = seconds * 10 + (text[i] - '0');
    if (seconds > kMaxTumSeconds) return std::nullopt;
  }
  std::int64_t fraction = 0;
  int fraction_digits = 0;
  bool round_up = false;
  if (i < text.size() && text[i] == '.') {
    ++i;
    for (; i < text.size() && text[i] >= '0' && text[i] <= '9'; ++i, ++digits) {
      if (fraction_digits < 9) {
        fraction = fraction * 10 + (text[i] - '0');
        ++fraction_digits;
      } else if (fraction_digits == 9) {
        round_up = text[i] >= '5';  // round half up on the first dropped digit
        ++fraction_digits;
      }
    }
  }
  if (i != text.size() || digits == 0) return std::nullopt;
  for (; fraction_digits < 9; ++fraction_digits) fraction *= 10;
  const std::int64_t ns = seconds * kNanosecondsPerSecond + fraction + (round_up ? 1 : 0);
  return negative ? -ns : ns;
}

void require_columns(const std::string& source, const Line& line, const std::vector<Field>& fields,
                     std::size_t expected, const char* layout) {
  if (fields.size() != expected) {
    fail_at(source, line, line.offset,
            "expected " + std::to_string(expected) + " columns (" + layout + "), got " +
                std::to_string(fields.size()));
  }
}

void require_increasing(const std::string& source, const Line& line, const Field& field,
                        std::optional<std::int64_t> previous, std::int64_t current) {
  if (previous && current <= *previous) {
    fail_at(source, line, field.offset,
            "timestamp " + std::to_string(current) + " does not increase (previous " +
                std::to_string(*previous) + ")");
  }
}

Eigen::Quaterniond checked_quaternion(const std::string& source, const Line& line,
                                      const Field& field, double w, double x, double y, double z) {
  Eigen::Quaterniond q(w, x, y, z);
  if (std::fabs(q.norm() - 1.0) > kQuaternionNormTolerance) {
    fail_at(source, line, field.offset,
            "quaternion norm " + std::to_string(q.norm()) + " is not 1");
  }
  q.normalize();
  return q;
}

// ---- yaml -------------------------------------------------------------------------------------

class YamlFile {
 public:
  YamlFile(std::string_view text, std::string source) : source_(std::move(source)) {
    try {
      root_ = YAML::Load(std::string(text));
    } catch (const YAML::Exception& e) {
      fail(e.mark, "yaml syntax error: " + e.msg);
    }
    if (!root_.IsMap()) fail(root_.Mark(), "top level is not a mapping");
  }

  [[noreturn]] void fail(const YAML::Mark& mark, const std::string& message) const {
    const bool known = !mark.is_null() && mark.pos >= 0;
    throw FormatError(source_ + ":" + std::to_string(known ? mark.line + 1 : 1),
                      known ? static_cast<std::uint64_t>(mark.pos) : 0, message);
  }

  [[nodiscard]] bool has(const char* key) const { return static_cast<bool>(root_[key]); }

  [[nodiscard]] YAML::Node node(const YAML::Node& parent, const char* key) const {
    const YAML::Node child = parent[key];
    if (!child) fail(parent.Mark(), std::string("missing key '") + key + "'");
    return child;
  }
  [[nodiscard]] YAML::Node node(const char* key) const { return node(root_, key); }

  [[nodiscard]] std::string string(const YAML::Node& n, const char* key) const {
    if (!n.IsScalar()) fail(n.Mark(), std::string("'") + key + "' is not a scalar");
    return n.Scalar();
  }

  [[nodiscard]] double number(const YAML::Node& n, const char* key) const {
    const auto value = to_double(trim_whitespace(string(n, key)));
    if (!value) fail(n.Mark(), std::string("'") + key + "' is not a finite number");
    return *value;
  }
  [[nodiscard]] double number(const char* key) const { return number(node(key), key); }

  [[nodiscard]] double positive(const char* key) const {
    const double value = number(key);
    if (value <= 0.0) fail(node(key).Mark(), std::string("'") + key + "' must be > 0");
    return value;
  }
  [[nodiscard]] double non_negative(const char* key) const {
    const double value = number(key);
    if (value < 0.0) fail(node(key).Mark(), std::string("'") + key + "' must be >= 0");
    return value;
  }

  [[nodiscard]] std::vector<double> numbers(const YAML::Node& n, const char* key,
                                            std::size_t min_count, std::size_t max_count) const {
    if (!n.IsSequence()) fail(n.Mark(), std::string("'") + key + "' is not a list");
    if (n.size() < min_count || n.size() > max_count) {
      fail(n.Mark(), std::string("'") + key + "' has " + std::to_string(n.size()) +
                         " entries, expected " +
                         (min_count == max_count
                              ? std::to_string(min_count)
                              : std::to_string(min_count) + " to " + std::to_string(max_count)));
    }
    std::vector<double> values;
    values.reserve(n.size());
    for (const auto& element : n) values.push_back(number(element, key));
    return values;
  }

  // T_BS: {rows: 4, cols: 4, data: [16 numbers, row-major]}, checked to be a rigid transform.
  [[nodiscard]] Eigen::Matrix4d transform(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsMap()) fail(n.Mark(), std::string("'") + key + "' is not a mapping");
    if (number(node(n, "rows"), "rows") != 4.0 || number(node(n, "cols"), "cols") != 4.0) {
      fail(n.Mark(), std::string("'") + key + "' must have rows: 4 and cols: 4");
    }
    const YAML::Node data = node(n, "data");
    const std::vector<double> values = numbers(data, "data", 16, 16);
    Eigen::Matrix4d T;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) T(r, c) = values[static_cast<std::size_t>(r * 4 + c)];
    }
    const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
    const double orthogonality =
        (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
    const bool last_row_ok = T.row(3).isApprox(Eigen::RowVector4d(0, 0, 0, 1), 1e-9);
    if (!last_row_ok || orthogonality > kRotationTolerance || R.determinant() <= 0.0) {
      fail(data.Mark(), std::string("'") + key +
                            "' is not a rigid transform (rotation not orthonormal with det +1, "
                            "or last row not 0 0 0 1)");
    }
    return T;
  }

 private:
  std::string source_;
  YAML::Node root_;
};

// Runs a yaml parse, turning any yaml-cpp exception raised while walking the tree into a
// FormatError (our own checks already throw FormatError).
template <class F>
auto with_yaml_errors(const std::string& source, F&& parse) {
  try {
    return parse();
  } catch (const YAML::Exception& e) {
    const bool known = !e.mark.is_null() && e.mark.pos >= 0;
    throw FormatError(source + ":" + std::to_string(known ? e.mark.line + 1 : 1),
                      known ? static_cast<std::uint64_t>(e.mark.pos) : 0, e.msg);
  }
}

}  // namespace

// ---- csv parsers ------------------------------------------------------------------------------

std::vector<EurocImageRecord> parse_euroc_camera_csv(std::string_view text,
                                                     const std::string& source,
                                                     const std::filesystem::path& image_dir) {
  std::vector<EurocImageRecord> records;
  std::vector<Field> fields;
  LineReader lines(text);
  Line line;
  std::optional<std::int64_t> previous;
  std::size_t columns = 0;  // 2 (plain EuRoC) or 3 (with exposure_ns), fixed by the first row
  while (lines.next(line)) {
    split_row(source, line, ',', 3, fields);
    if (columns == 0) {
      if (fields.size() < 2) {
        fail_at(source, line, line.offset,
                "expected 2 columns (timestamp [ns],filename) or 3 (...,exposure_ns), got " +
                    std::to_string(fields.size()));
      }
      columns = fields.size();
    }
    require_columns(
        source, line, fields, columns,
        columns == 2 ? "timestamp [ns],filename" : "timestamp [ns],filename,exposure_ns");
    EurocImageRecord record;
    const std::int64_t t = parse_int(source, line, fields[0], "timestamp [ns]");
    require_increasing(source, line, fields[0], previous, t);
    previous = t;
    record.timestamp = SensorTime(t);
    const std::string_view name = fields[1].text;
    if (name.empty() || name.front() == '/' || name.find('\0') != std::string_view::npos) {
      fail_at(source, line, fields[1].offset,
              "filename must be a non-empty path relative to the data folder");
    }
    record.path = image_dir / std::string(name);
    if (columns == 3) {
      const std::int64_t exposure = parse_int(source, line, fields[2], "exposure_ns");
      if (exposure < 0) fail_at(source, line, fields[2].offset, "exposure_ns must be >= 0");
      record.exposure = Nanoseconds(exposure);
    }
    records.push_back(std::move(record));
  }
  return records;
}

std::vector<EurocImuRecord> parse_euroc_imu_csv(std::string_view text, const std::string& source) {
  std::vector<EurocImuRecord> records;
  std::vector<Field> fields;
  LineReader lines(text);
  Line line;
  std::optional<std::int64_t> previous;
  static constexpr const char* kNames[] = {"timestamp [ns]", "w_RS_S_x", "w_RS_S_y", "w_RS_S_z",
                                           "a_RS_S_x",       "a_RS_S_y", "a_RS_S_z"};
  while (lines.next(line)) {
    split_row(source, line, ',', 7, fields);
    require_columns(source, line, fields, 7, "timestamp [ns],w_RS_S xyz,a_RS_S xyz");
    EurocImuRecord record;
    const std::int64_t t = parse_int(source, line, fields[0], kNames[0]);
    require_increasing(source, line, fields[0], previous, t);
    previous = t;
    record.timestamp = SensorTime(t);
    for (int i = 0; i < 3; ++i) {
      const auto gi = static_cast<std::size_t>(1 + i);
      const auto ai = static_cast<std::size_t>(4 + i);
      record.gyro_rad_s[i] = parse_double(source, line, fields[gi], kNames[gi]);
      record.accel_m_s2[i] = parse_double(source, line, fields[ai], kNames[ai]);
    }
    records.push_back(record);
  }
  return records;
}

std::vector<TrajectoryPose> parse_euroc_groundtruth_csv(std::string_view text,
                                                        const std::string& source) {
  std::vector<TrajectoryPose> poses;
  std::vector<Field> fields;
  LineReader lines(text);
  Line line;
  std::optional<std::int64_t> previous;
  static constexpr const char* kNames[] = {"timestamp [ns]", "p_RS_R_x", "p_RS_R_y", "p_RS_R_z",
                                           "q_RS_w",         "q_RS_x",   "q_RS_y",   "q_RS_z"};
  while (lines.next(line)) {
    split_row(source, line, ',', kMaxGroundtruthColumns, fields);
    if (fields.size() < 8) {
      fail_at(source, line, line.offset,
              "expected at least 8 columns (timestamp [ns],p_RS_R xyz,q_RS wxyz), got " +
                  std::to_string(fields.size()));
    }
    TrajectoryPose pose;
    const std::int64_t t = parse_int(source, line, fields[0], kNames[0]);
    require_increasing(source, line, fields[0], previous, t);
    previous = t;
    pose.timestamp = SensorTime(t);
    double v[8] = {};
    for (std::size_t i = 1; i < 8; ++i) v[i] = parse_double(source, line, fields[i], kNames[i]);
    pose.p_world_body = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.q_world_body = checked_quaternion(source, line, fields[4], v[4], v[5], v[6], v[7]);
    poses.push_back(pose);
  }
  return poses;
}

std::vector<TrajectoryPose> parse_tum_trajectory(std::string_view text, const std::string& source) {
  std::vector<TrajectoryPose> poses;
  std::vector<Field> fields;
  LineReader lines(text);
  Line line;
  std::optional<std::int64_t> previous;
  static constexpr const char* kNames[] = {
      "timestamp [s]", "tx", "ty", "tz", "qx", "qy", "qz", "qw"};
  while (lines.next(line)) {
    split_row(source, line, ' ', 8, fields);
    require_columns(source, line, fields, 8, "timestamp tx ty tz qx qy qz qw");
    TrajectoryPose pose;
    const auto t = seconds_text_to_ns(fields[0].text);
    if (!t) {
      fail_at(source, line, fields[0].offset,
              "timestamp [s]: '" + std::string(fields[0].text) + "' is not a time in seconds");
    }
    require_increasing(source, line, fields[0], previous, *t);
    previous = t;
    pose.timestamp = SensorTime(*t);
    double v[8] = {};
    for (std::size_t i = 1; i < 8; ++i) v[i] = parse_double(source, line, fields[i], kNames[i]);
    pose.p_world_body = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.q_world_body = checked_quaternion(source, line, fields[4], v[7], v[4], v[5], v[6]);
    poses.push_back(pose);
  }
  return poses;
}

// ---- yaml parsers -----------------------------------------------------------------------------

EurocCameraCalibration parse_euroc_camera_yaml(std::string_view text, const std::string& source) {
  return with_yaml_errors(source, [&] {
    const YamlFile yaml(text, source);
    EurocCameraCalibration calibration;
    calibration.T_body_sensor = yaml.transform("T_BS");
    calibration.rate_hz = yaml.positive("rate_hz");

    const YAML::Node resolution = yaml.node("resolution");
    const std::vector<double> size = yaml.numbers(resolution, "resolution", 2, 2);
    for (const double side : size) {
      if (side < 1.0 || side > kMaxImageSide || side != std::floor(side)) {
        yaml.fail(resolution.Mark(), "'resolution' must be two positive integers [width, height]");
      }
    }
    calibration.width = static_cast<int>(size[0]);
    calibration.height = static_cast<int>(size[1]);

    const YAML::Node model = yaml.node("camera_model");
    if (yaml.string(model, "camera_model") != "pinhole") {
      yaml.fail(model.Mark(), "camera_model '" + model.Scalar() + "' is not supported (pinhole)");
    }
    const YAML::Node intrinsics = yaml.node("intrinsics");
    const std::vector<double> k = yaml.numbers(intrinsics, "intrinsics", 4, 4);
    if (k[0] <= 0.0 || k[1] <= 0.0) {
      yaml.fail(intrinsics.Mark(), "'intrinsics' [fu, fv, cu, cv] need fu > 0 and fv > 0");
    }
    std::copy(k.begin(), k.end(), calibration.intrinsics.begin());

    const YAML::Node distortion = yaml.node("distortion_model");
    const std::string distortion_name = yaml.string(distortion, "distortion_model");
    std::size_t min_coefficients = 0;
    std::size_t max_coefficients = 0;
    if (distortion_name == "radial-tangential" || distortion_name == "radtan") {
      calibration.distortion_model = EurocDistortionModel::kRadialTangential;
      min_coefficients = 4;
      max_coefficients = 5;
    } else if (distortion_name == "equidistant") {
      calibration.distortion_model = EurocDistortionModel::kEquidistant;
      min_coefficients = max_coefficients = 4;
    } else if (distortion_name == "none") {
      calibration.distortion_model = EurocDistortionModel::kNone;
    } else {
      yaml.fail(distortion.Mark(), "distortion_model '" + distortion_name +
                                       "' is not one of radial-tangential, equidistant, none");
    }
    if (max_coefficients > 0 || yaml.has("distortion_coefficients")) {
      calibration.distortion_coefficients =
          yaml.numbers(yaml.node("distortion_coefficients"), "distortion_coefficients",
                       min_coefficients, max_coefficients);
    }
    return calibration;
  });
}

EurocImuCalibration parse_euroc_imu_yaml(std::string_view text, const std::string& source) {
  return with_yaml_errors(source, [&] {
    const YamlFile yaml(text, source);
    EurocImuCalibration calibration;
    calibration.T_body_sensor = yaml.transform("T_BS");
    calibration.rate_hz = yaml.positive("rate_hz");
    calibration.gyroscope_noise_density = yaml.non_negative("gyroscope_noise_density");
    calibration.gyroscope_random_walk = yaml.non_negative("gyroscope_random_walk");
    calibration.accelerometer_noise_density = yaml.non_negative("accelerometer_noise_density");
    calibration.accelerometer_random_walk = yaml.non_negative("accelerometer_random_walk");
    return calibration;
  });
}

// ---- file readers -----------------------------------------------------------------------------

std::vector<EurocImageRecord> read_euroc_camera_csv(const std::filesystem::path& csv) {
  return parse_euroc_camera_csv(read_csv_text(csv), csv.string(), csv.parent_path() / "data");
}

std::vector<EurocImuRecord> read_euroc_imu_csv(const std::filesystem::path& csv) {
  return parse_euroc_imu_csv(read_csv_text(csv), csv.string());
}

std::vector<TrajectoryPose> read_euroc_groundtruth_csv(const std::filesystem::path& csv) {
  return parse_euroc_groundtruth_csv(read_csv_text(csv), csv.string());
}

std::vector<TrajectoryPose> read_tum_trajectory(const std::filesystem::path& path) {
  return parse_tum_trajectory(read_csv_text(path), path.string());
}

EurocCameraCalibration read_euroc_camera_yaml(const std::filesystem::path& yaml) {
  return parse_euroc_camera_yaml(read_file_text(yaml, kMaxYamlBytes), yaml.string());
}

EurocImuCalibration read_euroc_imu_yaml(const std::filesystem::path& yaml) {
  return parse_euroc_imu_yaml(read_file_text(yaml, kMaxYamlBytes), yaml.string());
}

// ---- folder -----------------------------------------------------------------------------------

namespace {

std::vector<std::string> sensor_folders(const std::filesystem::path& mav0,
                                        std::string_view prefix) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(mav0, ec)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_directory() && name.size() > prefix.size() && name.starts_with(prefix) &&
        std::all_of(name.begin() + static_cast<std::ptrdiff_t>(prefix.size()), name.end(),
                    [](char c) { return c >= '0' && c <= '9'; })) {
      names.push_back(name);
    }
  }
  std::sort(names.begin(), names.end());
  return names;
}

}  // namespace

EurocFolder::EurocFolder(const std::filesystem::path& root) {
  if (root.filename() == "mav0" && std::filesystem::is_directory(root)) {
    mav0_ = root;
  } else if (std::filesystem::is_directory(root / "mav0")) {
    mav0_ = root / "mav0";
  } else {
    throw Error(root.string() + ": not an EuRoC/ASL dataset folder (no mav0/ inside)");
  }
}

std::vector<std::string> EurocFolder::cameras() const {
  return sensor_folders(mav0_, "cam");
}
std::vector<std::string> EurocFolder::imus() const {
  return sensor_folders(mav0_, "imu");
}

std::vector<EurocImageRecord> EurocFolder::images(std::string_view camera) const {
  return read_euroc_camera_csv(mav0_ / std::string(camera) / "data.csv");
}

EurocCameraCalibration EurocFolder::camera_calibration(std::string_view camera) const {
  return read_euroc_camera_yaml(mav0_ / std::string(camera) / "sensor.yaml");
}

std::vector<EurocImuRecord> EurocFolder::imu(std::string_view imu) const {
  return read_euroc_imu_csv(mav0_ / std::string(imu) / "data.csv");
}

EurocImuCalibration EurocFolder::imu_calibration(std::string_view imu) const {
  return read_euroc_imu_yaml(mav0_ / std::string(imu) / "sensor.yaml");
}

std::optional<std::vector<TrajectoryPose>> EurocFolder::groundtruth() const {
  const auto csv = mav0_ / "state_groundtruth_estimate0" / "data.csv";
  if (!std::filesystem::exists(csv)) return std::nullopt;
  return read_euroc_groundtruth_csv(csv);
}

}  // namespace livod::io
