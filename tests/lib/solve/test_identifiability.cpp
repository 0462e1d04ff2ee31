// Identifiability analysis: it must find the UR's non-identifiable parameters from the data
// alone. Asserted by properties (ranks, one per redundant group, what each combination
// contains), not by one seed's list.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/solve/identifiability.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::identifiability_test {
namespace {

constexpr int kTheta1 = model_param_index(0, DhField::theta_offset);
constexpr int kD1 = model_param_index(0, DhField::d);
constexpr int kD2 = model_param_index(1, DhField::d);
constexpr int kD3 = model_param_index(2, DhField::d);
constexpr int kD4 = model_param_index(3, DhField::d);
constexpr int kD6 = model_param_index(5, DhField::d);
constexpr int kToolZ = tool_param_index(kSixJoints, 2);
constexpr int kBaseRz = base_rotation_param_index(kSixJoints, 2);
constexpr int kBaseTz = base_translation_param_index(kSixJoints, 2);

ParamMask mask_of(std::initializer_list<int> indices) {
  ParamMask mask = 0;
  for (int i : indices) mask |= param_bit(i);
  return mask;
}

/// Joint 6's DH parameters and the tool point: 7 parameters, 3 identifiable (a point in frame 5).
ParamMask wrist_and_tool() {
  ParamMask mask = 0;
  for (int f = 0; f < kParamsPerJoint; ++f) mask |= param_bit(5 * kParamsPerJoint + f);
  for (int axis = 0; axis < 3; ++axis) mask |= param_bit(tool_param_index(kSixJoints, axis));
  return mask;
}

int dropped_in(const IdentifiabilityReport& report, ParamMask group) {
  return mask_count(report.free_mask & ~report.kept_mask & group);
}

/// Parameters of a dropped entry's combination.
ParamMask members(const DroppedParam& entry) {
  ParamMask mask = 0;
  for (int index : entry.component_index) {
    if (index >= 0) mask |= param_bit(index);
  }
  return mask;
}

/// Normal equations of `model` seen through `base` at the poses of `dataset`.
const NormalEquations& normal_equations(const RobotModel& model, const RigidTransform& base,
                                        const DatasetBase& dataset) {
  static NormalEquations eq;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = accumulate_normal_equations(model, base, dataset.samples(), PointLoss{}, &eq));
  EXPECT_EQ(status, Status::ok);
  return eq;
}

IdentifiabilityReport analyse(const NormalEquations& eq, ParamMask free_mask) {
  static IdentifiabilityWorkspace ws;
  static IdentifiabilityReport report;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = analyze_identifiability(eq.jtwj, free_mask, kDefaultIdentifiabilityThreshold, &ws, &report));
  EXPECT_EQ(status, Status::ok);
  return report;
}

/// The generic-pose properties, for any arm and seed.
void expect_generic_ur_structure(const IdentifiabilityReport& report) {
  EXPECT_EQ(report.kept_count(), 25);
  EXPECT_EQ(report.dropped_count, 8);
  EXPECT_EQ(dropped_in(report, mask_of({kTheta1, kBaseRz})), 1);  // base rotation about z absorbs theta1
  EXPECT_EQ(dropped_in(report, mask_of({kD1, kBaseTz})), 1);      // base height absorbs d1
  EXPECT_EQ(dropped_in(report, mask_of({kD2, kD3, kD4})), 2);     // only d2 + d3 + d4 on parallel axes
  EXPECT_EQ(dropped_in(report, wrist_and_tool()), 4);             // tool point in frame 5: 3 of 7
  for (int d = 0; d < report.dropped_count; ++d) {
    const DroppedParam& entry = report.dropped[d];
    EXPECT_EQ(entry.reason, UnidentifiableReason::null_combination);
    EXPECT_LT(entry.singular_ratio, 1e-6) << full_param_name(entry.index, kSixJoints);
    EXPECT_EQ(entry.component_index[0], entry.index);
    EXPECT_EQ(entry.component[0], 1.0);
    // Each combination stays inside the group that explains it.
    const ParamMask m = members(entry);
    const bool in_group = (m & ~mask_of({kTheta1, kBaseRz})) == 0 || (m & ~mask_of({kD1, kBaseTz})) == 0 ||
                          (m & ~mask_of({kD2, kD3, kD4})) == 0 || (m & ~wrist_and_tool()) == 0;
    EXPECT_TRUE(in_group) << full_param_name(entry.index, kSixJoints);
    EXPECT_GE(mask_count(m), 2) << full_param_name(entry.index, kSixJoints);
  }
  ASSERT_EQ(report.singular_count_before, rigid_param_count(kSixJoints));
  ASSERT_EQ(report.singular_count_after, 25);
  const double sigma_max = report.singular_values_before[0];
  for (int k = 1; k < report.singular_count_before; ++k) {
    EXPECT_LE(report.singular_values_before[k], report.singular_values_before[k - 1]);
  }
  EXPECT_GT(report.singular_values_before[24], 1e-3 * sigma_max);  // a wide gap to the nulls
  EXPECT_LT(report.singular_values_before[25], 1e-6 * sigma_max);
  EXPECT_GT(report.condition_before, 1e6);
  EXPECT_LT(report.condition_after, 1e3);
  EXPECT_NEAR(report.condition_after,
              report.singular_values_after[0] / report.singular_values_after[report.singular_count_after - 1], 1e-9);
}

