// LM with the nominal model as a prior (LmOptions::prior, docs/solver-lm.md "The nominal model
// as a prior"): a direction the poses barely determine stays at nominal instead of moving by
// centimetres, what they determine is estimated as without it, a parameter held by the prior
// keeps about its tolerance as sigma, and no prior is least squares, bit for bit.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>

#include "hivecal/core/random.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::lm_prior_test {
namespace {

test::LmTestStorage<400>& storage() {
  static test::LmTestStorage<400> s;
  return s;
}

/// fill_narrow_wrist_dataset into a cleared *out.
void fill_narrow_wrist(const RobotModel& truth, std::size_t count, double effect_m, Random* random, DatasetBase* out) {
  out->clear();
  test::fill_narrow_wrist_dataset(truth, count, effect_m, random, out);
  ASSERT_EQ(out->size(), count);
}

/// The UR10 of these tests: perturbed by 0.5 mm / 0.5 mrad, the tool point 2 mm off the
/// flange axis (and the start's guess on it).
RobotModel truth_ur10() {
  Random random(5201);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur10), &random, 0.5e-3, 0.5e-3);
  truth.tool_m << 0.002, 0.0, 0.12;
  return truth;
}

RobotModel start_ur10() {
  RobotModel start = nominal_model(RobotType::ur10);
  start.tool_m << 0.0, 0.0, 0.12;
  return start;
}

/// Mean 3-D error of `result`'s fit on `fresh` against the points without noise and effect.
double fresh_mae_m(const LmResult& result, const RobotModel& truth, Span<const Sample> fresh) {
  const RigidTransform base = test::example_base_to_tracker();
  double sum_m = 0.0;
  for (const Sample& s : fresh) {
    sum_m +=
        (result.base_to_tracker.apply(fk_tool_point(result.model, s.q_rad)) - base.apply(fk_tool_point(truth, s.q_rad)))
            .norm();
  }
  return sum_m / static_cast<double>(fresh.size());
}

/// Change of parameter `field` of joint `joint` (0-based) from the start [m] or [rad].
double change(const LmResult& result, const RobotModel& start, int joint, DhField field) {
  const int i = model_param_index(joint, field);
  return to_params(result.model)(i) - to_params(start)(i);
}

TEST(LmPrior, ADirectionThePosesBarelyDetermineStaysAtNominal) {
  // 300 poses with wrist 2 within +-0.05 rad of -pi/2 and 0.3 mm of unmodelled deflection: d5
  // and alpha5 are told apart by the tool point's 2 mm off the flange axis only (kept by the
  // analysis, correlation near 1), and least squares swings alpha5 by a tenth of a radian to
  // absorb the deflection. The prior keeps them near nominal and predicts as well.
  const RobotModel truth = truth_ur10();
  const RobotModel start = start_ur10();
  auto& s = storage();
  Random random(5202);
  fill_narrow_wrist(truth, 300, 0.3e-3, &random, &s.train);
  fill_narrow_wrist(truth, 300, 0.0, &random, &s.fresh);
  LmOptions plain;
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), plain, &s.workspace, &s.result), Status::ok);
  const double plain_alpha5_rad = change(s.result, start, 4, DhField::alpha);
  const double plain_mae_m = fresh_mae_m(s.result, truth, s.fresh.samples());
  ASSERT_TRUE(mask_has(s.result.identifiability.kept_mask, model_param_index(4, DhField::d)));
  LmOptions with_prior;
  with_prior.prior = LmPrior{&start, LmPriorTolerances{1e-3, 5e-3, 0.02}};
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate_lm(start, nullptr, s.train.samples(), with_prior, &s.workspace, &s.result));
  ASSERT_EQ(status, Status::ok);
  const double prior_mae_m = fresh_mae_m(s.result, truth, s.fresh.samples());
  std::printf("alpha5 %+.2f mrad (least squares) -> %+.3f mrad, d5 %+.3f mm; fresh poses %.2f -> %.2f um\n",
              plain_alpha5_rad * 1e3, change(s.result, start, 4, DhField::alpha) * 1e3,
              change(s.result, start, 4, DhField::d) * 1e3, plain_mae_m * 1e6, prior_mae_m * 1e6);
  EXPECT_GT(std::fabs(plain_alpha5_rad), 0.05);
  for (int i = 0; i < kParamsPerJoint * kSixJoints; ++i) {
    const double moved = to_params(s.result.model)(i) - to_params(start)(i);
    EXPECT_LT(std::fabs(moved), 5e-3) << full_param_name(i, kSixJoints);  // 5 mm, 5 mrad
  }
  EXPECT_LT(prior_mae_m, 1.01 * plain_mae_m);
  // What only the prior determines keeps about its tolerance as sigma: the posterior's.
  const double sigma_d5_m = s.result.sigma(model_param_index(4, DhField::d));
  EXPECT_GT(sigma_d5_m, 0.3e-3);
  EXPECT_LE(sigma_d5_m, 1e-3);
  EXPECT_GT(s.result.prior_chi_square, 0.0);
}

