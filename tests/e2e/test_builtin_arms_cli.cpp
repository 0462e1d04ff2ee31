// The built-in seven-axis arms through the command line: `--robot-model iiwa14` (panda, fr3,
// gen3, wam) is a description in the maker's convention with the maker's joint limits, which
// `check-robot` prints (table with joint types, limits, the flange at q = 0 in the maker's base);
// the WAM's table is the one the real WAM grid's targets were computed with; and the features
// made for Universal Robots' arms refuse these by name.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "commands/fit_checks.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/dh_convention.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/shared_data.hpp"
#include "textio/robot_description.hpp"

namespace hivecal::builtin_arms_cli_test {
namespace {

using test::run;

/// What `hivecal check-robot NAME` prints, and its exit code into *code.
std::string check_robot_output(const std::string& name, int* code) {
  ::testing::internal::CaptureStdout();
  *code = run(cli::check_robot_main, {name});
  return ::testing::internal::GetCapturedStdout();
}

/// The lines of `text`.
std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

#if HIVECAL_MAX_JOINTS >= 7

TEST(BuiltinArmsCli, ANameIsTheMakersTableConventionAndLimits) {
  textio::RobotDescription gen3;
  bool from_file = true;
  const port::Error error = textio::robot_description_from_value("gen3", &gen3, &from_file);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_FALSE(from_file);
  EXPECT_EQ(gen3.robot, "gen3");
  EXPECT_EQ(gen3.model.joint_count, 7);
  EXPECT_EQ(gen3.convention, DhConvention::modified);  // Kinova's base to frame 0 turn: alpha_0
  EXPECT_EQ(gen3.modified_base.alpha0_rad, math::kPi);
  ASSERT_TRUE(gen3.has_joint_limits);
  EXPECT_EQ(gen3.lower_rad(1), -2.41);
  EXPECT_EQ(gen3.upper_rad(5), 2.23);
  textio::RobotDescription ur5;
  ASSERT_TRUE(textio::robot_description_from_value("ur5", &ur5).ok());
  EXPECT_EQ(ur5.convention, DhConvention::standard);
  EXPECT_FALSE(ur5.has_joint_limits);  // UR's joints turn +-360 deg: as before
}

TEST(BuiltinArmsCli, CheckRobotPrintsTheTableWithTypesTheLimitsAndTheFlange) {
  struct Case {
    const char* name;
    const char* convention;
    const char* limits;  // the line's start
    const char* flange;  // the FK line's tool point at q = 0, in the maker's base (its end)
  };
  const Case cases[] = {
      {"iiwa14", "standard-dh", "joint limits: 1 -170.0..170.0 deg, 2 -120.0..120.0 deg, 3 -170.0..170.0 deg",
       "0.0000, 0.0000, 1306.0000 mm"},
      {"panda", "modified-dh",
       "joint limits: 1 -166.0..166.0 deg, 2 -101.0..101.0 deg, 3 -166.0..166.0 deg, 4 -176.0..-4.0",
       "88.0000, 0.0000, 926.0000 mm"},
      {"fr3", "modified-dh", "joint limits: 1 -157.2..157.2 deg", "88.0000, 0.0000, 926.0000 mm"},
      {"gen3", "modified-dh", "joint limits: 1 -360.0..360.0 deg, 2 -138.1..138.1 deg",
       "0.0000, -24.6000, 1187.3000 mm"},
      {"wam", "standard-dh", "joint limits: 1 -149.0..149.0 deg, 2 -114.6..114.6 deg", "0.0000, 0.0000, 910.0000 mm"},
  };
  for (const Case& c : cases) {
    int code = -1;
    const std::string out = check_robot_output(c.name, &code);
    EXPECT_EQ(code, cli::kExitOk) << c.name;
    const std::vector<std::string> lines = lines_of(out);
    ASSERT_GE(lines.size(), 13U) << out;
    EXPECT_EQ(lines[0], std::string("robot: ") + c.name + " (built-in table)");
    EXPECT_EQ(lines[1], std::string("convention: ") + c.convention);
    // The header, then a row per joint, each revolute.
    EXPECT_NE(lines[2].find("type"), std::string::npos) << lines[2];
    for (int j = 0; j < 7; ++j) {
      const std::string& row = lines[3 + static_cast<std::size_t>(j)];
      EXPECT_EQ(row.substr(0, 5), "    " + std::to_string(j + 1)) << c.name << ": " << row;
      EXPECT_EQ(row.substr(row.size() - 10), "  revolute") << c.name << ": " << row;
    }
    EXPECT_EQ(lines[10].find("    8"), std::string::npos) << c.name << ": seven rows, not " << lines[10];
    EXPECT_NE(out.find(std::string("\n") + c.limits), std::string::npos) << c.name << ":\n" << out;
    const std::string fk = "FK at q = 0 (q [deg] 0.000 0.000 0.000 0.000 0.000 0.000 0.000): tool 1 at ";
    const std::size_t at = out.find(fk);
    ASSERT_NE(at, std::string::npos) << c.name << ":\n" << out;
    std::string point = out.substr(at + fk.size());
    for (std::size_t minus = point.find("-0.0000,"); minus != std::string::npos; minus = point.find("-0.0000,"))
      point.erase(minus, 1);  // a zero rounded from below (sin pi) prints with its sign
    EXPECT_EQ(point.rfind(c.flange, 0), 0U) << c.name << ":\n" << out;
  }
}

/// The WAM grid (../shared/data/wam-grid): its targets are the nominal FK of the WAM table its
/// README states, with the SMR 44 mm out on the last axis; the built-in `wam` is that table, and
/// every commanded pose lies within Barrett's joint limits.
TEST(BuiltinArmsCli, TheWamGridsTargetsAreTheBuiltinWamsPoints) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("wam-grid/3D_WAM_uncalibrated_grid_cleaned.csv");
  std::ifstream file(test::shared_data_path("wam-grid/3D_WAM_uncalibrated_grid_cleaned.csv"));
  std::string line;
  ASSERT_TRUE(std::getline(file, line));
  ASSERT_EQ(line.rfind("step_order,x_t,y_t,z_t,x_dif,y_dif,z_dif,joint_1,", 0), 0U) << line;
  RobotModel wam = nominal_model(RobotType::wam);
  wam.tool_m = Vec3(0.0, 0.0, 0.044);
  JointVector lower;
  JointVector upper;
  ASSERT_EQ(maker_joint_limits(RobotType::wam, &lower, &upper), Status::ok);
  int poses = 0;
  double worst_m = 0.0;
  while (std::getline(file, line)) {
    std::vector<double> v;
    std::istringstream fields(line);
    for (std::string field; std::getline(fields, field, ',');) v.push_back(std::stod(field));
    ASSERT_EQ(v.size(), 14U) << line;
    JointVector q = JointVector::Zero();
    for (int j = 0; j < 7; ++j) q(j) = v[7 + static_cast<std::size_t>(j)] * math::kRadPerDeg;
    const Vec3 target_m = Vec3(v[1], v[2], v[3]) * 1e-3;
    worst_m = std::fmax(worst_m, (fk_tool_point(wam, q) - target_m).norm());
    for (int j = 0; j < 7; ++j) {
      EXPECT_TRUE(q(j) >= lower(j) && q(j) <= upper(j)) << "pose " << v[0] << " joint " << j + 1;
    }
    ++poses;
  }
  EXPECT_EQ(poses, 216);
  std::printf("WAM grid: targets vs the built-in wam's FK, worst %.4f mm\n", worst_m * 1e3);
  EXPECT_LT(worst_m, 1e-5);  // the file's targets are rounded; another table misses by centimetres
}

/// Samples of `type`'s nominal arm with its tool 0.1 m out, at random joints, seen by a tracker.
std::vector<Sample> nominal_samples(RobotType type, int count) {
  RobotModel model = nominal_model(type);
  model.tool_m = Vec3(0.0, 0.0, 0.1);
  Random random(53);
  std::vector<Sample> samples;
  for (int i = 0; i < count; ++i) {
    Sample sample;
    for (int j = 0; j < model.joint_count; ++j) sample.q_rad(j) = random.uniform(-1.5, 1.5);
    sample.point_m = Vec3(1.5, 0.2, -0.3) + fk_tool_point(model, sample.q_rad);
    sample.index = static_cast<std::uint32_t>(i);
    samples.push_back(sample);
  }
  return samples;
}

/// "This looks like a ...": among the arms of as many joints as the one named, a WAM's data
/// named an iiwa 14 is a WAM; a UR's data never suggests a seven-axis arm, nor the reverse.
TEST(BuiltinArmsCli, TheOtherArmHintComparesArmsOfTheSameJointCount) {
  const std::vector<Sample> wam = nominal_samples(RobotType::wam, 40);
  RobotModel iiwa = nominal_model(RobotType::iiwa14);
  iiwa.tool_m = Vec3(0.0, 0.0, 0.1);
  const std::string hint = cli::other_arm_hint("iiwa14", iiwa, Span<const Sample>(wam.data(), wam.size()));
  EXPECT_EQ(hint.rfind("this looks like a wam (--robot-model wam): ", 0), 0U) << hint;
  const std::vector<Sample> ur10 = nominal_samples(RobotType::ur10, 40);
  RobotModel ur5 = nominal_model(RobotType::ur5);
  ur5.tool_m = Vec3(0.0, 0.0, 0.1);
  EXPECT_EQ(cli::other_arm_hint("ur5", ur5, Span<const Sample>(ur10.data(), ur10.size()))
                .rfind("this looks like a ur10 (--robot-model ur10)", 0),
            0U);
}

/// The features made for Universal Robots' controllers refuse the seven-axis arms by name.
TEST(BuiltinArmsCli, UrOnlyFeaturesRefuseTheSevenAxisArms) {
  const test::TempDir dir("hivecal_arms");
  ASSERT_FALSE(dir.path().empty());
  std::string csv = "q1,q2,q3,q4,q5,q6,q7,x,y,z\n";
  for (const Sample& s : nominal_samples(RobotType::iiwa14, 30)) {
    for (int j = 0; j < 7; ++j) csv += std::to_string(s.q_rad(j)) + ",";
    csv += std::to_string(s.point_m.x()) + "," + std::to_string(s.point_m.y()) + "," + std::to_string(s.point_m.z()) +
           "\n";
  }
  const std::string samples = dir.write("iiwa.csv", csv);
  const std::string out = dir.path() + "/result.json";
  for (const char* name : {"iiwa14", "panda", "fr3", "gen3", "wam"}) {
    test::expect_refusals(
        cli::calibrate_main, {"--samples", samples, "--robot-model", name, "--out", out, "--quiet"},
        {{{"--ur-deltas", dir.path() + "/deltas.conf"},
          "--ur-deltas (calibration.conf) is a Universal Robots controller's (six revolute joints); " +
              std::string(name) + " has 7 revolute joints"},
         {{"--ur-calibration", samples},
          "a calibration.conf is a Universal Robots controller's (six revolute joints); " + std::string(name) +
              " has 7 revolute joints"}});
  }
  // Results of built-in seven-axis arms: the UR driver's kinematics YAML cannot hold them, a URDF can.
  struct Export {
    RobotType type;
    const char* message;
  };
  const Export exports[] = {
      {RobotType::iiwa14,
       "--format ur-kinematics: the UR kinematics YAML describes UR arms (six revolute joints); this arm has 7 "
       "revolute joints: use --format urdf"},
      {RobotType::panda,
       "--format ur-kinematics: the arm is described in modified DH: not a UR arm; use --format urdf"},
  };
  for (const Export& e : exports) {
    record::CalibrationFile file;
    file.robot = robot_type_name(e.type);
    file.model = nominal_model(e.type);
    file.convention = nominal_convention(e.type, &file.modified_base);
    const std::string result = dir.write(file.robot + ".json", record::format_calibration_json(file));
    std::string err;
    EXPECT_EQ(test::run_capturing_stderr(cli::export_main,
                                         {"--calibration", result, "--format", "ur-kinematics", "--ur-hash", "calib_1",
                                          "--out", dir.path() + "/kinematics.yaml"},
                                         &err),
              cli::kExitBadInput)
        << file.robot;
    EXPECT_NE(err.find(e.message), std::string::npos) << err;
    EXPECT_EQ(run(cli::export_main, {"--calibration", result, "--format", "urdf", "--out", dir.path() + "/arm.urdf"}),
              cli::kExitOk)
        << file.robot;
  }
}

#endif

}  // namespace
}  // namespace hivecal::builtin_arms_cli_test
