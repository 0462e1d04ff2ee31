/* Binary64 addition and conversions in integer arithmetic (see soft_double.h for why), and on
 * a core without a double-precision FPU the ARM run-time ABI entries that replace libgcc's
 * _arm_addsubdf3.o as a whole (a partial replacement would link both and clash). */
#include "soft_double.h"

#define SIGN_BIT 0x8000000000000000ull
#define FRACTION_MASK 0x000fffffffffffffull
#define HIDDEN_BIT 0x0010000000000000ull
#define QUIET_BIT 0x0008000000000000ull
#define INFINITY_BITS 0x7ff0000000000000ull
#define DEFAULT_NAN 0x7ff8000000000000ull
#define EXPONENT_ALL_ONES 0x7ffu
/* Working significands carry three bits below the last place: guard, round, sticky. */
#define EXTRA_BITS 3
#define WORK_HIDDEN_BIT (HIDDEN_BIT << EXTRA_BITS)

static unsigned exponent_of(uint64_t bits) {
  return (unsigned)(bits >> 52) & EXPONENT_ALL_ONES;
}

static int leading_zeros(uint64_t value) {
  return value == 0 ? 64 : __builtin_clzll(value);
}

/* `value` shifted right by `count`, the bits shifted out ORed into bit 0 (sticky). */
static uint64_t shift_right_sticky(uint64_t value, unsigned count) {
  if (count == 0) return value;
  if (count >= 64) return value != 0;
  const uint64_t lost = value & ((1ull << count) - 1);
  return (value >> count) | (lost != 0);
}

/* Rounds a working significand (hidden bit at WORK_HIDDEN_BIT when normal) with biased
 * exponent `exponent` >= 1 to nearest-even and packs it. A significand below the hidden bit
 * at exponent 1 is subnormal. */
static uint64_t round_and_pack(uint64_t sign, int exponent, uint64_t significand) {
  const uint64_t extra = significand & ((1u << EXTRA_BITS) - 1);
  significand >>= EXTRA_BITS;
  const uint64_t half = 1u << (EXTRA_BITS - 1);
  if (extra > half || (extra == half && (significand & 1))) ++significand;
  if (significand == (HIDDEN_BIT << 1)) {  // rounding carried into the next binade
    significand >>= 1;
    ++exponent;
  }
  if (exponent >= (int)EXPONENT_ALL_ONES) return sign | INFINITY_BITS;
  const uint64_t exponent_field = significand >= HIDDEN_BIT ? (uint64_t)exponent : 0;
  return sign | (exponent_field << 52) | (significand & FRACTION_MASK);
}

static uint64_t add_special(uint64_t a, uint64_t b) {
  const int a_nan = exponent_of(a) == EXPONENT_ALL_ONES && (a & FRACTION_MASK) != 0;
  const int b_nan = exponent_of(b) == EXPONENT_ALL_ONES && (b & FRACTION_MASK) != 0;
  if (a_nan) return a | QUIET_BIT;
  if (b_nan) return b | QUIET_BIT;
  if (exponent_of(a) == EXPONENT_ALL_ONES && exponent_of(b) == EXPONENT_ALL_ONES)
    return ((a ^ b) & SIGN_BIT) != 0 ? DEFAULT_NAN : a;  // inf - inf
  return exponent_of(a) == EXPONENT_ALL_ONES ? a : b;
}

uint64_t soft_double_add(uint64_t a, uint64_t b) {
  if (exponent_of(a) == EXPONENT_ALL_ONES || exponent_of(b) == EXPONENT_ALL_ONES) return add_special(a, b);
  if ((a & ~SIGN_BIT) < (b & ~SIGN_BIT)) {  // |a| >= |b| from here on
    const uint64_t larger = b;
    b = a;
    a = larger;
  }
  const uint64_t sign = a & SIGN_BIT;
  if ((b & ~SIGN_BIT) == 0) {  // x + 0; and +0 + -0 is +0 in round-to-nearest
    if ((a & ~SIGN_BIT) == 0) return a & b & SIGN_BIT;
    return a;
  }
  const unsigned a_exponent = exponent_of(a);
  const unsigned b_exponent = exponent_of(b);
  /* Subnormals have exponent 1 and no hidden bit. */
  uint64_t a_significand = ((a & FRACTION_MASK) | (a_exponent != 0 ? HIDDEN_BIT : 0)) << EXTRA_BITS;
  uint64_t b_significand = ((b & FRACTION_MASK) | (b_exponent != 0 ? HIDDEN_BIT : 0)) << EXTRA_BITS;
  int exponent = a_exponent != 0 ? (int)a_exponent : 1;
  const unsigned b_effective = b_exponent != 0 ? b_exponent : 1;
  b_significand = shift_right_sticky(b_significand, (unsigned)exponent - b_effective);
  uint64_t significand = 0;
  if (((a ^ b) & SIGN_BIT) == 0) {
    significand = a_significand + b_significand;
    if (significand >= (WORK_HIDDEN_BIT << 1)) {
      significand = shift_right_sticky(significand, 1);
      ++exponent;
    }
  } else {
    significand = a_significand - b_significand;
    if (significand == 0) return 0;  // x - x is +0 in round-to-nearest
    /* Normalise: exact, because a difference that cancels more than one leading bit comes
     * from an alignment shift of at most one, which lost nothing. Stop at the subnormals. */
    int shift = leading_zeros(significand) - leading_zeros(WORK_HIDDEN_BIT);
    if (shift > exponent - 1) shift = exponent - 1;
    if (shift > 0) {
      significand <<= shift;
      exponent -= shift;
    }
  }
  return round_and_pack(sign, exponent, significand);
}

