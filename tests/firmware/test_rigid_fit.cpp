// Rigid fit (Kabsch) on the MCU: exact recovery, reflection guard, weights, and the
// specific error of each degenerate input. The checks are tests/testkit/rigid_fit_checks.hpp,
// shared with the host suite; the MCU runs fewer random trials.
#include "harness.hpp"
#include "testkit/rigid_fit_checks.hpp"

namespace hivecal {
namespace {

FW_TEST(RigidFit, RecoversRandomTransformsExactly) {
  FW_CHECK_LOG(test::rigid_fit_recovers_random_transforms(50));
}

FW_TEST(RigidFit, NeverReturnsAReflection) {
  FW_CHECK_LOG(test::rigid_fit_never_returns_a_reflection());
}

FW_TEST(RigidFit, WeightsSelectThePairsThatCount) {
  FW_CHECK_LOG(test::rigid_fit_weights_select_the_pairs_that_count());
}

FW_TEST(RigidFit, DegenerateInputsGetSpecificErrors) {
  FW_CHECK_LOG(test::rigid_fit_degenerate_inputs_get_specific_errors());
}

FW_TEST(RigidFit, FarFromOriginStaysAccurate) {
  FW_CHECK_LOG(test::rigid_fit_far_from_origin_stays_accurate());
}

}  // namespace
}  // namespace hivecal
