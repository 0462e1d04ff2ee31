// Issue 5's accuracy claims on the simulated paper-like session (simulator defaults, seed 1:
// what scripts/demo.sh runs), through the real entry points: `hivecal simulate` writes the
// captures, `hivecal calibrate` reads them (decoder -> clock sync -> extraction -> solvers),
// the result is validated as `hivecal validate` does (fresh random poses against the
// simulator's noise-free truth).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/validation.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "sim/sim_model.hpp"
#include "testkit/cli_run.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::paper_session_test {
namespace {

using test::run;

constexpr long kValidationPoses = 1000;  // `hivecal validate` defaults
constexpr std::uint64_t kValidationSeed = 7;

/// The default session, simulated once for the whole suite.
class PaperSession : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = test::make_temp_dir("hivecal_paper");
    ASSERT_FALSE(dir_.empty());
    ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir_, "--seed", "1"}), cli::kExitOk);
  }
  static void TearDownTestSuite() {
    for (const char* name : {"robot.cap", "tracker.cap", "robot_joints.csv", "tracker.csv", "truth.json",
                             "truth_samples.csv", "ideal_samples.csv", "captures.json", "ideal.json", "paper.json"})
      std::remove((dir_ + "/" + name).c_str());
    ::rmdir(dir_.c_str());
  }
  static std::string path(const char* name) { return dir_ + "/" + name; }

  /// Validation MAE of a result file against the simulator's truth.json [m].
  static double validation_mae_m(const std::string& result_path) {
    record::CalibrationFile result;
    record::CalibrationFile truth;
    const port::Error r1 = record::read_calibration_json(result_path, &result);
    const port::Error r2 = record::read_calibration_json(path("truth.json"), &truth);
    EXPECT_TRUE(r1.ok()) << r1.message;
    EXPECT_TRUE(r2.ok()) << r2.message;
    return cli::validate_on_fresh_poses(result.model, result.base_to_tracker, truth.model, truth.base_to_tracker,
                                        kValidationPoses, kValidationSeed)
        .mae_m;
  }

  static std::string dir_;
};
std::string PaperSession::dir_;

/// The "methods" rows of a calibrate result: method name -> test MAE [m].
std::vector<std::pair<std::string, double>> test_mae_by_method(const std::string& result_path) {
  std::string text;
  std::vector<std::pair<std::string, double>> rows;
  EXPECT_TRUE(port::read_whole_file(result_path, port::kMaxTextInputBytes, &text).ok());
  textio::JsonValue root;
  EXPECT_TRUE(textio::parse_json(text, &root).ok());
  const textio::JsonValue* methods = root.find("methods");
  if (methods == nullptr) return rows;
  for (const textio::JsonValue& m : methods->array) {
    const textio::JsonValue* name = m.find("method");
    const textio::JsonValue* mae = m.find("test_mae_m");
    if (name != nullptr && mae != nullptr) rows.emplace_back(name->string, mae->number);
  }
  return rows;
}

