// `hivecal calibrate` with an arm of seven joints (issue 53): a seven-row description and a
// q1..q7 samples file calibrate; the same file against a six-joint model is refused naming both
// counts (it used to drop q7 and fit a UR5); a lab's joint_1 .. joint_7 read through --columns.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "hivecal/core/math.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/temp_dir.hpp"
#include "textio/csv.hpp"
#include "textio/robot_description.hpp"
#include "textio/text_util.hpp"

namespace hivecal::joint_count_cli_test {
namespace {

using test::ManyJointArm;

/// Mean distance [m] between a result's and the truth's tracker-frame points on fresh poses.
double fresh_mae_m(const record::CalibrationFile& r, const RobotModel& truth, const RigidTransform& base) {
  Random random(99);
  double sum_m = 0.0;
  for (int i = 0; i < 300; ++i) {
    const JointVector q = test::many_joint_arm_joints(ManyJointArm::iiwa14, &random);
    sum_m += (r.base_to_tracker.apply(fk_tool_point(r.model, q)) - base.apply(fk_tool_point(truth, q))).norm();
  }
  return sum_m / 300.0;
}

/// A lab's export of `samples`: joint_1 .. joint_7 in degrees, then x, y, z in mm.
std::string lab_export(Span<const Sample> samples) {
  std::string out = "joint_1,joint_2,joint_3,joint_4,joint_5,joint_6,joint_7,px,py,pz\n";
  for (const Sample& s : samples) {
    for (int j = 0; j < 7; ++j) out += textio::format_double(s.q_rad(j) / math::kRadPerDeg) + ",";
    out += textio::format_double(s.point_m.x() * 1e3) + "," + textio::format_double(s.point_m.y() * 1e3) + "," +
           textio::format_double(s.point_m.z() * 1e3) + "\n";
  }
  return out;
}

/// The test's seven-joint arm as a description (its nominal, tool 100 mm out).
textio::RobotDescription iiwa_description() {
  textio::RobotDescription description;
  description.robot = "kuka-iiwa14";
  description.model = test::many_joint_arm_model(ManyJointArm::iiwa14);
  return description;
}

TEST(JointCountCli, SevenJointSamplesCalibrateAndAreNeverCutToSix) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_joints");
  Random random(53);
  const RobotModel truth = test::many_joint_arm_truth(ManyJointArm::iiwa14, &random);
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<200> samples;
  samples.clear();
  test::fill_many_joint_arm(ManyJointArm::iiwa14, truth, base, 200, 1e-5, &random, &samples);
  const textio::RobotDescription description = iiwa_description();
  const std::string arm = dir.write("iiwa14.json", textio::format_robot_description(description));
  const std::string csv = dir.write("samples.csv", textio::format_samples_csv(samples.samples(), 7));

  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(test::run(cli::calibrate_main,
                      {"--robot-model", arm, "--samples", csv, "--method", "lm", "--out", result, "--quiet"}),
            cli::kExitOk);
  record::CalibrationFile calibrated;
  ASSERT_TRUE(record::read_calibration_json(result, &calibrated).ok());
  EXPECT_EQ(calibrated.model.joint_count, 7);
  EXPECT_LT(fresh_mae_m(calibrated, truth, base), 5e-5);
  // The report's samples carry the seven joints, its domain names q7's range, and `report` reads
  // the result back.
  const textio::JsonValue root = test::read_json_file(result);
  const textio::JsonValue* report = root.find("report");
  ASSERT_NE(report, nullptr);
  EXPECT_EQ(report->find("samples")->array[0].find("q_rad")->array.size(), 7u);
  std::string info_lines;
  for (const textio::JsonValue& line : report->find("info")->array) info_lines += line.string + "\n";
  EXPECT_NE(info_lines.find(", q7 "), std::string::npos) << info_lines;
  EXPECT_EQ(test::run(cli::report_main, {"--calibration", result, "--out", dir.path() + "/report"}), cli::kExitOk);

  // predict reads q1..q7 poses and gives the true points.
  Random fresh(7);
  std::vector<JointVector> poses;
  for (int i = 0; i < 20; ++i) poses.push_back(test::many_joint_arm_joints(ManyJointArm::iiwa14, &fresh));
  const std::string joints_csv =
      dir.write("joints.csv", textio::format_joints_csv(Span<const JointVector>(poses.data(), poses.size()), 7));
  const std::string predicted = dir.path() + "/predicted.csv";
  ASSERT_EQ(test::run(cli::predict_main, {"--calibration", result, "--joints", joints_csv, "--out", predicted}),
            cli::kExitOk);
  const std::string points = test::read_text_file(predicted);
  std::size_t at = points.find('\n') + 1;
  for (const JointVector& q : poses) {
    const Vec3 truth_m = base.apply(fk_tool_point(truth, q));
    double x_m = 0.0;
    double y_m = 0.0;
    double z_m = 0.0;
    ASSERT_EQ(std::sscanf(points.c_str() + at, "%lf,%lf,%lf", &x_m, &y_m, &z_m), 3);
    EXPECT_LT((Vec3(x_m, y_m, z_m) - truth_m).norm(), 2e-4);
    at = points.find('\n', at) + 1;
  }

