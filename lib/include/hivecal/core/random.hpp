// The library's own seeded pseudo-random generator, so that a seed means the same
// stream on every compiler, libc and CPU (std:: distributions are implementation-defined).
//
// Stream definition (stable, part of the library's contract):
//   state  = four successive outputs of SplitMix64 started at `seed`
//   next() = xoshiro256** (Blackman & Vigna, 2018) on that state
//   uniform01() = (next() >> 11) * 2^-53            in [0, 1)
//   uniform(lo, hi) = lo + (hi - lo) * uniform01()
//   below(n)  = next() % n after rejecting the top (2^64 mod n) values (unbiased)
//   normal()  = Marsaglia polar method on uniform(-1, 1) pairs, own log, second value cached
#pragma once

#include <cstdint>

namespace hivecal {

/// Deterministic PRNG (xoshiro256** seeded by SplitMix64); 32 bytes of state plus a cached normal.
class Random {
 public:
  /// Starts the stream defined above for `seed` (any value, 0 included).
  explicit Random(std::uint64_t seed);

  /// Next 64 uniformly distributed bits.
  std::uint64_t next();
  /// Uniform double in [0, 1) with 53 random bits.
  double uniform01();
  /// Uniform double in [lo, hi).
  double uniform(double lo, double hi);
  /// Uniform integer in [0, n); n must be > 0 (returns 0 for n == 0).
  std::uint64_t below(std::uint64_t n);
  /// Standard normal deviate (mean 0, sigma 1).
  double normal();

 private:
  std::uint64_t state_[4];
  double cached_normal_ = 0.0;
  bool has_cached_normal_ = false;
};

/// One SplitMix64 step: advances *state and returns the mixed output.
std::uint64_t splitmix64_next(std::uint64_t* state);

}  // namespace hivecal
