// Issue 16 through the command line: `hivecal calibrate --compliance` on a simulated session
// whose joints bend (the simulator's own compliance, `simulate --compliance-urad`), the
// result's "compliance" key, `predict` applying it, and what the options refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "commands/validation.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/other_arms.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::compliance_cli_test {
namespace {

using test::run;

/// A short simulated UR5e session (an arm with published masses) with a stiff but real compliance, simulated once.
class ComplianceCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("hivecal_compliance");
    ASSERT_FALSE(dir_->path().empty());
    ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir_->path(), "--robot-model", "ur5e", "--seed", "2", "--waypoints",
                                       "30", "--duration-s", "300", "--compliance-urad", "200,100"}),
              cli::kExitOk);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path() + "/" + name; }
  /// calibrate on the session's captures with `extra` options; the exit code.
  static int calibrate(const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> args = {
        "--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--robot-model", "ur5e", "--out",
        out,       "--quiet"};
    args.insert(args.end(), extra.begin(), extra.end());
    return run(cli::calibrate_main, args);
  }
  static test::TempDir* dir_;
};
test::TempDir* ComplianceCli::dir_ = nullptr;

/// Exit code and stderr of calibrate with `args`.
int calibrate_stderr(const std::vector<std::string>& args, std::string* err) {
  return test::run_capturing_stderr(cli::calibrate_main, args, err);
}

/// Points of a predict output (x,y,z CSV in metres).
std::vector<Vec3> read_points(const std::string& file) {
  std::string text;
  EXPECT_TRUE(port::read_whole_file(file, port::kMaxTextInputBytes, &text).ok());
  std::vector<Vec3> points;
  std::size_t at = text.find('\n') + 1;  // after the header
  while (at < text.size()) {
    const std::size_t end = text.find('\n', at);
    const std::string line = text.substr(at, end - at);
    Vec3 p;
    std::size_t start = 0;
    for (int axis = 0; axis < 3; ++axis) {
      const std::size_t comma = line.find(',', start);
      EXPECT_TRUE(textio::parse_double(line.substr(start, comma - start), &p(axis))) << line;
      start = comma + 1;
    }
    points.push_back(p);
    at = end + 1;
  }
  return points;
}