  // The same file against a six-joint model: refused, nothing written.
  const std::string refused = dir.path() + "/refused.json";
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--robot-model", "ur5", "--samples", csv, "--out", refused, "--quiet"}, &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find("samples.csv: its header has joint columns up to q7, but the robot model has 6 joints (q1..q6)"),
            std::string::npos)
      << err;
  struct stat info {};
  EXPECT_NE(::stat(refused.c_str(), &info), 0);

  // A lab's own names, read through --columns: q7=joint_7 for the seven-row description.
  const std::string lab = dir.write("lab.csv", lab_export(samples.samples()));
  const std::string columns =
      "q1=joint_1[deg],q2=joint_2[deg],q3=joint_3[deg],q4=joint_4[deg],q5=joint_5[deg],q6=joint_6[deg],"
      "q7=joint_7[deg],x=px[mm],y=py[mm],z=pz[mm]";
  const std::string from_lab = dir.path() + "/lab.json";
  ASSERT_EQ(test::run(cli::calibrate_main, {"--robot-model", arm, "--samples", lab, "--columns", columns, "--method",
                                            "lm", "--out", from_lab, "--quiet"}),
            cli::kExitOk);
  record::CalibrationFile lab_result;
  ASSERT_TRUE(record::read_calibration_json(from_lab, &lab_result).ok());
  EXPECT_LT(fresh_mae_m(lab_result, truth, base), 5e-5);
  EXPECT_EQ(test::run_capturing_stderr(
                cli::calibrate_main,
                {"--robot-model", arm, "--samples", lab, "--columns",
                 columns.substr(0, columns.find(",q7")) + ",x=px[mm],y=py[mm],z=pz[mm]", "--out", refused, "--quiet"},
                &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--columns names q1..q6, but the robot model has 7 joints (q1..q7): name q7 too"),
            std::string::npos)
      << err;
}

// `plan` for a seven-joint arm: q1..q7 poses within each joint's limits (--joint-limits clamped
// to the arm's own range on every joint, the seventh too); URScript is a UR's; a slide has no
// default travel.
TEST(JointCountCli, PlanFollowsTheArmsJoints) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_joints");
  textio::RobotDescription description = iiwa_description();
  description.has_joint_limits = true;
  for (int j = 0; j < 7; ++j) {
    description.lower_rad(j) = -2.0 - 0.1 * j;
    description.upper_rad(j) = 2.0 + 0.1 * j;
  }
  const std::string arm = dir.write("iiwa14.json", textio::format_robot_description(description));
  std::string limits = "lower,upper\n";
  for (int j = 0; j < 7; ++j) limits += j == 6 ? "-3,3\n" : "-1.5,1.5\n";
  const std::string limits_csv = dir.write("limits.csv", limits);
  const std::vector<std::string> cell = {"--robot-model",      arm,         "--count",    "12",
                                         "--tracker-position", "2,0.5,0.6", "--restarts", "1"};
  const std::string poses = dir.path() + "/poses.csv";
  std::vector<std::string> args = cell;
  for (const char* more : {"--joint-limits", limits_csv.c_str(), "--out", poses.c_str()}) args.push_back(more);
  std::string err;
  ASSERT_EQ(test::run_capturing_stderr(cli::plan_main, args, &err), cli::kExitOk) << err;
  EXPECT_NE(err.find("--joint-limits joint 7 [-3.0000, 3.0000] rad goes beyond the kuka-iiwa14's own range "
                     "[-2.6000, 2.6000] rad: clamped to it"),
            std::string::npos)
      << err;
  std::vector<JointVector> planned;
  textio::InputUnits units;
  units.joints = textio::input_joints(description.model);
  ASSERT_TRUE(textio::read_joints_csv(poses, &planned, units).ok());
  ASSERT_EQ(planned.size(), 12u);
  EXPECT_EQ(test::read_text_file(poses).substr(0, 21), "q1,q2,q3,q4,q5,q6,q7\n");
  for (const JointVector& q : planned) {
    for (int j = 0; j < 7; ++j) {
      const double limit_rad = j == 6 ? 2.6 : 1.5;
      EXPECT_LE(std::fabs(q(j)), limit_rad + 1e-9) << j;
    }
  }
  test::expect_refusals(
      cli::plan_main, cell,
      {{{"--out", poses, "--urscript", dir.path() + "/s.script"},
        "--urscript (URScript) is a Universal Robots controller's (six revolute joints); kuka-iiwa14 has 7 revolute "
        "joints"}});
  textio::RobotDescription rail;
  rail.robot = "ur10-on-rail";
  rail.model = test::many_joint_arm_model(ManyJointArm::rail_ur10);
  std::vector<std::string> on_rail = cell;
  on_rail[1] = dir.write("rail.json", textio::format_robot_description(rail));
  test::expect_refusals(cli::plan_main, on_rail,
                        {{{"--out", poses},
                          "ur10-on-rail's joint 1 is prismatic: its travel has no default; give \"joint_limits\" in "
                          "the description or --joint-limits FILE (a prismatic joint's row in m)"}});
}

