#include "hivecal/wire/cobs.hpp"

#include <cstring>

namespace hivecal {
namespace {

// A code byte c announces c - 1 data bytes; every code but this one is followed by an
// implied 0x00 (unless it ends the frame).
constexpr std::uint8_t kFullRunCode = 0xFF;

}  // namespace

Status cobs_encode(Span<const std::uint8_t> packet, Span<std::uint8_t> out, std::size_t* written) {
  if (written == nullptr) return Status::invalid_argument;
  *written = 0;
  if (out.size() < cobs_max_encoded_bytes(packet.size())) return Status::buffer_too_small;
  std::size_t code_at = 0;  // where the current run's code byte goes
  std::size_t next = 1;     // next output position
  std::uint8_t code = 1;
  for (const std::uint8_t byte : packet) {
    if (byte != 0) {
      out[next++] = byte;
      ++code;
    }
    if (byte == 0 || code == kFullRunCode) {
      out[code_at] = code;
      code_at = next++;
      code = 1;
    }
  }
  // A packet ending in a full run gets a final empty run ("01"), as in the reference encoder.
  out[code_at] = code;
  *written = next;
  return Status::ok;
}

Status cobs_decode(Span<const std::uint8_t> encoded, Span<std::uint8_t> out, std::size_t* written) {
  if (written == nullptr) return Status::invalid_argument;
  *written = 0;
  if (encoded.empty()) return Status::cobs_error;
  std::size_t in = 0;
  std::size_t produced = 0;
  while (in < encoded.size()) {
    const std::uint8_t code = encoded[in++];
    if (code == 0) return Status::cobs_error;
    const std::size_t run = code - 1u;
    if (run > encoded.size() - in) return Status::cobs_error;
    if (run != 0 && std::memchr(encoded.data() + in, 0, run) != nullptr) return Status::cobs_error;
    const bool implied_zero = code != kFullRunCode && in + run < encoded.size();
    if (run + (implied_zero ? 1u : 0u) > out.size() - produced) return Status::buffer_too_small;
    // memmove: in-place decoding writes at or before the bytes it reads.
    if (run != 0) std::memmove(out.data() + produced, encoded.data() + in, run);
    produced += run;
    in += run;
    if (implied_zero) out[produced++] = 0;
  }
  *written = produced;
  return Status::ok;
}

}  // namespace hivecal
