// What `hivecal export --format urdf` writes, read by ROS's own libraries (kdl_parser and
// orocos KDL, tests/kdl/kdl_chain.hpp): a rigid calibration's URDF is hivecal's forward
// kinematics to a nanometre, at the tool point and in the tracker frame; the URDF of a fit with
// joint terms (which URDF cannot hold) predicts the training poses as well as a rigid fit of the
// same session does (within 5 %), where the fit's rigid part alone did not.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "hivecal/core/random.hpp"
#include "kdl/kdl_chain.hpp"
#include "record/report_json.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/shared_data.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/json.hpp"

namespace hivecal::urdf_kdl_test {
namespace {

using test::run;

/// The URDF `export` writes for `result` (a result file).
std::string exported_urdf(const std::string& result, const std::string& out) {
  EXPECT_EQ(run(cli::export_main, {"--calibration", result, "--format", "urdf", "--out", out}), cli::kExitOk);
  return test::read_text_file(out);
}

/// The chain `root` -> `tip` of `urdf` as KDL reads it (a test failure when it does not).
test::KdlChain chain_of(const std::string& urdf, const std::string& root, const std::string& tip) {
  test::KdlChain chain;
  std::string error;
  EXPECT_TRUE(chain.load(urdf, root, tip, &error)) << error;
  return chain;
}

/// The training samples a result's report keeps.
std::vector<report::SampleRow> training_samples(const std::string& result) {
  textio::JsonValue root;
  EXPECT_TRUE(textio::parse_json(test::read_text_file(result), &root).ok());
  report::ReportData data;
  const textio::JsonValue* saved = root.find("report");
  EXPECT_NE(saved, nullptr);
  if (saved == nullptr) return {};
  EXPECT_TRUE(record::parse_report_data(*saved, result, &data).ok());
  std::vector<report::SampleRow> train;
  for (const report::SampleRow& s : data.samples)
    if (!s.test) train.push_back(s);
  return train;
}

/// Mean 3-D distance of the samples' tracker points from `urdf`'s tcp, each in the tracker
/// frame: KDL's base_link -> tcp, then the inverse of base_link -> tracker [m].
double urdf_mae_m(const std::string& urdf, const std::vector<report::SampleRow>& samples) {
  const test::KdlChain tcp = chain_of(urdf, "base_link", "tcp");
  const RigidTransform tracker = chain_of(urdf, "base_link", "tracker").fk({});
  double sum_m = 0.0;
  for (const report::SampleRow& s : samples) {
    const Vec3 in_base_m = tcp.fk(std::vector<double>(s.q_rad, s.q_rad + 6)).translation_m;
    sum_m += (tracker.inverse().apply(in_base_m) - s.measured_m).norm();
  }
  return sum_m / static_cast<double>(samples.size());
}

/// Mean 3-D distance of the samples' tracker points from `file`'s own predictions [m].
double model_mae_m(const record::CalibrationFile& file, const std::vector<report::SampleRow>& samples) {
  double sum_m = 0.0;
  for (const report::SampleRow& s : samples) {
    const JointVector q = joint_vector(s.q_rad);
    sum_m += (file.base_to_tracker.apply(fk_tool_point(file.model, q)) - s.measured_m).norm();
  }
  return sum_m / static_cast<double>(samples.size());
}

/// A simulated UR5e session whose joints bend (the simulator's compliance, 200 / 100 urad),
/// calibrated rigid and with --compliance (LM, the same split), once.
class UrdfKdl : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("hivecal_urdf_kdl");
    ASSERT_FALSE(dir_->path().empty());
    ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir_->path(), "--robot-model", "ur5e", "--seed", "2", "--waypoints",
                                       "30", "--duration-s", "300", "--compliance-urad", "200,100"}),
              cli::kExitOk);
    for (const bool compliance : {false, true}) {
      std::vector<std::string> args = {"--robot",
                                       path("robot.cap"),
                                       "--tracker",
                                       path("tracker.cap"),
                                       "--robot-model",
                                       "ur5e",
                                       "--method",
                                       "lm",
                                       "--quiet",
                                       "--out",
                                       path(compliance ? "compliance.json" : "rigid.json")};
      if (compliance) args.push_back("--compliance");
      ASSERT_EQ(run(cli::calibrate_main, args), cli::kExitOk);
    }
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path() + "/" + name; }
  static test::TempDir* dir_;
};
test::TempDir* UrdfKdl::dir_ = nullptr;

