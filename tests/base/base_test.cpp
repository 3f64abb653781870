// The ground floor (include/selfsense/base): number text that round-trips, errno text.
#include <gtest/gtest.h>

#include <cerrno>
#include <charconv>
#include <cmath>
#include <limits>
#include <string>

#include "selfsense/base/errno_text.hpp"
#include "selfsense/base/format_number.hpp"

namespace selfsense::base {
namespace {

TEST(FormatNumber, IsTheShortestTextThatReadsBackTheSame) {
  EXPECT_EQ(format_number(0.2), "0.2");
  EXPECT_EQ(format_number(2000.0), "2000");
  EXPECT_EQ(format_number(-1e-7), "-1e-07");
  EXPECT_EQ(format_number(std::numeric_limits<double>::infinity()), "inf");
  EXPECT_EQ(format_number(std::nan("")), "nan");
  for (const double x : {0.1 + 0.2, -2.2250738585072014e-308, 1.0 / 3.0, 6.02214076e23}) {
    const std::string text = format_number(x);
    double back = 0.0;
    std::from_chars(text.data(), text.data() + text.size(), back);
    EXPECT_EQ(back, x) << text;
  }
}

TEST(ErrnoText, NamesTheErrorAndSaysWhenThereIsNone) {
  EXPECT_EQ(errno_text(ENOENT), "No such file or directory");
  EXPECT_EQ(errno_text(0), "unknown reason");
}

}  // namespace
}  // namespace selfsense::base
