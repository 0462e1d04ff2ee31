// The build's capacities agree with each other: the full model, the eigen-solver and the
// parameter masks are all sized from the one joint-term capacity.
#include <gtest/gtest.h>

#include "hivecal/core/capacity.hpp"
#include "hivecal/linalg/symmetric_eigen.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/model/full_params.hpp"

namespace hivecal::capacity_test {
namespace {

TEST(Capacity, OneJointTermCapacitySizesTheModelTheSolverAndTheMasks) {
  EXPECT_EQ(kMaxComplianceTerms, kMaxJointTerms);
  EXPECT_EQ(kFullParamCount, kRigidParamCount + kMaxJointTerms);
  EXPECT_EQ(kSymmetricCapacity, kFullParamCount);
  // Every parameter and the "other targets' tools" flag fit in the mask: one word up to 30 joint
  // terms (63 parameters), two beyond.
  EXPECT_EQ(sizeof(ParamMask), kFullParamCount < 64 ? 8U : 16U);
  EXPECT_EQ(mask_count(kValidParamsMask), kFullParamCount);
  EXPECT_EQ(kValidParamsMask & kOtherTargetTools, ParamMask{0});
  EXPECT_NE(kOtherTargetTools, ParamMask{0});
}

TEST(Capacity, EveryParameterHasADistinctName) {
  for (int i = 0; i < kFullParamCount; ++i) {
    ASSERT_STRNE(full_param_name(i), "?") << i;
    for (int k = 0; k < i; ++k) EXPECT_STRNE(full_param_name(i), full_param_name(k)) << i << " " << k;
  }
  EXPECT_STREQ(full_param_name(kFullParamCount), "?");
}

}  // namespace
}  // namespace hivecal::capacity_test
