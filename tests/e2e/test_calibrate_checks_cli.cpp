// What `calibrate` says about a set too small for what it is asked (issue 54 M2, S9) and what
// a new user missed (issue 54, friction): the poses each cross-validation fold held out, the
// lab's flange -> probe transform as the tool, a hint when the arm looks like another UR.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/plan/inverse_kinematics.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"

namespace hivecal::calibrate_checks_cli_test {
namespace {

/// A samples CSV of `poses` random poses of `type` (tool 0,0,0.1695) seen by the example
/// tracker with 10 um noise, seeded.
std::string session_csv(RobotType type, std::size_t poses, std::uint64_t seed) {
  static Dataset<512> data;
  data.clear();
  Random random(seed);
  RobotModel truth = nominal_model(type);
  truth.tool_m = Vec3(0.0, 0.0, 0.1695);
  test::fill_dataset(truth, test::example_base_to_tracker(), poses, 1e-5, &random, &data);
  return textio::format_samples_csv(data.samples());
}

/// A pendant-like export of `poses` random poses of a nominal UR5e: q1..q6, the TCP (tool
/// 0,0,0.1 m) in the base frame and its rotation vector rx, ry, rz, SI; with `constant_rotation`
/// every row's rx, ry, rz are the first row's.
std::string pendant_csv(std::size_t poses, std::uint64_t seed, bool constant_rotation) {
  RobotModel arm = nominal_model(RobotType::ur5e);
  arm.tool_m = Vec3(0.0, 0.0, 0.1);
  Random random(seed);
  std::string out = "q1,q2,q3,q4,q5,q6,x,y,z,rx,ry,rz\n";
  Vec3 first_rotation = Vec3::Zero();
  for (std::size_t i = 0; i < poses; ++i) {
    const JointVector q = test::random_joints(&random);
    const Vec3 point_m = fk_tool_point(arm, q);
    Vec3 rotation = rotation_vector_of(fk_flange(arm, q).rotation);
    if (i == 0) first_rotation = rotation;
    if (constant_rotation) rotation = first_rotation;
    for (int j = 0; j < kSixJoints; ++j) out += textio::format_double(q(j)) + ",";
    for (int k = 0; k < 3; ++k) out += textio::format_double(point_m(k)) + ",";
    for (int k = 0; k < 3; ++k) out += textio::format_double(rotation(k)) + (k < 2 ? "," : "\n");
  }
  return out;
}

TEST(CalibrateChecks, TooFewPosesForTheModelAreSaid) {
  const test::TempDir dir;
  std::string err;
  // Two pendant poses: each gives a position and an orientation, 12 numbers for some 30 parameters.
  const std::string two = dir.write("two.csv", pendant_csv(2, 1, false));
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", two, "--robot-model", "ur5e", "--tool", "0,0,0.1", "--split", "1",
                                        "--quiet", "--out", dir.path() + "/two.json"},
                                       &err),
            cli::kExitWarnings);
  EXPECT_NE(err.find("warning: the 6 training samples stand at only 2 distinct poses (12 coordinates) for the "),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("too few poses for the model, so the fit passes through them"), std::string::npos) << err;
  EXPECT_EQ(err.find("this looks like"), std::string::npos) << err;  // no other arm on two poses
  // Six poses of one reflector: 18 coordinates for the UR5's 27 or so.
  const std::string six = dir.write("six.csv", session_csv(RobotType::ur5, 6, 2));
  EXPECT_EQ(
      test::run_capturing_stderr(
          cli::calibrate_main,
          {"--samples", six, "--split", "1", "--method", "lm", "--quiet", "--out", dir.path() + "/six.json"}, &err),
      cli::kExitWarnings);
  EXPECT_NE(err.find("stand at only 6 distinct poses (18 coordinates) for the"), std::string::npos) << err;
  EXPECT_NE(err.find("measure at least "), std::string::npos) << err;
  // Forty poses span it: nothing to say.
  const std::string forty = dir.write("forty.csv", session_csv(RobotType::ur5, 40, 2));
  EXPECT_EQ(
      test::run_capturing_stderr(
          cli::calibrate_main,
          {"--samples", forty, "--split", "1", "--method", "lm", "--quiet", "--out", dir.path() + "/forty.json"}, &err),
      cli::kExitOk)
      << err;
}

TEST(CalibrateChecks, ConstantOrientationColumnsAreSaid) {
  const test::TempDir dir;
  std::string err;
  const std::string constant = dir.write("constant.csv", pendant_csv(12, 4, true));
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", constant, "--robot-model", "ur5e", "--tool", "0,0,0.1", "--split",
                                        "1", "--quiet", "--out", dir.path() + "/constant.json"},
                                       &err),
            cli::kExitWarnings);
  EXPECT_NE(err.find("warning: the orientation columns rx, ry, rz hold one value on every row, and the fit's residual "
                     "sigma is "),
            std::string::npos)
      << err;
  EXPECT_NE(err.find("the orientation carries no information here"), std::string::npos) << err;
  // The measured orientation itself: consistent, nothing to say.
  const std::string measured = dir.write("measured.csv", pendant_csv(12, 4, false));
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", measured, "--robot-model", "ur5e", "--tool", "0,0,0.1", "--split",
                                        "1", "--quiet", "--out", dir.path() + "/measured.json"},
                                       &err),
            cli::kExitOk)
      << err;
}

