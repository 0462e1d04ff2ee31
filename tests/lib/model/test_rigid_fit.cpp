// Rigid fit (Kabsch): the checks are tests/testkit/rigid_fit_checks.hpp, shared with the
// firmware image; here with more random trials and under the allocation trap.
#include <gtest/gtest.h>

#include "testkit/alloc_trap.hpp"
#include "testkit/check_log_gtest.hpp"
#include "testkit/rigid_fit_checks.hpp"

namespace hivecal::rigid_fit_test {
namespace {

TEST(RigidFit, RecoversRandomTransformsExactly) {
  test::CheckLog log;
  EXPECT_NO_HEAP(log = test::rigid_fit_recovers_random_transforms(500));
  EXPECT_CHECKS(log);
}

TEST(RigidFit, NeverReturnsAReflection) {
  EXPECT_CHECKS(test::rigid_fit_never_returns_a_reflection());
}

TEST(RigidFit, WeightsSelectThePairsThatCount) {
  EXPECT_CHECKS(test::rigid_fit_weights_select_the_pairs_that_count());
}

TEST(RigidFit, DegenerateInputsGetSpecificErrors) {
  EXPECT_CHECKS(test::rigid_fit_degenerate_inputs_get_specific_errors());
}

TEST(RigidFit, FarFromOriginStaysAccurate) {
  EXPECT_CHECKS(test::rigid_fit_far_from_origin_stays_accurate());
}

}  // namespace
}  // namespace hivecal::rigid_fit_test
