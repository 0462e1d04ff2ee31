// The build's capacities agree with each other: the full model, the eigen-solver and the
// parameter masks are all sized from the joint and joint-term capacities, and a model's
// parameter indices follow its own joint count (a six-joint model's are the same in every build).
#include <gtest/gtest.h>

#include "hivecal/core/capacity.hpp"
#include "hivecal/linalg/symmetric_eigen.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/model/full_params.hpp"

namespace hivecal::capacity_test {
namespace {

TEST(Capacity, OneJointAndTermCapacitySizeTheModelTheSolverAndTheMasks) {
  EXPECT_EQ(kMaxComplianceTerms, kMaxJointTerms);
  EXPECT_GE(kMaxJoints, kSixJoints);
  EXPECT_EQ(kMaxRigidParamCount, 4 * kMaxJoints + 9);
  EXPECT_EQ(kFullParamCount, kMaxRigidParamCount + kMaxJointTerms);
  EXPECT_EQ(kSymmetricCapacity, kFullParamCount);
  // Every parameter and the "other targets' tools" flag fit in the mask: one word up to 63
  // parameters, two beyond.
  EXPECT_EQ(sizeof(ParamMask), kFullParamCount < 64 ? 8U : 16U);
  EXPECT_EQ(mask_count(valid_params_mask(kMaxJoints)), kFullParamCount);
  EXPECT_EQ(valid_params_mask(kMaxJoints) & kOtherTargetTools, ParamMask{0});
  EXPECT_NE(kOtherTargetTools, ParamMask{0});
}

TEST(Capacity, ASixJointModelHasTheIndicesOfEveryBuild) {
  EXPECT_EQ(model_param_count(kSixJoints), 27);
  EXPECT_EQ(rigid_param_count(kSixJoints), 33);
  EXPECT_EQ(tool_param_index(kSixJoints, 0), 24);
  EXPECT_EQ(base_rotation_param_index(kSixJoints, 0), 27);
  EXPECT_EQ(base_translation_param_index(kSixJoints, 2), 32);
  EXPECT_EQ(compliance_param_index(kSixJoints, 0), 33);
  EXPECT_EQ(rigid_params_mask(kSixJoints), (ParamMask{1} << 33U) - 1U);
  EXPECT_STREQ(full_param_name(24, kSixJoints), "tool_x");
  EXPECT_STREQ(full_param_name(33, kSixJoints), "compliance1");
}

TEST(Capacity, EveryJointCountNamesEachOfItsParametersOnce) {
  for (int joints = 1; joints <= kMaxJoints; ++joints) {
    const int count = rigid_param_count(joints) + kMaxComplianceTerms;
    EXPECT_EQ(mask_count(valid_params_mask(joints)), count) << joints;
    for (int i = 0; i < count; ++i) {
      ASSERT_STRNE(full_param_name(i, joints), "?") << joints << " " << i;
      for (int k = 0; k < i; ++k) EXPECT_STRNE(full_param_name(i, joints), full_param_name(k, joints)) << i << " " << k;
    }
    EXPECT_STREQ(full_param_name(count, joints), "?");
    EXPECT_STREQ(full_param_name(tool_param_index(joints, 0), joints), "tool_x");
    EXPECT_STREQ(full_param_name(model_param_index(joints - 1, DhField::alpha), joints),
                 (std::string("alpha") + std::to_string(joints)).c_str());
  }
  EXPECT_STREQ(full_param_name(0, 0), "?");
  EXPECT_STREQ(full_param_name(0, kMaxJoints + 1), "?");
}

}  // namespace
}  // namespace hivecal::capacity_test
