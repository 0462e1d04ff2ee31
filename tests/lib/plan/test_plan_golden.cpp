// The planner's golden digest: the same bits on every target and -O level (the golden scope,
// tests/CMakeLists.txt, builds only the test_*golden*.cpp files).
#include <gtest/gtest.h>

#include "hivecal/plan/pose_plan.hpp"
#include "testkit/plan_test_data.hpp"

namespace hivecal::plan_golden_test {
namespace {

PlanWorkspace workspace;
PlanResult result;

using test::digest_of;
using test::planning_model;
using test::small_options;

// The same bits on every target (docs/determinism.md): the poses, the criterion, the sigmas
// and the path time of one plan, against the value measured on x86-64. It changes only when
// the planner's or the kinematics' numbers are meant to change.
TEST(PosePlan, GoldenDigest) {
  ASSERT_EQ(plan_session(planning_model(), small_options(256, 20, 5), &workspace, &result), Status::ok);
  EXPECT_EQ(digest_of(result), 0x920a169975c2f7c1ULL);
}

}  // namespace
}  // namespace hivecal::plan_golden_test
