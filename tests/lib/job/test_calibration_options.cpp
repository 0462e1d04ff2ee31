// The job's options (job/calibration_options.hpp): the methods' names both ways, and the
// defaults the command line documents.
#include <gtest/gtest.h>

#include <string>

#include "hivecal/calibration.hpp"

namespace hivecal::calibration_options_test {
namespace {

TEST(CalibrationMethodNames, EveryNameReadsBackAndTheListHoldsEachOnce) {
  const std::string list = calibration_method_names();
  std::string joined;
  for (CalibrationMethod m : {CalibrationMethod::abc_lm, CalibrationMethod::gsa_lm, CalibrationMethod::lm,
                              CalibrationMethod::abc, CalibrationMethod::gsa, CalibrationMethod::all}) {
    CalibrationMethod read = CalibrationMethod::all == m ? CalibrationMethod::lm : CalibrationMethod::all;
    ASSERT_EQ(calibration_method_from_name(calibration_method_name(m), &read), Status::ok);
    EXPECT_EQ(read, m);
    joined += (joined.empty() ? "" : ", ") + std::string(calibration_method_name(m));
  }
  EXPECT_EQ(list, joined);
  CalibrationMethod untouched = CalibrationMethod::gsa;
  EXPECT_EQ(calibration_method_from_name("ABC", &untouched), Status::invalid_argument);
  EXPECT_EQ(calibration_method_from_name("abc+", &untouched), Status::invalid_argument);
  EXPECT_EQ(calibration_method_from_name(nullptr, &untouched), Status::invalid_argument);
  EXPECT_EQ(untouched, CalibrationMethod::gsa);
}

TEST(CalibrationOptionsDefaults, AreTheCommandLinesJob) {
  const CalibrationOptions options;
  EXPECT_EQ(options.method, CalibrationMethod::abc_lm);
  EXPECT_EQ(options.params, CalibrationParams::full);
  EXPECT_EQ(options.train_fraction, kDefaultTrainFraction);
  EXPECT_EQ(options.significance_t, kDefaultSignificance);
  EXPECT_EQ(options.population_subset, kDefaultPopulationSubset);
  EXPECT_FALSE(options.compliance.enabled);
  EXPECT_EQ(options.compliance.model.term_count, 0);  // the start geometry's default terms
  EXPECT_EQ(options.prior.dh_length_m, kDefaultPriorTolerances.dh_length_m);
  EXPECT_FALSE(options.base_known || options.tool_known || options.detect_controller_frames);
}

}  // namespace
}  // namespace hivecal::calibration_options_test
