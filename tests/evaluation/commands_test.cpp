// What the commands of `selfsense` compute, in the evaluation library: the demo's figures of the
// typical stack, the inverse compensation over a trajectory and the main job's page input.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>
#include <vector>

#include "selfsense/evaluation/feedforward.hpp"
#include "selfsense/evaluation/main_job_input.hpp"
#include "selfsense/evaluation/stack_demo.hpp"
#include "selfsense/operators/hysteresis_creep.hpp"
#include "support/scratch_dir.hpp"
#include "support/transducer_data.hpp"

namespace selfsense::evaluation {
namespace {

// `selfsense demo --hold 2` printed (before the move into this library, and since): loop width
// 13.2 % of the stroke, the linear gain's error 22.93 % of the range, the inverse compensator's
// 8.93e-14 %, creep 1.52-1.71 % of each jump per decade. Asserted within 1.3x; the
// compensator's error at rounding level.
TEST(StackDemo, TheTypicalStacksFigures) {
  StackDemoSettings settings;
  settings.hold_s = 2.0;
  const StackDemoFigures f = stack_demo(settings);
  ASSERT_GT(f.stroke, 0.0);
  EXPECT_NEAR(f.stroke * 10e-3 * 1e6, 15.17, 0.01);  // um of a 10 mm stack
  EXPECT_GT(f.loop_width / f.stroke, 0.132 / 1.3);
  EXPECT_LT(f.loop_width / f.stroke, 0.132 * 1.3);
  const double range = 0.8 * f.stroke;
  EXPECT_GT(f.error_linear / range, 0.2293 / 1.3);
  EXPECT_LT(f.error_linear / range, 0.2293 * 1.3);
  EXPECT_LT(f.error_compensated / range, 1e-12);
  EXPECT_EQ(f.limited, 0U);
  ASSERT_EQ(f.stairs.size(), 5U);
  for (const StackDemoFigures::Step& step : f.stairs) {
    const double per_decade = step.creep / f.decades / step.jump;
    EXPECT_GT(per_decade, 0.0152 / 1.3);
    EXPECT_LT(per_decade, 0.0171 * 1.3);
  }
}

// The model is the plant here: the field the compensator finds for the strain the actuator side
// gives is the field that gave it.
TEST(Feedforward, FindsTheFieldThatGaveTheStrain) {
  constexpr double kTs = 1e-3;
  const models::TransducerModel model = test::typical_transducer(kTs);
  const models::SideModel& a = *model.actuator;
  operators::HysteresisCreep forward(a.op, a.sample_time);
  forward.set_history(a.history);
  std::vector<double> t;
  std::vector<double> e;
  std::vector<double> s;
  for (std::size_t k = 0; k < 3000; ++k) {
    t.push_back(static_cast<double>(k) * kTs);
    e.push_back(1e6 + 0.8e6 * std::sin(2.0 * std::numbers::pi * t.back()));
    s.push_back(forward.step(e.back()));
  }
  io::Recording trajectory;
  trajectory.set_column("t", t);
  trajectory.set_column("S", s);
  const FeedforwardRun run = feedforward(model, trajectory, 0.0, 2e6, "m.yaml", "s.csv");
  EXPECT_EQ(run.limited, 0U);
  ASSERT_EQ(run.recording.rows(), t.size());
  const auto field = run.recording.column("E");
  double worst = 0.0;
  for (std::size_t k = 0; k < e.size(); ++k)
    worst = std::max(worst, std::abs(field[k] - e[k]));
  EXPECT_LT(worst, 1e-6 * 2e6);
  EXPECT_FALSE(run.recording.has("u"));  // no geometry

  io::Recording slower;
  std::vector<double> t2 = t;
  for (double& v : t2)
    v *= 2.0;
  slower.set_column("t", t2);
  slower.set_column("S", s);
  EXPECT_THROW(static_cast<void>(feedforward(model, slower, 0.0, 2e6, "m.yaml", "s.csv")),
               io::RecordingError);
  models::TransducerModel sensor_only = model;
  sensor_only.actuator.reset();
  EXPECT_THROW(static_cast<void>(feedforward(sensor_only, trajectory, 0.0, 2e6, "m.yaml", "s.csv")),
               std::invalid_argument);
}

// A run whose SEGMENT.path names nothing and one whose recording is missing are on the page
// with their errors, and named among the problems; the summary keeps the damping line.
TEST(MainJobInput, NamesWhatItCannotRead) {
  const test::ScratchDir dir("main-job-input");
  test::write_text(dir.path() / "figures.txt",
                   "position: S_hat 0.1 %\ndamping: ratio 5.2\nforce: T_hat 1 %\n");
  test::write_text(dir.path() / "force.path", (dir.path() / "missing.csv").string() + "\n");
  const std::vector<std::string> segments{"position", "force"};
  const MainJobInput in = read_main_job(dir.path(), segments, "a title");
  EXPECT_EQ(in.page.title, "a title");
  ASSERT_EQ(in.page.runs.size(), 2U);
  EXPECT_EQ(in.page.runs[0].figures, "position: S_hat 0.1 %");
  EXPECT_NE(in.page.runs[0].error.find("no recording: "), std::string::npos);
  EXPECT_EQ(in.page.runs[1].kind, report::MainJobRun::Kind::kForce);
  EXPECT_NE(in.page.runs[1].error.find("no plot: "), std::string::npos);
  ASSERT_EQ(in.problems.size(), 2U);
  EXPECT_EQ(in.page.summary, std::vector<std::string>{"damping: ratio 5.2"});
}

}  // namespace
}  // namespace selfsense::evaluation