TEST(Identifiability, GenericPosesDropExactlyTheUrRedundancies) {
  for (RobotType type : {RobotType::ur5, RobotType::ur10, RobotType::ur5e}) {
    for (std::uint64_t seed : {201u, 202u}) {
      SCOPED_TRACE(robot_type_name(type));
      Random random(seed);
      // Generic truth: joints 2-4 not exactly parallel here; the nulls are still < 1e-6.
      RobotModel truth = test::perturbed_model(nominal_model(type), &random, 3e-4, 3e-4);
      truth.tool_m = Vec3(0.01, -0.02, 0.15);
      static Dataset<100> dataset;
      dataset.clear();
      test::fill_dataset(truth, test::example_base_to_tracker(), 100, 0.0, &random, &dataset);
      expect_generic_ur_structure(
          analyse(normal_equations(truth, test::example_base_to_tracker(), dataset), rigid_params_mask(kSixJoints)));
    }
  }
}

TEST(Identifiability, ToolAlwaysDownDropsTheToolHeightAgainstTheBaseHeight) {
  Random random(203);
  const RobotModel truth = test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.01, -0.02, 0.15));
  const RigidTransform base = test::example_base_to_tracker();
  static Dataset<100> generic;
  static Dataset<100> down;
  generic.clear();
  down.clear();
  test::fill_dataset(truth, base, 100, 0.0, &random, &generic);
  test::fill_tool_down_dataset(truth, base, 100, 0.0, &random, &down);
  for (const Sample& s : down.samples()) EXPECT_NEAR(test::joint6_axis(truth, s.q_rad).z(), -1.0, 1e-12);

  // A vertical tool translation (d6, tool z) is a z shift in the base frame when joint 6
  // always points down: indistinguishable from the base height (base_tz, d1).
  const ParamMask tool_height = mask_of({kD6, kToolZ});
  const ParamMask base_height = mask_of({kD1, kBaseTz});
  auto couples_heights = [&](const DroppedParam& entry) {
    const ParamMask m = members(entry);
    return (m & tool_height) != 0 && (m & base_height) != 0;
  };
  const IdentifiabilityReport generic_report =
      analyse(normal_equations(truth, base, generic), rigid_params_mask(kSixJoints));
  const IdentifiabilityReport down_report = analyse(normal_equations(truth, base, down), rigid_params_mask(kSixJoints));
  EXPECT_EQ(down_report.kept_count(), generic_report.kept_count() - 1);
  EXPECT_EQ(down_report.dropped_count, generic_report.dropped_count + 1);
  int generic_couplings = 0;
  int down_couplings = 0;
  for (int d = 0; d < generic_report.dropped_count; ++d)
    generic_couplings += couples_heights(generic_report.dropped[d]);
  for (int d = 0; d < down_report.dropped_count; ++d) down_couplings += couples_heights(down_report.dropped[d]);
  EXPECT_EQ(generic_couplings, 0);
  EXPECT_GE(down_couplings, 1);
  // Three of the four heights are gone; one carries their sum.
  EXPECT_EQ(dropped_in(down_report, tool_height | base_height), 3);

  // And the solver, on tool-down data, still predicts tool-down poses exactly.
  static LmWorkspace ws;
  static LmResult result;
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.15);
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = calibrate_lm(start, nullptr, down.samples(), LmOptions{}, &ws, &result));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  EXPECT_EQ(result.identifiability.kept_count(), 24);
  static Dataset<50> fresh_down;
  fresh_down.clear();
  test::fill_tool_down_dataset(truth, base, 50, 0.0, &random, &fresh_down);
  EXPECT_LE(test::max_prediction_gap(result.model, result.base_to_tracker, truth, base, fresh_down.samples()), 1e-9);
}

TEST(Identifiability, FixedBaseMakesTheta1AndD1Identifiable) {
  Random random(204);
  RobotModel truth = test::perturbed_model(nominal_model(RobotType::ur5), &random, 3e-4, 3e-4);
  truth.tool_m = Vec3(0.01, -0.02, 0.15);
  static Dataset<100> dataset;
  dataset.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), 100, 0.0, &random, &dataset);
  const ParamMask model_only =
      rigid_params_mask(kSixJoints) & ~(((ParamMask{1} << kBaseParamCount) - 1U) << model_param_count(kSixJoints));
  const IdentifiabilityReport report =
      analyse(normal_equations(truth, test::example_base_to_tracker(), dataset), model_only);
  EXPECT_EQ(report.free_mask, model_only);
  EXPECT_TRUE(mask_has(report.kept_mask, kTheta1));
  EXPECT_TRUE(mask_has(report.kept_mask, kD1));
  EXPECT_EQ(report.kept_count(), 27 - 6);  // d2/d3 and joint 6 against the tool remain
}

