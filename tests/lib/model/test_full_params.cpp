// The full model's parameters (model/full_params.hpp): index layout and masks against hand
// values and a bit-counting loop, every name, skew against the cross product, and how an
// increment applies (model fields, compliance terms only, base as a local increment).
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/model/full_params.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::full_params_test {
namespace {

/// A second random word for two-word masks (builds with the harmonics of order 3); one-word
/// masks have none.
[[maybe_unused]] void add_high_word(std::uint64_t* /*mask*/, Random* /*random*/) {}
[[maybe_unused]] void add_high_word(WideMask* mask, Random* random) {
  *mask |= WideMask{random->next()} << 64U;
}

/// A random mask over every word of ParamMask.
ParamMask random_mask(Random* random) {
  ParamMask mask = random->next();
  add_high_word(&mask, random);
  return mask;
}

/// A mask in hexadecimal, for failure messages.
std::string hex(std::uint64_t mask) {
  char text[24];
  std::snprintf(text, sizeof text, "%llx", static_cast<unsigned long long>(mask));
  return text;
}
[[maybe_unused]] std::string hex(const WideMask& mask) {
  return hex(mask.high_word()) + ":" + hex(mask.low_word());
}

/// Bits set in the low kFullParamCount bits of `mask`, by clearing the lowest one at a time.
int popcount_params(ParamMask mask) {
  ParamMask bits = mask & ((ParamMask{1} << kFullParamCount) - 1U);
  int count = 0;
  while (bits != 0) {
    bits &= bits - 1U;
    ++count;
  }
  return count;
}

Vec3 gaussian(Random* random) {
  Vec3 v;
  v << random->normal(), random->normal(), random->normal();
  return v;
}

/// A perturbed UR5 with compliance terms (two of four used), other tool points and a tool.
RobotModel compliant_model(Random* random) {
  RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5), random, 1e-3, 1e-3);
  model.tool_m << 0.01, -0.02, 0.12;
  model.other_tools_m[0] << 0.03, 0.0, 0.1;
  model.other_tools_m[1] << -0.03, 0.01, 0.09;
  EXPECT_EQ(default_compliance_terms(model, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &model.compliance),
            Status::ok);
  for (int t = 0; t < kMaxComplianceTerms; ++t) model.compliance.coefficient[t] = 1e-4 * (t + 1);
  model.compliance.term_count = 2;
  return model;
}

TEST(FullParams, LayoutIsGeometryThenBaseThenCompliance) {
  EXPECT_EQ(kBaseParamCount, 6);
  EXPECT_EQ(rigid_param_count(kSixJoints), 33);
  EXPECT_EQ(kFullParamCount, rigid_param_count(kMaxJoints) + kMaxJointTerms);  // 37, 73 or 81: the build's capacity
  // A six-joint model's layout in a build of any capacity (below: the six-joint indices).
  EXPECT_EQ(base_rotation_param_index(kSixJoints, 0), 27);
  EXPECT_EQ(base_rotation_param_index(kSixJoints, 2), 29);
  EXPECT_EQ(base_translation_param_index(kSixJoints, 0), 30);
  EXPECT_EQ(base_translation_param_index(kSixJoints, 2), 32);
  EXPECT_EQ(compliance_param_index(kSixJoints, 0), 33);
  EXPECT_EQ(compliance_param_index(kSixJoints, 3), 36);
  EXPECT_EQ(param_bit(0), ParamMask{1});
  EXPECT_EQ(param_bit(36), ParamMask{0x1000000000});
  EXPECT_EQ(rigid_params_mask(kSixJoints), ParamMask{0x1FFFFFFFF});            // bits 0 .. 32
  const int six_joint_count = rigid_param_count(kSixJoints) + kMaxJointTerms;  // a six-joint model's parameters
  EXPECT_EQ(compliance_params_mask(kSixJoints, kMaxComplianceTerms),
            ((ParamMask{1} << six_joint_count) - 1U) & ~rigid_params_mask(kSixJoints));  // 33 ..
  EXPECT_EQ(valid_params_mask(kSixJoints), (ParamMask{1} << six_joint_count) - 1U);      // every parameter
  EXPECT_EQ(valid_params_mask(kMaxJoints), (ParamMask{1} << kFullParamCount) - 1U);      // the capacity
  EXPECT_EQ(kOtherTargetTools, param_bit(kFullParamCount));                              // past every parameter
  EXPECT_EQ(compliance_params_mask(kSixJoints, 0), ParamMask{0});
  EXPECT_EQ(compliance_params_mask(kSixJoints, 1), ParamMask{0x200000000});
  EXPECT_EQ(compliance_params_mask(kSixJoints, 2), ParamMask{0x600000000});
  EXPECT_EQ(compliance_params_mask(kSixJoints, 4), ParamMask{0x1E00000000});  // bits 33 .. 36
  EXPECT_EQ(compliance_params_mask(kSixJoints, kMaxComplianceTerms),
            compliance_params_mask(kSixJoints, kMaxComplianceTerms));
  EXPECT_TRUE(mask_has(rigid_params_mask(kSixJoints), 32));
  EXPECT_FALSE(mask_has(rigid_params_mask(kSixJoints), 33));
  EXPECT_TRUE(mask_has(compliance_params_mask(kSixJoints, kMaxComplianceTerms), 33));
  EXPECT_FALSE(mask_has(compliance_params_mask(kSixJoints, kMaxComplianceTerms), 0));
}

