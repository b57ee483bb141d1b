#pragma once
// NMEA 0183 $--RMC sentences as embedded in Velodyne position packets (§4.2): UTC date and time,
// fix status, position. Parsed without allocation (the position packet is decoded in the
// capture thread).

#include <cstdint>
#include <optional>
#include <string_view>

namespace livod::drivers::velodyne {

struct RmcFix {
  std::int64_t utc_ns = 0;  // UTC date + time of day, ns since the Unix epoch
  bool valid = false;       // status 'A' (a 'V' sentence still carries the receiver's time)
  std::optional<double> latitude_deg;   // north positive
  std::optional<double> longitude_deg;  // east positive
  std::optional<double> speed_knots;
  std::optional<double> course_deg;
};

// Parses "$GPRMC,hhmmss[.sss],A,ddmm.mmmm,N,dddmm.mmmm,W,speed,course,ddmmyy,..." (any talker
// id). Returns nullopt if the sentence is not RMC, is malformed, has a wrong checksum, or lacks
// the time or the date. Two-digit years are 1980..2079.
[[nodiscard]] std::optional<RmcFix> parse_rmc(std::string_view sentence);

}  // namespace livod::drivers::velodyne
