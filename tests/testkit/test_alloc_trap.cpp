// The allocation trap must itself be able to fail, in every build type: EIGEN_NO_MALLOC
// asserts vanish under NDEBUG, so they cannot be the guard.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdlib>
#include <memory>

#include "testkit/alloc_trap.hpp"

namespace hivecal::alloc_trap_test {
namespace {

// The compiler may elide a malloc/free or new/delete pair it can see; an escaping
// pointer keeps the allocation real.
void* volatile g_sink = nullptr;

TEST(AllocTrap, CatchesMallocNewAndDynamicEigen) {
  EXPECT_EQ(test::count_allocations([] {
              g_sink = std::malloc(16);
              std::free(g_sink);
            }),
            1u);
  EXPECT_EQ(test::count_allocations([] {
              auto p = std::make_unique<int>(3);
              g_sink = p.get();
            }),
            1u);
  EXPECT_GE(test::count_allocations([] {
              Eigen::MatrixXd m(7, 7);
              m.setZero();
            }),
            1u);
  EXPECT_EQ(test::count_allocations([] {
              Eigen::Matrix<double, 7, 7> m;
              m.setZero();
            }),
            0u);
}

TEST(AllocTrap, WorksWithNdebugToo) {
#ifdef NDEBUG
  SUCCEED() << "NDEBUG build: EIGEN_NO_MALLOC would be silent here, the trap is not";
#endif
  EXPECT_EQ(test::count_allocations([] {
              g_sink = std::calloc(4, 4);
              std::free(g_sink);
            }),
            1u);
}

}  // namespace
}  // namespace hivecal::alloc_trap_test
