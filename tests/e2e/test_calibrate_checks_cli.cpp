// What `calibrate` says about a set too small for what it is asked (issue 54 M2, S9) and what
// a new user missed (issue 54, friction): the poses each cross-validation fold held out, the
// lab's flange -> probe transform as the tool, a hint when the arm looks like another UR.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "commands/commands.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/cli_run.hpp"
#include "testkit/temp_dir.hpp"
#include "testkit/test_data.hpp"
#include "textio/csv.hpp"

namespace hivecal::calibrate_checks_cli_test {
namespace {

/// A samples CSV of `poses` random poses of `type` (tool 0,0,0.1695) seen by the example
/// tracker with 10 um noise, seeded.
std::string session_csv(RobotType type, std::size_t poses, std::uint64_t seed) {
  static Dataset<512> data;
  data.clear();
  Random random(seed);
  RobotModel truth = nominal_model(type);
  truth.tool_m = Vec3(0.0, 0.0, 0.1695);
  test::fill_dataset(truth, test::example_base_to_tracker(), poses, 1e-5, &random, &data);
  return textio::format_samples_csv(data.samples());
}

TEST(CalibrateChecks, CrossValidationOnTooFewPosesSaysSo) {
  const test::TempDir dir;
  const std::string three = dir.write("three.csv", session_csv(RobotType::ur5, 3, 1));
  const std::string four = dir.write("four.csv", session_csv(RobotType::ur5, 4, 1));
  const std::string out = dir.path() + "/r.json";
  std::string err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main, {"--samples", three, "--split", "1", "--cv", "2", "--out", out}, &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--cv 2 on 3 samples: a fold trains on 1 of them, and a fit needs at least 3 (as --split's "
                     "training set): too few samples for 2 folds; measure more samples, or hold out fewer at a time "
                     "(more folds; --cv loo: one)"),
            std::string::npos)
      << err;
  EXPECT_EQ(err.find("same joint positions"), std::string::npos) << err;
  EXPECT_EQ(test::run_capturing_stderr(cli::calibrate_main, {"--samples", three, "--split", "1", "--cv", "loo", "--out", out}, &err),
            cli::kExitUsage);
  EXPECT_NE(err.find("--cv loo on 3 samples: a fold trains on 2 of them"), std::string::npos) << err;
  EXPECT_EQ(err.find("hold out fewer"), std::string::npos) << err;  // loo holds out one already
  // Four poses leave three to every leave-one-out fold: the folds run.
  const int code = test::run_capturing_stderr(
      cli::calibrate_main, {"--samples", four, "--cv", "loo", "--method", "lm", "--quiet", "--out", out}, &err);
  EXPECT_TRUE(code == cli::kExitOk || code == cli::kExitWarnings) << err;
  EXPECT_NE(test::read_text_file(out).find("\"cross_validation\""), std::string::npos);
}

}  // namespace
}  // namespace hivecal::calibrate_checks_cli_test