TEST(FullParams, MaskCountAndIndicesAgreeWithABitLoopOnRandomMasks) {
  Random random(501);
  for (int trial = 0; trial < 300; ++trial) {
    ParamMask mask = random_mask(&random);
    if (trial % 3 == 0) mask &= random_mask(&random);  // sparser masks too
    if (trial == 0) mask = 0;
    if (trial == 1) mask = ~ParamMask{0};
    int count = -1;
    int index[kFullParamCount] = {};
    int listed = -1;
    EXPECT_NO_HEAP(count = mask_count(mask));
    EXPECT_NO_HEAP(listed = mask_indices(mask, index));
    const int expected = popcount_params(mask);
    ASSERT_EQ(count, expected) << hex(mask);
    ASSERT_EQ(listed, expected) << hex(mask);
    ParamMask rebuilt = 0;
    for (int k = 0; k < listed; ++k) {
      if (k > 0) {
        EXPECT_LT(index[k - 1], index[k]);
      }
      ASSERT_GE(index[k], 0);
      ASSERT_LT(index[k], kFullParamCount);
      rebuilt |= ParamMask{1} << static_cast<unsigned>(index[k]);
    }
    EXPECT_EQ(rebuilt, mask & valid_params_mask(kMaxJoints)) << hex(mask);
  }
  int index[kFullParamCount] = {};
  EXPECT_EQ(mask_count(kOtherTargetTools), 0);  // not a parameter
  EXPECT_EQ(mask_indices(kOtherTargetTools | param_bit(5), index), 1);
  EXPECT_EQ(index[0], 5);
  EXPECT_EQ(mask_count(rigid_params_mask(kSixJoints)), 33);
  EXPECT_EQ(mask_count(compliance_params_mask(kSixJoints, 3)), 3);
}

