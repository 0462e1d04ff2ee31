// The job's result (job/calibration_result.hpp): the names of its steps, solvers, stages and
// blunder verdicts, as the tables and result.json print them, and a result before any run.
#include <gtest/gtest.h>

#include <set>
#include <string>

#include "hivecal/calibration.hpp"

namespace hivecal::calibration_result_test {
namespace {

TEST(CalibrationResultNames, EveryStepAndVerdictHasItsOwnName) {
  std::set<std::string> steps;
  for (CalibrationStep step :
       {CalibrationStep::input, CalibrationStep::split, CalibrationStep::baseline, CalibrationStep::gsa,
        CalibrationStep::abc, CalibrationStep::lm, CalibrationStep::done}) {
    steps.insert(calibration_step_name(step));
  }
  EXPECT_EQ(steps, (std::set<std::string>{"input", "split", "baseline", "gsa", "abc", "lm", "done"}));
  std::set<std::string> verdicts;
  for (BlunderVerdict verdict :
       {BlunderVerdict::not_searched, BlunderVerdict::clean, BlunderVerdict::removed, BlunderVerdict::model_error,
        BlunderVerdict::list_full, BlunderVerdict::at_threshold, BlunderVerdict::prediction_error}) {
    verdicts.insert(blunder_verdict_name(verdict));
  }
  EXPECT_EQ(verdicts, (std::set<std::string>{"not_searched", "clean", "removed", "model_error", "list_full",
                                             "at_threshold", "prediction_error"}));
}

TEST(CalibrationResultNames, AStageIsNamedAfterItsSolverAndTheStageItRefines) {
  CalibrationStage abc;
  abc.solver = CalibrationSolver::abc;
  CalibrationStage gsa;
  gsa.solver = CalibrationSolver::gsa;
  CalibrationStage lm;
  lm.solver = CalibrationSolver::lm;
  EXPECT_STREQ(calibration_stage_name(abc, nullptr), "ABC");
  EXPECT_STREQ(calibration_stage_name(gsa, nullptr), "GSA");
  EXPECT_STREQ(calibration_stage_name(lm, &abc), "LM");  // from the start geometry: not a hybrid
  lm.refines_previous = true;
  EXPECT_STREQ(calibration_stage_name(lm, &abc), "ABC+LM");
  EXPECT_STREQ(calibration_stage_name(lm, &gsa), "GSA+LM");
  EXPECT_STREQ(calibration_solver_name(CalibrationSolver::lm), "LM");
}

TEST(CalibrationResultNames, AResultBeforeAnyRunHasNoStage) {
  const CalibrationResult result;
  EXPECT_EQ(result.status, Status::invalid_argument);
  EXPECT_EQ(result.step, CalibrationStep::input);
  EXPECT_EQ(result.final_stage(), nullptr);
  EXPECT_TRUE(result.stage_list().empty());
  EXPECT_TRUE(result.outlier_list().empty());
}

}  // namespace
}  // namespace hivecal::calibration_result_test
