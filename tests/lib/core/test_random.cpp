// The library's PRNG: the documented stream (checks shared with the firmware) and the moments of
// its distributions.
#include <gtest/gtest.h>

#include "hivecal/core/random.hpp"
#include "testkit/check_log_gtest.hpp"
#include "testkit/random_checks.hpp"

namespace hivecal::random_test {
namespace {

TEST(OwnRandom, StreamIsTheDocumentedOne) {
  EXPECT_CHECKS(test::random_stream_is_the_documented_one());
}

TEST(OwnRandom, DistributionsHaveTheirMoments) {
  Random random(7);
  const test::NormalMoments moments = test::normal_moments(&random, 200000);
  EXPECT_NEAR(moments.mean, 0.0, 0.01);
  EXPECT_NEAR(moments.mean_square, 1.0, 0.01);
  int counts[5] = {};
  for (int i = 0; i < 50000; ++i) ++counts[random.below(5)];
  for (int k : counts) EXPECT_NEAR(k, 10000, 400);
  for (int i = 0; i < 1000; ++i) {
    const double u = random.uniform01();
    EXPECT_GE(u, 0.0);
    EXPECT_LT(u, 1.0);
  }
}

}  // namespace
}  // namespace hivecal::random_test
