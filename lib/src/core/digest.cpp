#include "hivecal/core/digest.hpp"

#include "hivecal/core/math.hpp"

namespace hivecal {

void Digest::add_bytes(const void* data, std::size_t count) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < count; ++i) {
    state_ ^= bytes[i];
    state_ *= 0x100000001b3ULL;
  }
}

void Digest::add_u64(std::uint64_t value) {
  unsigned char bytes[8];
  for (unsigned i = 0; i < 8; ++i) bytes[i] = static_cast<unsigned char>(value >> (8U * i));
  add_bytes(bytes, sizeof bytes);
}

void Digest::add_mask(const WideMask& mask) {
  add_u64(mask.low_word());
  if (mask.high_word() != 0) add_u64(mask.high_word());
}

void Digest::add(double value) {
  add_u64(math::bits_of(value));
}

}  // namespace hivecal
