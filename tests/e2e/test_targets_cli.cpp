// Several reflectors per pose end to end: a samples CSV with a `target` column, calibrate
// (every target's tool point in the result's "tools"), predict --target K; a bad target in
// the CSV or on the command line is refused and named.
#include <gtest/gtest.h>

#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/target_data.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "record/result_json.hpp"

namespace hivecal::targets_cli_test {
namespace {

using test::run;

TEST(TargetsCsv, TargetColumnIsReadAndABadOneRefusedWithItsLine) {
  const test::TempDir dir("hivecal_targets");
  ASSERT_FALSE(dir.path().empty());
  Random random(3);
  static Dataset<64> written;
  written.clear();
  const RobotModel truth = test::with_plate(nominal_model(RobotType::ur5), Vec3(0.0, 0.0, 0.17));
  test::fill_target_dataset(truth, test::example_base_to_tracker(), 5, 3, 1e-5, &random, &written);
  const std::string text = textio::format_samples_csv(written.samples(), kSixJoints);
  EXPECT_EQ(text.substr(0, text.find('\n')), "q1,q2,q3,q4,q5,q6,x,y,z,target");
  static Dataset<64> read_back;
  read_back.clear();
  ASSERT_TRUE(textio::read_samples_csv(dir.write("s.csv", text), &read_back).ok());
  ASSERT_EQ(read_back.size(), 15u);
  for (std::size_t i = 0; i < 15; ++i) {
    EXPECT_EQ(read_back.samples()[i].target, static_cast<int>(i % 3));
    EXPECT_EQ(read_back.samples()[i].point_m, written.samples()[i].point_m);
  }
  // Without the column every row is target 1.
  read_back.clear();
  ASSERT_TRUE(
      textio::read_samples_csv(dir.write("one.csv", "q1,q2,q3,q4,q5,q6,x,y,z\n0,0,0,0,0,0,1,2,3\n"), &read_back).ok());
  EXPECT_EQ(read_back.samples()[0].target, 0);
  for (const char* bad : {"0", "4", "1.5", "-1"}) {
    read_back.clear();
    const std::string path = dir.write("bad.csv", std::string("q1,q2,q3,q4,q5,q6,x,y,z,target\n0,0,0,0,0,0,1,2,3,1\n"
                                                              "0,0,0,0,0,0,1,2,3,") +
                                                      bad + "\n");
    const port::Error error = textio::read_samples_csv(path, &read_back);
    EXPECT_FALSE(error.ok()) << bad;
    EXPECT_NE(error.message.find("bad.csv:3:"), std::string::npos) << error.message;
    EXPECT_NE(error.message.find("target"), std::string::npos) << error.message;
  }
}

/// Predicted points of target K (1-based) of `result` on `joints_csv`, via the CLI.
std::vector<Vec3> predict_target(const test::TempDir& dir, const std::string& result, const std::string& joints_csv,
                                 int target) {
  const std::string out = dir.path() + "/predicted" + std::to_string(target) + ".csv";
  EXPECT_EQ(run(cli::predict_main,
                {"--calibration", result, "--joints", joints_csv, "--target", std::to_string(target), "--out", out}),
            cli::kExitOk);
  std::string text;
  EXPECT_TRUE(port::read_whole_file(out, port::kMaxTextInputBytes, &text).ok());
  std::vector<Vec3> points;
  std::size_t at = text.find('\n') + 1;
  while (at < text.size()) {
    Vec3 p;
    EXPECT_EQ(std::sscanf(text.c_str() + at, "%lf,%lf,%lf", &p.x(), &p.y(), &p.z()), 3);
    points.push_back(p);
    at = text.find('\n', at) + 1;
  }
  return points;
}

TEST(TargetsCli, CalibratesThreeReflectorsAndPredictsEachTarget) {
  const test::TempDir dir("hivecal_targets");
  ASSERT_FALSE(dir.path().empty());
  Random random(2027);
  const Vec3 tool_m(0.01, -0.004, 0.172);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m), tool_m);
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<300> samples;
  samples.clear();
  test::fill_target_dataset(truth, base, 80, 3, 1e-5, &random, &samples);
  const std::string csv = dir.write("samples.csv", textio::format_samples_csv(samples.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(run(cli::calibrate_main, {"--robot-model", "ur5", "--tool", "0,0,0.17", "--samples", csv, "--method", "lm",
                                      "--out", result, "--quiet"}),
            cli::kExitOk);
  record::CalibrationFile file;
  const port::Error parsed = record::read_calibration_json(result, &file);
  ASSERT_TRUE(parsed.ok()) << parsed.message;
  EXPECT_EQ(file.target_count, 3);

  std::vector<JointVector> poses;
  for (int i = 0; i < 30; ++i) poses.push_back(test::random_joints(&random));
  const std::string joints_csv = dir.write(
      "joints.csv", textio::format_joints_csv(Span<const JointVector>(poses.data(), poses.size()), kSixJoints));
  for (int target = 1; target <= 3; ++target) {
    const std::vector<Vec3> points = predict_target(dir, result, joints_csv, target);
    ASSERT_EQ(points.size(), poses.size());
    double worst_m = 0.0;
    for (std::size_t i = 0; i < poses.size(); ++i) {
      worst_m = std::fmax(worst_m, (points[i] - base.apply(fk_target_point(truth, poses[i], target - 1))).norm());
    }
    std::printf("target %d: worst fresh-pose error %.2f um\n", target, worst_m * 1e6);
    EXPECT_LT(worst_m, 5e-5) << "target " << target;
  }
  // The default abc+lm: ABC on the link lengths with every sample's own tool point (fixed
  // there, from the baseline's fit), then LM: the same accuracy.
  const std::string paper = dir.path() + "/abc_lm.json";
  ASSERT_EQ(run(cli::calibrate_main,
                {"--robot-model", "ur5", "--tool", "0,0,0.17", "--samples", csv, "--out", paper, "--quiet"}),
            cli::kExitOk);
  for (int target = 1; target <= 3; ++target) {
    const std::vector<Vec3> points = predict_target(dir, paper, joints_csv, target);
    ASSERT_EQ(points.size(), poses.size());
    for (std::size_t i = 0; i < poses.size(); ++i) {
      EXPECT_LT((points[i] - base.apply(fk_target_point(truth, poses[i], target - 1))).norm(), 5e-5);
    }
  }
  // Target 4 is not in the result; 0 and text are no target numbers.
  for (const char* bad : {"4", "0", "two"}) {
    EXPECT_EQ(run(cli::predict_main,
                  {"--calibration", result, "--joints", joints_csv, "--target", bad, "--out", dir.path() + "/x.csv"}),
              cli::kExitUsage)
        << bad;
  }
  // The result is a valid start model again, with its tool points.
  record::CalibrationFile again;
  std::string text;
  ASSERT_TRUE(port::read_whole_file(result, port::kMaxTextInputBytes, &text).ok());
  EXPECT_NE(text.find("\"tools\""), std::string::npos);
  EXPECT_NE(text.find("\"tool3_z\""), std::string::npos);  // estimated, with its sigma
  ASSERT_TRUE(record::parse_calibration_json(text, result, &again).ok());
  EXPECT_EQ(again.model.other_tools_m[1], file.model.other_tools_m[1]);
  const std::string mismatch =
      dir.write("mismatch.json", text.substr(0, text.find("\"tools\"")) + "\"tools\": [[9, 9, 9]]," +
                                     text.substr(text.find("\"base_to_tracker\"")));
  EXPECT_FALSE(record::read_calibration_json(mismatch, &again).ok());
}

// Three reflectors on an arm with joint errors no rigid model takes (testkit
// fill_plate_with_joint_errors, seed 2): one pose sits at the blunder threshold, failing while
// fitted and passing when left out. The command line keeps it, names it and says why, and the
// result's verdict is at_threshold; a row set aside would have had to fail the final test.
TEST(TargetsCli, APoseAtTheThresholdIsKeptAndNamedByItsLine) {
  const test::TempDir dir("hivecal_threshold");
  ASSERT_FALSE(dir.path().empty());
  static Dataset<300> written;
  written.clear();
  const Vec3 tool_m(0.012, -0.006, 0.17);
  test::fill_plate_with_joint_errors(2, 100, tool_m, 100, 0.0, &written);
  const std::string samples = dir.write("plate.csv", textio::format_samples_csv(written.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(run(cli::calibrate_main, {"--samples", samples, "--robot-model", "ur5", "--tool", "0.012,-0.006,0.17",
                                      "--quiet", "--out", result, "--report", dir.path() + "/report"}),
            0);
  const std::string json = test::read_text_file(result);
  EXPECT_NE(json.find("\"blunder_verdict\": \"at_threshold\""), std::string::npos);
  EXPECT_NE(json.find("kept at the threshold: " + samples + ":245, w 8."),
            std::string::npos);  // pose 81: lines 245-247
  EXPECT_EQ(json.find("set aside as a blunder"), std::string::npos);
  EXPECT_NE(test::read_text_file(dir.path() + "/report/index.html").find("A pose at the threshold fails the test"),
            std::string::npos);
}

// Many poses failing is the model's fault, not a threshold's: no pose is named as kept at the
// threshold (only the verdict at_threshold names those), and the console says the model is wrong.
TEST(TargetsCli, ManyFailingPosesAreNotNamedAsAtTheThreshold) {
  const test::TempDir dir("hivecal_many_failing");
  ASSERT_FALSE(dir.path().empty());
  static Dataset<256> written;
  written.clear();
  Random random(11);
  RobotModel truth = nominal_model(RobotType::ur5);
  truth.tool_m = Vec3(0.0, 0.0, 0.15);
  test::fill_dataset(truth, test::example_base_to_tracker(), 200, 1e-5, &random, &written);
  static Dataset<256> shifted;  // 15 of the 200 poses (7.5 %) 2 mm off: more than the 5 % a search removes
  shifted.clear();
  for (const Sample& s : written.samples()) {
    ASSERT_EQ(shifted.add(s.q_rad, s.point_m + Vec3(0.0, 0.0, s.index % 13 == 5 ? 2e-3 : 0.0)), Status::ok);
  }
  const std::string samples = dir.write("shifted.csv", textio::format_samples_csv(shifted.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  const int code = run(cli::calibrate_main, {"--samples", samples, "--robot-model", "ur5", "--tool", "0,0,0.15",
                                             "--method", "lm", "--quiet", "--out", result});
  ASSERT_TRUE(code == 0 || code == 5) << code;  // 5: written, with a warning (the shifted poses bend the fit)
  const std::string json = test::read_text_file(result);
  EXPECT_NE(json.find("\"blunder_verdict\": \"model_error\""), std::string::npos);
  EXPECT_NE(json.find("the model, not the data, is wrong"), std::string::npos);
  EXPECT_EQ(json.find("kept at the threshold"), std::string::npos);
}

}  // namespace
// Few poses of an arm with unmodelled effects, the default split: the fit of 6 poses predicts
// its 2 test poses no better than the effects and the test rejects both. The command line sets
// none aside (a set shrunk by them failed its own test poses in turn, down to an unfittable
// base frame), and the console, the result and the report say why. Plain least squares
// (--prior off): the default prior holds what 6 poses do not determine, and its fit predicts them.
TEST(TargetsCli, TestPosesTheFitCannotPredictAreNotSetAside) {
  const test::TempDir dir("hivecal_prediction_error");
  ASSERT_FALSE(dir.path().empty());
  static Dataset<16> written;
  written.clear();
  Random random(3);
  RobotModel truth = nominal_model(RobotType::ur5);
  truth.tool_m = Vec3(0.0, 0.0, 0.15);
  test::fill_with_unmodelled_effect(truth, test::example_base_to_tracker(), 8, &random, &written);
  const std::string samples = dir.write("few.csv", textio::format_samples_csv(written.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  const int code =
      run(cli::calibrate_main, {"--samples", samples, "--robot-model", "ur5", "--tool", "0,0,0.15", "--quiet", "--out",
                                result, "--report", dir.path() + "/report", "--prior", "off"});
  ASSERT_TRUE(code == 0 || code == 5) << code;  // 5: written, with a warning (the test error)
  const std::string json = test::read_text_file(result);
  EXPECT_NE(json.find("\"blunder_verdict\": \"prediction_error\""), std::string::npos);
  EXPECT_NE(json.find("1 test pose(s) fail as predictions"), std::string::npos);
  EXPECT_EQ(json.find("set aside as a blunder"), std::string::npos);
  EXPECT_NE(test::read_text_file(dir.path() + "/report/index.html").find("More test poses fail as predictions"),
            std::string::npos);
}

}  // namespace hivecal::targets_cli_test
