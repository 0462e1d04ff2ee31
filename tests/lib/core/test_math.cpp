// The library's own sin/cos, exp/log and atan2 against libm, in units in the last place.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"

namespace hivecal::math_test {
namespace {

/// Distance in units in the last place between two doubles of the same sign region.
std::int64_t ulp_distance(double a, double b) {
  if (a == b) return 0;
  std::int64_t ia = 0;
  std::int64_t ib = 0;
  std::memcpy(&ia, &a, sizeof a);
  std::memcpy(&ib, &b, sizeof b);
  if (ia < 0) ia = std::numeric_limits<std::int64_t>::min() - ia;
  if (ib < 0) ib = std::numeric_limits<std::int64_t>::min() - ib;
  return ia > ib ? ia - ib : ib - ia;
}

// libm (glibc's sin/cos are correctly rounded in practice) is the reference; ours must be
// within 1 ulp of it everywhere a joint angle plus offset can be.
TEST(OwnTrig, SinCosWithinOneUlpOfLibmOverJointRange) {
  Random random(1);
  std::int64_t worst_sin = 0;
  std::int64_t worst_cos = 0;
  for (int i = 0; i < 400000; ++i) {
    const double x = random.uniform(-4.0 * math::kPi, 4.0 * math::kPi);
    double s = 0.0;
    double c = 0.0;
    math::sincos(x, &s, &c);
    worst_sin = std::max(worst_sin, ulp_distance(s, std::sin(x)));
    worst_cos = std::max(worst_cos, ulp_distance(c, std::cos(x)));
  }
  EXPECT_LE(worst_sin, 1);
  EXPECT_LE(worst_cos, 1);
}

TEST(OwnTrig, NearMultiplesOfHalfPiStayAccurate) {
  for (int k = -8; k <= 8; ++k) {
    const double center = k * math::kHalfPi;
    for (double dx : {0.0, 1e-12, -1e-12, 1e-8, -1e-8, 1e-4}) {
      const double x = center + dx;
      EXPECT_LE(ulp_distance(math::sin(x), std::sin(x)), 1) << x;
      EXPECT_LE(ulp_distance(math::cos(x), std::cos(x)), 1) << x;
    }
  }
}

TEST(OwnTrig, SmallAndSpecialArguments) {
  EXPECT_EQ(math::sin(0.0), 0.0);
  EXPECT_EQ(math::cos(0.0), 1.0);
  EXPECT_EQ(math::sin(1e-300), 1e-300);
  EXPECT_TRUE(std::isnan(math::sin(std::numeric_limits<double>::infinity())));
  EXPECT_TRUE(std::isnan(math::cos(std::numeric_limits<double>::quiet_NaN())));
  EXPECT_TRUE(std::isnan(math::sin(2.0 * math::kTrigMaxArgument_rad)));
  EXPECT_LE(ulp_distance(math::sin(1000.0), std::sin(1000.0)), 1);
}

TEST(OwnExpLog, WithinOneUlpOfLibm) {
  Random random(2);
  std::int64_t worst_exp = 0;
  std::int64_t worst_log = 0;
  for (int i = 0; i < 200000; ++i) {
    const double x = random.uniform(-700.0, 700.0);
    worst_exp = std::max(worst_exp, ulp_distance(math::exp(x), std::exp(x)));
    const double y = std::ldexp(random.uniform(0.5, 1.0), static_cast<int>(random.below(2000)) - 1000);
    worst_log = std::max(worst_log, ulp_distance(math::log(y), std::log(y)));
  }
  EXPECT_LE(worst_exp, 1);
  EXPECT_LE(worst_log, 1);
  EXPECT_EQ(math::exp(0.0), 1.0);
  EXPECT_EQ(math::log(1.0), 0.0);
  EXPECT_TRUE(std::isinf(math::exp(800.0)));
  EXPECT_EQ(math::exp(-800.0), 0.0);
  EXPECT_TRUE(std::isnan(math::log(-1.0)));
  EXPECT_TRUE(std::isinf(math::log(0.0)));
  EXPECT_LE(ulp_distance(math::log(4.9e-320), std::log(4.9e-320)), 1);  // subnormal input
}

TEST(OwnAtan2, WithinTwoUlpOfLibmAllQuadrants) {
  Random random(3);
  std::int64_t worst = 0;
  for (int i = 0; i < 200000; ++i) {
    const double y = random.uniform(-10.0, 10.0);
    const double x = random.uniform(-10.0, 10.0);
    worst = std::max(worst, ulp_distance(math::atan2(y, x), std::atan2(y, x)));
  }
  EXPECT_LE(worst, 2);
  EXPECT_EQ(math::atan2(0.0, -1.0), math::kPi);
  EXPECT_EQ(math::atan2(1.0, 0.0), math::kHalfPi);
  EXPECT_NEAR(math::acos_clamped(0.5), std::acos(0.5), 4e-16);
  EXPECT_EQ(math::acos_clamped(1.5), 0.0);
}

}  // namespace
}  // namespace hivecal::math_test
