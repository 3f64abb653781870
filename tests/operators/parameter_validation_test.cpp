#include <gtest/gtest.h>

#include <limits>
#include <string>

#include "selfsense/operators/hysteresis_creep.hpp"
#include "selfsense/operators/parameter_error.hpp"
#include "selfsense/operators/play.hpp"

namespace selfsense::operators {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Constructing must throw ParameterError whose message contains `names`.
template <typename Make>
void expect_rejected(Make make, const std::string& names) {
  try {
    make();
    FAIL() << "accepted, expected an error naming " << names;
  } catch (const ParameterError& e) {
    EXPECT_NE(std::string(e.what()).find(names), std::string::npos) << e.what();
  }
}

TEST(ParameterValidation, PlayAndStopThresholds) {
  expect_rejected([] { PlayOperator p(-0.1); }, "PlayOperator.threshold");
  expect_rejected([] { PlayOperator p(kNaN); }, "PlayOperator.threshold");
  expect_rejected([] { StopOperator s(kInf); }, "PlayOperator.threshold");
}

TEST(ParameterValidation, PrandtlIshlinskii) {
  using P = PrandtlIshlinskii::Params;
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {0.1, -0.2}, {0.1, 0.1}});
      },
      "PrandtlIshlinskii.thresholds[1]");
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {0.3, 0.2}, {0.1, 0.1}});
      },
      "PrandtlIshlinskii.thresholds[1]: 0.2 must be > PrandtlIshlinskii.thresholds[0]");
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {0.0}, {0.1}});
      },
      "PrandtlIshlinskii.thresholds[0]");
  expect_rejected([] { PrandtlIshlinskii h(P{0.0, {}, {}}); }, "PrandtlIshlinskii.linear_weight");
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {0.1, 0.2}, {-0.5, -0.6}});
      },
      "PrandtlIshlinskii.weights[1]: partial sum");
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {0.1}, {kNaN}});
      },
      "PrandtlIshlinskii.weights[0]");
  expect_rejected(
      [] {
        PrandtlIshlinskii h(P{1.0, {kInf}, {0.1}});
      },
      "PrandtlIshlinskii.thresholds[0]");
  expect_rejected([] { PrandtlIshlinskii h(P{1.0, {0.1, 0.2}, {0.1}}); }, "has 2 elements");
}

TEST(ParameterValidation, DeadZoneSuperposition) {
  using S = DeadZoneSuperposition::Params;
  expect_rejected(
      [] {
        DeadZoneSuperposition s(S{1.0, {0.5}, {-1.5}, {}, {}});
      },
      "DeadZoneSuperposition.upper_weights[0]: slope");
  expect_rejected(
      [] {
        DeadZoneSuperposition s(S{1.0, {}, {}, {0.5}, {0.1}});
      },
      "DeadZoneSuperposition.lower_thresholds[0]: 0.5 must be < 0");
  expect_rejected(
      [] {
        DeadZoneSuperposition s(S{1.0, {}, {}, {-0.5, -0.2}, {0.1, 0.1}});
      },
      "DeadZoneSuperposition.lower_thresholds[1]");
  expect_rejected(
      [] {
        DeadZoneSuperposition s(S{-1.0, {}, {}, {}, {}});
      },
      "DeadZoneSuperposition.linear_weight");
  expect_rejected(
      [] {
        DeadZoneSuperposition s(S{1.0, {1.0, 0.5}, {0.1, 0.1}, {}, {}});
      },
      "DeadZoneSuperposition.upper_thresholds[1]");
}

TEST(ParameterValidation, Creep) {
  using L = LinearCreep::Params;
  expect_rejected([] { LinearCreep c(L{{1.0}, {-0.1}}, 1e-3); }, "LinearCreep.weights[0]");
  expect_rejected([] { LinearCreep c(L{{0.0}, {0.1}}, 1e-3); }, "LinearCreep.eigenvalues[0]");
  expect_rejected([] { LinearCreep c(L{{1.0}, {0.1}}, 0.0); }, "LinearCreep.sample_time");
  expect_rejected([] { LinearCreep c(L{{1.0, 2.0}, {0.1}}, 1e-3); }, "LinearCreep.eigenvalues");
  using T = ThresholdCreep::Params;
  expect_rejected(
      [] {
        ThresholdCreep c(T{{0.0, 0.5}, {1.0}, {0.1}}, 1e-3);
      },
      "ThresholdCreep.weights has 1 elements");
  expect_rejected(
      [] {
        ThresholdCreep c(T{{-0.5}, {1.0}, {0.1}}, 1e-3);
      },
      "ThresholdCreep.thresholds[0]");
  expect_rejected(
      [] {
        ThresholdCreep c(T{{0.0}, {kNaN}, {0.1}}, 1e-3);
      },
      "ThresholdCreep.eigenvalues[0]");
  expect_rejected([] { static_cast<void>(log_spaced_eigenvalues(1.0, 10.0, 3)); },
                  "fastest must be > slowest");
}

TEST(ParameterValidation, HysteresisCreepNamesThePart) {
  HysteresisCreep::Params p;
  p.creep = {{0.0}, {1.0}, {-0.2}};
  expect_rejected([&] { HysteresisCreep h(p, 1e-3); },
                  "HysteresisCreep.creep.ThresholdCreep.weights[0]");
  p = HysteresisCreep::Params{};
  p.hysteresis.linear_weight = kNaN;
  expect_rejected([&] { HysteresisCreep h(p, 1e-3); }, "HysteresisCreep.hysteresis.");
  expect_rejected([] { HysteresisCreep h(HysteresisCreep::Params{}, -1.0); },
                  "HysteresisCreep.sample_time");
  expect_rejected(
      [] { HysteresisCreepCompensator c(HysteresisCreep(HysteresisCreep::Params{}, 1e-3), 1, 0); },
      "input_max");
  // Eq. (28) with a negative PI weight would need negative creep weights.
  expect_rejected(
      [] {
        static_cast<void>(
            HysteresisCreep::with_nonlinear_creep({1.0, {0.1}, {-0.5}}, {}, {{1.0}, {0.1}}));
      },
      "negative");
}

TEST(ParameterValidation, IsValidReportsWithoutThrowing) {
  std::string why;
  EXPECT_FALSE((PrandtlIshlinskii::Params{1.0, {-1.0}, {0.1}}.is_valid(&why)));
  EXPECT_NE(why.find("thresholds[0]"), std::string::npos);
  EXPECT_TRUE((PrandtlIshlinskii::Params{1.0, {1.0}, {0.1}}.is_valid(nullptr)));
}

}  // namespace
}  // namespace selfsense::operators
