// Own elementary functions and PRNG on the MCU: reference values from glibc (correctly
// rounded in practice) within the host suite's ulp bounds, special arguments, and the
// documented random stream.
#include <cstdint>
#include <limits>

#include "harness.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/random_checks.hpp"

namespace hivecal {
namespace {

using math::bits_of;
using math::from_bits;

/// Distance in units in the last place (monotonic integer mapping of the doubles).
std::uint64_t ulp_distance(double a, double b) {
  const auto ordered = [](double x) {
    const std::uint64_t u = bits_of(x);
    return (u >> 63) != 0 ? 0x8000000000000000ULL - (u & 0x7fffffffffffffffULL) : u + 0x8000000000000000ULL;
  };
  const std::uint64_t ia = ordered(a);
  const std::uint64_t ib = ordered(b);
  return ia > ib ? ia - ib : ib - ia;
}

struct TrigReference {
  double x_rad;
  std::uint64_t sin_bits;
  std::uint64_t cos_bits;
};

// glibc sin/cos, also near multiples of pi/2 where the reduction must keep its precision.
constexpr TrigReference kTrigReferences[] = {
    {0.5, 0x3fdeaee8744b05f0ULL, 0x3fec1528065b7d50ULL},
    {1.0, 0x3feaed548f090ceeULL, 0x3fe14a280fb5068cULL},
    {-1.0, 0xbfeaed548f090ceeULL, 0x3fe14a280fb5068cULL},
    {2.0, 0x3fed18f6ead1b446ULL, 0xbfdaa22657537205ULL},
    {3.0, 0x3fc210386db6d55bULL, 0xbfefae04be85e5d2ULL},
    {-2.5, 0xbfe326af0dcfcab1ULL, 0xbfe9a2f7ef858b7dULL},
    {1.5707963267948966, 0x3ff0000000000000ULL, 0x3c91a62633145c07ULL},
    {3.141592653589793, 0x3ca1a62633145c07ULL, 0xbff0000000000000ULL},
    {1.5707963367948965, 0x3ff0000000000000ULL, 0xbe45798eddcb3b3aULL},
    {4.71238898038469, 0xbff0000000000000ULL, 0xbcaa79394c9e8a0aULL},
    {6.283185307179586, 0xbcb1a62633145c07ULL, 0x3ff0000000000000ULL},
    {10.0, 0xbfe1689ef5f34f52ULL, 0xbfead9ac890c6b1fULL},
    {-12.566370614359172, 0x3cc1a62633145c07ULL, 0x3ff0000000000000ULL},
    {1000.0, 0x3fea75cc150a206bULL, 0x3fe1ff026793f1bbULL},
    {0.7853981633974483, 0x3fe6a09e667f3bccULL, 0x3fe6a09e667f3bcdULL},
    {1e-05, 0x3ee4f8b588e1e8a2ULL, 0x3feffffffff920c8ULL},
};

FW_TEST(OwnTrig, ReferenceValuesWithinOneUlp) {
  for (const TrigReference& ref : kTrigReferences) {
    double s = 0.0;
    double c = 0.0;
    math::sincos(ref.x_rad, &s, &c);
    FW_CHECK_LE(ulp_distance(s, from_bits(ref.sin_bits)), 1u);
    FW_CHECK_LE(ulp_distance(c, from_bits(ref.cos_bits)), 1u);
    FW_CHECK_EQ(bits_of(math::sin(ref.x_rad)), bits_of(s));
    FW_CHECK_EQ(bits_of(math::cos(ref.x_rad)), bits_of(c));
  }
}

FW_TEST(OwnTrig, SmallAndSpecialArguments) {
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  FW_CHECK_EQ(math::sin(0.0), 0.0);
  FW_CHECK_EQ(math::cos(0.0), 1.0);
  FW_CHECK_EQ(math::sin(1e-300), 1e-300);
  FW_CHECK(!math::is_finite(math::sin(inf)));
  FW_CHECK(!math::is_finite(math::cos(nan)));
  FW_CHECK(!math::is_finite(math::sin(2.0 * math::kTrigMaxArgument_rad)));
  FW_CHECK(math::is_finite(1e308));
  FW_CHECK(!math::is_finite(-inf));
}

FW_TEST(OwnExpLog, ReferenceValuesWithinOneUlp) {
  struct Reference {
    double x;
    std::uint64_t bits;
  };
  constexpr Reference kExp[] = {{1.0, 0x4005bf0a8b145769ULL},   {-1.0, 0x3fd78b56362cef38ULL},
                                {0.5, 0x3ffa61298e1e069cULL},   {10.0, 0x40d5829dcf950560ULL},
                                {-20.0, 0x3e21b48655f37267ULL}, {700.0, 0x7f0d945df4f8ec8eULL}};
  constexpr Reference kLog[] = {{2.0, 0x3fe62e42fefa39efULL},
                                {0.5, 0xbfe62e42fefa39efULL},
                                {10.0, 0x40026bb1bbb55516ULL},
                                {1e-300, 0xc085963447f87fb5ULL},
                                {123456.789, 0x40277281cad8a844ULL}};
  for (const Reference& ref : kExp) FW_CHECK_LE(ulp_distance(math::exp(ref.x), from_bits(ref.bits)), 1u);
  for (const Reference& ref : kLog) FW_CHECK_LE(ulp_distance(math::log(ref.x), from_bits(ref.bits)), 1u);
  FW_CHECK_EQ(math::exp(0.0), 1.0);
  FW_CHECK_EQ(math::log(1.0), 0.0);
  FW_CHECK(!math::is_finite(math::exp(800.0)));
  FW_CHECK_EQ(math::exp(-800.0), 0.0);
  FW_CHECK(math::log(-1.0) != math::log(-1.0));  // NaN
  FW_CHECK(!math::is_finite(math::log(0.0)));
}

FW_TEST(OwnAtan2, ReferenceValuesWithinTwoUlp) {
  struct Reference {
    double y;
    double x;
    std::uint64_t bits;
  };
  constexpr Reference kAtan2[] = {{1.0, 1.0, 0x3fe921fb54442d18ULL},
                                  {1.0, -2.0, 0x40056c6e7397f5aeULL},
                                  {-3.0, -0.5, 0xbffbc66e44cbc074ULL},
                                  {-0.25, 4.0, 0xbfaff55bb72cfdeaULL}};
  for (const Reference& ref : kAtan2) {
    FW_CHECK_LE(ulp_distance(math::atan2(ref.y, ref.x), from_bits(ref.bits)), 2u);
  }
  FW_CHECK_EQ(math::atan2(0.0, -1.0), math::kPi);
  FW_CHECK_EQ(math::atan2(1.0, 0.0), math::kHalfPi);
  FW_CHECK_NEAR(math::acos_clamped(0.5), 1.0471975511965979, 4e-16);
  FW_CHECK_EQ(math::acos_clamped(1.5), 0.0);
}

// Binary64 sums rounded to nearest on this core: exponents 33 apart with a result one
// binade lower, where libgcc's ARM soft-float addition (used on a core without a double FPU
// unless the port replaces it: port/baremetal/src/soft_double.h) is one ulp off.
FW_TEST(Arithmetic, SumsAcrossThirtyThreeBinadesAreRoundedToNearest) {
  volatile double one = 1.0;
  volatile double small = from_bits(0x3de81adc4a7df110ULL);  // 0x1.81adc4a7df110p-33
  FW_CHECK_EQ(bits_of(one - small), 0x3fefffffffe7e524ULL);
  FW_CHECK_EQ(bits_of(-small + one), 0x3fefffffffe7e524ULL);
}

FW_TEST(OwnRandom, StreamIsTheDocumentedOne) {
  FW_CHECK_LOG(test::random_stream_is_the_documented_one());
}

FW_TEST(OwnRandom, DistributionsHaveTheirMoments) {
  Random random(7);
  const test::NormalMoments moments = test::normal_moments(&random, 20000);
  FW_CHECK_NEAR(moments.mean, 0.0, 0.03);
  FW_CHECK_NEAR(moments.mean_square, 1.0, 0.03);
  bool in_range = true;
  for (int i = 0; i < 1000; ++i) {
    const double u = random.uniform01();
    in_range = in_range && u >= 0.0 && u < 1.0;
  }
  FW_CHECK(in_range);
  bool below_in_range = true;
  for (int i = 0; i < 1000; ++i) below_in_range = below_in_range && random.below(5) < 5u;
  FW_CHECK(below_in_range);
  FW_CHECK_EQ(random.below(0), 0u);
}

}  // namespace
}  // namespace hivecal
