// The calibration job entry (calibration.hpp): every method on a simulated session, without
// heap; one bad input per Status it returns, with the step that failed; training on every
// sample; the same bits with and without LM's joint trig storage; and the same bits as the
// stage functions called by hand.
#include <gtest/gtest.h>

#include <cstring>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/rigid_fit.hpp"
#include "hivecal/model/spanning_subset.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/quick_job.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::calibration_test {
namespace {

constexpr std::size_t kSamples = 256;
using SmallWorkspace = CalibrationWorkspace<kSamples, double, 40, 300>;
using TrigWorkspace = CalibrationWorkspace<kSamples, double, 40, 300, kSamples>;

SmallWorkspace workspace;
TrigWorkspace trig_workspace;
CalibrationResult result;
CalibrationResult other;
Dataset<kSamples> dataset;

bool same_bits(const RobotModel& a, const RobotModel& b) {
  const ModelParams pa = to_params(a);
  const ModelParams pb = to_params(b);
  return std::memcmp(pa.data(), pb.data(), sizeof(double) * model_param_count(kSixJoints)) == 0;
}

/// A perturbed UR5 seen by a tracker with 10 um noise.
void fill(std::size_t count, DatasetBase* out) {
  Random random(7);
  const RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  out->clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), count, 10e-6, &random, out);
}

using test::quick_options;

/// The job's answer (the tests check stage_count first).
const CalibrationStage& last(const CalibrationResult& r) {
  return r.stages[r.stage_count - 1];
}

const RobotModel& start() {
  static const RobotModel model = nominal_model(RobotType::ur5);
  return model;
}

struct MethodCase {
  CalibrationMethod method;
  std::size_t stages;
  const char* final_name;
};

TEST(CalibrationJob, EveryMethodRunsWithoutHeapAndImprovesOnTheBaseline) {
  const MethodCase cases[] = {{CalibrationMethod::lm, 1, "LM"},         {CalibrationMethod::abc, 1, "ABC"},
                              {CalibrationMethod::gsa, 1, "GSA"},       {CalibrationMethod::abc_lm, 2, "ABC+LM"},
                              {CalibrationMethod::gsa_lm, 2, "GSA+LM"}, {CalibrationMethod::all, 3, "LM"}};
  for (const MethodCase& c : cases) {
    fill(120, &dataset);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate(start(), &dataset, quick_options(c.method), &workspace, &result));
    ASSERT_EQ(status, Status::ok) << calibration_method_name(c.method) << ": " << calibration_step_name(result.step);
    EXPECT_EQ(result.step, CalibrationStep::done);
    EXPECT_EQ(result.train_count, 84u);
    EXPECT_EQ(result.test_count, 36u);
    ASSERT_EQ(result.stage_count, c.stages) << calibration_method_name(c.method);
    EXPECT_STREQ(result.stage_name(c.stages - 1), c.final_name);
    EXPECT_EQ(result.has_lm, std::strstr(c.final_name, "LM") != nullptr);
    const double before = result.baseline.test.mae(ErrorAxis::norm_3d);
    for (const CalibrationStage& stage : result.stage_list()) {
      EXPECT_LT(stage.test.mae(ErrorAxis::norm_3d), before) << calibration_solver_name(stage.solver);
      EXPECT_EQ(stage.test.count, 36u);
      EXPECT_GT(stage.trace_m.size(), 0u);
    }
    if (result.has_lm) {
      EXPECT_LT(last(result).test.mae(ErrorAxis::norm_3d), 50e-6);
    }
  }
}

TEST(CalibrationJob, AllIsTheTableOneOrderEachFromTheStart) {
  fill(120, &dataset);
  ASSERT_EQ(calibrate(start(), &dataset, quick_options(CalibrationMethod::all), &workspace, &result), Status::ok);
  EXPECT_EQ(result.stages[0].solver, CalibrationSolver::gsa);
  EXPECT_EQ(result.stages[1].solver, CalibrationSolver::abc);
  EXPECT_EQ(result.stages[2].solver, CalibrationSolver::lm);
  EXPECT_FALSE(result.stages[2].refines_previous);
}

