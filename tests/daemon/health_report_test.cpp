// The health estimate as the daemon reports it: the status JSON's `health` object and the
// selfsense_health_* families (health_report.hpp), the names outside tools rely on.
#include "selfsense/daemon/health_report.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "daemon/exposition_check.hpp"

namespace selfsense::daemon {
namespace {

runtime::HealthStatus measured() {
  runtime::HealthStatus h;
  h.enabled = true;
  h.figures.has_capacitance = true;
  h.figures.capacitance_f_per_m = 2.1e-8;
  h.figures.has_dissipation = true;
  h.figures.dissipation_j_per_m3 = 3200.0;
  h.figures.baseline_ready = true;
  h.figures.has_depolarisation = true;
  h.figures.depolarisation = 0.031;
  h.figures.depolarisation_per_h = 0.05;
  h.figures.cycles = 7200;
  h.latched = adaptation::bit(adaptation::HealthAlarm::kDepolarisation);
  h.active = h.latched;
  h.raised_at_s = {-1.0, 2170.5, -1.0};
  return h;
}

TEST(HealthReport, StatusJsonNamesEveryFigureAndAlarm) {
  EXPECT_EQ(health_json(runtime::HealthStatus{}), nlohmann::json({{"enabled", false}}));
  const nlohmann::json j = health_json(measured());
  EXPECT_EQ(j.at("enabled"), true);
  EXPECT_EQ(j.at("fault"), false);
  EXPECT_DOUBLE_EQ(j.at("capacitance_f_per_m").get<double>(), 2.1e-8);
  EXPECT_DOUBLE_EQ(j.at("depolarisation_pct").get<double>(), 3.1);
  EXPECT_DOUBLE_EQ(j.at("depolarisation_pct_per_h").get<double>(), 5.0);
  EXPECT_TRUE(j.at("leakage_resistivity_ohm_m").is_null());  // no hold measured
  EXPECT_EQ(j.at("cycles"), 7200);
  EXPECT_EQ(j.at("alarms").at("depolarisation").at("latched"), true);
  EXPECT_DOUBLE_EQ(j.at("alarms").at("depolarisation").at("raised_at_s").get<double>(), 2170.5);
  EXPECT_TRUE(j.at("alarms").at("overheating").at("raised_at_s").is_null());
  for (const char* key :
       {"capacitance_change_per_h", "dissipation_j_per_m3", "dissipation_change_per_h",
        "baseline_ready", "leakage_conductivity_s_per_m", "compared_cycles", "holds"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_TRUE(j.at("alarms").contains("insulation"));
}

// Configured but nothing measured yet (the loop's snapshot before its first cycle): enabled,
// every figure null, no alarm raised.
TEST(HealthReport, ConfiguredButNotYetMeasuredReportsNullFigures) {
  runtime::HealthStatus h;
  h.enabled = true;
  h.raised_at_s.fill(-1.0);
  const nlohmann::json j = health_json(h);
  EXPECT_EQ(j.at("enabled"), true);
  for (const char* key : {"capacitance_f_per_m", "dissipation_j_per_m3", "depolarisation_pct",
                          "leakage_resistivity_ohm_m"}) {
    EXPECT_TRUE(j.at(key).is_null()) << key;
  }
  EXPECT_EQ(j.at("cycles"), 0);
  EXPECT_EQ(j.at("baseline_ready"), false);
  EXPECT_TRUE(j.at("alarms").at("overheating").at("raised_at_s").is_null());
}

TEST(HealthReport, PrometheusFamiliesAreValidExposition) {
  EXPECT_TRUE(health_metrics(runtime::HealthStatus{}).empty());
  runtime::HealthStatus h = measured();
  h.figures.has_leakage = true;
  h.figures.leakage_resistivity_ohm_m = std::numeric_limits<double>::infinity();
  const std::string text = format_exposition(health_metrics(h));
  const test::Exposition x = test::check_exposition(text);
  EXPECT_TRUE(x.problems.empty()) << text;
  EXPECT_DOUBLE_EQ(x.samples.at("selfsense_health_depolarisation_ratio").at(""), 0.031);
  EXPECT_DOUBLE_EQ(x.samples.at("selfsense_health_capacitance_farads_per_metre").at(""), 2.1e-8);
  EXPECT_EQ(x.samples.at("selfsense_health_alarm_latched").at("alarm=depolarisation;"), 1.0);
  EXPECT_EQ(x.samples.at("selfsense_health_alarm_active").at("alarm=overheating;"), 0.0);
  EXPECT_EQ(x.samples.at("selfsense_health_cycles_total").at(""), 7200.0);
  EXPECT_EQ(x.types.at("selfsense_health_cycles_total"), "counter");
  EXPECT_TRUE(x.samples.count("selfsense_health_leakage_resistivity_ohm_metres") != 0U);
}

}  // namespace
}  // namespace selfsense::daemon