TEST_F(ComplianceCli, ResultHoldsTheCompliancePredictAppliesIt) {
  const std::string out = path("compliant.json");
  ASSERT_EQ(calibrate(out, {"--method", "lm", "--compliance"}), cli::kExitOk);
  // The key: kind, gravity, four terms with joint, load, coefficient, unit and sigma.
  const textio::JsonValue root = test::read_json_file(out);
  const textio::JsonValue* compliance = root.find("compliance");
  ASSERT_NE(compliance, nullptr);
  EXPECT_EQ(compliance->find("kind")->string, "basis");
  const textio::JsonValue* gravity = compliance->find("gravity_direction");
  ASSERT_NE(gravity, nullptr);
  EXPECT_EQ(gravity->array.at(2).number, -1.0);
  const textio::JsonValue* terms = compliance->find("terms");
  ASSERT_NE(terms, nullptr);
  ASSERT_EQ(terms->array.size(), 4u);
  // An estimated term has its sigma; one the significance test fixed stays at 0, without.
  const textio::JsonValue* estimated = root.find("identifiability")->find("estimated");
  int estimated_terms = 0;
  for (const textio::JsonValue& term : terms->array) {
    EXPECT_EQ(term.find("unit")->string, "rad/m");
    const double joint = term.find("joint")->number;
    EXPECT_TRUE(joint == 2.0 || joint == 3.0) << joint;  // a UR's shoulder and elbow
    bool was_estimated = false;
    for (const textio::JsonValue& name : estimated->array)
      was_estimated = was_estimated || name.string == term.find("name")->string;
    estimated_terms += was_estimated ? 1 : 0;
    const textio::JsonValue* sigma = term.find("sigma");
    EXPECT_EQ(sigma != nullptr, was_estimated) << term.find("name")->string;
    if (sigma != nullptr) {
      EXPECT_GT(sigma->number, 0.0);
    }
    EXPECT_EQ(term.find("coefficient")->number != 0.0, was_estimated) << term.find("name")->string;
  }
  EXPECT_GE(estimated_terms, 1);
  // Table 1 has the compliance stage after the rigid one.
  const textio::JsonValue* methods = root.find("methods");
  ASSERT_NE(methods, nullptr);
  const std::string final_method = methods->array.back().find("method")->string;
  EXPECT_NE(final_method.find("compliance"), std::string::npos) << final_method;
  const double train_mae_m = methods->array.back().find("train_mae_m")->number;

  // predict on the training joints reproduces the fitted points: their mean distance to the
  // measured points is the final stage's training MAE.
  const textio::JsonValue* samples = root.find("report")->find("samples");
  ASSERT_NE(samples, nullptr);
  std::vector<JointVector> joints;
  std::vector<Vec3> measured;
  for (const textio::JsonValue& s : samples->array) {
    if (s.find("test")->boolean) continue;
    JointVector q;
    for (int j = 0; j < kSixJoints; ++j) q(j) = s.find("q_rad")->array.at(static_cast<std::size_t>(j)).number;
    joints.push_back(q);
    const textio::JsonValue* m = s.find("measured_m");
    measured.emplace_back(m->array.at(0).number, m->array.at(1).number, m->array.at(2).number);
  }
  ASSERT_GT(joints.size(), 100u);
  const std::string joints_csv = dir_->write(
      "train_joints.csv", textio::format_joints_csv(Span<const JointVector>(joints.data(), joints.size()), kSixJoints));
  ASSERT_EQ(run(cli::predict_main, {"--calibration", out, "--joints", joints_csv, "--out", path("compliant.csv")}),
            cli::kExitOk);
  const std::vector<Vec3> points = read_points(path("compliant.csv"));
  ASSERT_EQ(points.size(), joints.size());
  double sum_m = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) sum_m += (points[i] - measured[i]).norm();
  const double predicted_mae_m = sum_m / static_cast<double>(points.size());
  std::printf("training MAE: calibrate %.4f um, predict %.4f um (%zu samples)\n", train_mae_m * 1e6,
              predicted_mae_m * 1e6, points.size());
  EXPECT_NEAR(predicted_mae_m, train_mae_m, 1e-12);

  // The same file without its compliance predicts other points, farther from the measured.
  record::CalibrationFile rigid;
  ASSERT_TRUE(record::read_calibration_json(out, &rigid).ok());
  ASSERT_EQ(rigid.model.compliance.term_count, 4);
  rigid.model.compliance = ComplianceModel{};
  const std::string rigid_json = dir_->write("rigid-copy.json", record::format_calibration_json(rigid));
  ASSERT_EQ(run(cli::predict_main, {"--calibration", rigid_json, "--joints", joints_csv, "--out", path("rigid.csv")}),
            cli::kExitOk);
  const std::vector<Vec3> rigid_points = read_points(path("rigid.csv"));
  ASSERT_EQ(rigid_points.size(), points.size());
  double largest_m = 0.0;
  double rigid_sum_m = 0.0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    largest_m = std::max(largest_m, (rigid_points[i] - points[i]).norm());
    rigid_sum_m += (rigid_points[i] - measured[i]).norm();
  }
  std::printf("deflection predict applies: up to %.2f um; without it the training MAE is %.2f um\n", largest_m * 1e6,
              rigid_sum_m / static_cast<double>(points.size()) * 1e6);
  EXPECT_GT(largest_m, 5e-6);
  EXPECT_GT(rigid_sum_m, sum_m);

  // As URDF the compliance cannot be written: the chain written is the rigid one fitted to the
  // full model over the training poses, said with what remains and what the terms' rigid part
  // alone (what export wrote before) would have cost.
  ::testing::internal::CaptureStderr();
  ASSERT_EQ(run(cli::export_main, {"--calibration", out, "--out", path("compliant.urdf")}), cli::kExitOk);
  const std::string note = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(note.find(std::to_string(estimated_terms) +
                      " compliance term(s) (joint deflection under gravity) cannot be written in URDF: the chain "
                      "written is the rigid chain that best reproduces the full model"),
            std::string::npos)
      << note;
  char costs[160];
  std::snprintf(costs, sizeof costs, "the MAE (3D) is %.2f um with the full model, ", train_mae_m * 1e6);
  EXPECT_NE(note.find(costs), std::string::npos) << note << "\nwanted: " << costs;
  std::snprintf(costs, sizeof costs, "um with the chain written, %.2f um with the full model's rigid part alone",
                rigid_sum_m / static_cast<double>(points.size()) * 1e6);
  EXPECT_NE(note.find(costs), std::string::npos) << note << "\nwanted: " << costs;

  // A robot description keeps every term: the full model goes out as it is.
  ASSERT_EQ(run(cli::export_main, {"--calibration", out, "--format", "robot-json", "--out", path("described.json")}),
            cli::kExitOk);
  textio::RobotDescription described;
  ASSERT_TRUE(textio::read_robot_description(path("described.json"), &described).ok());
  record::CalibrationFile full;
  ASSERT_TRUE(record::read_calibration_json(out, &full).ok());
  ASSERT_EQ(described.model.compliance.term_count, 4);
  for (int t = 0; t < 4; ++t) {
    EXPECT_EQ(described.model.compliance.coefficient[t], full.model.compliance.coefficient[t]) << t;
  }

  // The result is a start model again (--robot-model result.json), its compliance kept.
  ASSERT_EQ(calibrate(path("again.json"), {"--robot-model", out, "--method", "lm", "--compliance"}), cli::kExitOk);
  record::CalibrationFile again;
  ASSERT_TRUE(record::read_calibration_json(path("again.json"), &again).ok());
  EXPECT_EQ(again.model.compliance.term_count, 4);
}