TEST(CalibrationJob, HybridHasTheBitsOfTheStageFunctionsCalledByHand) {
  fill(120, &dataset);
  CalibrationOptions options = quick_options(CalibrationMethod::abc_lm);
  options.significance_t = 0.0;  // every identifiable parameter, as one LM call by hand
  ASSERT_EQ(calibrate(start(), &dataset, options, &workspace, &result), Status::ok);
  fill(120, &dataset);
  ASSERT_EQ(dataset.split(0.7, 1), Status::ok);
  static Paper6Cost<kSamples> cost;
  static AbcSolver<40, kPaper6Dimension> abc;
  static LmWorkspace lm_workspace;
  static LmResult lm;
  // The baseline: tool point and base with the nominal joints; the stages start from it.
  RigidTransform base;
  ASSERT_EQ(fit_base_to_tracker(start(), dataset.train(), &base), Status::ok);
  LmOptions baseline_options;
  baseline_options.params = LmParamSet::custom;
  baseline_options.custom_mask = 0;
  for (int axis = 0; axis < 3; ++axis) {
    baseline_options.custom_mask |= param_bit(tool_param_index(kSixJoints, axis)) |
                                    param_bit(base_rotation_param_index(kSixJoints, axis)) |
                                    param_bit(base_translation_param_index(kSixJoints, axis));
  }
  ASSERT_EQ(calibrate_lm(start(), &base, dataset.train(), baseline_options, &lm_workspace, &lm), Status::ok);
  const RobotModel baseline = lm.model;
  EXPECT_TRUE(same_bits(result.baseline.model, baseline));
  AbcOptions abc_options;
  abc_options.food_sources = 20;
  abc_options.cycles = 20;
  Paper6StageResult population;
  ASSERT_EQ(calibrate_paper6_abc(baseline, dataset.train(), {}, abc_options, kPaper6DefaultHalfWidth_m, &cost, &abc,
                                 &population),
            Status::ok);
  // Every LM fit of the job holds the start model (the given tool point) as its prior.
  const RobotModel nominal_start = start();
  LmOptions lm_options;
  lm_options.prior = LmPrior{&nominal_start, options.prior};
  ASSERT_EQ(
      calibrate_lm(population.model, &population.base_to_tracker, dataset.train(), lm_options, &lm_workspace, &lm),
      Status::ok);
  // What LM dropped goes back to its start value, and LM runs once more from where it ended.
  ModelParams from = to_params(lm.model);
  const ModelParams nominal = to_params(baseline);
  bool reset = false;
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(lm.identifiability.kept_mask, i) && from(i) != nominal(i)) {
      from(i) = nominal(i);
      reset = true;
    }
  }
  EXPECT_TRUE(reset) << "ABC moves d1, which the full model cannot separate from the base";
  const RigidTransform warm_base = lm.base_to_tracker;
  ASSERT_EQ(
      calibrate_lm(with_model_params(baseline, from), &warm_base, dataset.train(), lm_options, &lm_workspace, &lm),
      Status::ok);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(lm.identifiability.kept_mask, i)) {
      EXPECT_EQ(to_params(last(result).model)(i), nominal(i)) << i;
    }
  }
  EXPECT_TRUE(same_bits(result.stages[0].model, population.model));
  EXPECT_TRUE(same_bits(last(result).model, lm.model));
  EXPECT_EQ(result.lm.rms_m, lm.rms_m);
}

