// `hivecal calibrate` with an arm of seven joints (issue 53): a seven-row description and a
// q1..q7 samples file calibrate; the same file against a six-joint model is refused naming both
// counts (it used to drop q7 and fit a UR5); a lab's joint_1 .. joint_7 read through --columns.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/validation.hpp"
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

/// How far `predict` of `result` puts 20 fresh q1..q7 poses (drawn by `seed`) from the true
/// points of `truth` seen from `base` [m]; fewer when predict fails or writes too few rows.
std::vector<double> predict_errors_m(const test::TempDir& dir, const std::string& result, std::uint64_t seed,
                                     const RobotModel& truth, const RigidTransform& base) {
  Random random(seed);
  std::vector<JointVector> poses;
  for (int i = 0; i < 20; ++i) poses.push_back(test::many_joint_arm_joints(ManyJointArm::iiwa14, &random));
  const std::string joints_csv =
      dir.write("joints.csv", textio::format_joints_csv(Span<const JointVector>(poses.data(), poses.size()), 7));
  const std::string predicted = dir.path() + "/predicted.csv";
  std::vector<double> errors_m;
  if (test::run(cli::predict_main, {"--calibration", result, "--joints", joints_csv, "--out", predicted}) !=
      cli::kExitOk)
    return errors_m;
  const std::string points = test::read_text_file(predicted);
  std::size_t at = points.find('\n') + 1;
  for (const JointVector& q : poses) {
    double xyz_m[3] = {};
    if (std::sscanf(points.c_str() + at, "%lf,%lf,%lf", &xyz_m[0], &xyz_m[1], &xyz_m[2]) != 3) break;
    errors_m.push_back((Vec3(xyz_m[0], xyz_m[1], xyz_m[2]) - base.apply(fk_tool_point(truth, q))).norm());
    at = points.find('\n', at) + 1;
  }
  return errors_m;
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
  const std::vector<double> predicted_errors_m = predict_errors_m(dir, result, 7, truth, base);
  EXPECT_EQ(predicted_errors_m.size(), 20u);
  for (const double error_m : predicted_errors_m) EXPECT_LT(error_m, 2e-4);

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

// validate --truth's fresh poses turn every joint of the arm: two seven-joint geometries that
// differ only in how joint 7's axis is tilted (alpha6), the tool off that axis and no offset
// along it (d7 = 0), put the tool at the same point when q7 = 0 and apart by ~0.1 mm x 1 mrad
// x |sin q7| elsewhere (the poses held q7 at 0 and saw no difference).
TEST(JointCountCli, FreshValidationPosesTurnEveryJoint) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  RobotModel model = test::many_joint_arm_model(ManyJointArm::iiwa14);
  model.joints[6].d_m = 0.0;
  model.tool_m = Vec3(0.1, 0.0, 0.0);
  RobotModel reference = model;
  reference.joints[5].alpha_rad += 1e-3;
  const RigidTransform base = test::example_base_to_tracker();
  const cli::ValidationStats stats = cli::validate_on_fresh_poses(model, base, reference, base, 500, 7);
  EXPECT_GT(stats.mae_m, 30e-6);
  EXPECT_LT(stats.max_m, 101e-6);
}

/// What `entry` printed to stdout, its exit code into *code.
template <typename Main>
std::string stdout_of(Main entry, std::vector<std::string> args, int* code) {
  ::testing::internal::CaptureStdout();
  *code = test::run(entry, std::move(args));
  return ::testing::internal::GetCapturedStdout();
}

/// The number after `label` in `text` (NaN when absent).
double number_after(const std::string& text, const std::string& label) {
  const std::size_t at = text.find(label);
  return at == std::string::npos ? std::nan("") : std::strtod(text.c_str() + at + label.size(), nullptr);
}

