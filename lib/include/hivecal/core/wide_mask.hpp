// A set of up to 128 flags that reads like an unsigned integer: the parameter mask of a model
// with more parameters than a 64-bit word has bits (model/full_params.hpp chooses it only then,
// so builds whose masks fit in one word keep std::uint64_t and its code).
#pragma once

#include <cstdint>

namespace hivecal {

/// 128 flags, bit i for parameter i, with the operators the masks use on std::uint64_t:
/// | & ~, shifts left, subtracting a small count (for "the low n bits": (1 << n) - 1) and
/// comparison. Built from an integer (the low word), so `mask != 0` and `WideMask{1} << n` read
/// as they do for a word.
class WideMask {
 public:
  constexpr WideMask() = default;
  // Implicit on purpose: integer literals and word masks convert as they do between integers.
  constexpr WideMask(std::uint64_t low) : low_(low) {}  // NOLINT(google-explicit-constructor)

  constexpr WideMask operator|(WideMask other) const { return {low_ | other.low_, high_ | other.high_}; }
  constexpr WideMask operator&(WideMask other) const { return {low_ & other.low_, high_ & other.high_}; }
  constexpr WideMask operator~() const { return {~low_, ~high_}; }
  /// Shifted left by `count` bits (0 .. 127; larger gives 0).
  constexpr WideMask operator<<(unsigned count) const {
    if (count == 0U) return *this;
    if (count >= 128U) return {};
    if (count >= 64U) return {0U, low_ << (count - 64U)};
    return {low_ << count, (high_ << count) | (low_ >> (64U - count))};
  }
  /// The mask minus `count` as a 128-bit unsigned integer (borrowing from the high word).
  constexpr WideMask operator-(std::uint64_t count) const { return {low_ - count, high_ - (low_ < count ? 1U : 0U)}; }
  constexpr WideMask& operator|=(WideMask other) { return *this = *this | other; }
  constexpr WideMask& operator&=(WideMask other) { return *this = *this & other; }
  friend constexpr bool operator==(WideMask a, WideMask b) { return a.low_ == b.low_ && a.high_ == b.high_; }
  friend constexpr bool operator!=(WideMask a, WideMask b) { return !(a == b); }

  constexpr std::uint64_t low_word() const { return low_; }    ///< flags 0 .. 63
  constexpr std::uint64_t high_word() const { return high_; }  ///< flags 64 .. 127

 private:
  constexpr WideMask(std::uint64_t low, std::uint64_t high) : low_(low), high_(high) {}
  std::uint64_t low_ = 0;
  std::uint64_t high_ = 0;
};

}  // namespace hivecal