TEST(LmPrior, WhatThePosesDetermineIsEstimatedAsWithoutIt) {
  // Generic poses of an arm 2 mm / 2 mrad off nominal (beyond the tolerances), 10 um noise:
  // every estimated parameter within a tenth of its sigma of the least-squares estimate.
  Random random(5203);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 2e-3, 2e-3);
  truth.tool_m << 0.02, -0.015, 0.12;  // off the flange axis: joint 5's parameters are determined
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = truth.tool_m;
  auto& s = storage();
  s.train.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), 200, 10e-6, &random, &s.train);
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), LmOptions{}, &s.workspace, &s.result), Status::ok);
  const ModelParams plain = to_params(s.result.model);
  const ParamMask kept = s.result.identifiability.kept_mask;
  LmOptions with_prior;
  with_prior.prior = LmPrior{&start, LmPriorTolerances{1e-3, 5e-3, 0.02}};
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), with_prior, &s.workspace, &s.result), Status::ok);
  EXPECT_EQ(s.result.identifiability.kept_mask, kept);
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    if (!mask_has(kept, i)) continue;
    EXPECT_LT(std::fabs(to_params(s.result.model)(i) - plain(i)), 0.1 * s.result.sigma(i))
        << full_param_name(i, kSixJoints);
  }
}

TEST(LmPrior, NoToleranceIsLeastSquaresBitForBit) {
  const RobotModel truth = truth_ur10();
  const RobotModel start = start_ur10();
  auto& s = storage();
  Random random(5204);
  fill_narrow_wrist(truth, 120, 0.3e-3, &random, &s.train);
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), LmOptions{}, &s.workspace, &s.result), Status::ok);
  const ModelParams plain = to_params(s.result.model);
  const double plain_rms_m = s.result.rms_m;
  LmOptions untoleranced;
  untoleranced.prior = LmPrior{&start, LmPriorTolerances{}};
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), untoleranced, &s.workspace, &s.result), Status::ok);
  EXPECT_TRUE(to_params(s.result.model) == plain);
  EXPECT_EQ(s.result.rms_m, plain_rms_m);
  EXPECT_EQ(s.result.prior_chi_square, 0.0);
}

/// Counts the iterations and the rejected trials since the last accepted one.
class TrialCount final : public LmObserver {
 public:
  bool on_iteration(const LmIterationInfo& info) override {
    trailing_rejections = info.accepted ? 0 : trailing_rejections + 1;
    ++iterations;
    return true;
  }
  int iterations = 0;           ///< iterations reported [-]
  int trailing_rejections = 0;  ///< rejected trials after the last accepted one [-]
};

