#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "selfsense/identification/fit_quality.hpp"
#include "selfsense/identification/transducer_fit.hpp"
#include "selfsense/models/reconstructor.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::models {
namespace {

using identification::defaults_for;
using identification::identify;
using identification::TransducerSignals;

using identification::fit_quality;

constexpr double kTs = 1e-3;

struct Estimates {
  std::vector<double> t, s;
};

Estimates reconstruct(const TransducerModel& model, const test::TransducerData& d, std::size_t from,
                      std::size_t to) {
  Reconstructor r(model);
  Estimates out;
  for (std::size_t k = 0; k < to; ++k) {
    const Reconstructor::Estimate est = r.step(d.e[k], d.d[k]);
    if (k >= from) {
      out.t.push_back(est.stress);
      out.s.push_back(est.strain);
    }
  }
  return out;
}

TEST(Reconstruction, ExactModelReconstructsStressAndStrainExactly) {
  const TransducerModel truth = test::typical_transducer(kTs);
  const test::TransducerData d = test::transducer_data(truth, 5000, 0.0, 1);
  const Estimates est = reconstruct(truth, d, 0, d.e.size());
  for (std::size_t k = 0; k < d.e.size(); ++k) {
    ASSERT_NEAR(est.t[k], d.t[k], 1e-6 * 2e7);
    ASSERT_NEAR(est.s[k], d.s[k], 1e-9 * 1.5e-3);
  }
}

TEST(Reconstruction, IdentifiedHysteresisCreepBeatsLinearOnHeldOutData) {
  const TransducerModel truth = test::typical_transducer(kTs);
  const test::TransducerData d = test::transducer_data(truth, 80000, 1e-4, 2);
  const std::size_t split = 60000;
  const TransducerSignals fit_part{std::span(d.e).first(split), std::span(d.d).first(split),
                                   std::span(d.t).first(split), std::span(d.s).first(split), kTs};
  const TransducerModel hc =
      identify(fit_part, Structure::kHysteresisCreep, defaults_for(Structure::kHysteresisCreep));
  const TransducerModel lin =
      identify(fit_part, Structure::kLinear, defaults_for(Structure::kLinear));
  ASSERT_TRUE(hc.is_valid(nullptr));
  // Held-out: the reconstructor runs over everything, figures on the last 20000 samples.
  const Estimates e_hc = reconstruct(hc, d, split, d.e.size());
  const Estimates e_lin = reconstruct(lin, d, split, d.e.size());
  const auto held = [&](const std::vector<double>& v) { return std::span(v).subspan(split); };
  const auto s_hc = fit_quality(held(d.s), e_hc.s);
  const auto t_hc = fit_quality(held(d.t), e_hc.t);
  const auto s_lin = fit_quality(held(d.s), e_lin.s);
  // Measured: S 0.24 % / 1.02 %, T 1.23 %, linear S 10.6 % (S 0.28 % / 1.07 %, T 1.42 % before
  // the remanent-state search of docs/identification.md).
  EXPECT_LT(s_hc.nrmse, 3.5e-3);
  EXPECT_LT(s_hc.max, 1.5e-2);
  EXPECT_LT(t_hc.nrmse, 2e-2);
  EXPECT_GT(s_lin.nrmse, 3.0 * s_hc.nrmse);
}

TEST(Reconstruction, NeedsASensorCoupling) {
  TransducerModel m = test::typical_transducer(kTs);
  m.sensor->linear_gains = {0.0};
  EXPECT_THROW(Reconstructor r(m), std::invalid_argument);
  m.sensor.reset();
  EXPECT_THROW(Reconstructor r(m), std::invalid_argument);
}

TEST(Reconstruction, StateSaveAndRestore) {
  const TransducerModel truth = test::typical_transducer(kTs);
  const test::TransducerData d = test::transducer_data(truth, 4000, 0.0, 3);
  Reconstructor r(truth);
  for (std::size_t k = 0; k < 2000; ++k)
    r.step(d.e[k], d.d[k]);
  std::vector<double> saved(r.state_size());
  r.save_state(saved);
  std::vector<double> first;
  for (std::size_t k = 2000; k < 4000; ++k)
    first.push_back(r.step(d.e[k], d.d[k]).strain);
  r.restore_state(saved);
  for (std::size_t k = 2000; k < 4000; ++k)
    ASSERT_EQ(r.step(d.e[k], d.d[k]).strain, first[k - 2000]);
}

}  // namespace
}  // namespace selfsense::models
