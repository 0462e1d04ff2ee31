// A set larger than any fixed capacity of the library's own types: the command takes every
// sample (its storage grows with the input) and the default job's ABC searches on a spanning
// subset, said in Table 1's row, while LM refines on every training sample. A set of more
// poses than 1.5 per parameter has its geometry estimated without the significance test, said.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/calibration.hpp"
#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/port/input_file.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "record/result_json.hpp"

namespace hivecal::large_set_cli_test {
namespace {

TEST(LargeSetCli, NineThousandPosesCalibrateWithTheDefaultJob) {
  const test::TempDir dir("hivecal_large");
  ASSERT_FALSE(dir.path().empty());
  constexpr std::size_t kPoses = 9000;  // above the 8,192 the command once held
  static Dataset<kPoses> written;
  written.clear();
  Random random(5);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-4, 1e-4);
  test::fill_dataset(truth, test::example_base_to_tracker(), kPoses, 1e-5, &random, &written);
  const std::string samples = dir.write("large.csv", textio::format_samples_csv(written.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(test::run(cli::calibrate_main, {"--samples", samples, "--out", result, "--quiet"}), cli::kExitOk);
  std::string text;
  ASSERT_TRUE(port::read_whole_file(result, port::kMaxTextInputBytes, &text).ok());
  EXPECT_NE(text.find("searched on " + std::to_string(kDefaultPopulationSubset) + " of 6300 samples"),
            std::string::npos);
  record::CalibrationFile file;
  ASSERT_TRUE(record::parse_calibration_json(text, result, &file).ok());
  const std::size_t hybrid = text.find("\"method\": \"ABC+LM\"", text.find("\"methods\""));  // Table 1's row
  const std::size_t test_mae = text.find("\"test_mae_m\": ", hybrid);
  ASSERT_NE(test_mae, std::string::npos);
  const double test_mae_m = std::strtod(text.c_str() + test_mae + 14, nullptr);
  EXPECT_LT(test_mae_m, 20e-6);  // the noise (10 um per axis) and nothing more
  EXPECT_GT(test_mae_m, 10e-6);
}

// 60 poses of an arm whose geometry is the start's (every change is noise): the default
// estimates all, says why in a line of the console and result.json, and marks the result; a
// given --significance 2 tests the geometry on this set too and fixes what did not move.
TEST(LargeSetCli, TheGeometryOfALargerSetIsNotTestedUnlessALevelIsGiven) {
  const test::TempDir dir("hivecal_large");
  ASSERT_FALSE(dir.path().empty());
  static Dataset<60> written;
  written.clear();
  Random random(8);
  const RobotModel truth = nominal_model(RobotType::ur5);
  test::fill_dataset(truth, test::example_base_to_tracker(), 60, 1e-5, &random, &written);
  const std::string samples = dir.write("sixty.csv", textio::format_samples_csv(written.samples(), kSixJoints));
  const std::string result = dir.path() + "/result.json";
  const std::vector<std::string> args = {"--samples", samples, "--method", "lm", "--split", "1", "--out", result};
  ::testing::internal::CaptureStdout();
  const int code = test::run(cli::calibrate_main, args);
  const std::string console = ::testing::internal::GetCapturedStdout();
  ASSERT_EQ(code, cli::kExitOk);
  const char* line = "significance test: the geometry is not tested on 60 training poses";
  EXPECT_NE(console.find(line), std::string::npos) << console;
  EXPECT_EQ(console.find("(not significant"), std::string::npos);
  std::string text = test::read_text_file(result);
  EXPECT_NE(text.find(line), std::string::npos);
  EXPECT_NE(text.find("\"significance_geometry_tested\": false"), std::string::npos);
  std::vector<std::string> given = args;
  given.insert(given.end(), {"--significance", "2", "--quiet"});
  ASSERT_EQ(test::run(cli::calibrate_main, given), cli::kExitOk);
  text = test::read_text_file(result);
  EXPECT_EQ(text.find(line), std::string::npos);
  EXPECT_NE(text.find("(not significant: change below 2 sigma"), std::string::npos);
  EXPECT_EQ(text.find("significance_geometry_tested"), std::string::npos);
}

// --profile says where the wall time went: the input, the job's phases and stages (each w-test
// of a rerun adds a pass), the tables and the outputs, which with the rest add up to the total.
TEST(LargeSetCli, TheProfileSaysWhereTheTimeWent) {
  const test::TempDir dir("hivecal_large");
  ASSERT_FALSE(dir.path().empty());
  static Dataset<400> written;
  written.clear();
  Random random(9);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-4, 1e-4);
  test::fill_dataset(truth, test::example_base_to_tracker(), 400, 1e-5, &random, &written);
  const std::string samples = dir.write("profiled.csv", textio::format_samples_csv(written.samples(), kSixJoints));
  const std::vector<std::string> args = {"--samples", samples, "--out", dir.path() + "/result.json", "--quiet"};
  std::string err;
  ASSERT_EQ(test::run_capturing_stderr(cli::calibrate_main, args, &err), cli::kExitOk);
  EXPECT_EQ(err.find("profile:"), std::string::npos) << "only when asked";
  std::vector<std::string> profiled = args;
  profiled.push_back("--profile");
  ASSERT_EQ(test::run_capturing_stderr(cli::calibrate_main, profiled, &err), cli::kExitOk);
  const std::size_t head = err.find("profile: wall time [s] of the command, ");
  ASSERT_NE(head, std::string::npos) << err;
  const double total_s = std::strtod(err.c_str() + head + 38, nullptr);
  EXPECT_GT(total_s, 0.0);
  double listed_s = 0.0;
  for (const char* part :
       {"read the input", "job: screen of the start geometry", "job: baseline fit", "job: ABC stage", "job: LM stage",
        "job: blunder search (w-tests, refits)", "job: the rest", "uncertainty: covariance and domain",
        "final w-test, accuracy and tables", "write the outputs", "other (options"}) {
    const std::size_t at = err.find(std::string("\n  ") + part, head);
    ASSERT_NE(at, std::string::npos) << part << "\n" << err;
    const std::size_t end = err.find('\n', at + 1);
    const std::string line = err.substr(at + 1, end - at - 1);
    const double seconds = std::strtod(line.c_str() + 43, nullptr);  // after the 40-character label
    EXPECT_GE(seconds, -1e-6) << line;
    listed_s += seconds;
  }
  EXPECT_NEAR(listed_s, total_s, 0.0065) << err;  // 12 parts, each printed to 1 ms
}

}  // namespace
}  // namespace hivecal::large_set_cli_test
