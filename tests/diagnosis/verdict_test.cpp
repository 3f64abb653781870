// The verdict of a diagnosis without a finding (diagnosis.hpp): a recording that the model
// explains to its sensor noise is `consistent`; one with a disturbance no candidate models, well
// above the noise, is `unexplained`, with where it is and how much of the residual that holds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/diagnosis/diagnosis.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::diagnosis {
namespace {

constexpr double kTs = 1e-3;
constexpr std::size_t kSamples = 20000;

struct Bench {
  models::TransducerModel model{test::typical_transducer(kTs)};
  test::TransducerData data{};
  double noise_d{0.0};
  Bench() {
    data = test::transducer_data(model, kSamples, 0.0, 5);
    std::mt19937_64 rng(17);
    std::normal_distribution<double> n01;
    const auto [dlo, dhi] = std::minmax_element(data.d.begin(), data.d.end());
    const auto [slo, shi] = std::minmax_element(data.s.begin(), data.s.end());
    noise_d = 1e-4 * (*dhi - *dlo);
    const double noise_s = 5e-4 * (*shi - *slo);
    for (std::size_t k = 0; k < kSamples; ++k) {
      data.d[k] += noise_d * n01(rng);
      data.s[k] += noise_s * n01(rng);
    }
  }
  [[nodiscard]] Signals signals() const { return {data.e, data.d, data.s, data.t, {}, kTs}; }
};

TEST(Verdict, ARecordingTheModelExplainsToItsNoiseIsConsistent) {
  const Bench b;
  const Result r = diagnose(b.model, b.signals());
  EXPECT_TRUE(r.findings.empty());
  EXPECT_EQ(r.verdict, Verdict::kConsistent) << to_string(r.verdict);
  EXPECT_TRUE(r.unexplained.empty());
  ASSERT_EQ(r.channels.size(), 2U);
  // The noise floor estimated from the residual is the noise put in (D: 1e-4 of range).
  EXPECT_NEAR(r.channels[0].noise_floor, b.noise_d, 0.1 * b.noise_d);
  EXPECT_NEAR(r.channels[0].residual_rms, b.noise_d, 0.1 * b.noise_d);
}

TEST(Verdict, ADisturbanceNoCandidateModelsIsUnexplainedWithItsPlace) {
  Bench b;
  // A 37 Hz burst of 50x the noise in D over 1 s in the middle (a ground loop, a loose cable):
  // it raises the residual's RMS over the whole record to about 8x the noise (the verdict reads
  // the record's RMS, so a burst of 30x over a twentieth of it, 4.9x, would stay `consistent`).
  const std::size_t from = 10000;
  const std::size_t to = 11000;
  for (std::size_t k = from; k < to; ++k) {
    b.data.d[k] +=
        50.0 * b.noise_d * std::sin(2.0 * std::numbers::pi * 37.0 * kTs * static_cast<double>(k));
  }
  const Result r = diagnose(b.model, b.signals());
  EXPECT_TRUE(r.findings.empty());
  ASSERT_EQ(r.channels.size(), 2U);
  EXPECT_EQ(r.verdict, Verdict::kUnexplained)
      << to_string(r.verdict) << ": D residual " << r.channels[0].residual_rms << ", noise floor "
      << r.channels[0].noise_floor;
  ASSERT_EQ(r.unexplained.size(), 1U);  // D only: S is at its noise floor
  const Unexplained& u = r.unexplained.front();
  EXPECT_EQ(u.channel, "D");
  EXPECT_GT(u.residual_rms, 5.0 * u.noise_floor);
  EXPECT_GT(u.share, 0.9);  // nearly all of it in the located stretch
  ASSERT_FALSE(u.where.empty());
  EXPECT_LE(u.where.front().begin, from + 200);
  EXPECT_GE(u.where.back().end, to - 200);
  EXPECT_LT(u.where.back().end - u.where.front().begin, 3 * (to - from));
}

TEST(Verdict, TooFewBlocksToJudgeAreRefusedByName) {
  const Bench b;
  Options o;
  o.blocks = 10;
  try {
    static_cast<void>(diagnose(b.model, b.signals(), o));
    FAIL() << "accepted 10 blocks";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("Options.blocks"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace selfsense::diagnosis
