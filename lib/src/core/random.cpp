#include "hivecal/core/random.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {
std::uint64_t rotate_left(std::uint64_t x, unsigned k) {
  return (x << k) | (x >> (64U - k));
}
}  // namespace

std::uint64_t splitmix64_next(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31U);
}

Random::Random(std::uint64_t seed) {
  std::uint64_t sm = seed;
  for (std::uint64_t& word : state_) word = splitmix64_next(&sm);
}

std::uint64_t Random::next() {
  const std::uint64_t result = rotate_left(state_[1] * 5U, 7U) * 9U;
  const std::uint64_t t = state_[1] << 17U;
  state_[2] ^= state_[0];
  state_[3] ^= state_[1];
  state_[1] ^= state_[2];
  state_[0] ^= state_[3];
  state_[2] ^= t;
  state_[3] = rotate_left(state_[3], 45U);
  return result;
}

double Random::uniform01() {
  return static_cast<double>(next() >> 11U) * 1.1102230246251565404236316680908203125e-16;
}

double Random::uniform(double lo, double hi) {
  return lo + (hi - lo) * uniform01();
}

std::uint64_t Random::below(std::uint64_t n) {
  if (n == 0) return 0;
  const std::uint64_t threshold = (0ULL - n) % n;  // 2^64 mod n
  for (;;) {
    const std::uint64_t r = next();
    if (r >= threshold) return r % n;
  }
}

double Random::normal() {
  if (has_cached_normal_) {
    has_cached_normal_ = false;
    return cached_normal_;
  }
  for (;;) {
    const double u = uniform(-1.0, 1.0);
    const double v = uniform(-1.0, 1.0);
    const double s = u * u + v * v;
    if (s >= 1.0 || s == 0.0) continue;
    const double factor = std::sqrt(-2.0 * math::log(s) / s);
    cached_normal_ = v * factor;
    has_cached_normal_ = true;
    return u * factor;
  }
}

}  // namespace hivecal
