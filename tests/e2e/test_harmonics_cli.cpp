// `hivecal calibrate --harmonics K` on a simulated session whose base has a second harmonic
// error (`simulate --harmonic-urad`, a gear's): the LM+harmonics stage, the result's "harmonic"
// terms read back to the same model, the test error against the rigid stage, the harmonics the
// waypoints do not turn their joint through (not admitted, and said), and what the options refuse.
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

/// The base turns 150 urad sin(2 q1) + 100 urad cos(2 q1) more than it reads (~100 um at the tool).
class HarmonicsCli : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new test::TempDir("hivecal_harmonics");
    ASSERT_FALSE(dir_->path().empty());
    ASSERT_EQ(run(sim::simulate_main, {"--out-dir", dir_->path(), "--seed", "3", "--compliance-urad", "0,0",
                                       "--harmonic-urad", "1,2,150,100"}),
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

TEST_F(HarmonicsCli, TheStageFindsTheBasesSecondHarmonicAndTheResultReadsBack) {
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
  // 24 terms, each with its function, order and unit; the base's second harmonic estimated.
  const textio::JsonValue* terms = root.find("compliance")->find("terms");
  ASSERT_NE(terms, nullptr);
  ASSERT_EQ(terms->array.size(), 24u);
  int base_estimated = 0;
  for (const textio::JsonValue& term : terms->array) {
    EXPECT_EQ(term.find("unit")->string, "rad");
    EXPECT_EQ(term.find("load"), nullptr);
    const std::string name = term.find("name")->string;
    const std::string function = term.find("harmonic")->string;
    EXPECT_EQ(name.substr(name.size() - 4), function.substr(0, 3) + function.substr(4)) << name << " " << function;
    if (name.rfind("h_j1_", 0) == 0 && name.back() == '2' && term.find("sigma") != nullptr) ++base_estimated;
  }
  EXPECT_EQ(base_estimated, 2);
  // The waypoints turn the elbow through less than three quarters of a turn: its first harmonic
  // is not admitted, and the result's report says why.
  const std::string text = test::read_text_file(path("h.json"));
  const std::size_t line = text.find("harmonics: not admitted: ");
  ASSERT_NE(line, std::string::npos);
  const std::string said = text.substr(line, text.find('\n', line) - line);
  EXPECT_NE(said.find("h_j3_sin1, h_j3_cos1"), std::string::npos) << said;
  EXPECT_NE(said.find("turn their joint through less than 0.75 of their period"), std::string::npos) << said;
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
