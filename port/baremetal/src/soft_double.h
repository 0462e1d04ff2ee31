/* IEEE-754 binary64 addition and conversions to binary64 in integer arithmetic, rounded to
 * nearest-even: the run-time support of a core without a double-precision FPU (Cortex-M4F).
 *
 * Why the port carries its own: libgcc's ARM soft-float addition (ieee754-df.S, GCC 12) rounds
 * wrongly when the exponents differ by 32 or 33 and the difference loses its leading bit: it
 * folds the smaller operand's low word into the sticky bit before the result is shifted left,
 * so the round bit is lost. 1.0 - 0x1.81adc4a7df110p-33 gives 0x1.fffffffe7e523p-1 instead of
 * ...524; on random operands about one subtraction in twenty at those exponent differences is
 * one ulp off. Multiplication and division are correct and stay libgcc's.
 *
 * Values are passed as their bit patterns, so this file compiles and is tested on any host.
 * Internal to the port. */
#ifndef HIVECAL_BAREMETAL_SOFT_DOUBLE_H
#define HIVECAL_BAREMETAL_SOFT_DOUBLE_H

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* a + b, correctly rounded to nearest-even (subnormals, infinities, signed zeros as IEEE-754;
 * a NaN operand is returned quiet, inf - inf is the default NaN 0x7ff8000000000000). */
uint64_t soft_double_add(uint64_t a, uint64_t b);
/* a - b, as soft_double_add(a, -b). */
uint64_t soft_double_sub(uint64_t a, uint64_t b);
/* The double nearest to an unsigned 64-bit integer (ties to even). */
uint64_t soft_double_from_u64(uint64_t value);
/* The double nearest to a signed 64-bit integer (ties to even). */
uint64_t soft_double_from_i64(int64_t value);
/* The double of a binary32 bit pattern (exact; a signalling NaN comes back quiet). */
uint64_t soft_double_from_float_bits(uint32_t value);

#ifdef __cplusplus
}
#endif

#endif