uint64_t soft_double_sub(uint64_t a, uint64_t b) {
  return soft_double_add(a, b ^ SIGN_BIT);
}

uint64_t soft_double_from_u64(uint64_t value) {
  if (value == 0) return 0;
  const int top_bit = 63 - leading_zeros(value);
  /* Place the top bit at WORK_HIDDEN_BIT (bit 55), the bits below bit 0 folded into sticky. */
  const int shift = top_bit - 55;
  const uint64_t significand = shift > 0 ? shift_right_sticky(value, (unsigned)shift) : value << (unsigned)(-shift);
  return round_and_pack(0, 1023 + top_bit, significand);
}

uint64_t soft_double_from_i64(int64_t value) {
  const uint64_t magnitude = value < 0 ? 0 - (uint64_t)value : (uint64_t)value;
  return (value < 0 ? SIGN_BIT : 0) | soft_double_from_u64(magnitude);
}

uint64_t soft_double_from_float_bits(uint32_t value) {
  const uint64_t sign = (uint64_t)(value >> 31) << 63;
  const unsigned exponent = (value >> 23) & 0xffu;
  uint64_t fraction = value & 0x7fffffu;
  if (exponent == 0xffu) return sign | INFINITY_BITS | (fraction << 29) | (fraction != 0 ? QUIET_BIT : 0);
  if (exponent == 0) {
    if (fraction == 0) return sign;
    /* Subnormal float: normal as a double. Shift its top bit up to the hidden bit (bit 23). */
    int binary_exponent = -126;
    while ((fraction & 0x800000u) == 0) {
      fraction <<= 1;
      --binary_exponent;
    }
    return sign | ((uint64_t)(binary_exponent + 1023) << 52) | ((fraction & 0x7fffffu) << 29);
  }
  return sign | ((uint64_t)(exponent - 127 + 1023) << 52) | (fraction << 29);
}

/* The run-time ABI entries (base procedure-call standard: doubles in r0-r3 as 64-bit
 * integers), only where doubles are not done in hardware. */
#if defined(__ARM_EABI__) && !(defined(__ARM_FP) && (__ARM_FP & 8))
#define AEABI __attribute__((pcs("aapcs"), used))

AEABI uint64_t __aeabi_dadd(uint64_t a, uint64_t b);
AEABI uint64_t __aeabi_dsub(uint64_t a, uint64_t b);
AEABI uint64_t __aeabi_drsub(uint64_t a, uint64_t b);
AEABI uint64_t __aeabi_ui2d(uint32_t value);
AEABI uint64_t __aeabi_i2d(int32_t value);
AEABI uint64_t __aeabi_ul2d(uint64_t value);
AEABI uint64_t __aeabi_l2d(int64_t value);
AEABI uint64_t __aeabi_f2d(uint32_t value);

AEABI uint64_t __aeabi_dadd(uint64_t a, uint64_t b) {
  return soft_double_add(a, b);
}
AEABI uint64_t __aeabi_dsub(uint64_t a, uint64_t b) {
  return soft_double_sub(a, b);
}
AEABI uint64_t __aeabi_drsub(uint64_t a, uint64_t b) {
  return soft_double_sub(b, a);
}
AEABI uint64_t __aeabi_ui2d(uint32_t value) {
  return soft_double_from_u64(value);
}
AEABI uint64_t __aeabi_i2d(int32_t value) {
  return soft_double_from_i64(value);
}
AEABI uint64_t __aeabi_ul2d(uint64_t value) {
  return soft_double_from_u64(value);
}
AEABI uint64_t __aeabi_l2d(int64_t value) {
  return soft_double_from_i64(value);
}
AEABI uint64_t __aeabi_f2d(uint32_t value) {
  return soft_double_from_float_bits(value);
}
/* libgcc's other names of the same entries (the object defines both). */
AEABI uint64_t __adddf3(uint64_t a, uint64_t b) __attribute__((alias("__aeabi_dadd")));
AEABI uint64_t __subdf3(uint64_t a, uint64_t b) __attribute__((alias("__aeabi_dsub")));
AEABI uint64_t __floatunsidf(uint32_t value) __attribute__((alias("__aeabi_ui2d")));
AEABI uint64_t __floatsidf(int32_t value) __attribute__((alias("__aeabi_i2d")));
AEABI uint64_t __floatundidf(uint64_t value) __attribute__((alias("__aeabi_ul2d")));
AEABI uint64_t __floatdidf(int64_t value) __attribute__((alias("__aeabi_l2d")));
AEABI uint64_t __extendsfdf2(uint32_t value) __attribute__((alias("__aeabi_f2d")));
#endif