// The built-in seven-joint arm through every command (issue 53): a simulated `iiwa14` session
// calibrates from its captures (the default ABC + LM, and the link lengths alone by ABC and
// GSA), predicts fresh poses, validates against the truth and on its own samples, exports a
// URDF of seven joints and reports one residual figure per joint: every step exits 0 and the
// figures are at the tracker noise (10 um per axis).
TEST(JointCountCli, BuiltInSevenJointArmThroughEveryCommand) {
  if (kMaxJoints < 7) GTEST_SKIP() << "a build of six joints holds no seven-joint arm";
  const test::TempDir dir("hivecal_iiwa");
  const std::string session = dir.path() + "/session";
  ASSERT_EQ(test::run(sim::simulate_main, {"--robot-model", "iiwa14", "--out-dir", session, "--compliance-urad", "0,0",
                                           "--duration-s", "300", "--waypoints", "30", "--seed", "3"}),
            cli::kExitOk);
  const std::vector<std::string> captures = {
      "--robot", session + "/robot.cap", "--tracker", session + "/tracker.cap", "--robot-model", "iiwa14", "--quiet"};
  const std::string result = dir.path() + "/result.json";
  std::vector<std::string> calibrate = captures;
  for (const std::string& more : {std::string("--out"), result, std::string("--report"), dir.path() + "/report"})
    calibrate.push_back(more);
  ASSERT_EQ(test::run(cli::calibrate_main, calibrate), cli::kExitOk);
  record::CalibrationFile calibrated;
  record::CalibrationFile truth;
  ASSERT_TRUE(record::read_calibration_json(result, &calibrated).ok());
  ASSERT_TRUE(record::read_calibration_json(session + "/truth.json", &truth).ok());
  ASSERT_EQ(calibrated.model.joint_count, 7);
  const textio::JsonValue root = test::read_json_file(result);
  EXPECT_LT(root.find("metrics")->find("test")->find("mae_m")->find("3d")->number, 25e-6);
  EXPECT_LT(fresh_mae_m(calibrated, truth.model, truth.base_to_tracker), 30e-6);

  // The report draws one residual figure per joint, the seventh too; `report` redraws it.
  const std::string html = test::read_text_file(dir.path() + "/report/index.html");
  EXPECT_NE(html.find("fig-residual-q7"), std::string::npos);
  EXPECT_EQ(html.find("fig-residual-q8"), std::string::npos);
  EXPECT_EQ(test::run(cli::report_main, {"--calibration", result, "--out", dir.path() + "/again"}), cli::kExitOk);

  // validate against the truth on fresh poses of all seven joints, and on the session's true points.
  int code = -1;
  const std::string fresh =
      stdout_of(cli::validate_main, {"--calibration", result, "--truth", session + "/truth.json"}, &code);
  EXPECT_EQ(code, cli::kExitOk);
  EXPECT_LT(number_after(fresh, "MAE 3D "), 30.0) << fresh;  // [um]
  const std::string scored = dir.path() + "/validation.json";
  EXPECT_EQ(test::run(cli::validate_main,
                      {"--calibration", result, "--samples", session + "/truth_samples.csv", "--out", scored}),
            cli::kExitOk);
  EXPECT_LT(test::read_json_file(scored).find("metrics")->find("mae_m")->find("3d")->number, 30e-6);

  // predict: q1..q7 poses to the true points.
  const std::vector<double> errors_m = predict_errors_m(dir, result, 11, truth.model, truth.base_to_tracker);
  ASSERT_EQ(errors_m.size(), 20u);
  double sum_m = 0.0;
  for (const double error_m : errors_m) sum_m += error_m;
  EXPECT_LT(sum_m / 20.0, 30e-6);

  // export: a URDF of seven joints that reads back to the calibrated flange.
  const std::string urdf = dir.path() + "/iiwa14.urdf";
  ASSERT_EQ(test::run(cli::export_main, {"--calibration", result, "--format", "urdf", "--out", urdf}), cli::kExitOk);
  textio::RobotDescription exported;
  ASSERT_TRUE(textio::read_robot_description(urdf, &exported).ok());
  EXPECT_EQ(exported.model.joint_count, 7);
  EXPECT_EQ(test::run(cli::check_robot_main, {urdf}), cli::kExitOk);

  // A UR RTDE log is a UR's: refused for the iiwa, naming the arm and its joints.
  const std::string rtde = dir.write("robot_rtde.txt",
                                     "timestamp actual_q_0 actual_q_1 actual_q_2 actual_q_3 actual_q_4 actual_q_5\n"
                                     "0 0 0 0 0 0 0\n");
  std::string refusal;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main,
                                       {"--robot", rtde, "--tracker", session + "/tracker.csv", "--robot-model",
                                        "iiwa14", "--out", dir.path() + "/rtde.json", "--quiet"},
                                       &refusal),
            cli::kExitBadInput);
  EXPECT_NE(refusal.find("robot_rtde.txt:1: a UR RTDE log (actual_q_0..actual_q_5: a UR controller's six revolute "
                         "joints), but the robot model 'iiwa14' has 7 joints (q1..q7): RTDE is UR's alone"),
            std::string::npos)
      << refusal;

  // The link lengths alone (--params paper) by ABC and by GSA search the arm's own four non-zero
  // lengths (the iiwa's d1, d3, d5, d7), the tool fitted. The lengths alone do not explain this
  // session's angle errors: GSA's held-out error may lose to the baseline (exit 5, its warning
  // written), never a refusal.
  for (const char* method : {"abc+lm", "gsa"}) {
    std::vector<std::string> paper = captures;
    const std::string out = dir.path() + "/paper-" + method + ".json";
    for (const std::string& more : {std::string("--params"), std::string("paper"), std::string("--method"),
                                    std::string(method), std::string("--out"), out})
      paper.push_back(more);
    std::string err;
    const int exit_code = test::run_capturing_stderr(cli::calibrate_main, paper, &err);
    EXPECT_TRUE(exit_code == cli::kExitOk || exit_code == cli::kExitWarnings) << method << ": " << err;
    const textio::JsonValue methods = *test::read_json_file(out).find("methods");
    ASSERT_GE(methods.array.size(), 2u);
    EXPECT_EQ(methods.array[1].find("params")->string.rfind("paper-4, tool fitted", 0), 0u) << method;
  }
}

}  // namespace
}  // namespace hivecal::joint_count_cli_test
