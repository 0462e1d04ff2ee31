// What `calibrate` says about a set too small for what it is asked (issue 54 M2, S9) and what
// a new user missed (issue 54, friction): the poses each cross-validation fold held out, the
// lab's flange -> probe transform as the tool, a hint when the arm looks like another UR.
#include <gtest/gtest.h>

#include <algorithm>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "commands/streams.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/plan/inverse_kinematics.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/sim_capture.hpp"
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
  return textio::format_samples_csv(data.samples(), kSixJoints);
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

/// What `entry` writes to `out` (one of `args`) when run with `args`, its console swallowed;
/// "<exit N>" when it fails.
template <typename Main>
std::string output_of(Main entry, const std::vector<std::string>& args, const std::string& out) {
  ::testing::internal::CaptureStdout();
  std::string err;
  const int code = test::run_capturing_stderr(entry, args, &err);
  ::testing::internal::GetCapturedStdout();
  return code == cli::kExitOk ? test::read_text_file(out) : "<exit " + std::to_string(code) + ">: " + err;
}

// --tool-transform was calibrate's only: plan, iso9283 and extract take the lab's 4x4 through the
// same option helper (cli::tool_point_option), in --length-unit, and give what --tool gives with
// its translation; iso9283 refuses it beside a calibration as it refuses --tool.
TEST(CalibrateChecks, TheLabsTransformIsTheToolOfEveryCommandThatTakesOne) {
  const test::TempDir dir;
  const std::string in_mm = dir.write("tool_in_flange_mm.txt", "0 -1 0 10\n1 0 0 20\n0 0 1 150\n0 0 0 1\n");
  const std::vector<std::string> transform = {"--tool-transform", in_mm, "--length-unit", "mm"};
  const std::string in_m = dir.write("tool_in_flange.txt", "0 -1 0 0.01\n1 0 0 0.02\n0 0 1 0.15\n0 0 0 1\n");
  const std::vector<std::string> transform_m = {"--tool-transform", in_m};  // the reaches are in metres
  const auto with = [](std::vector<std::string> args, const std::vector<std::string>& tool) {
    args.insert(args.end(), tool.begin(), tool.end());
    return args;
  };
  // plan: the same poses.
  const std::string planned = dir.path() + "/planned.csv";
  const std::vector<std::string> plan = {"--robot-model", "ur5e", "--count",    "6", "--tracker-position", "2,0.5,0.6",
                                         "--candidates",  "256",  "--restarts", "1", "--refine",           "0",
                                         "--out",         planned};
  const std::string by_tool = output_of(cli::plan_main, with(plan, {"--tool", "0.01,0.02,0.15"}), planned);
  EXPECT_EQ(by_tool.substr(0, 18), "q1,q2,q3,q4,q5,q6\n") << by_tool;
  EXPECT_EQ(output_of(cli::plan_main, with(plan, transform), planned), by_tool);
  EXPECT_NE(output_of(cli::plan_main, plan, planned), by_tool);  // the tool matters to what is planned
  // iso9283 with the nominal model: the same table.
  RobotModel arm = nominal_model(RobotType::ur5);
  arm.tool_m = Vec3(0.01, 0.02, 0.15);
  Random random(9283);
  std::string reaches = "q1,q2,q3,q4,q5,q6,x,y,z\n";
  for (int pose = 0; pose < 5; ++pose) {
    const JointVector q = test::random_joints(&random);
    for (int cycle = 0; cycle < 3; ++cycle) {
      const Vec3 point_m = test::example_base_to_tracker().apply(fk_tool_point(arm, q)) +
                           Vec3(random.normal(), random.normal(), random.normal()) * 1e-5;
      for (int j = 0; j < kSixJoints; ++j) reaches += textio::format_double(q(j)) + ",";
      reaches += textio::format_double(point_m.x()) + "," + textio::format_double(point_m.y()) + "," +
                 textio::format_double(point_m.z()) + "\n";
    }
  }
  const std::string reached = dir.write("reaches.csv", reaches);
  const std::string table = dir.path() + "/iso.csv";
  const std::vector<std::string> iso = {"--samples", reached, "--robot-model", "ur5", "--out", table};
  const std::string iso_by_tool = output_of(cli::iso9283_main, with(iso, {"--tool", "0.01,0.02,0.15"}), table);
  EXPECT_EQ(std::count(iso_by_tool.begin(), iso_by_tool.end(), '\n'), 6) << iso_by_tool;
  EXPECT_EQ(output_of(cli::iso9283_main, with(iso, transform_m), table), iso_by_tool);
  EXPECT_NE(output_of(cli::iso9283_main, iso, table), iso_by_tool);
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(
                cli::iso9283_main,
                with({"--samples", reached, "--calibration", "unread.json", "--out", table}, transform_m), &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--tool-transform goes with --robot-model: a calibration result carries its own calibrated tool"),
            std::string::npos)
      << err;
  // extract: the same samples (its tool sets the speeds that tell the arm still).
  const test::SimCapture& capture = test::sim_capture();
  const std::string robot = dir.write("robot.cap", std::string(capture.robot_bytes.begin(), capture.robot_bytes.end()));
  const std::string tracker =
      dir.write("tracker.cap", std::string(capture.tracker_bytes.begin(), capture.tracker_bytes.end()));
  const std::string pairs = dir.path() + "/pairs.csv";
  const std::vector<std::string> extract = {"--robot", robot, "--tracker", tracker, "--samples", pairs};
  const std::string extracted = output_of(streams::extract_main, with(extract, {"--tool", "0.01,0.02,0.15"}), pairs);
  EXPECT_GT(std::count(extracted.begin(), extracted.end(), '\n'), 10) << extracted.substr(0, 200);
  EXPECT_EQ(output_of(streams::extract_main, with(extract, transform), pairs), extracted);
  EXPECT_NE(output_of(streams::extract_main, with(extract, {"--tool", "0,0,1"}), pairs), extracted);
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
