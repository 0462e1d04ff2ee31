// Bad input to the LM calibration gets a specific Status, never a result with ok.
#include <gtest/gtest.h>

#include <limits>

#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::lm_errors_test {
namespace {

struct LmErrors : ::testing::Test {
  /// The fixture's samples (train), workspace and result.
  static test::LmTestStorage<64>& lm() {
    static test::LmTestStorage<64> storage;
    return storage;
  }
  RobotModel model = nominal_model(RobotType::ur5);
  RigidTransform base = test::example_base_to_tracker();

  void SetUp() override {
    Random random(501);
    lm().train.clear();
    test::fill_dataset(model, base, 64, 1e-5, &random, &lm().train);
  }
  Status run(Span<const Sample> samples, const LmOptions& options = LmOptions{}, const RigidTransform* start = nullptr,
             const RobotModel* start_model = nullptr) {
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = calibrate_lm(start_model != nullptr ? *start_model : model, start, samples, options,
                                         &lm().workspace, &lm().result));
    return status;
  }
};

TEST_F(LmErrors, EmptyOrTooFewSamplesForTheFreeParameters) {
  EXPECT_EQ(run({}), Status::dataset_empty);
  // No floor but the base frame's: 2 samples (6 residuals) cannot determine its 6 parameters.
  EXPECT_EQ(run(lm().train.samples().subspan(0, 2)), Status::too_few_samples);
  // 8 samples, 24 residuals for 33 candidates: fewer are estimated, the rest named as dropped.
  EXPECT_EQ(run(lm().train.samples().subspan(0, 8)), Status::ok);
  EXPECT_LT(lm().result.identifiability.kept_count(), 24);
  EXPECT_EQ(lm().result.identifiability.dropped_count, 33 - lm().result.identifiability.kept_count());
  EXPECT_GT(lm().result.residual_sigma_m, 0.0);
  EXPECT_EQ(run(lm().train.samples().subspan(0, 12)), Status::ok);
  LmOptions paper6;
  paper6.params = LmParamSet::link_lengths;  // 12 free parameters
  EXPECT_EQ(run(lm().train.samples().subspan(0, 2), paper6), Status::too_few_samples);
  EXPECT_EQ(run(lm().train.samples().subspan(0, 4), paper6), Status::ok);  // 12 residuals: 11 or fewer kept
  EXPECT_LT(lm().result.identifiability.kept_count(), 12);
}

TEST_F(LmErrors, NonFiniteStartModelBaseOrSample) {
  RobotModel bad_model = model;
  bad_model.joints[2].a_m = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(run(lm().train.samples(), LmOptions{}, nullptr, &bad_model), Status::non_finite_input);
  bad_model = model;
  bad_model.tool_m.z() = std::numeric_limits<double>::infinity();
  EXPECT_EQ(run(lm().train.samples(), LmOptions{}, &base, &bad_model), Status::non_finite_input);
  RigidTransform bad_base = base;
  bad_base.translation_m.x() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(run(lm().train.samples(), LmOptions{}, &bad_base), Status::non_finite_input);
  Sample samples[20];
  for (int i = 0; i < 20; ++i) samples[i] = lm().train.samples()[static_cast<std::size_t>(i)];
  samples[13].point_m.y() = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(run(samples), Status::non_finite_input);
}

TEST_F(LmErrors, AllSamplesAtOnePose) {
  Sample samples[40];
  Random random(502);
  const JointVector q = test::random_joints(&random);
  for (Sample& s : samples) {
    s.q_rad = q;
    s.point_m = base.apply(fk_tool_point(model, q)) + 1e-5 * test::gaussian_vector(&random);
  }
  EXPECT_EQ(run(samples), Status::poses_not_distinct);
  EXPECT_EQ(run(samples, LmOptions{}, &base), Status::poses_not_distinct);
  EXPECT_STREQ(status_message(Status::poses_not_distinct), "all samples at the same joint positions");
}

TEST_F(LmErrors, InvalidOptions) {
  const auto with = [](auto change) {
    LmOptions options;
    change(&options);
    return options;
  };
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->max_iterations = 0; })), Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->cost_tolerance = -1.0; })), Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->initial_damping = 0.0; })), Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->huber_threshold_m = -1e-3; })),
            Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->identifiability_threshold = 0.0; })),
            Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) { o->identifiability_threshold = 1.0; })),
            Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) {
                  o->params = LmParamSet::custom;
                  o->custom_mask = 0;
                })),
            Status::invalid_argument);
  EXPECT_EQ(run(lm().train.samples(), with([](LmOptions* o) {
                  o->params = LmParamSet::custom;
                  o->custom_mask = param_bit(kFullParamCount);
                })),
            Status::invalid_argument);
}

TEST_F(LmErrors, CustomMaskOfParametersWithoutEffectIsSingular) {
  // The tool point on the flange axis: theta6 moves nothing, alone it cannot be estimated.
  RobotModel on_axis = model;
  on_axis.tool_m = Vec3(0.0, 0.0, 0.1);
  LmOptions options;
  options.params = LmParamSet::custom;
  options.custom_mask = param_bit(model_param_index(5, DhField::theta_offset));
  EXPECT_EQ(run(lm().train.samples(), options, &base, &on_axis), Status::singular_system);
}

}  // namespace
}  // namespace hivecal::lm_errors_test
