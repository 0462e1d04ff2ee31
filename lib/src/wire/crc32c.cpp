// Byte-wise table CRC-32C. The 1 KiB table is computed at compile time (constexpr), so it
// lands in read-only memory (flash on firmware) and is the same on every target.
#include "hivecal/wire/crc32c.hpp"

namespace hivecal {
namespace {

constexpr std::uint32_t kReflectedPolynomial = 0x82F63B78u;

struct CrcTable {
  std::uint32_t entry[256];
};

constexpr CrcTable make_table() {
  CrcTable table{};
  for (std::uint32_t byte = 0; byte < 256; ++byte) {
    std::uint32_t crc = byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1u) != 0 ? (crc >> 1) ^ kReflectedPolynomial : crc >> 1;
    table.entry[byte] = crc;
  }
  return table;
}

constexpr CrcTable kTable = make_table();

constexpr std::uint32_t crc32c_update(std::uint32_t crc, const std::uint8_t* data, std::size_t count) {
  for (std::size_t i = 0; i < count; ++i) crc = kTable.entry[(crc ^ data[i]) & 0xFFu] ^ (crc >> 8);
  return crc;
}

// The spec's check value, verified by the compiler on every target.
constexpr std::uint8_t kCheckInput[9] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
static_assert((crc32c_update(0xFFFFFFFFu, kCheckInput, 9) ^ 0xFFFFFFFFu) == 0xE3069283u, "CRC-32C check value");

}  // namespace

std::uint32_t crc32c(const std::uint8_t* data, std::size_t count) {
  if (data == nullptr) count = 0;
  return crc32c_update(0xFFFFFFFFu, data, count) ^ 0xFFFFFFFFu;
}

}  // namespace hivecal