// The default command from captures vs the same full-model fit on ideal paired samples:
// every tracker instant that is truly quasi-static by the extraction's rule (true tool speed,
// whatever the point's status: nothing dropped), paired with the true joints at that instant
// (true clock), the noise-free point plus the tracker's noise (same sigma, own draws).
// Both fit every sample (--split 1): a split keeps a stop's repeated readings together, and the
// robot's reported joints hold still at a stop while the ideal samples' true joints still creep
// at the end of a move, so a split would train the two on different shares of the stops.
// Claim: the captures' validation MAE is within 10 % of the ideal one.
TEST_F(PaperSession, CapturesReachTheValidationMaeOfIdealSamplesWithin10Percent) {
  sim::SimConfig config;  // what `simulate --seed 1` built
  config.seed = 1;
  const sim::Session session(config);
  record::CalibrationFile truth;
  ASSERT_TRUE(record::read_calibration_json(path("truth.json"), &truth).ok());
  ASSERT_EQ(truth.model.joints[1].a_m, session.truth().model.joints[1].a_m) << "not the simulated session";

  ASSERT_EQ(run(cli::calibrate_main, {"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--out",
                                      path("captures.json"), "--split", "1", "--quiet"}),
            cli::kExitOk);
  const double captures_m = validation_mae_m(path("captures.json"));

  // One noise draw moves the ideal fit's validation MAE by about +-12 % (29-38 um over ten
  // draws), as much as the claim's margin: the reference is the mean over kDraws draws.
  constexpr int kDraws = 4;
  const ExtractionConfig rule = make_extraction_config(session.truth().nominal);  // the quasi-static rule
  const std::vector<sim::TruthSample> truth_samples =
      sim::quasi_static_truth_samples(session, rule.max_speed_m_s, static_cast<double>(rule.window_us) * 1e-6);
  double ideal_m = 0.0;
  for (int draw = 0; draw < kDraws; ++draw) {
    std::vector<Sample> ideal;
    Random noise(0x6964656131ULL + static_cast<std::uint64_t>(draw));
    for (const sim::TruthSample& t : truth_samples) {
      Sample s;
      s.q_rad = t.q_rad;
      s.point_m = t.point_m;
      for (int axis = 0; axis < 3; ++axis) s.point_m(axis) += config.tracker_noise_m * noise.normal();
      ideal.push_back(s);
    }
    const port::Error written =
        textio::write_text_file(path("ideal_samples.csv"),
                                textio::format_samples_csv(Span<const Sample>(ideal.data(), ideal.size()), kSixJoints));
    ASSERT_TRUE(written.ok()) << written.message;
    ASSERT_EQ(run(cli::calibrate_main,
                  {"--samples", path("ideal_samples.csv"), "--out", path("ideal.json"), "--split", "1", "--quiet"}),
              cli::kExitOk);
    const double draw_m = validation_mae_m(path("ideal.json"));
    std::printf("ideal samples (%zu), noise draw %d: validation MAE %.2f um\n", ideal.size(), draw, draw_m * 1e6);
    ideal_m += draw_m / kDraws;
  }
  std::printf("validation MAE on %ld fresh poses: captures %.2f um, ideal samples %.2f um (mean of %d), ratio %.3f\n",
              kValidationPoses, captures_m * 1e6, ideal_m * 1e6, kDraws, captures_m / ideal_m);
  EXPECT_GT(ideal_m, 0.0);
  EXPECT_LE(captures_m, 1.10 * ideal_m);
}

// Paper-6 + ABC on the captures: the paper gets 75.4 -> 60.1 um (-20.3 %) against a baseline
// that keeps the tool guess. hivecal's baseline fits the tool point and the base with the
// nominal joints (issue 11: the fair comparison) and ABC starts from that tool point, so both
// rows move: 64.6 -> 34.3 um (-47 %) on the default session. The band 35-60 % pins that
// default session (seed 1's geometry errors were drawn for a paper-like session,
// docs/streams.md); the uncalibrated MAE must be paper-like too.
TEST_F(PaperSession, Paper6AbcImprovesTheUncalibratedTestMaeAsInThePaper) {
  ASSERT_EQ(run(cli::calibrate_main, {"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--params",
                                      "paper", "--method", "abc", "--out", path("paper.json"), "--quiet"}),
            cli::kExitOk);
  double uncalibrated_m = -1.0;
  double abc_m = -1.0;
  for (const auto& [method, mae_m] : test_mae_by_method(path("paper.json"))) {
    if (method == "uncalibrated") uncalibrated_m = mae_m;
    if (method == "ABC") abc_m = mae_m;
  }
  ASSERT_GT(uncalibrated_m, 0.0);
  ASSERT_GT(abc_m, 0.0);
  const double improvement = 1.0 - abc_m / uncalibrated_m;
  std::printf("test MAE: uncalibrated %.1f um, paper-6 ABC %.1f um, improvement %.1f %%\n", uncalibrated_m * 1e6,
              abc_m * 1e6, improvement * 100.0);
  EXPECT_GT(uncalibrated_m, 55e-6);  // paper: 75.4 um
  EXPECT_LT(uncalibrated_m, 95e-6);
  EXPECT_GE(improvement, 0.35);
  EXPECT_LE(improvement, 0.60);
}

}  // namespace
}  // namespace hivecal::paper_session_test