TEST(CalibrateChecks, CrossValidationOnTooFewPosesSaysSo) {
  const test::TempDir dir;
  const std::string three = dir.write("three.csv", session_csv(RobotType::ur5, 3, 1));
  const std::string four = dir.write("four.csv", session_csv(RobotType::ur5, 4, 1));
  const std::string out = dir.path() + "/r.json";
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", three, "--split", "1", "--cv", "2", "--out", out}, &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--cv 2 on 3 samples: a fold trains on 1 of them, and a fit needs at least 3 (as --split's "
                     "training set): too few samples for 2 folds; measure more samples, or hold out fewer at a time "
                     "(more folds; --cv loo: one)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("same joint positions"), std::string::npos) << err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", three, "--split", "1", "--cv", "loo", "--out", out}, &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--cv loo on 3 samples: a fold trains on 2 of them"), std::string::npos) << err;
  EXPECT_EQ(err.find("hold out fewer"), std::string::npos) << err;  // loo holds out one already
  // Four poses leave three to every leave-one-out fold: the folds run.
  const int code = test::run_capturing_stderr(
      cli::calibrate_main, {"--samples", four, "--cv", "loo", "--method", "lm", "--quiet", "--out", out}, &err);
  EXPECT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << err;
  EXPECT_NE(test::read_text_file(out).find("\"cross_validation\""), std::string::npos);
}

/// "2-4, 7" -> {2, 3, 4, 7}.
std::vector<std::size_t> expand_ranges(const std::string& ranges) {
  std::vector<std::size_t> numbers;
  std::size_t at = 0;
  while (at < ranges.size()) {
    std::size_t end = ranges.find(", ", at);
    if (end == std::string::npos) end = ranges.size();
    const std::string range = ranges.substr(at, end - at);
    const std::size_t dash = range.find('-');
    const std::size_t first = std::stoul(range.substr(0, dash));
    const std::size_t last = dash == std::string::npos ? first : std::stoul(range.substr(dash + 1));
    for (std::size_t n = first; n <= last; ++n) numbers.push_back(n);
    at = end + 2;
  }
  return numbers;
}

TEST(CalibrateChecks, EachFoldSaysWhichLinesItHeldOut) {
  const test::TempDir dir;
  const std::string samples = dir.write("twelve.csv", session_csv(RobotType::ur5, 12, 3));
  const std::string out = dir.path() + "/r.json";
  ::testing::internal::CaptureStdout();
  const int code = test::run(cli::calibrate_main, {"--samples", samples, "--cv", "3", "--method", "lm", "--out", out});
  const std::string console = ::testing::internal::GetCapturedStdout();
  ASSERT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << console;
  EXPECT_NE(console.find("  fold  train  test  MAE [mm]  held out (lines of " + samples + ")"), std::string::npos)
      << console;
  const textio::JsonValue result = test::read_json_file(out);
  const textio::JsonValue* cv = result.find("cross_validation");
  ASSERT_NE(cv, nullptr);
  EXPECT_EQ(cv->find("held_out_of")->string, "lines of " + samples);
  const textio::JsonValue* folds = cv->find("per_fold");
  ASSERT_EQ(folds->array.size(), 3u);
  std::vector<int> held_by(14, 0);  // lines 2 .. 13 hold the 12 poses
  for (std::size_t k = 0; k < folds->array.size(); ++k) {
    const textio::JsonValue& fold = folds->array[k];
    const std::vector<std::size_t> lines = expand_ranges(fold.find("held_out")->string);
    EXPECT_EQ(static_cast<double>(lines.size()), fold.find("test_count")->number) << k;
    for (const std::size_t line : lines) {
      ASSERT_TRUE(line >= 2 && line <= 13) << line;
      ++held_by[line];
    }
    // The console shows the same ranges in the fold's row.
    EXPECT_NE(console.find(fold.find("held_out")->string + "\n"), std::string::npos) << console;
  }
  for (std::size_t line = 2; line <= 13; ++line) EXPECT_EQ(held_by[line], 1) << "line " << line << " held out";
}

