// $GPRMC parsing and the top-of-hour rule (§4.2, §4.6).

#include <gtest/gtest.h>

#include "drivers/velodyne/nmea.hpp"
#include "drivers/velodyne/top_of_hour.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr std::int64_t kNs = 1'000'000'000;

TEST(Nmea, ParsesTheVlp16PositionPacketSentence) {
  // §4.2: VGAD data/position.pcap.
  const auto fix =
      parse_rmc("$GPRMC,214106,A,3707.8178,N,12139.2690,W,010.3,188.2,230715,013.8,E,D*05\r\n");
  ASSERT_TRUE(fix);
  EXPECT_TRUE(fix->valid);
  EXPECT_EQ(fix->utc_ns, 1'437'687'666 * kNs);  // 2015-07-23 21:41:06 UTC
  EXPECT_NEAR(*fix->latitude_deg, 37.0 + 7.8178 / 60.0, 1e-12);
  EXPECT_NEAR(*fix->longitude_deg, -(121.0 + 39.2690 / 60.0), 1e-12);
  EXPECT_DOUBLE_EQ(*fix->speed_knots, 10.3);
  EXPECT_DOUBLE_EQ(*fix->course_deg, 188.2);
}

TEST(Nmea, FractionalSecondsVoidFixesAndOtherTalkers) {
  const auto fix = parse_rmc("$GNRMC,000000.25,V,,,,,,,010100,,*06");
  ASSERT_TRUE(fix);
  EXPECT_FALSE(fix->valid);
  EXPECT_EQ(fix->utc_ns, 946'684'800 * kNs + 250'000'000);  // 2000-01-01 00:00:00.25
  EXPECT_FALSE(fix->latitude_deg);
  EXPECT_TRUE(parse_rmc("$GPRMC,235959,A,0000.0000,S,00000.0000,E,0,0,311299,,"));  // no checksum
}

TEST(Nmea, RejectsWrongChecksumsAndOtherSentences) {
  EXPECT_FALSE(
      parse_rmc("$GPRMC,214106,A,3707.8178,N,12139.2690,W,010.3,188.2,230715,013.8,E,D*06"));
  EXPECT_FALSE(parse_rmc("$GPGGA,214106,3707.8178,N,12139.2690,W,2,07,1.0,9.0,M,,,,*7D"));
  EXPECT_FALSE(parse_rmc("$GPRMC,214106,A,3707.8178,N,12139.2690,W,010.3,188.2,320715,,"));  // 32nd
  EXPECT_FALSE(parse_rmc("$GPRMC,2141,A,,,,,,,230715,,"));
  EXPECT_FALSE(parse_rmc(""));
  EXPECT_FALSE(parse_rmc("$GPRMC"));
}

TEST(TopOfHour, HourRuleChoosesTheNearestHour) {
  const std::int64_t hour = 3600 * kNs;
  const std::int64_t ref = 1000 * hour + 10 * 60 * kNs;  // 10 min past an hour
  EXPECT_EQ(resolve_top_of_hour(5 * 60 * 1'000'000U, ref), 1000 * hour + 5 * 60 * kNs);
  // 55 min past the hour, reference 10 min past: belongs to the previous hour.
  EXPECT_EQ(resolve_top_of_hour(55 * 60 * 1'000'000U, ref), 999 * hour + 55 * 60 * kNs);
  // Reference 58 min past, stamp 1 min past: the next hour.
  EXPECT_EQ(resolve_top_of_hour(60 * 1'000'000U, 1000 * hour + 58 * 60 * kNs),
            1001 * hour + 60 * kNs);
}

TEST(TopOfHour, ClockUnwrapsRolloversAndToleratesReordering) {
  TopOfHourClock clock;
  const std::int64_t hour = 3600 * kNs;
  const std::uint32_t almost = 3'599'999'000U;  // 1 ms before the top of the hour
  EXPECT_EQ(clock.to_sensor_ns(almost, 7 * hour), 6 * hour + almost * 1000LL);
  EXPECT_EQ(clock.to_sensor_ns(500U, 0), 7 * hour + 500'000);  // rolled over
  EXPECT_EQ(clock.hour_rollovers(), 1U);
  EXPECT_EQ(clock.to_sensor_ns(almost + 10, 0), 6 * hour + (almost + 10) * 1000LL);  // late packet
  EXPECT_EQ(clock.to_sensor_ns(1000U, 0), 7 * hour + 1'000'000);
  EXPECT_EQ(clock.hour_rollovers(), 1U);
  clock.shift_hours(-2);
  EXPECT_EQ(clock.to_sensor_ns(2000U, 0), 5 * hour + 2'000'000);
}

}  // namespace
}  // namespace livod::drivers::velodyne
