#include "selfsense/daemon/csv_row.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <limits>
#include <string>

namespace selfsense::daemon {
namespace {

TEST(RowFormat, ColumnsFollowTheContractWithOrWithoutReferences) {
  EXPECT_EQ(RowFormat(true).header_block({"a comment"}),
            "# a comment\nt,E,D,T_hat,S_hat,setpoint,command,state,S,T,mode,faults,"
            "estimate_status,driver_status,nonfinite,cycle\n");
  EXPECT_EQ(RowFormat(false).header_block({}),
            "t,E,D,T_hat,S_hat,setpoint,command,state,mode,faults,estimate_status,driver_status,"
            "nonfinite,cycle\n");
}

TEST(RowFormat, RowHoldsShortestRoundTripValuesAndFlagsNonFiniteOnes) {
  runtime::LoopSample s;
  s.cycle = 42;
  s.t = 0.0021;
  s.e = 1.5e6;
  s.d = 0.0123;
  s.t_hat = -250000.0;
  s.s_hat = 0.1 + 0.2;  // 0.30000000000000004: every digit kept
  s.setpoint = 3e-4;
  s.command = std::numeric_limits<double>::infinity();
  s.state = runtime::LoopState::kReady;
  s.mode = runtime::ControlMode::kForce;
  s.faults = 0x12;
  s.estimate_status = 2;
  s.driver_status = 7;
  // s_ref and t_ref stay NaN: no reference sensor.
  std::array<char, kMaxRowBytes> row{};
  const std::size_t n = RowFormat(true).format(s, row.data());
  EXPECT_EQ(std::string(row.data(), n),
            "0.0021,1500000,0.0123,-250000,0.30000000000000004,3e-04,0,1,0,0,1,18,2,7,224,42\n");
  // 224 = command 32 + S 64 + T 128
}

TEST(RowFormat, TemperatureColumnsFollowTheReferencesOnlyWhenAsked) {
  EXPECT_EQ(RowFormat(true, true, true).header_block({}),
            "t,E,D,T_hat,S_hat,setpoint,command,state,S,T,temp,temp_equivalent,mode,faults,"
            "estimate_status,driver_status,nonfinite,cycle\n");
  EXPECT_EQ(RowFormat(true, true, false).header_block({}),
            "t,E,D,T_hat,S_hat,setpoint,command,state,S,T,temp,mode,faults,estimate_status,"
            "driver_status,nonfinite,cycle\n");
  EXPECT_EQ(RowFormat(true, false, false).header_block({}), RowFormat(true).header_block({}));
  runtime::LoopSample s;
  s.cycle = 7;
  s.t = 0.5;
  s.e = 1.0;
  s.d = 2.0;
  s.t_hat = 3.0;
  s.s_hat = 4.0;
  s.setpoint = 5.0;
  s.command = 6.0;
  s.s_ref = 7.0;
  s.t_ref = 8.0;
  s.temp_ref = 41.25;
  // temp_equivalent stays NaN: written as 0 and flagged (512).
  std::array<char, kMaxRowBytes> row{};
  const std::size_t n = RowFormat(true, true, true).format(s, row.data());
  EXPECT_EQ(std::string(row.data(), n), "0.5,1,2,3,4,5,6,0,7,8,41.25,0,0,0,0,0,512,7\n");
  // The longest row fits: every double 24 characters, every integer at its widest.
  s.e = s.d = s.t_hat = s.s_hat = s.setpoint = s.command = s.s_ref = s.t_ref = s.temp_ref =
      s.temp_equivalent = -1.2345678901234567e-300;
  s.t = 1.2345678901234567e+300;
  s.cycle = std::numeric_limits<std::int64_t>::min();
  s.faults = std::numeric_limits<std::uint32_t>::max();
  s.driver_status = std::numeric_limits<std::uint16_t>::max();
  s.estimate_status = std::numeric_limits<std::uint8_t>::max();
  EXPECT_LE(RowFormat(true, true, true).format(s, row.data()), kMaxRowBytes);
}

TEST(RowFormat, PaddingLengthensTheLastCellWithoutChangingItsValue) {
  std::array<char, 64> row{};
  const std::string text = "1.5,2,-17\n";
  text.copy(row.data(), text.size());
  const std::size_t n = RowFormat::pad(row.data(), text.size(), 5);
  EXPECT_EQ(std::string(row.data(), n), "1.5,2,-0000017\n");
  const std::string text2 = "1.5,2,3\n";
  text2.copy(row.data(), text2.size());
  EXPECT_EQ(std::string(row.data(), RowFormat::pad(row.data(), text2.size(), 3)), "1.5,2,0003\n");
}

}  // namespace
}  // namespace selfsense::daemon
