// `hivecal calibrate --harmonics K` on a simulated session whose elbow encoder is eccentric
// (`simulate --harmonic-urad`): the LM+harmonics stage, the result's "harmonic" terms read back
// to the same model, the test error against the rigid stage, and what the options refuse.
#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "commands/commands.hpp"
#include "commands/simulate.hpp"
#include "hivecal/core/capacity.hpp"
#include "hivecal/port/input_file.hpp"
#include "record/result_json.hpp"
#include "testkit/cli_run.hpp"
#include "textio/json.hpp"

namespace hivecal::harmonics_cli_test {
namespace {

using test::run;

/// The elbow turns 150 urad sin(q3) + 100 urad cos(q3) more than it reads (60 um at the tool).
class HarmonicsCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("hivecal_harmonics");
    ASSERT_FALSE(dir_->path().empty());
    ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir_->path(), "--seed", "3", "--compliance-urad", "0,0",
                                       "--harmonic-urad", "3,1,150,100"}),
              cli::kExitOk);
  }
  static void TearDownTestSuite() {
    delete dir_;
    dir_ = nullptr;
  }
  static std::string path(const std::string& name) { return dir_->path() + "/" + name; }
  static std::vector<std::string> inputs() {
    return {"--robot", path("robot.cap"), "--tracker", path("tracker.cap"), "--robot-model", "ur5", "--quiet"};
  }
  static test::TempDir* dir_;
};
test::TempDir* HarmonicsCli::dir_ = nullptr;

TEST_F(HarmonicsCli, TheStageFindsTheElbowsHarmonicAndTheResultReadsBack) {
  if (4 * kSixJoints > kMaxComplianceTerms)
    GTEST_SKIP() << "this build holds " << kMaxComplianceTerms << " joint terms";
  std::vector<std::string> args = inputs();
  args.insert(args.end(), {"--method", "lm", "--harmonics", "2", "--out", path("h.json")});
  ASSERT_EQ(run(cli::calibrate_main, args), cli::kExitOk);
  const textio::JsonValue root = test::read_json_file(path("h.json"));
  const textio::JsonValue* methods = root.find("methods");
  ASSERT_NE(methods, nullptr);
  ASSERT_GE(methods->array.size(), 3u);  // uncalibrated, LM, LM+harmonics
  const textio::JsonValue& rigid = methods->array[methods->array.size() - 2];
  const textio::JsonValue& harmonic = methods->array.back();
  EXPECT_EQ(rigid.find("method")->string, "LM");
  EXPECT_EQ(harmonic.find("method")->string, "LM+harmonics");
  const double rigid_m = rigid.find("test_mae_m")->number;
  const double harmonic_m = harmonic.find("test_mae_m")->number;
  std::printf("test MAE: LM %.2f um, LM+harmonics %.2f um\n", 1e6 * rigid_m, 1e6 * harmonic_m);
  EXPECT_LT(harmonic_m, 0.95 * rigid_m);
  // 24 terms, each with its function, order and unit; the elbow's first harmonic estimated.
  const textio::JsonValue* terms = root.find("compliance")->find("terms");
  ASSERT_NE(terms, nullptr);
  ASSERT_EQ(terms->array.size(), 24u);
  bool elbow_estimated = false;
  for (const textio::JsonValue& term : terms->array) {
    EXPECT_EQ(term.find("unit")->string, "rad");
    EXPECT_EQ(term.find("load"), nullptr);
    const std::string name = term.find("name")->string;
    const std::string function = term.find("harmonic")->string;
    EXPECT_EQ(name.substr(name.size() - 4), function.substr(0, 3) + function.substr(4)) << name << " " << function;
    if (name.rfind("h_j3_", 0) == 0 && name.back() == '1' && term.find("sigma") != nullptr) elbow_estimated = true;
  }
  EXPECT_TRUE(elbow_estimated);
  // Read back: the same terms and coefficients, bit for bit.
  record::CalibrationFile file;
  ASSERT_TRUE(record::read_calibration_json(path("h.json"), &file).ok());
  const ComplianceModel& c = file.model.compliance;
  ASSERT_EQ(c.term_count, 24);
  for (int t = 0; t < c.term_count; ++t) {
    EXPECT_TRUE(is_harmonic(c.terms[t]));
    EXPECT_EQ(compliance_term_name(c, t), terms->array[static_cast<std::size_t>(t)].find("name")->string);
    EXPECT_EQ(c.coefficient[t], terms->array[static_cast<std::size_t>(t)].find("coefficient")->number);
  }
}

TEST_F(HarmonicsCli, RefusedWithoutLmOrBeyondTheOrdersAndTheCapacity) {
  std::vector<std::string> common = inputs();
  common.insert(common.end(), {"--out", path("bad.json")});
  std::vector<test::Refusal> refusals = {
      {{"--harmonics", "4"}, "--harmonics"},
      {{"--harmonics", "0"}, "--harmonics"},
      {{"--harmonics", "one"}, "--harmonics"},
      {{"--harmonics", "1", "--method", "abc"}, "--harmonics needs a method with LM"},
      {{"--harmonics", "1", "--gravity", "0,0,-1"}, "--gravity needs --compliance"},
  };
  // Three orders of six joints and the four gravity terms: 40 joint terms, the hosted builds'
  // capacity; a build that holds fewer refuses them by name.
  if (kMaxJointTerms < 40) {
    refusals.push_back({{"--harmonics", "3", "--compliance"}, "joint terms with the others; this build holds"});
  }
  test::expect_refusals(cli::calibrate_main, common, refusals);
}

}  // namespace
}  // namespace hivecal::harmonics_cli_test