TEST(FullParams, EveryParameterHasItsName) {
  static const char* const kExpected[rigid_param_count(kSixJoints) + 4] = {
      "theta1",  "d1",          "a1",          "alpha1",      "theta2",     "d2",      "a2",      "alpha2",
      "theta3",  "d3",          "a3",          "alpha3",      "theta4",     "d4",      "a4",      "alpha4",
      "theta5",  "d5",          "a5",          "alpha5",      "theta6",     "d6",      "a6",      "alpha6",
      "tool_x",  "tool_y",      "tool_z",      "base_rx",     "base_ry",    "base_rz", "base_tx", "base_ty",
      "base_tz", "compliance1", "compliance2", "compliance3", "compliance4"};
  const char* names[kFullParamCount] = {};
  EXPECT_NO_HEAP(for (int i = 0; i < kFullParamCount; ++i) names[i] = full_param_name(i, kSixJoints));
  for (int i = 0; i < rigid_param_count(kSixJoints) + 4; ++i) EXPECT_STREQ(names[i], kExpected[i]) << i;
  const int six_joint_count = rigid_param_count(kSixJoints) + kMaxJointTerms;
  for (int i = rigid_param_count(kSixJoints) + 4; i < six_joint_count; ++i) {  // a larger capacity: the same pattern
    EXPECT_EQ(std::string(names[i]), "compliance" + std::to_string(i - rigid_param_count(kSixJoints) + 1)) << i;
  }
  EXPECT_STREQ(full_param_name(model_param_index(4, DhField::d), kSixJoints), "d5");
  EXPECT_STREQ(full_param_name(base_translation_param_index(kSixJoints, 1), kSixJoints), "base_ty");
  EXPECT_STREQ(full_param_name(compliance_param_index(kSixJoints, 1), kSixJoints), "compliance2");
  EXPECT_STREQ(full_param_name(-7, kSixJoints), "?");
  if (six_joint_count < kFullParamCount) {  // beyond a six-joint model's
    EXPECT_STREQ(names[six_joint_count], "?");
  }
  EXPECT_STREQ(full_param_name(kFullParamCount + 1, kSixJoints), "?");
}

TEST(FullParams, ComplianceNamesFollowTheModelsTerms) {
  Random random(502);
  RobotModel model = compliant_model(&random);
  model.compliance.term_count = 4;  // the default point terms
  const char* names[kFullParamCount + 2] = {};
  EXPECT_NO_HEAP(for (int i = -1; i <= kFullParamCount; ++i) names[i + 1] = full_param_name(i, model));
  const auto name = [&](int index) { return names[index + 1]; };
  // The UR5's default point terms (compliance.hpp): shoulder (joint 2) with loads at frames 2
  // and 4, elbow (joint 3) with loads at frame 4 and the tool.
  EXPECT_STREQ(name(compliance_param_index(kSixJoints, 0)), "c_j2_o2");
  EXPECT_STREQ(name(compliance_param_index(kSixJoints, 1)), "c_j2_o4");
  EXPECT_STREQ(name(compliance_param_index(kSixJoints, 2)), "c_j3_o4");
  EXPECT_STREQ(name(compliance_param_index(kSixJoints, 3)), "c_j3_tool");
  EXPECT_STREQ(name(0), "theta1");  // the rigid ones keep their plain names
  EXPECT_STREQ(name(base_rotation_param_index(kSixJoints, 1)), "base_ry");
  EXPECT_STREQ(name(-1), "?");
  EXPECT_STREQ(name(kFullParamCount), "?");
  model.compliance.term_count = 2;  // terms 3 and 4 are not the model's
  EXPECT_STREQ(full_param_name(compliance_param_index(kSixJoints, 1), model), "c_j2_o4");
  EXPECT_STREQ(full_param_name(compliance_param_index(kSixJoints, 2), model), "?");
  EXPECT_STREQ(full_param_name(compliance_param_index(kSixJoints, 3), model), "?");
  const RobotModel rigid = nominal_model(RobotType::ur10);
  EXPECT_STREQ(full_param_name(compliance_param_index(kSixJoints, 0), rigid), "?");
}

TEST(FullParams, OtherToolNamesCoverTargetsTwoAndThreeOnly) {
  const char* n[6] = {};
  EXPECT_NO_HEAP(for (int k = 0; k < 6; ++k) n[k] = other_tool_param_name(1 + k / 3, k % 3));
  EXPECT_STREQ(n[0], "tool2_x");
  EXPECT_STREQ(n[1], "tool2_y");
  EXPECT_STREQ(n[2], "tool2_z");
  EXPECT_STREQ(n[3], "tool3_x");
  EXPECT_STREQ(n[4], "tool3_y");
  EXPECT_STREQ(n[5], "tool3_z");
  EXPECT_STREQ(other_tool_param_name(0, 0), "?");  // target 1's tool point is tool_x ..
  EXPECT_STREQ(other_tool_param_name(kMaxTargets, 0), "?");
  EXPECT_STREQ(other_tool_param_name(1, 3), "?");
  EXPECT_STREQ(other_tool_param_name(2, -1), "?");
}

