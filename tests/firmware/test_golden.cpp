// The core golden digest on the MCU: the same computation (tests/testkit/golden_core.hpp) and
// the same committed constant as the host suite. Equal bits here prove the determinism recipe
// (docs/determinism.md) holds on Cortex-M with newlib and its FPU (or soft-float doubles).
#include "harness.hpp"
#include "testkit/golden_core.hpp"

namespace hivecal {
namespace {

FW_TEST(Golden, CoreDigestIsTheSameOnEveryTarget) {
  const std::uint64_t digest = test::core_golden_digest();
  fw::print("  core digest: ");
  fw::print_hex(digest);
  fw::print("\n");
  FW_CHECK_EQ(digest, test::kCoreGoldenDigest);
}

}  // namespace
}  // namespace hivecal
