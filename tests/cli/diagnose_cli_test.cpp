// `selfsense diagnose` end to end through the tool (docs/diagnose.md): plant recordings written by
// `selfsense plant`, a base model by `selfsense identify`, then the diagnosis with --validate;
// the JSON contract, the improved model loaded by simulate and reconstruct, the report, a
// consistent case and bad input.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

const std::string kTool = SELFSENSE_CLI;
const std::string kData = SELFSENSE_SOURCE_DIR "/tests/diagnosis/data/";

std::string read(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs the tool with `args`; returns the exit status, output in `log`.
int run(const fs::path& dir, const std::string& args, std::string* log = nullptr) {
  const fs::path out = dir / "log.txt";
  const std::string cmd = kTool + " " + args + " > " + out.string() + " 2>&1";
  const int status = std::system(cmd.c_str());
  if (log != nullptr) *log = read(out);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

class DiagnoseCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir = fs::temp_directory_path() / ("selfsense_diagnose_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    const std::string d = dir.string() + "/";
    ASSERT_EQ(run(dir, "plant --config " + kData +
                           "bench_base.yaml --excitation mix --seed 11 --out " + d + "base.csv"),
              0);
    ASSERT_EQ(
        run(dir, "plant --config " + kData +
                     "bench_leakage_creep.yaml --excitation mix --seed 21 --out " + d + "fit.csv"),
        0);
    ASSERT_EQ(
        run(dir, "plant --config " + kData +
                     "bench_leakage_creep.yaml --excitation mix --seed 22 --out " + d + "val.csv"),
        0);
    ASSERT_EQ(run(dir, "identify --recording " + d +
                           "base.csv --structure hysteresis-creep --out " + d + "base_model.yaml"),
              0);
  }
  static void TearDownTestSuite() { fs::remove_all(dir); }
  static std::string path(const std::string& name) { return (dir / name).string(); }
  static fs::path dir;
};
fs::path DiagnoseCli::dir;

TEST_F(DiagnoseCli, NamesModelsAndShowsTheFitImproveOnValidationData) {
  std::string log;
  ASSERT_EQ(run(dir,
                "diagnose --model " + path("base_model.yaml") + " --recording " + path("fit.csv") +
                    " --validate " + path("val.csv") + " --json " + path("d.json") + " --report " +
                    path("d.html") + " --out " + path("improved.yaml"),
                &log),
            0)
      << log;
  const json j = json::parse(read(path("d.json")));
  EXPECT_EQ(j.at("verdict"), "mismatch");
  bool leakage = false;
  bool creep = false;
  for (const json& f : j.at("findings")) {
    leakage |= f.at("effect") == "charge_leakage" && f.at("channel") == "D";
    creep |= f.at("effect") == "creep" && f.at("channel") == "S";
    EXPECT_GT(f.at("explains").get<double>(), 0.3);
    EXPECT_FALSE(f.at("evidence").get<std::string>().empty());
    for (const json& a : f.at("alternatives")) {  // each with its own figure and evidence
      EXPECT_FALSE(a.at("effect").get<std::string>().empty());
      EXPECT_GT(a.at("explains").get<double>(), 0.0);
      EXPECT_FALSE(a.at("evidence").get<std::string>().empty());
    }
    for (const json& w : f.at("where")) {
      EXPECT_LT(w.at("t_start").get<double>(), w.at("t_end").get<double>());
    }
  }
  EXPECT_TRUE(leakage) << j.dump(2);
  EXPECT_TRUE(creep) << j.dump(2);
  // Contract figures on every channel, before and after, on the data and on validation.
  for (const char* part : {"fit", "validation"}) {
    for (const char* ch : {"D", "S", "T_hat", "S_hat"}) {
      const double before = j.at(part).at("before").at(ch).at("nrmse");
      const double after = j.at(part).at("after").at(ch).at("nrmse");
      EXPECT_GT(j.at(part).at("after").at(ch).at("max").get<double>(), 0.0);
      EXPECT_LE(after, 0.5 * before) << part << " " << ch << " " << before << " -> " << after;
    }
  }
  // The improved model runs in the tools (and so in the daemon, same runtime model).
  EXPECT_EQ(run(dir, "simulate --model " + path("improved.yaml") + " --recording " +
                         path("val.csv") + " --out " + path("sim.csv")),
            0);
  EXPECT_EQ(run(dir, "reconstruct --model " + path("improved.yaml") + " --recording " +
                         path("val.csv") + " --out " + path("rec.csv")),
            0);
  // Over a 100 s record a 1500 s leak of the charge amplifier and a parallel conductance look
  // alike: either form of charge_leakage is in the model.
  const std::string improved = read(path("improved.yaml"));
  EXPECT_TRUE(improved.find("leakage_tau_s") != std::string::npos ||
              improved.find("drive_integral_per_s") != std::string::npos)
      << improved;
  const std::string html = read(path("d.html"));
  EXPECT_NE(html.find("<svg"), std::string::npos);
  EXPECT_NE(html.find("charge_leakage"), std::string::npos);
}

// The base model against the recording it was identified on: nothing to name, but a
// hysteresis-creep model of the Preisach plant leaves a residual 15x (D) and 26x (S) its noise
// floor (measured), well above the 5x that makes it `unexplained`: the user learns where and how
// much, and the model is left as it is.
TEST_F(DiagnoseCli, ModelOfTheRecordingNamesNothingAndSaysWhatIsLeft) {
  std::string log;
  ASSERT_EQ(run(dir,
                "diagnose --model " + path("base_model.yaml") + " --recording " + path("base.csv") +
                    " --json " + path("c.json") + " --report " + path("c.html") + " --out " +
                    path("same.yaml"),
                &log),
            0)
      << log;
  const json j = json::parse(read(path("c.json")));
  EXPECT_EQ(j.at("verdict"), "unexplained") << j.dump(2);
  EXPECT_TRUE(j.at("findings").empty());
  EXPECT_FALSE(j.contains("validation"));
  EXPECT_EQ(j.at("fit").at("before").at("S").at("nrmse"),
            j.at("fit").at("after").at("S").at("nrmse"));
  std::vector<std::string> channels;
  for (const json& u : j.at("unexplained")) {
    channels.push_back(u.at("channel"));
    const double ratio = u.at("residual_rms").get<double>() / u.at("noise_floor").get<double>();
    EXPECT_GT(ratio, 5.0) << u.dump();
    EXPECT_LT(ratio, 100.0) << u.dump();
    EXPECT_GT(u.at("share").get<double>(), 0.0);
    EXPECT_LE(u.at("share").get<double>(), 1.0);
    ASSERT_FALSE(u.at("where").empty());
    EXPECT_LT(u.at("where").front().at("t_start").get<double>(),
              u.at("where").back().at("t_end").get<double>());
  }
  EXPECT_EQ(channels, (std::vector<std::string>{"D", "S"}));
  EXPECT_NE(log.find("unexplained on D"), std::string::npos) << log;
  EXPECT_NE(read(path("c.html")).find("unexplained"), std::string::npos);
}

TEST_F(DiagnoseCli, RecordingWithoutReferencesIsRefusedByName) {
  {
    std::ofstream f(path("bare.csv"));
    f << "t,E\n";
    for (int k = 0; k < 500; ++k)
      f << 1e-3 * k << "," << 1e3 * k << "\n";
  }
  std::string log;
  EXPECT_NE(run(dir,
                "diagnose --model " + path("base_model.yaml") + " --recording " + path("bare.csv") +
                    " --json " + path("x.json") + " --report " + path("x.html") + " --out " +
                    path("x.yaml"),
                &log),
            0);
  EXPECT_NE(log.find("bare.csv"), std::string::npos) << log;
  EXPECT_NE(log.find("reference"), std::string::npos) << log;
  EXPECT_FALSE(fs::exists(path("x.yaml")));
}

}  // namespace
