#include "selfsense/evaluation/diagnosis_output.hpp"

#include <algorithm>
#include <cstdio>
#include <span>
#include <string>

namespace selfsense::evaluation {
namespace {

report::ReportCorrelation correlation(const std::string& channel,
                                      const diagnosis::CorrelationTest& c) {
  return {channel, c.max_lag, c.autocorrelation, c.cross_correlation, c.bound};
}

nlohmann::json where_json(const std::vector<diagnosis::Segment>& segments,
                          const std::vector<double>& t) {
  nlohmann::json where = nlohmann::json::array();
  for (const report::ReportSegment& s : seconds(segments, t)) {
    where.push_back({{"t_start", s.t_start}, {"t_end", s.t_end}});
  }
  return where;
}

}  // namespace

std::vector<report::ReportSegment> seconds(const std::vector<diagnosis::Segment>& segments,
                                           const std::vector<double>& t) {
  std::vector<report::ReportSegment> out;
  out.reserve(segments.size());
  for (const diagnosis::Segment& s : segments) {
    out.push_back({t[s.begin], t[std::min(s.end, t.size()) - 1]});
  }
  return out;
}

std::vector<report::ReportFigure> report_figures(const std::vector<ChannelFigures>& figures) {
  std::vector<report::ReportFigure> out;
  out.reserve(figures.size());
  for (const ChannelFigures& c : figures)
    out.push_back({c.channel, c.figures.nrmse, c.figures.max});
  return out;
}

nlohmann::json to_json(const diagnosis::Result& result, const std::vector<double>& t) {
  nlohmann::json j;
  j["verdict"] = diagnosis::to_string(result.verdict);
  j["findings"] = nlohmann::json::array();
  for (const diagnosis::Finding& f : result.findings) {
    nlohmann::json alternatives = nlohmann::json::array();
    for (const diagnosis::Alternative& a : f.alternatives) {
      alternatives.push_back(
          {{"effect", a.effect}, {"explains", a.explains}, {"evidence", a.evidence}});
    }
    j["findings"].push_back({{"effect", f.effect},
                             {"channel", f.channel},
                             {"where", where_json(f.where, t)},
                             {"explains", f.explains},
                             {"evidence", f.evidence},
                             {"alternatives", alternatives}});
  }
  j["unexplained"] = nlohmann::json::array();
  for (const diagnosis::Unexplained& u : result.unexplained) {
    j["unexplained"].push_back({{"channel", u.channel},
                                {"where", where_json(u.where, t)},
                                {"share", u.share},
                                {"residual_rms", u.residual_rms},
                                {"noise_floor", u.noise_floor}});
  }
  nlohmann::json channels = nlohmann::json::array();
  for (const diagnosis::ChannelResult& c : result.channels) {
    const auto test = [](const diagnosis::CorrelationTest& ct) {
      return nlohmann::json{{"bound", ct.bound},
                            {"autocorrelation_outside", ct.auto_outside},
                            {"cross_correlation_outside", ct.cross_outside}};
    };
    channels.push_back(
        {{"channel", c.channel},
         {"noise_floor", c.noise_floor},
         {"residual_rms", c.residual_rms},
         {"located", where_json(c.located, t)},
         {"residual_test", {{"before", test(c.test_before)}, {"after", test(c.test_after)}}}});
  }
  j["channels"] = channels;
  return j;
}

report::ReportInput report_input(const diagnosis::Result& result, const FieldSignals& recording,
                                 models::Drive drive) {
  const std::vector<double>& t = recording.t;
  report::ReportInput report;
  report.verdict = diagnosis::to_string(result.verdict);
  for (const diagnosis::Unexplained& u : result.unexplained) {
    const std::vector<report::ReportSegment> where = seconds(u.where, t);
    char line[256];
    static_cast<void>(std::snprintf(
        line, sizeof line,
        "%s: residual RMS %.3g, %.1fx its noise floor %.3g; %.0f %% of it in %zu "
        "stretch(es) between %.3g s and %.3g s; no candidate reduces it on held-out data",
        u.channel.c_str(), u.residual_rms,
        u.noise_floor > 0.0 ? u.residual_rms / u.noise_floor : 0.0, u.noise_floor, 100.0 * u.share,
        where.size(), where.empty() ? 0.0 : where.front().t_start,
        where.empty() ? 0.0 : where.back().t_end));
    report.unexplained.emplace_back(line);
  }
  report.t = t;
  const std::span<const double> x = recording.drive(drive);
  report.drive.assign(x.begin(), x.end());
  if (drive == models::Drive::kCharge) {
    report.drive_name = "D";
    report.drive_unit = "C/m^2";
  }
  for (const diagnosis::ChannelResult& c : result.channels) {
    report::ReportChannel rc;
    rc.name = c.channel;
    rc.unit = c.channel == "S" ? "-" : (c.channel == "D" ? "C/m^2" : "V/m");
    rc.recorded = c.recorded;
    rc.before = c.before;
    rc.after = c.after;
    rc.located = seconds(c.located, t);
    rc.test_before = correlation(c.channel, c.test_before);
    rc.test_after = correlation(c.channel, c.test_after);
    report.channels.push_back(std::move(rc));
  }
  for (const diagnosis::Finding& f : result.findings) {
    report::ReportFinding rf;
    rf.effect = f.effect;
    rf.channel = f.channel;
    rf.where = seconds(f.where, t);
    rf.explains = f.explains;
    rf.evidence = f.evidence;
    for (const diagnosis::Alternative& a : f.alternatives)
      rf.alternatives.push_back({a.effect, a.explains, a.evidence});
    rf.feature_name = f.feature_name;
    rf.feature = f.feature;
    for (const diagnosis::ChannelResult& c : result.channels) {
      if (c.channel != f.channel) continue;
      rf.residual.resize(c.recorded.size());
      for (std::size_t k = 0; k < c.recorded.size(); ++k)
        rf.residual[k] = c.recorded[k] - c.before[k];
    }
    report.findings.push_back(std::move(rf));
  }
  return report;
}

}  // namespace selfsense::evaluation
