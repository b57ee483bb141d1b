// trim_whitespace (core/text.hpp): the one trim the line parsers share (EuRoC csv, HTTP headers,
// ROS message definitions, Hesai calibration csv).

#include "core/text.hpp"

#include <gtest/gtest.h>

namespace livod {
namespace {

TEST(TrimWhitespace, RemovesEveryKindOfWhitespaceAtBothEndsOnly) {
  EXPECT_EQ(trim_whitespace(" \t a b\t c \r\n"), "a b\t c");
  EXPECT_EQ(trim_whitespace("\v\fx\f\v"), "x");
  EXPECT_EQ(trim_whitespace("x"), "x");
  // A CSV field with a Windows line end, as EuRoC files written on Windows have.
  EXPECT_EQ(trim_whitespace("1403636579763555584\r"), "1403636579763555584");
}

TEST(TrimWhitespace, BlankOrEmptyGivesEmpty) {
  EXPECT_TRUE(trim_whitespace("").empty());
  EXPECT_TRUE(trim_whitespace(" \t\r\n").empty());
}

TEST(TrimWhitespace, ResultIsAViewIntoTheInput) {
  const std::string_view line = "  value  ";
  const std::string_view trimmed = trim_whitespace(line);
  EXPECT_EQ(trimmed.data(), line.data() + 2);
  EXPECT_EQ(trimmed.size(), 5u);
}

}  // namespace
}  // namespace livod