TEST(FullParams, SkewIsTheCrossProductMatrix) {
  const Mat3 k = skew(Vec3(1.0, 2.0, 3.0));
  Mat3 expected;
  expected << 0.0, -3.0, 2.0, 3.0, 0.0, -1.0, -2.0, 1.0, 0.0;
  EXPECT_EQ(k, expected);
  Random random(503);
  for (int trial = 0; trial < 200; ++trial) {
    const Vec3 v = gaussian(&random);
    const Vec3 x = gaussian(&random);
    Mat3 s;
    EXPECT_NO_HEAP(s = skew(v));
    EXPECT_LT((s * x - v.cross(x)).norm(), 1e-15 * (1.0 + v.norm() * x.norm()));
    EXPECT_EQ(s.transpose(), -s);
  }
}

TEST(FullParams, RotationVectorAgreesOnBothSidesOfTheSeriesSwitch) {
  // The series branch is taken below |v| = 1e-4; both sides against cos/sin of std.
  for (const double angle : {0.5e-4, 0.999e-4, 1.001e-4, 2e-4, 0.5 * math::kPi}) {
    Mat3 r;
    EXPECT_NO_HEAP(r = rotation_from_vector(Vec3(angle, 0.0, 0.0)));
    Mat3 expected;
    expected << 1.0, 0.0, 0.0, 0.0, std::cos(angle), -std::sin(angle), 0.0, std::sin(angle), std::cos(angle);
    EXPECT_LT((r - expected).cwiseAbs().maxCoeff(), 1e-15) << angle;
  }
  // A quarter turn about z takes x to y.
  const Vec3 turned = rotation_from_vector(Vec3(0.0, 0.0, 0.5 * math::kPi)) * Vec3(1.0, 0.0, 0.0);
  EXPECT_LT((turned - Vec3(0.0, 1.0, 0.0)).norm(), 1e-15);
}

TEST(ApplyFullIncrement, AddsToTheModelAndToTheUsedComplianceTermsOnly) {
  Random random(504);
  for (int trial = 0; trial < 50; ++trial) {
    RobotModel model = compliant_model(&random);
    RigidTransform base = test::example_base_to_tracker();
    const RobotModel before = model;
    FullParams increment;
    for (int i = 0; i < kFullParamCount; ++i) increment(i) = 1e-3 * random.normal();
    increment.segment<kBaseParamCount>(model_param_count(kSixJoints)).setZero();  // the base is the next test's
    EXPECT_NO_HEAP(apply_full_increment(increment, &model, &base));
    const ModelParams after_params = to_params(model);
    const ModelParams before_params = to_params(before);
    for (int i = 0; i < model_param_count(kSixJoints); ++i) {
      EXPECT_EQ(after_params(i), before_params(i) + increment(i)) << full_param_name(i, kSixJoints);
    }
    EXPECT_EQ(model.joints[1].a_m, before.joints[1].a_m + increment(model_param_index(1, DhField::a)));
    EXPECT_EQ(model.tool_m.z(), before.tool_m.z() + increment(tool_param_index(kSixJoints, 2)));
    for (int t = 0; t < 2; ++t) {
      EXPECT_EQ(model.compliance.coefficient[t],
                before.compliance.coefficient[t] + increment(compliance_param_index(kSixJoints, t)));
    }
    // Terms 3 and 4 are not in use (term_count 2): their coefficients stay.
    EXPECT_EQ(model.compliance.coefficient[2], before.compliance.coefficient[2]);
    EXPECT_EQ(model.compliance.coefficient[3], before.compliance.coefficient[3]);
    EXPECT_EQ(model.compliance.term_count, 2);
    EXPECT_EQ(model.compliance.terms[1].frame, before.compliance.terms[1].frame);
    EXPECT_EQ(model.compliance.gravity_direction, before.compliance.gravity_direction);
    EXPECT_EQ(model.other_tools_m[0], before.other_tools_m[0]);
    EXPECT_EQ(model.other_tools_m[1], before.other_tools_m[1]);
    // No base entry: the transform keeps every bit.
    EXPECT_EQ(base.rotation, test::example_base_to_tracker().rotation);
    EXPECT_EQ(base.translation_m, test::example_base_to_tracker().translation_m);
  }
}