// On more training samples than options.population_subset, a hybrid's population stage
// searches on the spanning subset (the bits of the stage function called with it by hand) and
// LM refines on every sample; the paper's methods and population_subset 0 search on all.
TEST(CalibrationJob, HybridSearchesASpanningSubsetOfLargeSets) {
  constexpr std::size_t kLarge = 500;
  static CalibrationWorkspace<kLarge, double, 20, 300> large_workspace;
  static Dataset<kLarge> large;
  fill(kLarge, &large);
  const CalibrationOptions options = quick_options(CalibrationMethod::abc_lm);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(start(), &large, options, &large_workspace, &result));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(result.stage_count, 2u);
  EXPECT_EQ(result.train_count, 350u);
  EXPECT_EQ(result.stages[0].searched_samples, kDefaultPopulationSubset);
  EXPECT_EQ(result.stages[0].train.count, 350u);  // its errors are on every training sample
  EXPECT_EQ(result.stages[1].searched_samples, 0u);
  EXPECT_LT(last(result).test.mae(ErrorAxis::norm_3d), 0.2 * result.baseline.test.mae(ErrorAxis::norm_3d));

  fill(kLarge, &large);
  ASSERT_EQ(large.split(0.7, 1), Status::ok);
  static double scratch[kLarge];
  std::uint32_t subset[kDefaultPopulationSubset] = {};
  ASSERT_EQ(spanning_subset(large.train(), kSixJoints, Span<double>(scratch), Span<std::uint32_t>(subset)),
            kDefaultPopulationSubset);
  static Paper6Cost<kLarge> cost;
  static AbcSolver<20, kPaper6Dimension> abc;
  AbcOptions abc_options;
  abc_options.food_sources = 20;
  abc_options.cycles = 20;
  Paper6StageResult population;
  ASSERT_EQ(calibrate_paper6_abc(result.baseline.model, large.train(), Span<const std::uint32_t>(subset), abc_options,
                                 kPaper6DefaultHalfWidth_m, &cost, &abc, &population),
            Status::ok);
  EXPECT_TRUE(same_bits(result.stages[0].model, population.model));

  for (const CalibrationMethod method : {CalibrationMethod::abc_lm, CalibrationMethod::abc, CalibrationMethod::all}) {
    CalibrationOptions every = quick_options(method);
    if (method == CalibrationMethod::abc_lm) every.population_subset = 0;
    ASSERT_EQ(calibrate(start(), &large, every, &large_workspace, &other), Status::ok);
    for (std::size_t k = 0; k < other.stage_count; ++k) {
      if (other.stages[k].solver != CalibrationSolver::lm) {
        EXPECT_EQ(other.stages[k].searched_samples, 350u) << calibration_method_name(method);
      }
    }
  }
  // The workspace holds room for more than the default: a larger subset is taken whole, and
  // one past the room is cut to it.
  for (const std::size_t wanted : {kMaxPopulationSubset, kMaxPopulationSubset + 1}) {
    CalibrationOptions larger = quick_options(CalibrationMethod::abc_lm);
    larger.population_subset = wanted;
    ASSERT_EQ(calibrate(start(), &large, larger, &large_workspace, &other), Status::ok);
    EXPECT_EQ(other.stages[0].searched_samples, kMaxPopulationSubset);
  }
}

TEST(CalibrationJob, TrainingOnEverySampleLeavesNoTestRows) {
  fill(60, &dataset);
  CalibrationOptions options = quick_options(CalibrationMethod::lm);
  options.train_fraction = 1.0;
  ASSERT_EQ(calibrate(start(), &dataset, options, &workspace, &result), Status::ok);
  EXPECT_EQ(result.train_count, 60u);
  EXPECT_EQ(result.test_count, 0u);
  EXPECT_EQ(result.baseline.test.count, 0u);
  EXPECT_EQ(last(result).test.count, 0u);
  EXPECT_EQ(last(result).train.count, 60u);
}

TEST(CalibrationJob, JointTrigStorageChangesTimeNotBits) {
  for (CalibrationMethod method : {CalibrationMethod::lm, CalibrationMethod::abc_lm}) {
    fill(120, &dataset);
    CalibrationOptions options = quick_options(method);
    options.robust = true;
    ASSERT_EQ(calibrate(start(), &dataset, options, &workspace, &result), Status::ok);
    fill(120, &dataset);
    ASSERT_EQ(calibrate(start(), &dataset, options, &trig_workspace, &other), Status::ok);
    EXPECT_TRUE(same_bits(last(result).model, last(other).model));
    EXPECT_EQ(result.lm.rms_m, other.lm.rms_m);
    EXPECT_EQ(result.lm.iterations, other.lm.iterations);
  }
}

/// Stops LM after its first iteration.
class Cancel final : public CalibrationObserver {
 public:
  void on_stage_begin(std::size_t, CalibrationSolver) override { ++begun; }
  void on_stage_end(std::size_t, const CalibrationStage&) override { ++ended; }
  bool on_iteration(const LmIterationInfo&) override { return false; }
  void on_iteration(const SolverProgress&) override { ++population_iterations; }
  int begun = 0;
  int ended = 0;
  int population_iterations = 0;
};

void expect_failure(Status status, Status expected, CalibrationStep expected_step) {
  EXPECT_EQ(status, expected) << status_message(status);
  EXPECT_EQ(result.status, expected);
  EXPECT_EQ(result.step, expected_step) << calibration_step_name(result.step);
}