// `hivecal validate` against where the simulated tool truly was (the simulator's own
// compliance, another form than the calibration's basis): the compliant fit predicts fresh
// poses better than the rigid one on the same split.
TEST_F(ComplianceCli, ValidatesCloserToTheTrueBentPointsThanTheRigidFit) {
  ASSERT_EQ(calibrate(path("v_rigid.json"), {"--method", "lm"}), cli::kExitOk);
  ASSERT_EQ(calibrate(path("v_compliant.json"), {"--method", "lm", "--compliance"}), cli::kExitOk);
  record::CalibrationFile truth;
  record::CalibrationFile fits[2];
  ASSERT_TRUE(record::read_calibration_json(path("truth.json"), &truth).ok());
  ASSERT_TRUE(record::read_calibration_json(path("v_rigid.json"), &fits[0]).ok());
  ASSERT_TRUE(record::read_calibration_json(path("v_compliant.json"), &fits[1]).ok());
  const cli::ReferenceCompliance bent{200e-6, 100e-6};  // simulate --compliance-urad 200,100
  double mae_m[2];
  for (int k = 0; k < 2; ++k) {
    mae_m[k] = cli::validate_on_fresh_poses(fits[k].model, fits[k].base_to_tracker, truth.model, truth.base_to_tracker,
                                            1000, 7, bent)
                   .mae_m;
  }
  std::printf("validation on 1000 fresh poses vs the true bent points: rigid %.2f um, LM+compliance %.2f um (%.2f)\n",
              mae_m[0] * 1e6, mae_m[1] * 1e6, mae_m[1] / mae_m[0]);
  EXPECT_LT(mae_m[1], 0.5 * mae_m[0]);
  // `hivecal validate` prints that comparison for a simulator's truth.
  ::testing::internal::CaptureStdout();
  EXPECT_EQ(run(cli::validate_main, {"--calibration", path("v_compliant.json"), "--truth", path("truth.json")}),
            cli::kExitOk);
  const std::string printed = ::testing::internal::GetCapturedStdout();
  char expected[64];
  std::snprintf(expected, sizeof expected, "MAE 3D %.2f um", mae_m[1] * 1e6);
  EXPECT_NE(printed.find("vs the true tool points (the simulated compliance included): " + std::string(expected)),
            std::string::npos)
      << printed;
}

// The demo's session (seed 1, 38 waypoints) of an arm that does not bend: --compliance must keep
// the rigid fit. With the geometry's 2 sigma for the compliance terms too, c_j3_tool passed at
// 2.4 sigma (correlated -0.92 with theta3) and fresh poses validated at 12.6 um instead of 4.5 um;
// a new model term must clear 3 sigma (CalibrationCompliance::significance_t).
TEST(ComplianceCliUnbent, AnArmThatDoesNotBendKeepsTheRigidFit) {
  test::TempDir dir("hivecal_compliance_unbent");
  ASSERT_FALSE(dir.path().empty());
  const std::string at = dir.path() + "/";
  ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir.path(), "--seed", "1", "--compliance-urad", "0,0"}),
            cli::kExitOk);
  const std::vector<std::string> common = {
      "--robot", at + "robot.cap", "--tracker", at + "tracker.cap", "--robot-model",
      "ur5",     "--method",       "lm",        "--quiet"};
  std::vector<std::string> rigid = common;
  rigid.insert(rigid.end(), {"--out", at + "rigid.json"});
  std::vector<std::string> compliant = common;
  compliant.insert(compliant.end(), {"--out", at + "compliant.json", "--compliance"});
  ASSERT_EQ(run(cli::calibrate_main, rigid), cli::kExitOk);
  ASSERT_EQ(run(cli::calibrate_main, compliant), cli::kExitOk);
  record::CalibrationFile truth;
  record::CalibrationFile fits[2];
  ASSERT_TRUE(record::read_calibration_json(at + "truth.json", &truth).ok());
  ASSERT_TRUE(record::read_calibration_json(at + "rigid.json", &fits[0]).ok());
  ASSERT_TRUE(record::read_calibration_json(at + "compliant.json", &fits[1]).ok());
  const ComplianceModel& c = fits[1].model.compliance;
  for (int t = 0; t < c.term_count; ++t) EXPECT_EQ(c.coefficient[t], 0.0) << compliance_term_name(c, t);
  double mae_m[2];
  for (int k = 0; k < 2; ++k) {
    mae_m[k] = cli::validate_on_fresh_poses(fits[k].model, fits[k].base_to_tracker, truth.model, truth.base_to_tracker,
                                            1000, 7, cli::ReferenceCompliance{})
                   .mae_m;
  }
  std::printf("unbent demo session, 1000 fresh poses: rigid %.2f um, --compliance %.2f um\n", mae_m[0] * 1e6,
              mae_m[1] * 1e6);
  EXPECT_LE(mae_m[1], 1.01 * mae_m[0]);
}

