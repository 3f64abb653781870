// The one validation vocabulary (include/selfsense/base/check.hpp): "<name>: <value> <constraint>".
#include "selfsense/base/check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <vector>

namespace selfsense::base::check {
namespace {

TEST(Check, OneMessageFormatNamesTheKeyTheValueAndTheConstraint) {
  std::string why;
  EXPECT_FALSE(positive("Pid.sample_time", 0.0, &why));
  EXPECT_EQ(why, "Pid.sample_time: 0 must be > 0");
  EXPECT_FALSE(non_negative("a.b", -0.001, &why));
  EXPECT_EQ(why, "a.b: -0.001 must be >= 0");
  EXPECT_FALSE(finite("x", std::nan(""), &why));
  EXPECT_EQ(why, "x: nan must be finite");
  EXPECT_FALSE(below("f", 3.0, 2.0, "0.45 * sample rate", &why));
  EXPECT_EQ(why, "f: 3 must be < 0.45 * sample rate = 2");
  EXPECT_FALSE(require(false, "hysteresis.levels", 4, "must be within [8, 1024]", &why));
  EXPECT_EQ(why, "hysteresis.levels: 4 must be within [8, 1024]");
  EXPECT_FALSE(fail("complete", "must be true", &why));
  EXPECT_EQ(why, "complete: must be true");
}

TEST(Check, PassingChecksLeaveTheMessageAloneAndNullIsAllowed) {
  std::string why = "untouched";
  EXPECT_TRUE(positive("a", 1.0, &why));
  EXPECT_TRUE(require(true, "n", std::size_t{3}, "must be small", &why));
  EXPECT_EQ(why, "untouched");
  EXPECT_FALSE(positive("a", -1.0, nullptr));
}

TEST(Check, SequencesNameTheElement) {
  std::string why;
  const std::vector<double> up{0.1, 0.2, 0.2};
  EXPECT_FALSE(strictly_increasing_above("t", up, 0.0, &why));
  EXPECT_EQ(why, "t[2]: 0.2 must be > t[1] = 0.2");
  const std::vector<double> down{-0.1, 0.5};
  EXPECT_FALSE(strictly_decreasing_below("d", down, 0.0, &why));
  EXPECT_EQ(why, "d[1]: 0.5 must be < d[0] = -0.1");
  EXPECT_FALSE(all_positive("w", std::vector<double>{1.0, 0.0}, &why));
  EXPECT_EQ(why, "w[1]: 0 must be > 0");
  EXPECT_FALSE(same_size("a", 3, "b", 2, &why));
  EXPECT_EQ(why, "a has 3 elements but b has 2");
}

}  // namespace
}  // namespace selfsense::base::check