// At its optimum up to rounding a trial is rejected, the damping raised, and again, a pass over
// the samples each: on a narrow-wrist grid of a UR5 with the prior 6 rejected trials ended the fit. A
// step whose predicted decrease the cost-change test would not count is not tried.
TEST(LmPrior, AStepThatPromisesNothingIsNotTried) {
  Random random(6003);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 1e-3, 1e-3);
  truth.tool_m << 0.02, -0.015, 0.12;
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m << 0.0, 0.0, 0.12;
  auto& s = storage();
  fill_narrow_wrist(truth, 300, 0.3e-3, &random, &s.train);
  LmOptions options;
  options.prior = LmPrior{&start, LmPriorTolerances{1e-3, 5e-3, 0.02}};
  TrialCount count;
  ASSERT_EQ(calibrate_lm(start, nullptr, s.train.samples(), options, &s.workspace, &s.result, nullptr, &count),
            Status::ok);
  EXPECT_EQ(s.result.termination, LmTermination::cost_change);
  EXPECT_EQ(count.trailing_rejections, 0);
  EXPECT_LE(count.iterations, 6);  // 11 before, 6 of them rejected trials at the end
}

TEST(LmPrior, SigmaOfEachKindIsItsTolerance) {
  RobotModel nominal = nominal_model(RobotType::ur5);
  const LmPrior prior{&nominal, LmPriorTolerances{1e-3, 5e-3, 0.02}};
  EXPECT_EQ(lm_prior_sigma(prior, model_param_index(1, DhField::a)), 1e-3);
  EXPECT_EQ(lm_prior_sigma(prior, model_param_index(3, DhField::d)), 1e-3);
  EXPECT_EQ(lm_prior_sigma(prior, model_param_index(4, DhField::alpha)), 5e-3);
  EXPECT_EQ(lm_prior_sigma(prior, model_param_index(0, DhField::theta_offset)), 5e-3);
  EXPECT_EQ(lm_prior_sigma(prior, tool_param_index(kSixJoints, 2)), 0.02);
  EXPECT_EQ(lm_prior_sigma(prior, base_rotation_param_index(kSixJoints, 0)), 0.0);
  EXPECT_EQ(lm_prior_sigma(prior, compliance_param_index(kSixJoints, 0)), 0.0);
  EXPECT_EQ(lm_prior_sigma(LmPrior{}, tool_param_index(kSixJoints, 0)), 0.0);
}

TEST(LmPrior, NegativeOrNonFiniteTolerancesAreRefused) {
  const RobotModel start = start_ur10();
  auto& s = storage();
  Random random(5205);
  fill_narrow_wrist(truth_ur10(), 40, 0.0, &random, &s.train);
  for (const double bad : {-1e-3, std::nan("")}) {
    LmOptions options;
    options.prior = LmPrior{&start, LmPriorTolerances{bad, 5e-3, 0.02}};
    EXPECT_EQ(calibrate_lm(start, nullptr, s.train.samples(), options, &s.workspace, &s.result),
              Status::invalid_argument);
  }
}

/// Fresh-pose MAE [m] of least squares and of the prior at the stated tolerances on `train`,
/// and the prior's widening.
struct PriorCheckFigures {
  double plain_mae_m = 0.0;  ///< least squares on fresh poses [m]
  double prior_mae_m = 0.0;  ///< with the prior on fresh poses [m]
  LmPriorTolerances held;    ///< LmResult::prior_tolerances [m], [rad]
  ModelParams prior_params;  ///< the prior's estimate
};

PriorCheckFigures fit_both(const RobotModel& truth, const RobotModel& start, Span<const Sample> train,
                           Span<const Sample> fresh) {
  auto& s = storage();
  PriorCheckFigures figures;
  EXPECT_EQ(calibrate_lm(start, nullptr, train, LmOptions{}, &s.workspace, &s.result), Status::ok);
  figures.plain_mae_m = fresh_mae_m(s.result, truth, fresh);
  LmOptions with_prior;
  with_prior.prior = LmPrior{&start, LmPriorTolerances{1e-3, 5e-3, 0.02}};
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate_lm(start, nullptr, train, with_prior, &s.workspace, &s.result));
  EXPECT_EQ(status, Status::ok);
  figures.prior_mae_m = fresh_mae_m(s.result, truth, fresh);
  figures.held = s.result.prior_tolerances;
  figures.prior_params = to_params(s.result.model);
  std::printf(
      "tolerances %.3g mm / %.3g mrad / %.3g mm (prior chi-square %.2f); fresh poses: least squares %.2f um, "
      "prior %.2f um\n",
      figures.held.dh_length_m * 1e3, figures.held.dh_angle_rad * 1e3, figures.held.tool_m * 1e3,
      s.result.prior_chi_square, figures.plain_mae_m * 1e6, figures.prior_mae_m * 1e6);
  return figures;
}

