// CRC-32C (Castagnoli), the checksum of the serial wire format (serial-protocol.md).
#pragma once

#include <cstddef>
#include <cstdint>

namespace hivecal {

/// CRC-32C of `count` bytes at `data` (nullptr allowed when count is 0): polynomial 0x1EDC6F41
/// reflected (0x82F63B78), init 0xFFFFFFFF, final xor 0xFFFFFFFF. crc32c("123456789") == 0xE3069283.
std::uint32_t crc32c(const std::uint8_t* data, std::size_t count);

}  // namespace hivecal
