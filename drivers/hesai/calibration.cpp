#include "drivers/hesai/calibration.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <numeric>
#include <sstream>

#include "core/error.hpp"
#include "core/text.hpp"

namespace livod::drivers::hesai {
namespace {

constexpr double kMaxElevationDeg = 85.0;
constexpr double kMaxAzimuthOffsetDeg = 30.0;

std::vector<std::string_view> split(std::string_view line) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  for (std::size_t i = 0; i <= line.size(); ++i) {
    if (i == line.size() || line[i] == ',') {
      out.push_back(trim_whitespace(line.substr(start, i - start)));
      start = i + 1;
    }
  }
  return out;
}

bool parse_double(std::string_view s, double& out) {
  if (s.empty()) return false;
  // std::from_chars for double is available in GCC 11+; accept a leading '+'.
  if (s.front() == '+') s.remove_prefix(1);
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return r.ec == std::errc() && r.ptr == s.data() + s.size() && std::isfinite(out);
}

bool parse_int(std::string_view s, int& out) {
  const auto r = std::from_chars(s.data(), s.data() + s.size(), out);
  return !s.empty() && r.ec == std::errc() && r.ptr == s.data() + s.size();
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (auto& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

}  // namespace

std::vector<std::uint16_t> AngleCorrections::rings() const {
  std::vector<std::size_t> order(channels.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [this](std::size_t a, std::size_t b) {
    return channels[a].elevation_deg < channels[b].elevation_deg;
  });
  std::vector<std::uint16_t> ring(channels.size());
  for (std::size_t rank = 0; rank < order.size(); ++rank) {
    ring[order[rank]] = static_cast<std::uint16_t>(rank);
  }
  return ring;
}

AngleCorrections parse_angle_corrections(std::string_view text, const std::string& source) {
  AngleCorrections out;
  out.source = source;
  bool header_seen = false;
  std::size_t offset = 0;
  if (text.substr(0, 3) == "\xEF\xBB\xBF") offset = 3;  // UTF-8 byte order mark
  while (offset < text.size()) {
    const std::size_t end = std::min(text.find('\n', offset), text.size());
    const std::string_view line = trim_whitespace(text.substr(offset, end - offset));
    const std::size_t line_offset = offset;
    offset = end + 1;
    if (line.empty()) continue;
    const auto fields = split(line);
    if (!header_seen) {
      // "Channel,Elevation,Azimuth" (XT series) or "Laser id,Elevation,Azimuth" (Pandar40P).
      if (fields.size() < 3 || lower(fields[1]) != "elevation" || lower(fields[2]) != "azimuth") {
        throw FormatError(source, line_offset,
                          "not a Hesai angle correction file (expected a header "
                          "'Channel,Elevation,Azimuth')");
      }
      header_seen = true;
      continue;
    }
    int channel = 0;
    ChannelCorrection c;
    if (fields.size() < 3 || !parse_int(fields[0], channel) ||
        !parse_double(fields[1], c.elevation_deg) || !parse_double(fields[2], c.azimuth_deg)) {
      throw FormatError(
          source, line_offset,
          "expected 'channel,elevation,azimuth' with numbers, got '" + std::string(line) + "'");
    }
    if (channel != static_cast<int>(out.channels.size()) + 1) {
      throw FormatError(source, line_offset,
                        "channel " + std::to_string(channel) + " out of sequence (expected " +
                            std::to_string(out.channels.size() + 1) + ")");
    }
    if (std::abs(c.elevation_deg) > kMaxElevationDeg ||
        std::abs(c.azimuth_deg) > kMaxAzimuthOffsetDeg) {
      throw FormatError(source, line_offset,
                        "channel " + std::to_string(channel) + " has an impossible angle");
    }
    out.channels.push_back(c);
  }
  if (!header_seen || out.channels.empty()) {
    throw FormatError(source, text.size(), "no channels in the angle correction file");
  }
  return out;
}

AngleCorrections load_angle_corrections(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error("cannot open angle correction file " + path.string());
  std::ostringstream buffer;
  buffer << in.rdbuf();
  return parse_angle_corrections(buffer.str(), path.string());
}

void check_corrections_match(const AngleCorrections& corrections, Model model) {
  const ModelTraits& t = traits(model);
  if (static_cast<int>(corrections.channels.size()) != t.channels) {
    throw Error(corrections.source + ": " + std::to_string(corrections.channels.size()) +
                " channels, the " + std::string(t.name) + " has " + std::to_string(t.channels));
  }
}

std::string format_angle_corrections(const AngleCorrections& corrections) {
  std::string out = "Channel,Elevation,Azimuth\n";
  char line[96];
  for (std::size_t i = 0; i < corrections.channels.size(); ++i) {
    const int n =
        std::snprintf(line, sizeof line, "%zu,%.6f,%.6f\n", i + 1,
                      corrections.channels[i].elevation_deg, corrections.channels[i].azimuth_deg);
    out.append(line, static_cast<std::size_t>(n));
  }
  return out;
}

}  // namespace livod::drivers::hesai
