// The nominal model as a prior through the command line (docs/solver-lm.md): a simulated UR10
// grid at one tool orientation (wrist 2 near -pi/2) with unmodelled deflection. Least squares
// (--prior off) swings alpha5 by a tenth of a radian along a direction the poses barely
// determine and warns that it moved; the default keeps every DH element within 5 mm / 5 mrad of
// nominal, predicts fresh poses as well, and names what the prior holds, its partner and what
// would separate them.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/lm_test_data.hpp"
#include "textio/csv.hpp"

namespace hivecal::prior_cli_test {
namespace {

TEST(PriorCli, AGridAtOneToolOrientationKeepsItsDhNearNominal) {
  const test::TempDir dir("hivecal_prior");
  ASSERT_FALSE(dir.path().empty());
  Random random(5301);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur10), &random, 0.5e-3, 0.5e-3);
  truth.tool_m << 0.002, 0.0, 0.12;
  static Dataset<400> grid;
  grid.clear();
  test::fill_narrow_wrist_dataset(truth, 300, 0.3e-3, &random, &grid);
  const std::string samples = dir.write("grid.csv", textio::format_samples_csv(grid.samples(), kSixJoints));
  const std::vector<std::string> common = {"--samples", samples, "--robot-model", "ur10", "--tool", "0,0,0.12",
                                           "--method",  "lm",    "--quiet"};
  std::vector<std::string> plain = common;
  for (const char* o : {"--prior", "off", "--out"}) plain.push_back(o);
  plain.push_back(dir.path() + "/plain.json");
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main, plain, &err), 5) << err;
  EXPECT_NE(err.find("warning: alpha5 moved"), std::string::npos) << err;
  std::vector<std::string> with_prior = common;
  with_prior.push_back("--out");
  with_prior.push_back(dir.path() + "/prior.json");
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main, with_prior, &err), 0) << err;
  record::CalibrationFile plain_file;
  record::CalibrationFile prior_file;
  ASSERT_TRUE(record::read_calibration_json(dir.path() + "/plain.json", &plain_file).ok());
  ASSERT_TRUE(record::read_calibration_json(dir.path() + "/prior.json", &prior_file).ok());
  const ModelParams nominal = to_params(nominal_model(RobotType::ur10));
  const ModelParams fitted = to_params(prior_file.model);
  for (int i = 0; i < kParamsPerJoint * kSixJoints; ++i)
    EXPECT_LT(std::fabs(fitted(i) - nominal(i)), 5e-3) << full_param_name(i, kSixJoints);
  EXPECT_GT(std::fabs(to_params(plain_file.model)(model_param_index(4, DhField::alpha)) -
                      nominal(model_param_index(4, DhField::alpha))),
            0.05);
  // What the prior holds is named, on the console and in the result's report, with its
  // partner in the data and what would tell them apart.
  const std::string json = test::read_text_file(dir.path() + "/prior.json");
  EXPECT_NE(json.find("held    alpha5   (by the nominal model's prior: sigma"), std::string::npos) << json;
  EXPECT_NE(json.find("correlated +0.998 with theta4 in the data: more tool orientations or a wider range of joint 5 "
                      "or a wider range of joint 4 would separate them"),
            std::string::npos);
  EXPECT_EQ(test::read_text_file(dir.path() + "/plain.json").find("held  "), std::string::npos);
}

}  // namespace
}  // namespace hivecal::prior_cli_test