TEST(Identifiability, DuplicateAndZeroColumnsOnHandmadeNormalEquations) {
  // J has columns e0, e1, e0 (duplicate), 0, 2 e2 over parameters 0..4.
  static NormalMatrix jtj;
  jtj.setZero();
  jtj(0, 0) = jtj(2, 2) = jtj(0, 2) = jtj(2, 0) = 1.0;
  jtj(1, 1) = 1.0;
  jtj(4, 4) = 4.0;
  static IdentifiabilityWorkspace ws;
  static IdentifiabilityReport report;
  Status status = Status::ok;
  EXPECT_NO_HEAP(status = analyze_identifiability(jtj, mask_of({0, 1, 2, 3, 4}), 1e-6, &ws, &report));
  ASSERT_EQ(status, Status::ok);
  EXPECT_EQ(report.kept_mask, mask_of({1, 2, 4}));
  ASSERT_EQ(report.dropped_count, 2);
  EXPECT_EQ(report.dropped[0].index, 3);
  EXPECT_EQ(report.dropped[0].reason, UnidentifiableReason::no_effect);
  EXPECT_EQ(report.dropped[1].index, 0);  // the lower index of the tied pair
  EXPECT_EQ(report.dropped[1].reason, UnidentifiableReason::null_combination);
  EXPECT_EQ(report.dropped[1].component_index[1], 2);
  EXPECT_NEAR(report.dropped[1].component[1], -1.0, 1e-12);
  EXPECT_EQ(report.dropped[1].component_index[2], -1);
  EXPECT_EQ(report.singular_count_before, 4);
  EXPECT_NEAR(report.singular_values_before[0], std::sqrt(2.0), 1e-12);
  EXPECT_EQ(report.singular_count_after, 3);
  EXPECT_NEAR(report.condition_after, 1.0, 1e-12);
  EXPECT_TRUE(std::isinf(report.condition_before) || report.condition_before > 1e7);
  const char* names[2] = {};
  EXPECT_NO_HEAP(names[0] = unidentifiable_reason_name(UnidentifiableReason::no_effect));
  EXPECT_NO_HEAP(names[1] = unidentifiable_reason_name(UnidentifiableReason::null_combination));
  EXPECT_STREQ(names[0], "no_effect");
  EXPECT_STREQ(names[1], "null_combination");
}

TEST(Identifiability, BadArguments) {
  static NormalMatrix jtj;
  jtj.setIdentity();
  static IdentifiabilityWorkspace ws;
  static IdentifiabilityReport report;
  const auto check = [&](ParamMask mask, double threshold, Status expected) {
    Status analysed = Status::ok;
    EXPECT_NO_HEAP(analysed = analyze_identifiability(jtj, mask, threshold, &ws, &report));
    EXPECT_EQ(analysed, expected);
  };
  check(rigid_params_mask(kSixJoints), 0.0, Status::invalid_argument);
  check(rigid_params_mask(kSixJoints), 1.0, Status::invalid_argument);
  check(0, 1e-4, Status::invalid_argument);
  check(param_bit(kFullParamCount), 1e-4, Status::invalid_argument);  // beyond the compliance coefficients
  jtj(3, 3) = std::nan("");
  check(rigid_params_mask(kSixJoints), 1e-4, Status::non_finite_input);
  jtj.setZero();
  check(rigid_params_mask(kSixJoints), 1e-4, Status::singular_system);
}

TEST(Identifiability, ParameterNames) {
  const char* names[kFullParamCount + 2] = {};
  EXPECT_NO_HEAP(for (int i = -1; i <= kFullParamCount; ++i) names[i + 1] = full_param_name(i, kSixJoints));
  const auto name = [&](int index) { return names[index + 1]; };
  EXPECT_STREQ(name(kTheta1), "theta1");
  EXPECT_STREQ(name(kD2), "d2");
  EXPECT_STREQ(name(model_param_index(2, DhField::a)), "a3");
  EXPECT_STREQ(name(model_param_index(3, DhField::alpha)), "alpha4");
  EXPECT_STREQ(name(tool_param_index(kSixJoints, 0)), "tool_x");
  EXPECT_STREQ(name(kToolZ), "tool_z");
  EXPECT_STREQ(name(base_rotation_param_index(kSixJoints, 0)), "base_rx");
  EXPECT_STREQ(name(kBaseTz), "base_tz");
  EXPECT_STREQ(name(-1), "?");
  EXPECT_STREQ(name(kFullParamCount), "?");
}

}  // namespace
}  // namespace hivecal::identifiability_test
