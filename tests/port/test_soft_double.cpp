// The bare-metal port's binary64 addition and conversions (port/baremetal/src/soft_double.c)
// against this machine's own double arithmetic, which is IEEE-754 round-to-nearest-even
// (SSE2 on x86-64, the FPU on aarch64/armhf): the same bits on every operand, including the
// exponent differences of 32 and 33 where libgcc's ARM soft-float addition rounds wrongly.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "soft_double.h"

namespace soft_double_test {
namespace {

std::uint64_t bits_of(double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  return bits;
}

double double_of(std::uint64_t bits) {
  double value = 0.0;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

/// xorshift64: operands that are the same on every run.
struct Operands {
  std::uint64_t state = 0x9e3779b97f4a7c15ULL;
  std::uint64_t next() {
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
  }
  /// A fraction with the patterns rounding cares about: random, few bits, nearly all ones,
  /// trailing zeros.
  std::uint64_t fraction() {
    const std::uint64_t r = next() & 0x000fffffffffffffULL;
    switch (next() % 4) {
      case 0: return r;
      case 1: return r & 0xff;
      case 2: return 0x000fffffffffffffULL - (r & 0xff);
      default: return r & ~((1ULL << (next() % 52)) - 1);
    }
  }
  /// A double with biased exponent `exponent` (0 = subnormal) and a random sign.
  std::uint64_t with_exponent(int exponent) {
    return fraction() | (static_cast<std::uint64_t>(exponent) << 52) | ((next() & 1) << 63);
  }
};

/// The sum by this machine's FPU and by the port, as bits; NaNs compare as NaN (payload and
/// sign of the default NaN differ between FPUs).
void expect_same_sum(std::uint64_t a, std::uint64_t b) {
  volatile double x = double_of(a);
  volatile double y = double_of(b);
  const double sum = x + y;
  const double difference = x - y;
  const std::uint64_t port_sum = soft_double_add(a, b);
  const std::uint64_t port_difference = soft_double_sub(a, b);
  if (std::isnan(sum)) {
    EXPECT_TRUE(std::isnan(double_of(port_sum))) << std::hex << a << " + " << b;
  } else {
    EXPECT_EQ(bits_of(sum), port_sum) << std::hex << a << " + " << b;
  }
  if (std::isnan(difference)) {
    EXPECT_TRUE(std::isnan(double_of(port_difference))) << std::hex << a << " - " << b;
  } else {
    EXPECT_EQ(bits_of(difference), port_difference) << std::hex << a << " - " << b;
  }
}

TEST(SoftDouble, TheCaseLibgccRoundsWronglyIsRoundedToNearest) {
  // 1 - 0x1.81adc4a7df110p-33: exponents 33 apart, the result one binade lower.
  EXPECT_EQ(soft_double_sub(0x3ff0000000000000ULL, 0x3de81adc4a7df110ULL), 0x3fefffffffe7e524ULL);
  expect_same_sum(0x3ff0000000000000ULL, 0x3de81adc4a7df110ULL);
}

TEST(SoftDouble, SumsMatchTheFpuAtEveryExponentDifference) {
  Operands operands;
  for (int difference = 0; difference <= 60; ++difference) {
    for (int i = 0; i < 4000; ++i) {
      const int exponent = 600 + static_cast<int>(operands.next() % 800);
      const std::uint64_t a = operands.with_exponent(exponent);
      const std::uint64_t b = operands.with_exponent(exponent - difference);
      expect_same_sum(a, b);
      expect_same_sum(b, a);
      if (::testing::Test::HasFailure()) return;  // one report, not thousands
    }
  }
}

TEST(SoftDouble, SumsNearPowersOfTwoMatchTheFpu) {
  // a = 2^k exactly (or a few ulps above): the difference drops a binade and must be
  // normalised, the case where a lost round bit shows.
  Operands operands;
  for (int i = 0; i < 200000; ++i) {
    const int exponent = 600 + static_cast<int>(operands.next() % 800);
    const std::uint64_t a = (static_cast<std::uint64_t>(exponent) << 52) | (operands.next() % 4);
    const int difference = static_cast<int>(operands.next() % 64);
    const std::uint64_t b = operands.with_exponent(exponent - difference) | (1ULL << 63);
    expect_same_sum(a, b);
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(SoftDouble, SubnormalsZerosInfinitiesAndNaNsMatchTheFpu) {
  Operands operands;
  const std::uint64_t specials[] = {0x0ULL,
                                    0x8000000000000000ULL,
                                    0x0000000000000001ULL,
                                    0x000fffffffffffffULL,
                                    0x0010000000000000ULL,
                                    0x7fefffffffffffffULL,
                                    0x7ff0000000000000ULL,
                                    0xfff0000000000000ULL,
                                    0x7ff8000000000000ULL,
                                    0x7ff0000000000001ULL,
                                    0x3ff0000000000000ULL,
                                    0xbff0000000000000ULL};
  for (std::uint64_t a : specials)
    for (std::uint64_t b : specials) expect_same_sum(a, b);
  for (int i = 0; i < 100000; ++i) {
    const int exponent_a = static_cast<int>(operands.next() % 3);
    const int exponent_b = static_cast<int>(operands.next() % 3);
    expect_same_sum(operands.with_exponent(exponent_a), operands.with_exponent(exponent_b));
    // Overflow: two large values.
    expect_same_sum(operands.with_exponent(2046 - static_cast<int>(operands.next() % 2)),
                    operands.with_exponent(2046 - static_cast<int>(operands.next() % 2)));
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(SoftDouble, IntegersConvertLikeTheFpu) {
  Operands operands;
  const std::uint64_t edges[] = {
      0ULL,       1ULL, (1ULL << 53) - 1, 1ULL << 53, (1ULL << 53) + 1, (1ULL << 54) + 2, (1ULL << 63) - 1,
      1ULL << 63, ~0ULL};
  for (std::uint64_t value : edges) {
    EXPECT_EQ(bits_of(static_cast<double>(value)), soft_double_from_u64(value)) << value;
    const auto signed_value = static_cast<std::int64_t>(value);
    EXPECT_EQ(bits_of(static_cast<double>(signed_value)), soft_double_from_i64(signed_value)) << signed_value;
  }
  for (int i = 0; i < 200000; ++i) {
    const std::uint64_t value = operands.next() >> (operands.next() % 64);
    EXPECT_EQ(bits_of(static_cast<double>(value)), soft_double_from_u64(value)) << value;
    const auto signed_value = static_cast<std::int64_t>(operands.next()) >> (operands.next() % 64);
    EXPECT_EQ(bits_of(static_cast<double>(signed_value)), soft_double_from_i64(signed_value)) << signed_value;
    if (::testing::Test::HasFailure()) return;
  }
}

TEST(SoftDouble, FloatsWidenExactly) {
  Operands operands;
  for (int i = 0; i < 200000; ++i) {
    // Every exponent, subnormals and infinities included; NaNs checked as NaN.
    const auto value = static_cast<std::uint32_t>(operands.next());
    float single = 0.0f;
    std::memcpy(&single, &value, sizeof single);
    volatile float widened_input = single;
    const double widened = static_cast<double>(widened_input);
    if (std::isnan(widened)) {
      EXPECT_TRUE(std::isnan(double_of(soft_double_from_float_bits(value)))) << std::hex << value;
    } else {
      EXPECT_EQ(bits_of(widened), soft_double_from_float_bits(value)) << std::hex << value;
    }
    if (::testing::Test::HasFailure()) return;
  }
  const std::uint32_t smallest_subnormal = 1;
  EXPECT_EQ(double_of(soft_double_from_float_bits(smallest_subnormal)), std::ldexp(1.0, -149));
  EXPECT_EQ(double_of(soft_double_from_float_bits(0x7f7fffffU)),
            static_cast<double>(std::numeric_limits<float>::max()));
}

}  // namespace
}  // namespace soft_double_test
