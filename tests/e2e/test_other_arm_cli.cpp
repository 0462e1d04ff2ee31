// `hivecal calibrate --robot-model irb120.json`: a non-UR arm described in the result's own
// JSON shape, in standard and in modified DH, calibrated from a testkit-written samples CSV;
// the result keeps the convention it was given and predicts the true points.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_arms.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "hivecal/port/input_file.hpp"
#include "record/result_json.hpp"

namespace hivecal::other_arm_cli_test {
namespace {

using test::OtherArm;
using test::run;

/// The description file of the IRB120-like arm in `convention` (tool guessed on the flange axis).
std::string description_text(DhConvention convention) {
  record::CalibrationFile file;
  file.robot = "abb-irb120";
  file.convention = convention;
  file.model = test::other_arm_model(OtherArm::irb120);
  file.model.tool_m = Vec3(0.0, 0.0, 0.1);
  return record::format_calibration_json(file);  // a result-shaped file: also a valid model
}

/// Mean distance [m] between a result's and the truth's tracker-frame points on fresh poses.
double fresh_mae_m(const record::CalibrationFile& r, const RobotModel& truth, const RigidTransform& base) {
  Random random(99);
  double sum_m = 0.0;
  for (int i = 0; i < 500; ++i) {
    const JointVector q = test::other_arm_joints(&random);
    sum_m += (r.base_to_tracker.apply(fk_tool_point(r.model, q)) - base.apply(fk_tool_point(truth, q))).norm();
  }
  return sum_m / 500.0;
}

TEST(OtherArmCli, CalibratesAnIrb120DescriptionInEitherConvention) {
  const test::TempDir dir("hivecal_arm");
  ASSERT_FALSE(dir.path().empty());
  Random random(2026);
  const RobotModel truth = test::other_arm_truth(OtherArm::irb120, &random);
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<200> samples;
  samples.clear();
  test::fill_other_arm(truth, base, 200, 1e-5, &random, &samples);
  const std::string csv = dir.write("samples.csv", textio::format_samples_csv(samples.samples(), kSixJoints));
  const std::string standard = dir.write("irb120.json", description_text(DhConvention::standard));
  const std::string modified = dir.write("irb120-craig.json", description_text(DhConvention::modified));

  record::CalibrationFile results[2];
  const std::string models[2] = {standard, modified};
  for (int k = 0; k < 2; ++k) {
    const std::string out = dir.path() + "/result" + std::to_string(k) + ".json";
    ASSERT_EQ(run(cli::calibrate_main, {"--robot-model", models[k], "--samples", csv, "--out", out, "--quiet"}),
              cli::kExitOk);
    std::string text;
    ASSERT_TRUE(port::read_whole_file(out, port::kMaxTextInputBytes, &text).ok());
    EXPECT_NE(text.find(k == 0 ? "\"standard-dh\"" : "\"modified-dh\""), std::string::npos);
    EXPECT_NE(text.find("\"abb-irb120\""), std::string::npos);
    EXPECT_NE(text.find("\"paper-5, tool fitted"), std::string::npos);  // ABC on the IRB120's five link lengths
    const port::Error parsed = record::parse_calibration_json(text, out, &results[k]);
    ASSERT_TRUE(parsed.ok()) << parsed.message;
    const double mae_m = fresh_mae_m(results[k], truth, base);
    std::printf("%s: fresh-pose MAE %.2f um\n", models[k].c_str(), mae_m * 1e6);
    EXPECT_LT(mae_m, 1e-5);
    // the result is a valid start model again
    ASSERT_EQ(run(cli::calibrate_main, {"--robot-model", out, "--samples", csv, "--method", "lm", "--out",
                                        dir.path() + "/again.json", "--quiet"}),
              cli::kExitOk);
  }
  // The same start (modified rows convert exactly), so the same calibration: the two files
  // predict the same points.
  Random poses(5);
  for (int i = 0; i < 200; ++i) {
    const JointVector q = test::other_arm_joints(&poses);
    const Vec3 a = results[0].base_to_tracker.apply(fk_tool_point(results[0].model, q));
    const Vec3 b = results[1].base_to_tracker.apply(fk_tool_point(results[1].model, q));
    EXPECT_LE((a - b).norm(), 1e-12);
  }
  // A bad description is named.
  const std::string bad = dir.write("bad.json", "{\"convention\": \"modified-dh\", \"dh\": [], \"tool\": [0, 0, 0]}");
  EXPECT_EQ(
      run(cli::calibrate_main, {"--robot-model", bad, "--samples", csv, "--out", dir.path() + "/x.json", "--quiet"}),
      cli::kExitBadInput);
}

// predict on a modified-DH result with a base offset (alpha_0, a_0): --frame base gives the
// points in the file's own base frame, --frame tracker its base_to_tracker times those.
TEST(OtherArmCli, PredictsInTheModifiedDhFilesOwnFrames) {
  const test::TempDir dir("hivecal_arm");
  ASSERT_FALSE(dir.path().empty());
  ModifiedDhRow rows[kSixJoints];
  Vec3 tool_m;
  const ModifiedDhBase offset{0.02, -0.015};
  test::other_arm_modified(OtherArm::kr6_r900, offset, rows, &tool_m);
  record::CalibrationFile file;
  file.robot = "kuka-kr6-r900";
  file.convention = DhConvention::modified;
  ASSERT_EQ(model_from_modified_dh(rows, tool_m, &file.model, &file.modified_base), Status::ok);
  const RigidTransform file_base_to_tracker = test::example_base_to_tracker();  // what the file will hold
  file.base_to_tracker = file_base_to_tracker.then_after(file.modified_base.transform());
  const std::string result = dir.write("kr6.json", record::format_calibration_json(file));
  Random random(4);
  std::vector<JointVector> poses;
  for (int i = 0; i < 20; ++i) poses.push_back(test::other_arm_joints(&random));
  const std::string joints_csv = dir.write(
      "joints.csv", textio::format_joints_csv(Span<const JointVector>(poses.data(), poses.size()), kSixJoints));
  for (const char* frame : {"base", "tracker"}) {
    const std::string out = dir.path() + "/" + frame + ".csv";
    ASSERT_EQ(run(cli::predict_main, {"--calibration", result, "--joints", joints_csv, "--frame", frame, "--out", out}),
              cli::kExitOk);
    std::string text;
    ASSERT_TRUE(port::read_whole_file(out, port::kMaxTextInputBytes, &text).ok());
    std::size_t at = text.find('\n') + 1;  // after the header
    for (const JointVector& q : poses) {
      double x = 0, y = 0, z = 0;
      ASSERT_EQ(std::sscanf(text.c_str() + at, "%lf,%lf,%lf", &x, &y, &z), 3);
      at = text.find('\n', at) + 1;
      const Vec3 in_base = test::modified_chain_point(rows, tool_m, q);
      const Vec3 expected = std::string(frame) == "base" ? in_base : file_base_to_tracker.apply(in_base);
      EXPECT_LE((Vec3(x, y, z) - expected).norm(), 1e-12) << frame;
    }
  }
}

// The whole chain on a modified-DH IRB120: simulate (captures and truth of the described
// arm) -> calibrate from the captures -> a modified-DH result close to the truth.
TEST(OtherArmCli, SimulatesAndCalibratesAModifiedDhIrb120FromCaptures) {
  const test::TempDir dir("hivecal_arm");
  ASSERT_FALSE(dir.path().empty());
  const std::string model = dir.write("irb120-craig.json", description_text(DhConvention::modified));
  ASSERT_EQ(run(sim::simulate_main, {"--robot-model", model, "--out-dir", dir.path(), "--waypoints", "40",
                                     "--duration-s", "240", "--errors", "large"}),
            cli::kExitOk);
  record::CalibrationFile truth;
  const port::Error read = record::read_calibration_json(dir.path() + "/truth.json", &truth);
  ASSERT_TRUE(read.ok()) << read.message;
  EXPECT_EQ(truth.robot, "abb-irb120");
  EXPECT_EQ(truth.convention, DhConvention::modified);
  const std::string out = dir.path() + "/result.json";
  ASSERT_EQ(run(cli::calibrate_main, {"--robot", dir.path() + "/robot.cap", "--tracker", dir.path() + "/tracker.cap",
                                      "--robot-model", model, "--method", "lm", "--out", out, "--quiet"}),
            cli::kExitOk);
  std::string text;
  ASSERT_TRUE(port::read_whole_file(out, port::kMaxTextInputBytes, &text).ok());
  record::CalibrationFile result;
  ASSERT_TRUE(record::parse_calibration_json(text, out, &result).ok());
  EXPECT_EQ(result.convention, DhConvention::modified);
  textio::JsonValue root;
  ASSERT_TRUE(textio::parse_json(text, &root).ok());
  const double test_mae_m = root.find("metrics")->find("test")->find("mae_m")->find("3d")->number;
  const double uncalibrated_m = root.find("uncalibrated_metrics")->find("test")->find("mae_m")->find("3d")->number;
  // Fresh poses spread wider than the session's waypoints, and the simulator's joint
  // compliance is not in the model: the generalisation error is larger than the test error.
  const double fresh_m = fresh_mae_m(result, truth.model, truth.base_to_tracker);
  std::printf(
      "simulated IRB120 (modified DH) from captures: test MAE %.1f um (uncalibrated %.1f um), fresh-pose MAE %.1f um\n",
      test_mae_m * 1e6, uncalibrated_m * 1e6, fresh_m * 1e6);
  EXPECT_LT(test_mae_m, 5e-5);
  EXPECT_LT(test_mae_m, 0.05 * uncalibrated_m);
  EXPECT_LT(fresh_m, 3e-4);
}

}  // namespace
}  // namespace hivecal::other_arm_cli_test