/// A UR5 `length_m` / `angle_rad` off nominal (seed `seed`), the tool point known, 60
/// well-spread poses with up to 3 mm of an effect no rigid model holds (the residual sigma a real
/// arm's model error gives), 300 fresh ones: fit_both's figures, *start the start model.
PriorCheckFigures figures_of_an_arm_off_nominal(std::uint64_t seed, double length_m, double angle_rad,
                                                RobotModel* start) {
  Random random(seed);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, length_m, angle_rad);
  truth.tool_m << 0.02, -0.015, 0.12;
  *start = nominal_model(RobotType::ur5);
  start->tool_m = truth.tool_m;
  auto& s = storage();
  s.train.clear();
  s.fresh.clear();
  test::fill_with_unmodelled_effect(truth, test::example_base_to_tracker(), 60, &random, &s.train);
  test::fill_dataset(truth, test::example_base_to_tracker(), 300, 0.0, &random, &s.fresh);
  return fit_both(truth, *start, s.train.samples(), s.fresh.samples());
}

TEST(LmPrior, AnArmFarBeyondItsTolerancesWidensThemAndPredictsAsLeastSquares) {
  // 10 mm / 20 mrad off: at 1 mm / 5 mrad the prior pulls what the poses determine less than the
  // residuals do back towards a nominal the data contradict (4.8 mm on fresh poses against least
  // squares' 1.4 mm); its chi-square says so, the tolerances widen, and the fit predicts fresh
  // poses as least squares does.
  RobotModel start;
  const PriorCheckFigures figures = figures_of_an_arm_off_nominal(5301, 10e-3, 20e-3, &start);
  EXPECT_GT(figures.held.dh_length_m, 2.0e-3);
  EXPECT_GT(figures.held.dh_angle_rad, 10e-3);
  EXPECT_LT(figures.prior_mae_m, 1.01 * figures.plain_mae_m);
}

TEST(LmPrior, EachKindOfToleranceFollowsItsOwnPseudoObservations) {
  // Lengths 10 mm off, angles within their 5 mrad: the lengths' tolerance widens, the angles'
  // stays near what was stated (each kind is a variance component of its own; one common factor
  // would have widened the angles as much as the lengths).
  RobotModel start;
  const PriorCheckFigures figures = figures_of_an_arm_off_nominal(5303, 10e-3, 1e-3, &start);
  EXPECT_GT(figures.held.dh_length_m, 3.0e-3);
  EXPECT_LT(figures.held.dh_angle_rad / 5e-3, 0.5 * figures.held.dh_length_m / 1e-3);
  EXPECT_GE(figures.held.dh_angle_rad, 5e-3);  // never below the stated tolerance
  EXPECT_LT(figures.prior_mae_m, 1.01 * figures.plain_mae_m);
}

TEST(LmPrior, AnArmWithinItsTolerancesKeepsThemExactly) {
  // 0.5 mm / 2 mrad off: the prior's chi-square is what its tolerances allow, the tolerances stay
  // as stated (factor exactly 1: the fit of the fixed prior, the same bits).
  RobotModel start;
  const PriorCheckFigures figures = figures_of_an_arm_off_nominal(5302, 0.5e-3, 2e-3, &start);
  EXPECT_EQ(figures.held.dh_length_m, 1e-3);
  EXPECT_EQ(figures.held.dh_angle_rad, 5e-3);
  EXPECT_EQ(figures.held.tool_m, 0.02);
  for (int i = 0; i < kParamsPerJoint * kSixJoints; ++i) {
    const double moved = figures.prior_params(i) - to_params(start)(i);
    EXPECT_LT(std::fabs(moved), 10e-3) << full_param_name(i, kSixJoints);
  }
}

}  // namespace
}  // namespace hivecal::lm_prior_test
