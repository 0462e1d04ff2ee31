// Numbers and advice on the command line (issue 54 M1, M4, M6): every numeric option goes
// through one check that names the option, its range with its unit and the value given, and
// says why a text that is a number to the eye is not one to a double (1e-400 underflows, 1e400
// overflows); messages advise only what the command has.
#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/streams.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "record/result_json.hpp"
#include "textio/json.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::cli_numbers_test {
namespace {

TEST(CliNumbers, OneCheckSaysTheRangeTheUnitAndWhy) {
  double value = 0.0;
  EXPECT_EQ(
      cli::check_number("--max-speed-mm-s", "1e9", cli::NumberRange{0.0, 1e6, true, true, "mm/s"}, &value).message,
      "--max-speed-mm-s must be within (0, 1e+06) mm/s, got '1e9'");
  EXPECT_EQ(cli::check_number("--x", "1e-400", cli::NumberRange{0.0, 1.0}, &value).message,
            "--x must be within [0, 1], got '1e-400': too small for a double (it underflows below 4.9e-324): give 0 "
            "or a larger value");
  EXPECT_EQ(cli::check_number("--x", "-1e400", cli::NumberRange{0.0, 1.0}, &value).message,
            "--x must be within [0, 1], got '-1e400': beyond a double's range (1.8e308)");
  EXPECT_EQ(cli::check_number("--x", "0.5 mm", cli::NumberRange{0.0, 1.0, false, false, "m"}, &value).message,
            "--x must be a number within [0, 1] m, got '0.5 mm': not a number");
  EXPECT_EQ(cli::check_number("--x", "nan", cli::NumberRange{0.0, 1.0}, &value).fault, port::Fault::usage);
  EXPECT_TRUE(cli::check_number("--x", "1e-310", cli::NumberRange{0.0, 1.0}, &value).ok());  // subnormal: a double
  EXPECT_EQ(value, 1e-310);
}

TEST(CliNumbers, CalibrateNamesEachOptionItsRangeAndTheValue) {
  test::expect_refusals(
      cli::calibrate_main, {"--samples", "unread.csv", "--out", "unwritten.json"},
      {
          {{"--compliance", "--gravity", "1e300,0,0"},
           "--gravity must be X,Y,Z (the direction of gravity in the robot base frame, any length), each within "
           "[-1e+06, 1e+06], got '1e300,0,0'"},
          {{"--tool", "1e-400,0,0"},
           "--tool must be X,Y,Z in metres, each within [-10, 10] m, got '1e-400,0,0': '1e-400' is too small for a "
           "double (it underflows below 4.9e-324)"},
          {{"--tool", "0,0,1e9"}, "--tool must be X,Y,Z in metres, each within [-10, 10] m, got '0,0,1e9'"},
          {{"--joint-sigma-deg", "100"}, "--joint-sigma-deg must be within [0, 57.2958) deg, got '100'"},
          {{"--joint-sigma-rad", "1e9"}, "--joint-sigma-rad must be within [0, 1) rad, got '1e9'"},
          {{"--max-change-mm", "1e10"}, "--max-change-mm must be within (0, 1e+06] mm, got '1e10'"},
          {{"--max-change-deg", "0"}, "--max-change-deg must be within (0, 360] deg, got '0'"},
          {{"--tracker-sigma-um", "1e9"}, "--tracker-sigma-um must be within (0, 1e+06) um, got '1e9'"},
          {{"--position-sigma-m", "1e-400"}, "--position-sigma-m must be within (0, 1) m, got '1e-400': too small"},
          {{"--orientation-lever-m", "2"}, "--orientation-lever-m must be within [0, 1] m, got '2'"},
          {{"--split", "0"}, "--split must be within (0, 1] (the training share), got '0'"},
          {{"--significance", "11"}, "--significance must be within [0, 10] sigma (or 'auto'), got '11'"},
          {{"--compliance", "masses", "--robot-model", "ur5", "--payload", "1e-400@0,0,0"},
           "--payload must be KG@X,Y,Z: its mass KG must be within [0, 10000) kg, got '1e-400': too small"},
          {{"--compliance", "masses", "--robot-model", "ur5", "--payload", "1@0,0,11"},
           "--payload must be KG@X,Y,Z: its centre must be X,Y,Z in the flange frame, each within [-10, 10] m"},
      });
}

TEST(CliNumbers, StreamCommandsSayTheRealRange) {
  test::expect_refusals(streams::extract_main, {"--robot", "r.cap", "--tracker", "t.cap"},
                        {
                            {{"--max-speed-mm-s", "1e9"}, "--max-speed-mm-s must be within (0, 1e+06), got '1e9'"},
                            {{"--window-s", "61"}, "--window-s must be within [0, 60], got '61'"},
                        });
  test::expect_refusals(sim::simulate_main, {"--out-dir", "/nonexistent/folder"},
                        {{{"--length-sigma-um", "1e10"}, "--length-sigma-um must be within [0, 100000], got '1e10'"}});
  test::expect_refusals(
      streams::record_main, {"--robot-port", "/nonexistent/port"},
      {{{"--duration-s", "-1"}, "--duration-s must be within [0, 1e+09] s (0: until Ctrl-C / SIGTERM), got '-1'"}});
}

// Options of several numbers (plan's cube, simulate's deflections and harmonic, --cv, the baud
// rates) went through their own parsers: 1e-400 or NaN was "not X,Y,Z,SIDE" without the reason,
// 115200.5 baud was taken as 115200. Each number now goes through check_number, named by its
// place in the option's form; 0 is advised for an underflow only where 0 is taken.
TEST(CliNumbers, EachNumberOfAnOptionOfSeveralIsCheckedAsOne) {
  double value = 0.0;
  EXPECT_EQ(cli::check_number("--x", "1e-400", cli::NumberRange{0.0, 1.0, true, false}, &value).message,
            "--x must be within (0, 1], got '1e-400': too small for a double (it underflows below 4.9e-324): give a "
            "larger value");
  double values[2] = {};
  const std::vector<cli::NumberField> pair = {{"A", cli::NumberRange{0.0, 1.0}}, {"B", cli::NumberRange{2.0, 3.0}}};
  EXPECT_TRUE(cli::check_numbers("--ab", "0.5,2.5", "two numbers", pair, values).ok());
  EXPECT_EQ(values[1], 2.5);
  EXPECT_EQ(cli::check_numbers("--ab", "0.5", "two numbers", pair, values).message,
            "--ab must be A,B (two numbers), got '0.5'");
  EXPECT_EQ(cli::check_numbers("--ab", "0.5,4", "two numbers", pair, values).message,
            "--ab A,B: B must be within [2, 3], got '4'");
  std::size_t count = 0;
  EXPECT_EQ(cli::check_count("--n", "2.5", cli::NumberRange{0.0, 9.0}, &count).message,
            "--n must be a whole number, not '2.5'");
  const std::vector<std::string> cell = {"--tracker-position", "2,0.5,0.6", "--out", "/nonexistent/folder/iso.csv"};
  test::expect_refusals(
      cli::plan_main, cell,
      {
          {{"--iso9283", "0.4,-0.3,0.5,1e-9"}, "--iso9283 X,Y,Z,SIDE: SIDE must be within [0.02, 10] m, got '1e-9'"},
          {{"--iso9283", "0.4,-0.3,1e-400,0.3"},
           "--iso9283 X,Y,Z,SIDE: Z must be within [-10, 10] m, got '1e-400': too small for a double"},
          {{"--iso9283", "0.4,nan,0.5,0.3"},
           "--iso9283 X,Y,Z,SIDE: Y must be a number within [-10, 10] m, got 'nan': not a number"},
          {{"--iso9283", "0.4,0.5,0.3"}, "--iso9283 must be X,Y,Z,SIDE (the cube's centre in the base frame"},
      });
  test::expect_refusals(
      sim::simulate_main, {"--out-dir", "/nonexistent/folder"},
      {
          {{"--compliance-urad", "1e-400,0"},
           "--compliance-urad J2,J3: J2 must be within [-10000, 10000] urad, got '1e-400': too small for a double"},
          {{"--compliance-urad", "40,nan"}, "--compliance-urad J2,J3: J3 must be a number within"},
          {{"--harmonic-urad", "3,1,1e5,0"},
           "--harmonic-urad J,K,S,C: S must be within [-10000, 10000] urad, got '1e5'"},
          {{"--harmonic-urad", "3.5,1,60,50"}, "the joint J and the order K are whole numbers, got '3.5,1,60,50'"},
          {{"--harmonic-urad", "7,1,60,50"}, "--harmonic-urad J,K,S,C: J must be within [1, 6], got '7'"},
      });
  // The joint of a harmonic is one of the arm's: seven for an iiwa 14.
  test::expect_refusals(
      sim::simulate_main, {"--out-dir", "/nonexistent/folder", "--robot-model", "iiwa14"},
      {
          {{"--harmonic-urad", "8,1,60,50"}, "--harmonic-urad J,K,S,C: J must be within [1, 7], got '8'"},
      });
  test::expect_refusals(
      cli::calibrate_main, {"--samples", "unread.csv", "--out", "unwritten.json"},
      {
          {{"--cv", "1e-400"}, "--cv must be within [2, 128] folds, or 'loo', got '1e-400': too small"},
          {{"--cv", "2.5"}, "--cv must be a whole number, not '2.5'"},
      });
  test::expect_refusals(
      streams::record_main, {"--robot-port", "/nonexistent/port"},
      {
          {{"--robot-baud", "115200.5"}, "--robot-baud must be a whole number, not '115200.5'"},
          {{"--robot-baud", "1234"}, "--robot-baud: unsupported baud rate 1234 (the port takes 9600, 19200, 38400"},
      });
}

TEST(CliAdvice, ABuiltInRobotNameWinsOverAFolderOfThatName) {
  const test::TempDir dir;
  ASSERT_EQ(::mkdir((dir.path() + "/ur5e").c_str(), 0700), 0);
  char previous[4096];
  ASSERT_NE(::getcwd(previous, sizeof previous), nullptr);
  ASSERT_EQ(::chdir(dir.path().c_str()), 0);
  textio::RobotDescription robot;
  bool from_file = true;
  const port::Error builtin = textio::robot_description_from_value("ur5e", &robot, &from_file);
  const port::Error named_file = textio::robot_description_from_value("./ur5e", &robot, nullptr);
  ASSERT_EQ(::chdir(previous), 0);
  EXPECT_TRUE(builtin.ok()) << builtin.message;
  EXPECT_FALSE(from_file);
  EXPECT_EQ(robot.robot, "ur5e");
  EXPECT_NE(named_file.message.find("'./ur5e': is a folder, not a regular file"), std::string::npos)
      << named_file.message;
}

TEST(CliAdvice, NoAdviceForOptionsTheCommandLacks) {
  const test::TempDir dir;
  const std::string joints = dir.write("joints.csv", "a,b,c,d,e,f\n0,0,0,0,0,0\n");
  std::string err;
  // check-robot and plan have no --columns: a header they cannot read does not suggest it.
  EXPECT_EQ(test::run_capturing_stderr(cli::check_robot_main, {"--robot-model", "ur5", "--joints", joints}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("unexpected header 'a,b,c,d,e,f'"), std::string::npos) << err;
  EXPECT_EQ(err.find("--columns"), std::string::npos) << err;
  const std::string limits = dir.write("limits.csv", "low,high\n-1,1\n");
  EXPECT_EQ(test::run_capturing_stderr(cli::plan_main,
                                       {"--robot-model", "ur5", "--count", "5", "--tracker-position", "2,0.5,0.6",
                                        "--joint-limits", limits, "--out", dir.path() + "/plan.csv"},
                                       &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("unexpected header 'low,high'"), std::string::npos) << err;
  EXPECT_EQ(err.find("--columns"), std::string::npos) << err;
  // A device given as an input that cannot be read from stdin is not told to use '-'.
  EXPECT_EQ(test::run_capturing_stderr(
                cli::calibrate_main,
                {"--robot", "/dev/null", "--tracker", "/dev/null", "--out", dir.path() + "/r.json"}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("'/dev/null': is a character device, not a regular file"), std::string::npos) << err;
  EXPECT_EQ(err.find("stdin"), std::string::npos) << err;
}

TEST(CliAdvice, TheArmsWithLinkMassesAreOneList) {
  // --help and the refusal of an arm without masses name the same types: every built-in one.
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(test::run(cli::calibrate_main, {"--help"}), cli::kExitOk);
  const std::string help = ::testing::internal::GetCapturedStdout();
  const std::string listed = "ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e";
  EXPECT_NE(help.find("or the link masses (" + listed + ")"), std::string::npos) << help;
  const test::TempDir dir;
  const std::string arm =
      dir.write("arm.json",
                "{\"robot\": \"abb-irb120\", \"dh\": [{\"theta_offset\": 0, \"d\": 0.29, "
                "\"a\": 0, \"alpha\": -1.5707963267948966}, {\"theta_offset\": -1.5707963267948966, "
                "\"d\": 0, \"a\": 0.27, \"alpha\": 0}, {\"theta_offset\": 0, \"d\": 0, \"a\": "
                "0.07, \"alpha\": -1.5707963267948966}, {\"theta_offset\": 0, \"d\": 0.302, \"a\": 0, "
                "\"alpha\": 1.5707963267948966}, {\"theta_offset\": 0, \"d\": 0, \"a\": 0, "
                "\"alpha\": -1.5707963267948966}, {\"theta_offset\": 0, \"d\": 0.072, \"a\": 0, "
                "\"alpha\": 0}], \"tool\": [0, 0, 0]}\n");
  std::string err;
  EXPECT_EQ(
      test::run_capturing_stderr(
          cli::calibrate_main,
          {"--samples", "unread.csv", "--robot-model", arm, "--compliance", "masses", "--out", "unwritten.json"}, &err),
      cli::kExitUsage);
  EXPECT_NE(err.find("known here for the built-in types (" + listed + ") only"), std::string::npos) << err;
}

TEST(CliFigures, ValidateBoundsTheSimulatedComplianceAndTheBase) {
  const test::TempDir dir;
  record::CalibrationFile file;
  file.robot = "ur5";
  file.model = nominal_model(RobotType::ur5);
  const std::string calibration = dir.write("calibration.json", record::format_calibration_json(file));
  const auto truth_with = [&](const char* joint2_rad) {
    return dir.write("truth.json", record::format_calibration_json(file, [&](textio::JsonWriter& json) {
                       json.key("simulation").begin_object().key("compliance").begin_object();
                       json.key("joint2_rad").value(std::stod(joint2_rad)).key("joint3_rad").value(0.0);
                       json.end_object().end_object();
                     }));
  };
  std::string err;
  EXPECT_EQ(
      test::run_capturing_stderr(cli::validate_main,
                                 {"--calibration", calibration, "--truth", truth_with("1e10"), "--poses", "10"}, &err),
      cli::kExitBadInput);
  EXPECT_NE(err.find("truth.json: \"simulation\".\"compliance\" joint2_rad = 10000000000 must be within +/-0.01 rad"),
            std::string::npos)
      << err;
  // A calibration whose points would overflow never gets as far as the figures: its base is
  // beyond any tracker's frame, refused by key as the result readers bound it (exit 3).
  record::CalibrationFile far = file;
  far.base_to_tracker.translation_m = Vec3(1e308, -1e308, 0.0);
  const std::string overflowing = dir.write("overflowing.json", record::format_calibration_json(far));
  EXPECT_EQ(
      test::run_capturing_stderr(cli::validate_main,
                                 {"--calibration", overflowing, "--truth", truth_with("2e-4"), "--poses", "10"}, &err),
      cli::kExitBadInput);
  EXPECT_NE(err.find("\"base_to_tracker\" puts the robot's base"), std::string::npos) << err;
}

}  // namespace
}  // namespace hivecal::cli_numbers_test
