// FNV-1a 64-bit digest over raw bytes: a compact fingerprint of results, used by the
// golden tests to show the same bits on every target.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/types.hpp"
#include "hivecal/core/wide_mask.hpp"

namespace hivecal {

/// Running FNV-1a 64 hash. Doubles are hashed as their IEEE-754 bits, little-endian.
class Digest {
 public:
  /// Hashes `count` raw bytes.
  void add_bytes(const void* data, std::size_t count);
  /// Hashes a 64-bit integer (little-endian bytes).
  void add_u64(std::uint64_t value);
  /// Hashes a parameter mask of one word (add_u64).
  void add_mask(std::uint64_t mask) { add_u64(mask); }
  /// Hashes a two-word mask: its low word, then its high word when that is not zero. A mask
  /// that fits in one word hashes as in a build whose masks are one word: results do not depend
  /// on the capacity, nor do their digests.
  void add_mask(const WideMask& mask);
  /// Hashes the bits of a double.
  void add(double value);
  /// Hashes every coefficient of an Eigen object, column-major.
  template <typename Derived>
  void add(const Eigen::MatrixBase<Derived>& m) {
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      for (Eigen::Index r = 0; r < m.rows(); ++r) add(static_cast<double>(m(r, c)));
  }
  /// Current hash value.
  std::uint64_t value() const { return state_; }

 private:
  std::uint64_t state_ = 0xcbf29ce484222325ULL;
};

}  // namespace hivecal
