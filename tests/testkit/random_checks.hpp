// Checks of the library's PRNG run by both tests/lib/core/test_random.cpp and the firmware image
// (tests/firmware/test_math.cpp): the documented stream, and the moments of its normals.
#pragma once

#include <cstdint>

#include "hivecal/core/random.hpp"
#include "testkit/check_log.hpp"

namespace hivecal::test {

/// SplitMix64 gives the reference implementation's first value; a seed repeats its stream
/// and another seed differs at every one of 100 draws.
inline CheckLog random_stream_is_the_documented_one() {
  CheckLog log;
  // SplitMix64 from seed 0 gives 0xe220a8397b1dcdaf first (reference implementation).
  std::uint64_t state = 0;
  log.check(splitmix64_next(&state) == 0xe220a8397b1dcdafULL, "first SplitMix64 value from seed 0");
  Random a(42);
  Random b(42);
  Random c(43);
  for (int i = 0; i < 100; ++i) {
    const std::uint64_t va = a.next();
    log.check(va == b.next(), "seed 42 twice gives the same draw");
    log.check(va != c.next(), "seeds 42 and 43 give different draws");
  }
  return log;
}

/// Mean and mean square of a run of standard normal draws.
struct NormalMoments {
  double mean = 0.0;
  double mean_square = 0.0;
};

/// Draws `count` normals from `random` (which goes on from there for the caller's next checks).
inline NormalMoments normal_moments(Random* random, int count) {
  double sum = 0.0;
  double sum_sq = 0.0;
  for (int i = 0; i < count; ++i) {
    const double z = random->normal();
    sum += z;
    sum_sq += z * z;
  }
  return NormalMoments{sum / count, sum_sq / count};
}

}  // namespace hivecal::test
