#include "drivers/velodyne/nmea.hpp"

#include <array>
#include <charconv>
#include <chrono>

namespace livod::drivers::velodyne {
namespace {

constexpr std::size_t kRmcMinFields = 10;  // $--RMC .. date
constexpr std::size_t kMaxFields = 16;

std::optional<int> digits(std::string_view s, std::size_t pos, std::size_t count) {
  if (pos + count > s.size()) return std::nullopt;
  int v = 0;
  for (std::size_t i = pos; i < pos + count; ++i) {
    if (s[i] < '0' || s[i] > '9') return std::nullopt;
    v = v * 10 + (s[i] - '0');
  }
  return v;
}

std::optional<double> number(std::string_view s) {
  if (s.empty()) return std::nullopt;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc{} || end != s.data() + s.size()) return std::nullopt;
  return v;
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

// "ddmm.mmmm" (or "dddmm.mmmm") with hemisphere letter -> signed degrees.
std::optional<double> coordinate(std::string_view value, std::string_view hemisphere,
                                 std::size_t degree_digits, char negative) {
  if (value.size() < degree_digits + 2 || hemisphere.size() != 1) return std::nullopt;
  const auto degrees = digits(value, 0, degree_digits);
  const auto minutes = number(value.substr(degree_digits));
  if (!degrees || !minutes || *minutes < 0.0 || *minutes >= 60.0) return std::nullopt;
  const double deg = *degrees + *minutes / 60.0;
  return hemisphere[0] == negative ? -deg : deg;
}

}  // namespace

std::optional<RmcFix> parse_rmc(std::string_view sentence) {
  // Strip trailing CR/LF/NUL.
  while (!sentence.empty() &&
         (sentence.back() == '\r' || sentence.back() == '\n' || sentence.back() == '\0')) {
    sentence.remove_suffix(1);
  }
  if (sentence.size() < 7 || sentence[0] != '$' || sentence.substr(3, 4) != "RMC,") {
    return std::nullopt;
  }
  std::string_view body = sentence.substr(1);
  if (const auto star = body.find('*'); star != std::string_view::npos) {
    if (star + 3 != body.size()) return std::nullopt;
    const int hi = hex_digit(body[star + 1]);
    const int lo = hex_digit(body[star + 2]);
    if (hi < 0 || lo < 0) return std::nullopt;
    unsigned checksum = 0;
    for (std::size_t i = 0; i < star; ++i) checksum ^= static_cast<unsigned char>(body[i]);
    if (checksum != static_cast<unsigned>(hi * 16 + lo)) return std::nullopt;
    body = body.substr(0, star);
  }

  std::array<std::string_view, kMaxFields> fields{};
  std::size_t count = 0;
  std::size_t start = 0;
  while (count < kMaxFields) {
    const auto comma = body.find(',', start);
    fields[count++] =
        body.substr(start, comma == std::string_view::npos ? body.npos : comma - start);
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  if (count < kRmcMinFields) return std::nullopt;

  const std::string_view time = fields[1];
  const std::string_view date = fields[9];
  const auto hh = digits(time, 0, 2);
  const auto mm = digits(time, 2, 2);
  const auto ss = digits(time, 4, 2);
  const auto day = digits(date, 0, 2);
  const auto month = digits(date, 2, 2);
  const auto yy = digits(date, 4, 2);
  if (!hh || !mm || !ss || !day || !month || !yy || date.size() != 6) return std::nullopt;
  if (*hh > 23 || *mm > 59 || *ss > 60) return std::nullopt;
  double fraction = 0.0;
  if (time.size() > 6) {
    if (time[6] != '.') return std::nullopt;
    const auto f = number(time.substr(6));
    if (!f) return std::nullopt;
    fraction = *f;
  }
  const int year = *yy < 80 ? 2000 + *yy : 1900 + *yy;
  const std::chrono::year_month_day ymd{std::chrono::year{year},
                                        std::chrono::month{static_cast<unsigned>(*month)},
                                        std::chrono::day{static_cast<unsigned>(*day)}};
  if (!ymd.ok()) return std::nullopt;
  const std::chrono::sys_days days{ymd};

  RmcFix fix;
  const std::int64_t seconds = static_cast<std::int64_t>(days.time_since_epoch().count()) * 86400 +
                               *hh * 3600 + *mm * 60 + *ss;
  fix.utc_ns = seconds * 1'000'000'000 + static_cast<std::int64_t>(fraction * 1e9 + 0.5);
  fix.valid = fields[2] == "A";
  fix.latitude_deg = coordinate(fields[3], fields[4], 2, 'S');
  fix.longitude_deg = coordinate(fields[5], fields[6], 3, 'W');
  fix.speed_knots = number(fields[7]);
  fix.course_deg = number(fields[8]);
  return fix;
}

}  // namespace livod::drivers::velodyne