TEST_F(ComplianceCli, MassesOfAUrWithAPayload) {
  const std::string out = path("masses.json");
  ASSERT_EQ(calibrate(out, {"--method", "lm", "--compliance", "masses", "--payload", "1.5@0,0,0.05"}), cli::kExitOk);
  const textio::JsonValue root = test::read_json_file(out);
  const textio::JsonValue* compliance = root.find("compliance");
  ASSERT_NE(compliance, nullptr);
  EXPECT_EQ(compliance->find("kind")->string, "masses");
  const textio::JsonValue* masses = compliance->find("masses");
  ASSERT_NE(masses, nullptr);
  EXPECT_EQ(masses->find("payload_kg")->number, 1.5);
  EXPECT_EQ(masses->find("payload_com_m")->array.at(2).number, 0.05);
  EXPECT_GT(masses->find("link_mass_kg")->array.at(1).number, 1.0);  // the UR5e's upper arm: kilograms
  for (const textio::JsonValue& term : compliance->find("terms")->array) {
    EXPECT_EQ(term.find("unit")->string, "rad/(kg m)");
    EXPECT_EQ(term.find("load")->string, "arm masses");
  }
  record::CalibrationFile file;
  const port::Error read = record::read_calibration_json(out, &file);
  ASSERT_TRUE(read.ok()) << read.message;
  EXPECT_EQ(file.model.compliance.load, ComplianceLoad::arm_masses);
  EXPECT_EQ(file.model.compliance.masses.payload_kg, 1.5);
}

TEST_F(ComplianceCli, MassesRefusedForAnArmWithoutMassData) {
  record::CalibrationFile irb;
  irb.robot = "abb-irb120";
  irb.model = test::other_arm_model(test::OtherArm::irb120);
  const std::string description = dir_->write("irb120.json", record::format_calibration_json(irb));
  std::string err;
  EXPECT_EQ(calibrate_stderr({"--robot-model", description, "--samples", path("truth_samples.csv"), "--compliance",
                              "masses", "--out", path("irb.json")},
                             &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--compliance masses needs the arm's link masses"), std::string::npos) << err;
  EXPECT_NE(err.find("'abb-irb120' has none: use --compliance basis"), std::string::npos) << err;
  EXPECT_NE(err.find("known here for the built-in types (ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e)"), std::string::npos)
      << err;
}

TEST_F(ComplianceCli, BadGravityAndPayloadRefused) {
  test::expect_refusals(
      cli::calibrate_main, {"--samples", path("truth_samples.csv"), "--robot-model", "ur5e", "--out", path("bad.json")},
      {
          {{"--compliance", "--gravity", "0,0,0"}, "--gravity must be X,Y,Z: the direction of gravity"},
          {{"--compliance", "--gravity", "0,-1"}, "--gravity must be X,Y,Z"},
          {{"--compliance", "--gravity", "down"}, "--gravity must be X,Y,Z"},
          {{"--compliance", "--gravity", "nan,0,-1"}, "--gravity must be X,Y,Z"},
          {{"--gravity", "0,0,-1"}, "--gravity needs --compliance"},
          {{"--compliance", "stiff"}, "--compliance must be 'basis' or 'masses', not 'stiff'"},
          {{"--compliance", "masses", "--payload", "2@0,0"}, "--payload must be KG@X,Y,Z"},
          {{"--compliance", "masses", "--payload", "-1@0,0,0"}, "--payload must be KG@X,Y,Z"},
          {{"--compliance", "masses", "--payload", "2"}, "--payload must be KG@X,Y,Z"},
          {{"--compliance", "masses", "--payload", "2@0,0,0,1"}, "--payload must be KG@X,Y,Z"},
          {{"--compliance", "--payload", "2@0,0,0"}, "--payload needs --compliance masses"},
          {{"--compliance", "--method", "abc"}, "--compliance needs a method with LM"},
      });
}

}  // namespace
}  // namespace hivecal::compliance_cli_test
