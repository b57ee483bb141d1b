#include "tools/eval/trajectory_io.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <system_error>

#include "core/error.hpp"

namespace livod::eval {
namespace {

// Largest trajectory file read (256 MiB: about two million TUM poses).
constexpr std::size_t kMaxTrajectoryBytes = std::size_t{256} << 20;
// Largest position coordinate accepted (m).
constexpr double kMaxCoordinateM = 1e7;

struct Field {
  std::string_view text;
  std::size_t offset = 0;  // byte offset of the field in the file
};

struct Line {
  std::string_view text;   // without the line terminator
  std::size_t number = 0;  // 1-based
  std::size_t offset = 0;  // byte offset of the first character
};

class LineParser {
 public:
  LineParser(std::string_view text, const std::string& source) : text_(text), source_(source) {}

  // Next line that is neither blank nor a '#' comment; false at the end of the text.
  bool next(Line& line) {
    while (pos_ < text_.size()) {
      const std::size_t end = std::min(text_.find('\n', pos_), text_.size());
      std::string_view content = text_.substr(pos_, end - pos_);
      if (!content.empty() && content.back() == '\r') content.remove_suffix(1);
      line = Line{content, ++line_number_, pos_};
      pos_ = end + 1;
      const std::size_t first = content.find_first_not_of(" \t");
      if (first == std::string_view::npos || content[first] == '#') continue;
      return true;
    }
    return false;
  }

  // Splits on any of `separators`; surrounding spaces and tabs are trimmed from each field, and
  // with whitespace separators runs of separators count once.
  void split(const Line& line, std::string_view separators, std::vector<Field>& fields) const {
    fields.clear();
    const bool whitespace = separators.find_first_not_of(" \t") == std::string_view::npos;
    std::size_t pos = 0;
    const std::string_view s = line.text;
    while (pos <= s.size()) {
      std::size_t end = s.find_first_of(separators, pos);
      if (end == std::string_view::npos) end = s.size();
      std::string_view f = s.substr(pos, end - pos);
      std::size_t lead = f.find_first_not_of(" \t");
      if (lead == std::string_view::npos) lead = f.size();
      const std::size_t last = f.find_last_not_of(" \t");
      f = lead < f.size() ? f.substr(lead, last - lead + 1) : std::string_view{};
      if (!(whitespace && f.empty())) fields.push_back(Field{f, line.offset + pos + lead});
      pos = end + 1;
    }
  }

  [[noreturn]] void fail(const Line& line, std::size_t offset, const std::string& message) const {
    throw FormatError(source_, offset, "line " + std::to_string(line.number) + ": " + message);
  }

  double number(const Line& line, const Field& field) const {
    std::string_view s = field.text;
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    double value = 0.0;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty() || !std::isfinite(value)) {
      fail(line, field.offset, "'" + std::string(field.text) + "' is not a finite number");
    }
    return value;
  }

  std::int64_t integer(const Line& line, const Field& field) const {
    std::int64_t value = 0;
    const std::string_view s = field.text;
    const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), value);
    if (ec != std::errc() || ptr != s.data() + s.size() || s.empty()) {
      fail(line, field.offset, "'" + std::string(field.text) + "' is not an integer");
    }
    return value;
  }

  void expect_count(const Line& line, const std::vector<Field>& fields, std::size_t expected,
                    std::string_view layout) const {
    if (fields.size() != expected) {
      fail(line, line.offset,
           "expected " + std::to_string(expected) + " values (" + std::string(layout) +
               "), found " + std::to_string(fields.size()));
    }
  }

  // Stamps may repeat (real ground-truth files do: TUM fr2_desk, EuRoC V1_02; evaluate() drops
  // the repeats and says so) but never go backwards: association and time deltas assume order.
  void check_monotonic(const Line& line, const Field& field, const std::vector<double>& stamps,
                       double t) const {
    if (!stamps.empty() && t < stamps.back()) {
      std::ostringstream msg;
      msg.precision(17);
      msg << "timestamp " << t << " is earlier than the previous one (" << stamps.back() << ")";
      fail(line, field.offset, msg.str());
    }
  }

  // A position in metres; beyond kMaxCoordinateM it is a unit or format mistake, and squaring it
  // in the metrics would overflow.
  void check_position(const Line& line, const Field& field, const Eigen::Vector3d& p) const {
    if (!(p.cwiseAbs().maxCoeff() <= kMaxCoordinateM)) {
      std::ostringstream msg;
      msg.precision(6);
      msg << "position (" << p.x() << ", " << p.y() << ", " << p.z()
          << ") is beyond 1e7 m: not a position in metres";
      fail(line, field.offset, msg.str());
    }
  }

 private:
  std::string_view text_;
  const std::string& source_;
  std::size_t pos_ = 0;
  std::size_t line_number_ = 0;
};

Eigen::Matrix3d rotation_from_quaternion(const LineParser& parser, const Line& line,
                                         const Field& first_field, double w, double x, double y,
                                         double z) {
  Eigen::Quaterniond q(w, x, y, z);
  const double norm = q.norm();
  // A zero quaternion has no direction; anything else is normalised (files keep 6-9 digits).
  if (!(norm > 1e-6)) parser.fail(line, first_field.offset, "quaternion has (near) zero norm");
  q.coeffs() /= norm;
  return q.toRotationMatrix();
}

