// The stream path on sessions of another generator (tests/testkit/other_session.hpp: other
// moves, dwells, orientations, robot, timing and link faults than apps/sim): `hivecal
// calibrate` from the captures against the same LM fit handed the oracle's samples (true
// clock, every tracker instant whose true tool speed is below 2 mm/s). Issue 12's target: the
// captures' validation MAE within 1.10x of the oracle's on every session.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/validation.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_session.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::other_sessions_test {
namespace {

using test::run;

/// Validation MAE [m] of a result file against the session's truth on 1000 fresh poses.
double validation_mae_m(const std::string& result_path, const test::OtherSession& session) {
  record::CalibrationFile result;
  const port::Error parsed = record::read_calibration_json(result_path, &result);
  EXPECT_TRUE(parsed.ok()) << parsed.message;
  return cli::validate_on_fresh_poses(result.model, result.base_to_tracker, session.truth, session.base_to_tracker,
                                      1000, 7)
      .mae_m;
}

bool write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(bytes.data(), 1, bytes.size(), f) == bytes.size();
  return std::fclose(f) == 0 && ok;
}

/// Kept samples of a captures run, read back from the result's inputs facts.
void expect_captures_near_oracle(const test::OtherSessionConfig& config, const char* label) {
  const test::OtherSession session = test::make_other_session(config);
  const std::string dir = test::make_temp_dir("hivecal_other");
  ASSERT_FALSE(dir.empty());
  const std::string robot = dir + "/robot.cap", tracker = dir + "/tracker.cap", ideal = dir + "/oracle.csv";
  ASSERT_TRUE(write_bytes(robot, session.robot_capture));
  ASSERT_TRUE(write_bytes(tracker, session.tracker_capture));
  const port::Error written = textio::write_text_file(
      ideal, textio::format_samples_csv(Span<const Sample>(session.oracle.data(), session.oracle.size()), kSixJoints));
  ASSERT_TRUE(written.ok()) << written.message;
  char tool[96];
  std::snprintf(tool, sizeof tool, "%.6f,%.6f,%.6f", session.nominal.tool_m.x(), session.nominal.tool_m.y(),
                session.nominal.tool_m.z());
  const std::string model = robot_type_name(config.robot);
  ASSERT_EQ(run(cli::calibrate_main, {"--robot", robot, "--tracker", tracker, "--robot-model", model, "--tool", tool,
                                      "--method", "lm", "--out", dir + "/captures.json", "--quiet"}),
            cli::kExitOk)
      << label;
  ASSERT_EQ(run(cli::calibrate_main, {"--samples", ideal, "--robot-model", model, "--tool", tool, "--method", "lm",
                                      "--out", dir + "/oracle.json", "--quiet"}),
            cli::kExitOk)
      << label;
  // Samples kept by the extraction against the speed rule on the truth: all but the points the
  // tracker itself marks lost or unstable (the oracle keeps every status).
  std::string text;
  ASSERT_TRUE(port::read_whole_file(dir + "/captures.json", port::kMaxTextInputBytes, &text).ok());
  textio::JsonValue root;
  ASSERT_TRUE(textio::parse_json(text, &root).ok());
  const textio::JsonValue* extraction = root.find("extraction");
  ASSERT_NE(extraction, nullptr);
  const textio::JsonValue* kept = extraction->find("kept");
  ASSERT_NE(kept, nullptr);
  const double usable =
      static_cast<double>(session.oracle.size()) * (1.0 - config.beam_lost_probability - config.unstable_probability);
  std::printf("%-40s kept %.0f of the %zu instants the speed rule keeps on the truth (%.0f with a usable status)\n",
              label, kept->number, session.oracle.size(), usable);
  EXPECT_GE(kept->number, 0.9 * usable) << label;
  const double captures_m = validation_mae_m(dir + "/captures.json", session);
  const double oracle_m = validation_mae_m(dir + "/oracle.json", session);
  std::printf("%-40s %5.0f s, oracle samples %4zu: validation captures %.2f um, oracle %.2f um, ratio %.3f\n", label,
              session.duration_s, session.oracle.size(), captures_m * 1e6, oracle_m * 1e6, captures_m / oracle_m);
  EXPECT_LE(captures_m, 1.10 * oracle_m) << label;
  for (const char* name : {"robot.cap", "tracker.cap", "oracle.csv", "captures.json", "oracle.json"})
    std::remove((dir + "/" + name).c_str());
  ::rmdir(dir.c_str());
}

TEST(OtherSessions, ShortDwellsVariedOrientationsUr10) {
  test::OtherSessionConfig config;
  config.robot = RobotType::ur10;
  config.seed = 31;
  config.waypoints = 60;
  config.min_dwell_s = config.max_dwell_s = 0.2;
  expect_captures_near_oracle(config, "UR10, 0.2 s dwells, varied orientations");
}

TEST(OtherSessions, NoisyLossyLinksLargeDrift) {
  test::OtherSessionConfig config;
  config.seed = 32;
  config.waypoints = 40;
  config.min_dwell_s = 0.3;
  config.max_dwell_s = 2.0;
  config.drift = 450e-6;
  config.tracker_noise_m = 15e-6;
  config.beam_lost_probability = 0.05;
  config.unstable_probability = 0.03;
  config.byte_error_probability = 2e-5;
  expect_captures_near_oracle(config, "UR5, noisy lossy links, 450 ppm drift");
}

TEST(OtherSessions, PaperLikeStopsOtherMoves) {
  test::OtherSessionConfig config;
  config.seed = 33;
  config.waypoints = 38;
  config.min_dwell_s = 1.5;
  config.max_dwell_s = 3.0;
  config.joint_speed_rad_s = 0.5;
  config.drift = 40e-6;
  config.tracker_noise_m = 10e-6;
  config.beam_lost_probability = 0.01;
  config.unstable_probability = 0.01;
  config.byte_error_probability = 0.0;
  expect_captures_near_oracle(config, "UR5, paper-like stops, trapezoid moves");
}

}  // namespace
}  // namespace hivecal::other_sessions_test
