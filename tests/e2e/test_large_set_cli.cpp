// A set larger than any fixed capacity of the library's own types: the command takes every
// sample (its storage grows with the input) and the default job's ABC searches on a spanning
// subset, said in Table 1's row, while LM refines on every training sample.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

#include "cli/options.hpp"
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
  const std::string samples = dir.write("large.csv", textio::format_samples_csv(written.samples()));
  const std::string result = dir.path() + "/result.json";
  ASSERT_EQ(test::run(cli::calibrate_main, {"--samples", samples, "--out", result, "--quiet"}), cli::kExitOk);
  std::string text;
  ASSERT_TRUE(port::read_whole_file(result, port::kMaxTextInputBytes, &text).ok());
  EXPECT_NE(text.find("searched on 256 of 6300 samples"), std::string::npos);
  record::CalibrationFile file;
  ASSERT_TRUE(record::parse_calibration_json(text, result, &file).ok());
  const std::size_t hybrid = text.find("\"method\": \"ABC+LM\"", text.find("\"methods\""));  // Table 1's row
  const std::size_t test_mae = text.find("\"test_mae_m\": ", hybrid);
  ASSERT_NE(test_mae, std::string::npos);
  const double test_mae_m = std::strtod(text.c_str() + test_mae + 14, nullptr);
  EXPECT_LT(test_mae_m, 20e-6);  // the noise (10 um per axis) and nothing more
  EXPECT_GT(test_mae_m, 10e-6);
}

}  // namespace
}  // namespace hivecal::large_set_cli_test