// Reads a trajectory text file, at most kMaxTrajectoryBytes (a device such as /dev/zero or a
// binary file is refused after its first block instead of being read until memory runs out).
std::string read_file(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open '" + path.string() + "'");
  std::string text;
  std::array<char, 1 << 16> block{};
  while (in) {
    in.read(block.data(), static_cast<std::streamsize>(block.size()));
    const auto n = static_cast<std::size_t>(in.gcount());
    if (std::memchr(block.data(), '\0', n) != nullptr) {
      throw Error("'" + path.string() + "' is not a text file (it contains NUL bytes near byte " +
                  std::to_string(text.size()) + ")");
    }
    text.append(block.data(), n);
    if (text.size() > kMaxTrajectoryBytes) {
      throw Error("'" + path.string() + "' is larger than " +
                  std::to_string(kMaxTrajectoryBytes >> 20) +
                  " MiB: not a trajectory (stopped reading there)");
    }
  }
  if (in.bad()) throw Error("cannot read '" + path.string() + "'");
  return text;
}

}  // namespace

std::optional<TrajectoryFormat> parse_trajectory_format(std::string_view name) {
  if (name == "tum") return TrajectoryFormat::kTum;
  if (name == "kitti") return TrajectoryFormat::kKitti;
  if (name == "euroc") return TrajectoryFormat::kEuroc;
  return std::nullopt;
}

std::string_view to_string(TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return "tum";
    case TrajectoryFormat::kKitti:
      return "kitti";
    case TrajectoryFormat::kEuroc:
      return "euroc";
  }
  return "?";
}

Trajectory parse_tum(std::string_view text, const std::string& source) {
  LineParser parser(text, source);
  Trajectory traj;
  std::vector<Field> f;
  Line line;
  while (parser.next(line)) {
    parser.split(line, " \t", f);
    parser.expect_count(line, f, 8, "timestamp tx ty tz qx qy qz qw");
    double v[8];
    for (std::size_t i = 0; i < 8; ++i) v[i] = parser.number(line, f[i]);
    parser.check_monotonic(line, f[0], traj.stamps_s, v[0]);
    traj.stamps_s.push_back(v[0]);
    parser.check_position(line, f[1], Eigen::Vector3d(v[1], v[2], v[3]));
    traj.poses.emplace_back(rotation_from_quaternion(parser, line, f[4], v[7], v[4], v[5], v[6]),
                            Eigen::Vector3d(v[1], v[2], v[3]));
  }
  return traj;
}

Trajectory parse_kitti(std::string_view text, const std::string& source) {
  LineParser parser(text, source);
  Trajectory traj;
  std::vector<Field> f;
  Line line;
  while (parser.next(line)) {
    parser.split(line, " \t", f);
    parser.expect_count(line, f, 12, "r11 r12 r13 tx r21 r22 r23 ty r31 r32 r33 tz");
    Eigen::Matrix<double, 3, 4> m;
    for (std::size_t i = 0; i < 12; ++i) {
      m(static_cast<Eigen::Index>(i / 4), static_cast<Eigen::Index>(i % 4)) =
          parser.number(line, f[i]);
    }
    parser.check_position(line, f[3], m.col(3));
    traj.poses.push_back(RigidTransform3d::from_matrix(m));
  }
  return traj;
}

std::vector<double> parse_times(std::string_view text, const std::string& source) {
  LineParser parser(text, source);
  std::vector<double> times;
  std::vector<Field> f;
  Line line;
  while (parser.next(line)) {
    parser.split(line, " \t", f);
    parser.expect_count(line, f, 1, "time in seconds");
    const double t = parser.number(line, f[0]);
    parser.check_monotonic(line, f[0], times, t);
    times.push_back(t);
  }
  return times;
}

Trajectory parse_euroc_csv(std::string_view text, const std::string& source) {
  LineParser parser(text, source);
  Trajectory traj;
  std::vector<Field> f;
  Line line;
  while (parser.next(line)) {
    parser.split(line, ",", f);
    if (f.size() < 8) {
      parser.fail(line, line.offset,
                  "expected at least 8 comma-separated values (timestamp_ns, p_x, p_y, p_z, "
                  "q_w, q_x, q_y, q_z), found " +
                      std::to_string(f.size()));
    }
    const std::int64_t stamp_ns = parser.integer(line, f[0]);
    double v[7];
    for (std::size_t i = 0; i < 7; ++i) v[i] = parser.number(line, f[i + 1]);
    const double t = static_cast<double>(stamp_ns) * 1e-9;
    parser.check_monotonic(line, f[0], traj.stamps_s, t);
    traj.stamps_s.push_back(t);
    parser.check_position(line, f[1], Eigen::Vector3d(v[0], v[1], v[2]));
    traj.poses.emplace_back(rotation_from_quaternion(parser, line, f[4], v[3], v[4], v[5], v[6]),
                            Eigen::Vector3d(v[0], v[1], v[2]));
  }
  return traj;
}

Trajectory read_tum(const std::filesystem::path& path) {
  return parse_tum(read_file(path), path.string());
}

Trajectory read_euroc_csv(const std::filesystem::path& path) {
  return parse_euroc_csv(read_file(path), path.string());
}

Trajectory read_kitti(const std::filesystem::path& path,
                      const std::optional<std::filesystem::path>& times) {
  Trajectory traj = parse_kitti(read_file(path), path.string());
  if (times) {
    std::vector<double> stamps = parse_times(read_file(*times), times->string());
    if (stamps.size() != traj.size()) {
      throw Error("'" + times->string() + "' has " + std::to_string(stamps.size()) +
                  " times but '" + path.string() + "' has " + std::to_string(traj.size()) +
                  " poses");
    }
    traj.stamps_s = std::move(stamps);
  }
  return traj;
}

}  // namespace livod::eval
