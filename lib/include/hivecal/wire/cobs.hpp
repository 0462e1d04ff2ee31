// Consistent Overhead Byte Stuffing (Cheshire & Baker, 1999): removes every 0x00 from a
// packet so that 0x00 can delimit frames on the wire (serial-protocol.md, "Framing").
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/status.hpp"
#include "hivecal/core/span.hpp"

namespace hivecal {

/// Longest COBS encoding of a packet of `packet_bytes` bytes: one code byte per started
/// run of 254 data bytes (delimiter not included).
constexpr std::size_t cobs_max_encoded_bytes(std::size_t packet_bytes) {
  return packet_bytes + packet_bytes / 254 + 1;
}

/// Encodes `packet` into `out` without the 0x00 delimiter; *written = encoded bytes.
/// buffer_too_small (nothing written) unless out holds cobs_max_encoded_bytes(packet.size()).
Status cobs_encode(Span<const std::uint8_t> packet, Span<std::uint8_t> out, std::size_t* written);

/// Decodes one encoded frame (delimiter excluded) into `out`; *written = packet bytes.
/// `out` may start at `encoded`'s first byte (in-place decoding): output never overtakes input.
/// cobs_error for an empty frame, a 0x00 inside it, or a code byte pointing past its end;
/// buffer_too_small if the packet does not fit in `out`. Reads only inside `encoded`.
Status cobs_decode(Span<const std::uint8_t> encoded, Span<std::uint8_t> out, std::size_t* written);

}  // namespace hivecal