// `simulate` of a seven-joint description writes q1..q7 logs and version-2 joint records; the
// captures go through clock sync and extraction and calibrate to the tracker noise (10 um).
TEST(JointCountCli, SimulatedSevenJointCapturesCalibrateToTheNoise) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_joints");
  const std::string arm = dir.write("iiwa14.json", textio::format_robot_description(iiwa_description()));
  const std::string session = dir.path() + "/session";
  ASSERT_EQ(test::run(sim::simulate_main, {"--robot-model", arm, "--out-dir", session, "--errors", "large",
                                           "--compliance-urad", "0,0", "--duration-s", "300", "--waypoints", "30"}),
            cli::kExitOk);
  const std::string log = test::read_text_file(session + "/robot_joints.csv");
  EXPECT_EQ(log.substr(0, log.find('\n')), "t,q1,q2,q3,q4,q5,q6,q7");
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(test::run(cli::calibrate_main,
                      {"--robot", session + "/robot.cap", "--tracker", session + "/tracker.cap", "--robot-model", arm,
                       "--tool", "0,0,0.1", "--method", "lm", "--out", result, "--quiet"}),
            cli::kExitOk);
  record::CalibrationFile calibrated;
  record::CalibrationFile truth;
  ASSERT_TRUE(record::read_calibration_json(result, &calibrated).ok());
  ASSERT_TRUE(record::read_calibration_json(session + "/truth.json", &truth).ok());
  EXPECT_EQ(truth.model.joint_count, 7);
  const textio::JsonValue root = test::read_json_file(result);
  const double test_mae_m = root.find("metrics")->find("test")->find("mae_m")->find("3d")->number;
  EXPECT_LT(test_mae_m, 25e-6);
  EXPECT_LT(fresh_mae_m(calibrated, truth.model, truth.base_to_tracker), 30e-6);
  // The seven-joint captures against a six-joint model: refused naming the records' fault.
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--robot", session + "/robot.cap", "--tracker", session + "/tracker.cap",
                                        "--robot-model", "ur5", "--out", dir.path() + "/ur5.json", "--quiet"},
                                       &err),
            cli::kExitBadInput);
  EXPECT_NE(err.find(" robot records carry another joint count than the robot model's 6 joints (q1..q6): the joint "
                     "states of another arm? (--robot-model names the arm)"),
            std::string::npos)
      << err;
  // Its CSV logs (t,q1..q7) read as the arm's seven joints, and are refused for six.
  const std::vector<std::string> logs = {
      "--robot", session + "/robot_joints.csv", "--tracker", session + "/tracker.csv", "--method", "lm", "--quiet"};
  std::vector<std::string> seven = logs;
  for (const std::string& more : {std::string("--robot-model"), arm, std::string("--tool"), std::string("0,0,0.1"),
                                  std::string("--out"), dir.path() + "/logs.json"})
    seven.push_back(more);
  ASSERT_EQ(test::run(cli::calibrate_main, seven), cli::kExitOk);
  record::CalibrationFile from_logs;
  ASSERT_TRUE(record::read_calibration_json(dir.path() + "/logs.json", &from_logs).ok());
  EXPECT_LT(fresh_mae_m(from_logs, truth.model, truth.base_to_tracker), 30e-6);
  std::vector<std::string> six = logs;
  for (const char* more : {"--robot-model", "ur5", "--out"}) six.push_back(more);
  six.push_back(dir.path() + "/six.json");
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main, six, &err), cli::kExitBadInput);
  EXPECT_NE(err.find("robot_joints.csv:1: its header has joint columns q1..q7, but the robot model has 6 joints "
                     "(q1..q6): the joints of another arm?"),
            std::string::npos)
      << err;
}

}  // namespace
}  // namespace hivecal::joint_count_cli_test