TEST(CalibrationJob, SaysWhichStepFailedAndWhy) {
  const CalibrationOptions options = quick_options(CalibrationMethod::abc_lm);
  fill(120, &dataset);
  EXPECT_EQ(calibrate(start(), &dataset, options, &workspace, nullptr), Status::invalid_argument);
  expect_failure(calibrate(start(), nullptr, options, &workspace, &result), Status::invalid_argument,
                 CalibrationStep::input);
  expect_failure(calibrate(start(), &dataset, options, nullptr, &result), Status::invalid_argument,
                 CalibrationStep::input);
  CalibrationOptions unknown = options;
  unknown.method = static_cast<CalibrationMethod>(42);
  expect_failure(calibrate(start(), &dataset, unknown, &workspace, &result), Status::invalid_argument,
                 CalibrationStep::input);

  dataset.clear();
  expect_failure(calibrate(start(), &dataset, options, &workspace, &result), Status::dataset_empty,
                 CalibrationStep::input);
  fill(2, &dataset);  // not even the base frame
  expect_failure(calibrate(start(), &dataset, options, &workspace, &result), Status::too_few_samples,
                 CalibrationStep::baseline);
  fill(8, &dataset);  // no floor: 8 samples estimate fewer parameters
  CalibrationOptions every = quick_options(CalibrationMethod::lm);
  every.train_fraction = 1.0;
  EXPECT_EQ(calibrate(start(), &dataset, every, &workspace, &result), Status::ok);
  EXPECT_LT(result.lm.identifiability.kept_count(), 24);

  fill(120, &dataset);
  CalibrationOptions no_training = options;
  no_training.train_fraction = 0.0;
  expect_failure(calibrate(start(), &dataset, no_training, &workspace, &result), Status::invalid_argument,
                 CalibrationStep::split);

  dataset.clear();
  for (int i = 0; i < 40; ++i) ASSERT_EQ(dataset.add(JointVector::Zero(), Vec3(1.0, 2.0, 3.0)), Status::ok);
  expect_failure(calibrate(start(), &dataset, options, &workspace, &result), Status::degenerate_geometry,
                 CalibrationStep::baseline);

  fill(120, &dataset);
  CalibrationOptions crowd = options;
  crowd.abc_food_sources = 41;  // the workspace holds 40
  expect_failure(calibrate(start(), &dataset, crowd, &workspace, &result), Status::population_out_of_range,
                 CalibrationStep::abc);
  CalibrationOptions gsa_crowd = quick_options(CalibrationMethod::all);
  gsa_crowd.gsa_agents = 41;
  fill(120, &dataset);
  expect_failure(calibrate(start(), &dataset, gsa_crowd, &workspace, &result), Status::population_out_of_range,
                 CalibrationStep::gsa);

  // A workspace without GSA (the firmware's): GSA refused as over capacity, ABC+LM runs.
  static CalibrationWorkspace<kSamples, float, 40, 8, 0, kPaper6Dimension, 1, 0, 0> no_gsa;
  fill(120, &dataset);
  expect_failure(calibrate(start(), &dataset, quick_options(CalibrationMethod::gsa_lm), &no_gsa, &result),
                 Status::population_out_of_range, CalibrationStep::gsa);
  fill(120, &dataset);
  EXPECT_EQ(calibrate(start(), &dataset, quick_options(CalibrationMethod::abc_lm), &no_gsa, &result), Status::ok);

  static CalibrationWorkspace<32, float, 40, 8> tiny;  // cost room for 32 training samples
  fill(120, &dataset);
  expect_failure(calibrate(start(), &dataset, options, &tiny, &result), Status::dataset_full, CalibrationStep::abc);

  fill(120, &dataset);
  Cancel cancel;
  expect_failure(calibrate(start(), &dataset, options, &workspace, &result, &cancel), Status::solver_cancelled,
                 CalibrationStep::lm);
  EXPECT_EQ(cancel.begun, 2);
  EXPECT_EQ(cancel.ended, 1);
  EXPECT_EQ(cancel.population_iterations, 20);
  EXPECT_EQ(result.stage_count, 1u);  // the ABC stage, kept
}

}  // namespace
}  // namespace hivecal::calibration_test