TEST(ApplyFullIncrement, ComposesTheBaseAsALocalIncrement) {
  Random random(505);
  for (int trial = 0; trial < 100; ++trial) {
    RobotModel model = test::perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
    const RobotModel model_before = model;
    RigidTransform base;
    base.rotation = test::random_rotation(&random);
    base.translation_m = gaussian(&random);
    const RigidTransform base_before = base;
    const Vec3 rotation = (trial % 2 == 0 ? 1e-3 : 0.8) * gaussian(&random);
    const Vec3 translation = 0.1 * gaussian(&random);
    FullParams increment = FullParams::Zero();
    increment.segment<3>(base_rotation_param_index(kSixJoints, 0)) = rotation;
    increment.segment<3>(base_translation_param_index(kSixJoints, 0)) = translation;
    EXPECT_NO_HEAP(apply_full_increment(increment, &model, &base));
    // base <- base * (Exp(rotation), translation), Exp by Eigen's angle-axis.
    const Mat3 exp = Eigen::AngleAxisd(rotation.norm(), rotation.normalized()).toRotationMatrix();
    EXPECT_LT((base.rotation - base_before.rotation * exp).norm(), 1e-14) << trial;
    EXPECT_LT((base.translation_m - (base_before.translation_m + base_before.rotation * translation)).norm(), 1e-14);
    EXPECT_EQ(to_params(model), to_params(model_before));  // the geometry is untouched
  }
  // By hand: identity base, a quarter turn about base z and 1 m along base x.
  RobotModel model = nominal_model(RobotType::ur5);
  RigidTransform base;
  base.translation_m << 0.0, 0.0, 2.0;
  FullParams increment = FullParams::Zero();
  increment(base_rotation_param_index(kSixJoints, 2)) = 0.5 * math::kPi;
  increment(base_translation_param_index(kSixJoints, 0)) = 1.0;
  apply_full_increment(increment, &model, &base);
  EXPECT_LT((base.translation_m - Vec3(1.0, 0.0, 2.0)).norm(), 1e-15);
  EXPECT_LT((base.rotation * Vec3(1.0, 0.0, 0.0) - Vec3(0.0, 1.0, 0.0)).norm(), 1e-15);
}

TEST(ApplyFullIncrement, BaseRzAndTzMoveTheRobotLikeTheta1AndD1) {
  Random random(506);
  for (int trial = 0; trial < 40; ++trial) {
    const RobotModel model = test::perturbed_model(nominal_model(RobotType::ur5e), &random, 2e-3, 2e-3);
    const RigidTransform base = test::example_base_to_tracker();
    const double h_rad = random.uniform(-0.05, 0.05);
    const double h_m = random.uniform(-0.05, 0.05);
    FullParams through_base = FullParams::Zero();
    through_base(base_rotation_param_index(kSixJoints, 2)) = h_rad;
    through_base(base_translation_param_index(kSixJoints, 2)) = h_m;
    FullParams through_joint = FullParams::Zero();
    through_joint(model_param_index(0, DhField::theta_offset)) = h_rad;
    through_joint(model_param_index(0, DhField::d)) = h_m;
    RobotModel model_a = model;
    RigidTransform base_a = base;
    RobotModel model_b = model;
    RigidTransform base_b = base;
    EXPECT_NO_HEAP(apply_full_increment(through_base, &model_a, &base_a));
    EXPECT_NO_HEAP(apply_full_increment(through_joint, &model_b, &base_b));
    for (int pose = 0; pose < 5; ++pose) {
      const JointVector q = test::random_joints(&random);
      const Vec3 a = base_a.apply(fk_tool_point(model_a, q));
      const Vec3 b = base_b.apply(fk_tool_point(model_b, q));
      EXPECT_LT((a - b).norm(), 1e-14) << trial;
      // and both moved the point (the test can tell them from no increment at all)
      EXPECT_GT((a - base.apply(fk_tool_point(model, q))).norm(), 1e-6 * (std::fabs(h_m) + std::fabs(h_rad)));
    }
  }
}

}  // namespace
}  // namespace hivecal::full_params_test
