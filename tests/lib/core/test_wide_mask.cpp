// WideMask (core/wide_mask.hpp) against the compiler's 128-bit integers where the target has
// them (x86-64, aarch64), over many random values and every shift; and by hand everywhere.
#include <gtest/gtest.h>

#include <cstdint>

#include "hivecal/core/digest.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/core/wide_mask.hpp"

namespace hivecal::wide_mask_test {
namespace {

WideMask make(std::uint64_t high, std::uint64_t low) {
  return (WideMask{high} << 64U) | WideMask{low};
}

TEST(WideMask, ShiftsCarryAcrossTheWordsAndSubtractionBorrows) {
  EXPECT_EQ((WideMask{1} << 63U).low_word(), std::uint64_t{1} << 63U);
  EXPECT_EQ((WideMask{1} << 64U).low_word(), 0U);
  EXPECT_EQ((WideMask{1} << 64U).high_word(), 1U);
  EXPECT_EQ((WideMask{3} << 63U).low_word(), std::uint64_t{1} << 63U);
  EXPECT_EQ((WideMask{3} << 63U).high_word(), 1U);
  EXPECT_EQ((WideMask{1} << 127U).high_word(), std::uint64_t{1} << 63U);
  EXPECT_EQ(WideMask{1} << 128U, WideMask{0});
  EXPECT_EQ(WideMask{5} << 0U, WideMask{5});
  const WideMask low_70 = (WideMask{1} << 70U) - 1U;  // the low 70 bits
  EXPECT_EQ(low_70.low_word(), ~std::uint64_t{0});
  EXPECT_EQ(low_70.high_word(), 0x3FU);
  EXPECT_EQ(WideMask{0} - 1U, ~WideMask{0});
  EXPECT_EQ(make(1, 0) - 1U, WideMask{~std::uint64_t{0}});
  EXPECT_EQ(~make(0xF0, 0x0F), make(~std::uint64_t{0xF0}, ~std::uint64_t{0x0F}));
  EXPECT_NE(make(1, 0), WideMask{0});
  EXPECT_TRUE(make(0, 7) == WideMask{7});
  WideMask m = make(1, 2);
  m |= make(4, 8);
  EXPECT_EQ(m, make(5, 10));
  m &= make(4, 2);
  EXPECT_EQ(m, make(4, 2));
}

TEST(WideMask, AOneWordMaskDigestsAsItsWord) {
  Digest word;
  word.add_mask(std::uint64_t{0x1234});
  Digest wide;
  wide.add_mask(WideMask{0x1234});
  EXPECT_EQ(wide.value(), word.value());
  Digest high;
  high.add_mask(make(1, 0x1234));
  EXPECT_NE(high.value(), word.value());
}

#ifdef __SIZEOF_INT128__
__extension__ typedef unsigned __int128 U128;  // __extension__: a GCC type, -Wpedantic allows it so

U128 as_u128(WideMask m) {
  return (static_cast<U128>(m.high_word()) << 64U) | m.low_word();
}

TEST(WideMask, EveryOperatorMatches128BitIntegersOnRandomValues) {
  Random random(128);
  for (int trial = 0; trial < 2000; ++trial) {
    const std::uint64_t words[4] = {random.next(), random.next(), random.next(), random.next()};
    const WideMask a = make(words[0], words[1]);
    const WideMask b = make(words[2], words[3]);
    const U128 x = as_u128(a);
    const U128 y = as_u128(b);
    ASSERT_TRUE(as_u128(a | b) == (x | y));
    ASSERT_TRUE(as_u128(a & b) == (x & y));
    ASSERT_TRUE(as_u128(~a) == static_cast<U128>(~x));
    const unsigned shift = static_cast<unsigned>(trial % 128);
    ASSERT_TRUE(as_u128(a << shift) == static_cast<U128>(x << shift)) << shift;
    const std::uint64_t small = words[3] % 1000U;
    ASSERT_TRUE(as_u128(a - small) == static_cast<U128>(x - small));
    ASSERT_EQ(a == b, x == y);
  }
}
#endif

}  // namespace
}  // namespace hivecal::wide_mask_test
