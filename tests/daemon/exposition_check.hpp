// A checker of the Prometheus text exposition format (0.0.4) for the daemon's telemetry tests,
// written from the format's description, independent of the formatter under test
// (src/daemon/prometheus.cpp): every line is a HELP, a TYPE or a sample; a family's HELP and
// TYPE come before its samples and each family appears in one block; metric names match
// [a-zA-Z_:][a-zA-Z0-9_:]*, label names [a-zA-Z_][a-zA-Z0-9_]*; label values are quoted with
// \\, \" and \n the only escapes; values are numbers (or NaN, +Inf, -Inf); counters are named
// *_total and are never negative; no two samples of a family have the same labels.
#pragma once

#include <cmath>
#include <cstdlib>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace selfsense::test {

struct Exposition {
  std::vector<std::string> problems{};
  // family -> "labels" -> value, as read back.
  std::map<std::string, std::map<std::string, double>> samples{};
  std::map<std::string, std::string> types{};
};

inline Exposition check_exposition(const std::string& text) {
  Exposition x;
  const std::regex help(R"(# HELP ([a-zA-Z_:][a-zA-Z0-9_:]*) (.*))");
  const std::regex type(
      R"(# TYPE ([a-zA-Z_:][a-zA-Z0-9_:]*) (counter|gauge|histogram|summary|untyped))");
  const std::regex sample(
      R"(([a-zA-Z_:][a-zA-Z0-9_:]*)(\{((?:[a-zA-Z_][a-zA-Z0-9_]*="(?:[^"\\\n]|\\[\\"n])*",?)*)\})? (\S+))");
  const std::regex label(R"re(([a-zA-Z_][a-zA-Z0-9_]*)="((?:[^"\\\n]|\\[\\"n])*)")re");
  std::set<std::string> helped;
  std::set<std::string> closed;  // families whose block has ended
  std::string current;
  std::istringstream in(text);
  std::string line;
  int n = 0;
  const auto problem = [&](const std::string& what) {
    x.problems.push_back("line " + std::to_string(n) + ": " + what + ": " + line);
  };
  const auto enter = [&](const std::string& name) {
    if (name == current) return;
    if (closed.count(name) != 0U) problem("family " + name + " appears in two blocks");
    if (!current.empty()) closed.insert(current);
    current = name;
  };
  if (!text.empty() && text.back() != '\n') x.problems.emplace_back("no line feed at the end");
  while (std::getline(in, line)) {
    ++n;
    std::smatch m;
    if (std::regex_match(line, m, help)) {
      enter(m[1]);
      if (!helped.insert(m[1]).second) problem("second HELP");
      if (x.samples.count(m[1]) != 0U) problem("HELP after samples");
    } else if (std::regex_match(line, m, type)) {
      enter(m[1]);
      if (x.types.count(m[1]) != 0U) problem("second TYPE");
      if (x.samples.count(m[1]) != 0U) problem("TYPE after samples");
      x.types[m[1]] = m[2];
    } else if (std::regex_match(line, m, sample)) {
      const std::string name = m[1];
      enter(name);
      if (helped.count(name) == 0U || x.types.count(name) == 0U) problem("sample before HELP/TYPE");
      const std::string value = m[4];
      char* end = nullptr;
      const double v = std::strtod(value.c_str(), &end);
      const bool special = value == "NaN" || value == "+Inf" || value == "-Inf";
      if (!special && (end == value.c_str() || *end != '\0')) problem("value not a number");
      // Labels in their canonical order, for a duplicate check.
      std::map<std::string, std::string> labels;
      const std::string body = m[3];
      for (auto it = std::sregex_iterator(body.begin(), body.end(), label);
           it != std::sregex_iterator(); ++it) {
        if (!labels.emplace((*it)[1], (*it)[2]).second) problem("label given twice");
        if ((*it)[1].str().rfind("__", 0) == 0) problem("reserved label name");
      }
      std::string key;
      for (const auto& [k, val] : labels) {
        key += k;
        key += '=';
        key += val;
        key += ';';
      }
      if (!x.samples[name].emplace(key, special ? std::nan("") : v).second)
        problem("two samples with the same labels");
      if (x.types[name] == "counter") {
        if (name.size() < 6 || name.substr(name.size() - 6) != "_total")
          problem("counter not *_total");
        if (!special && v < 0.0) problem("negative counter");
      }
    } else {
      problem("not a HELP, TYPE or sample line");
    }
  }
  return x;
}

}  // namespace selfsense::test