TEST(CalibrateChecks, TheToolPointFromTheLabsFlangeProbeTransform) {
  const test::TempDir dir;
  const std::string samples = dir.write("session.csv", session_csv(RobotType::ur5, 30, 5));
  // The probe's frame turned 90 deg about the flange axis, its origin 169.5 mm out: as a
  // 4x4 of the tool frame's pose in the flange frame, and the other way round (a lab's T_TOOL_F).
  const std::string tool_in_flange = dir.write("tool_in_flange.txt",
                                               "0 -1 0 0\n"
                                               "1 0 0 0\n"
                                               "0 0 1 0.1695\n"
                                               "0 0 0 1\n");
  const std::string flange_in_tool = dir.write("flange_in_tool.txt",
                                               "# T_TOOL_F\n"
                                               "0. 1. 0. 0.\n"
                                               "-1. 0. 0. 0.\n"
                                               "0. 0. 1. -0.1695\n"
                                               "0. 0. 0. 1.\n");
  const std::string by_tool = dir.path() + "/by_tool.json";
  ASSERT_EQ(test::run(cli::calibrate_main,
                      {"--samples", samples, "--method", "lm", "--quiet", "--tool", "0,0,0.1695", "--out", by_tool}),
            cli::kExitOk);
  const std::string expected_tool =
      test::read_text_file(by_tool).substr(test::read_text_file(by_tool).find("\"tool\""), 80);
  for (const std::vector<std::string>& given :
       {std::vector<std::string>{"--tool-transform", tool_in_flange},
        std::vector<std::string>{"--tool-transform", flange_in_tool, "--tool-transform-inverse"}}) {
    const std::string out = dir.path() + "/by_transform.json";
    std::vector<std::string> args = {"--samples", samples, "--method", "lm", "--out", out};
    args.insert(args.end(), given.begin(), given.end());
    ::testing::internal::CaptureStdout();
    const int code = test::run(cli::calibrate_main, args);
    const std::string console = ::testing::internal::GetCapturedStdout();
    ASSERT_EQ(code, cli::kExitOk) << console;
    EXPECT_NE(console.find("tool point from --tool-transform " + given[1] + ": 0.000, 0.000, 169.500 mm"),
              std::string::npos)
        << console;
    EXPECT_NE(console.find("its rotation, 90.000 deg, is not used"), std::string::npos) << console;
    EXPECT_EQ(console.find("behind the flange"), std::string::npos) << console;
    // The same start as --tool: the same calibrated tool point.
    const std::string json = test::read_text_file(out);
    EXPECT_EQ(json.substr(json.find("\"tool\""), 80), expected_tool);
  }
  // The lab's file read the wrong way round puts the point behind the flange: said, with the fix.
  ::testing::internal::CaptureStdout();
  test::run(cli::calibrate_main, {"--samples", samples, "--method", "lm", "--tool-transform", flange_in_tool, "--out",
                                  dir.path() + "/behind.json"});
  const std::string behind = ::testing::internal::GetCapturedStdout();
  EXPECT_NE(behind.find("0.000, 0.000, -169.500 mm (the translation of the file's transform"), std::string::npos)
      << behind;
  EXPECT_NE(behind.find("the point lies behind the flange (z < 0): if the file is the flange's pose in the tool frame "
                        "(a lab's T_TOOL_F), add --tool-transform-inverse (the point at 0.000, 0.000, 169.500 mm)"),
            std::string::npos)
      << behind;
  // Refused: both tools, the inverse alone, a matrix that is no rigid transform, millimetres read as metres.
  const std::string sheared = dir.write("sheared.txt", "1 0.1 0 0\n0 1 0 0\n0 0 1 0.1\n0 0 0 1\n");
  const std::string in_mm = dir.write("mm.txt", "1 0 0 0\n0 1 0 0\n0 0 1 169.5\n0 0 0 1\n");
  test::expect_refusals(
      cli::calibrate_main, {"--samples", samples, "--out", dir.path() + "/no.json"},
      {{{"--tool", "0,0,0.1", "--tool-transform", tool_in_flange}, "give --tool or --tool-transform, not both"},
       {{"--tool-transform-inverse"}, "--tool-transform-inverse needs --tool-transform FILE"}});
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(
                cli::calibrate_main,
                {"--samples", samples, "--tool-transform", sheared, "--out", dir.path() + "/no.json"}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("sheared.txt: not a rigid transform"), std::string::npos) << err;
  EXPECT_EQ(test::run_capturing_stderr(
                cli::calibrate_main,
                {"--samples", samples, "--tool-transform", in_mm, "--out", dir.path() + "/no.json"}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("mm.txt: its translation is 169.5 m long in [m] (more than 100 m): looks like millimetres: use "
                     "--length-unit mm"),
            std::string::npos)
      << err;
}

TEST(CalibrateChecks, AUr10CalibratedAsTheDefaultUr5GetsTheHint) {
  const test::TempDir dir;
  const std::string samples = dir.write("ur10.csv", session_csv(RobotType::ur10, 40, 7));
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(
                cli::calibrate_main,
                {"--samples", samples, "--method", "lm", "--quiet", "--out", dir.path() + "/r.json"}, &err),
            cli::kExitWarnings);
  EXPECT_NE(
      err.find("warning: this looks like a ur10 (--robot-model ur10): its nominal geometry with the tool point and "
               "base fitted leaves 0.0"),
      std::string::npos)
      << err;
  EXPECT_NE(test::read_text_file(dir.path() + "/r.json").find("this looks like a ur10"), std::string::npos);
  // With the right model there is nothing to say.
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--samples", samples, "--robot-model", "ur10", "--method", "lm", "--quiet",
                                        "--out", dir.path() + "/r10.json"},
                                       &err),
            cli::kExitOk)
      << err;
  EXPECT_EQ(err.find("looks like"), std::string::npos) << err;
}

}  // namespace
}  // namespace hivecal::calibrate_checks_cli_test