TEST_F(UrdfKdl, ARigidResultsUrdfIsHivecalsForwardKinematicsToANanometre) {
  record::CalibrationFile file;
  ASSERT_TRUE(record::read_calibration_json(path("rigid.json"), &file).ok());
  const std::string urdf = exported_urdf(path("rigid.json"), path("rigid.urdf"));
  const test::KdlChain tcp = chain_of(urdf, "base_link", "tcp");
  ASSERT_EQ(tcp.joints(), 6u);
  const RigidTransform tracker = chain_of(urdf, "base_link", "tracker").fk({});
  Random random(5401);
  double worst_m = 0.0;
  for (int i = 0; i < 200; ++i) {
    const JointVector q = test::random_joints(&random);
    const Vec3 kdl_m = tcp.fk(test::joint_values(file.model, q)).translation_m;
    const Vec3 hivecal_m = fk_tool_point(file.model, q);
    worst_m = std::fmax(worst_m, (kdl_m - hivecal_m).norm());
    worst_m = std::fmax(worst_m, (tracker.inverse().apply(kdl_m) - file.base_to_tracker.apply(hivecal_m)).norm());
  }
  std::printf("KDL against hivecal's FK, 200 poses: worst %.3g m\n", worst_m);
  EXPECT_LT(worst_m, 1e-9);
}

TEST_F(UrdfKdl, TheUrdfOfAFitWithJointTermsPredictsItsTrainingPosesAsARigidFit) {
  record::CalibrationFile compliant;
  ASSERT_TRUE(record::read_calibration_json(path("compliance.json"), &compliant).ok());
  ASSERT_GT(compliant.model.compliance.term_count, 0);
  const std::vector<report::SampleRow> train = training_samples(path("compliance.json"));
  ASSERT_FALSE(train.empty());
  record::CalibrationFile rigid;
  ASSERT_TRUE(record::read_calibration_json(path("rigid.json"), &rigid).ok());
  const double rigid_fit_m = model_mae_m(rigid, training_samples(path("rigid.json")));
  const double urdf_m = urdf_mae_m(exported_urdf(path("compliance.json"), path("compliance.urdf")), train);
  record::CalibrationFile rigid_part = compliant;  // what export wrote before: the terms left out
  rigid_part.model.compliance = ComplianceModel{};
  const double rigid_part_m = model_mae_m(rigid_part, train);
  std::printf("training poses: URDF (KDL) %.2f um, rigid fit %.2f um, the fit's rigid part alone %.2f um\n",
              urdf_m * 1e6, rigid_fit_m * 1e6, rigid_part_m * 1e6);
  EXPECT_LE(urdf_m, 1.05 * rigid_fit_m);
}

// The real UR10 of the T-Mac export (../shared/data), positions: --compliance and --harmonics 3
// against the default job's rigid fit, on the same split. Their rigid parts alone were worse
// than the uncalibrated arm (1,051 um against 1,026 um for --compliance).
TEST(UrdfKdlRealArm, TheUrdfOfFitsWithJointTermsPredictsTheTrainingPosesAsTheRigidFit) {
  HIVECAL_SKIP_WITHOUT_SHARED_DATA("ur10-tmac/measurements_joint_configurations.csv");
  const test::TempDir dir("hivecal_urdf_kdl_tmac");
  ASSERT_FALSE(dir.path().empty());
  const std::vector<std::string> common = {
      "--samples",     test::shared_data_path("ur10-tmac/measurements_joint_configurations.csv"),
      "--robot-model", "ur10",
      "--tool",        "0,0,0.109",
      "--length-unit", "mm",
      "--columns",     "x=measurement_x,y=measurement_y,z=measurement_z",
      "--quiet"};
  const auto calibrate = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> args = common;
    args.push_back("--out");
    args.push_back(out);
    args.insert(args.end(), extra.begin(), extra.end());
    EXPECT_EQ(run(cli::calibrate_main, args), cli::kExitOk) << out;
  };
  calibrate(dir.path() + "/rigid.json", {});
  record::CalibrationFile rigid;
  ASSERT_TRUE(record::read_calibration_json(dir.path() + "/rigid.json", &rigid).ok());
  const double rigid_fit_m = model_mae_m(rigid, training_samples(dir.path() + "/rigid.json"));
  for (const std::vector<std::string>& terms :
       std::vector<std::vector<std::string>>{{"--compliance"}, {"--harmonics", "3"}}) {
    const std::string result = dir.path() + "/terms.json";
    calibrate(result, terms);
    const std::vector<report::SampleRow> train = training_samples(result);
    const double urdf_m = urdf_mae_m(exported_urdf(result, dir.path() + "/terms.urdf"), train);
    std::printf("%s: training poses: URDF (KDL) %.2f um, rigid fit %.2f um\n", terms[0].c_str(), urdf_m * 1e6,
                rigid_fit_m * 1e6);
    EXPECT_LE(urdf_m, 1.05 * rigid_fit_m) << terms[0];
  }
}

}  // namespace
}  // namespace hivecal::urdf_kdl_test
