// Golden digest: FK, Jacobian, transform fit, cost and metrics over a fixed synthetic
// data set, hashed over their raw bits. The committed value must come out on every
// target and optimisation level (host -O0/-O3/-march=native, aarch64, armhf, and the
// Cortex-M firmware, which runs the same testkit/golden_core.hpp).
#include <gtest/gtest.h>

#include <cstdio>

#include "testkit/alloc_trap.hpp"
#include "testkit/golden_core.hpp"

namespace hivecal::golden_core_test {
namespace {

TEST(Golden, CoreDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = test::core_golden_digest());
  std::printf("core digest: 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, test::kCoreGoldenDigest);
}

}  // namespace
}  // namespace hivecal::golden_core_test
