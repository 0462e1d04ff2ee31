// CRC-32C (wire/crc32c.hpp): the spec's check value, RFC 3720 vectors, agreement with a
// bitwise reference over random buffers, the codeword residue, affinity, and detection of
// every single-bit error and every burst of up to 32 bits.
#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/wire/crc32c.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::crc32c_test {
namespace {

using Bytes = std::vector<std::uint8_t>;

std::uint32_t crc_of(const Bytes& bytes) {
  return test::no_heap([&] { return crc32c(bytes.data(), bytes.size()); });
}

/// The textbook bit-at-a-time CRC-32C (reflected polynomial 0x82F63B78, init and final xor
/// 0xFFFFFFFF), written from the spec's parameters: no table, nothing shared with the library.
std::uint32_t bitwise_crc32c(const std::uint8_t* data, std::size_t count) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (std::size_t i = 0; i < count; ++i) {
    crc ^= data[i];
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0x82F63B78u & (0u - (crc & 1u)));
  }
  return ~crc;
}

Bytes random_bytes(Random* random, std::size_t size) {
  Bytes bytes(size);
  for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(random->next());
  return bytes;
}

TEST(Crc32c, CheckValueAndEmptyInput) {
  const auto* check = reinterpret_cast<const std::uint8_t*>("123456789");
  std::uint32_t crc = 0;
  EXPECT_NO_HEAP(crc = crc32c(check, 9));
  EXPECT_EQ(crc, 0xE3069283u);
  EXPECT_EQ(test::no_heap([&] { return crc32c(nullptr, 0); }), 0u);
  EXPECT_EQ(test::no_heap([&] { return crc32c(check, 0); }), 0u);
}

TEST(Crc32c, Rfc3720TestVectors) {
  // RFC 3720 (iSCSI), appendix B.4: 32-byte patterns; the RFC lists the CRC bytes in wire
  // (little-endian) order, e.g. "aa 36 91 8a" for zeros.
  Bytes zeros(32, 0x00);
  Bytes ones(32, 0xFF);
  Bytes incrementing(32);
  Bytes decrementing(32);
  for (std::size_t i = 0; i < 32; ++i) {
    incrementing[i] = static_cast<std::uint8_t>(i);
    decrementing[i] = static_cast<std::uint8_t>(31 - i);
  }
  EXPECT_EQ(crc_of(zeros), 0x8A9136AAu);
  EXPECT_EQ(crc_of(ones), 0x62A8AB43u);
  EXPECT_EQ(crc_of(incrementing), 0x46DD794Eu);
  EXPECT_EQ(crc_of(decrementing), 0x113FDB5Cu);
  // One zero byte: the init value makes leading zeros count.
  EXPECT_EQ(crc_of(Bytes{0x00}), 0x527D5351u);
}

TEST(Crc32c, MatchesABitwiseReferenceOnRandomBuffersAtAnyAlignment) {
  Random random(32);
  const Bytes pool = random_bytes(&random, 700);
  for (int trial = 0; trial < 600; ++trial) {
    const auto offset = static_cast<std::size_t>(random.below(8));  // unaligned starts too
    const auto size = static_cast<std::size_t>(random.below(600));
    const std::uint8_t* data = pool.data() + offset;
    EXPECT_EQ(test::no_heap([&] { return crc32c(data, size); }), bitwise_crc32c(data, size))
        << "offset " << offset << " size " << size;
  }
  EXPECT_EQ(bitwise_crc32c(reinterpret_cast<const std::uint8_t*>("123456789"), 9), 0xE3069283u);  // the oracle itself
}

TEST(Crc32c, LeadingZeroBytesChangeTheCrc) {
  // With init 0xFFFFFFFF (not 0), runs of zeros of different lengths have different CRCs.
  std::vector<std::uint32_t> seen;
  for (std::size_t n = 0; n <= 64; ++n) {
    const std::uint32_t crc = crc_of(Bytes(n, 0));
    for (const std::uint32_t other : seen) EXPECT_NE(crc, other) << n;
    seen.push_back(crc);
  }
}

TEST(Crc32c, MessageFollowedByItsCrcHasTheConstantResidue) {
  // A codeword (message + its CRC, little-endian as on the wire) always has the CRC-32C
  // residue 0xB798B438 (RevEng catalogue, CRC-32/ISCSI), i.e. 0x48674BC7 after the final xor.
  Random random(33);
  for (int trial = 0; trial < 300; ++trial) {
    Bytes message = random_bytes(&random, static_cast<std::size_t>(random.below(300)));
    const std::uint32_t crc = crc_of(message);
    for (int i = 0; i < 4; ++i) message.push_back(static_cast<std::uint8_t>(crc >> (8 * i)));
    EXPECT_EQ(crc_of(message), 0x48674BC7u) << trial;
  }
}

TEST(Crc32c, IsAffineOverBuffersOfOneLength) {
  // crc(a ^ b) = crc(a) ^ crc(b) ^ crc(zeros) for a, b of the same length (linearity over
  // GF(2), init and final xor folded into the zeros' CRC).
  Random random(34);
  for (int trial = 0; trial < 300; ++trial) {
    const auto size = static_cast<std::size_t>(random.below(400));
    const Bytes a = random_bytes(&random, size);
    const Bytes b = random_bytes(&random, size);
    Bytes a_xor_b(size);
    for (std::size_t i = 0; i < size; ++i) a_xor_b[i] = static_cast<std::uint8_t>(a[i] ^ b[i]);
    EXPECT_EQ(crc_of(a_xor_b), crc_of(a) ^ crc_of(b) ^ crc_of(Bytes(size, 0))) << size;
  }
}

TEST(Crc32c, EverySingleBitFlipAndShortBurstIsDetected) {
  Random random(35);
  for (int trial = 0; trial < 500; ++trial) {
    const Bytes base = random_bytes(&random, 1 + static_cast<std::size_t>(random.below(300)));
    const std::uint32_t crc = crc_of(base);
    // One flipped bit anywhere.
    Bytes flipped = base;
    const auto bit = static_cast<std::size_t>(random.below(8 * base.size()));
    flipped[bit / 8] = static_cast<std::uint8_t>(flipped[bit / 8] ^ (1u << (bit % 8)));
    EXPECT_NE(crc_of(flipped), crc) << "bit " << bit << " of " << base.size() << " bytes";
    // A burst: bits first..first+length-1 xored with a pattern whose first and last bits are set.
    const auto length = static_cast<std::size_t>(1 + random.below(32));
    const std::size_t total_bits = 8 * base.size();
    if (length > total_bits) continue;
    const auto first = static_cast<std::size_t>(random.below(total_bits - length + 1));
    Bytes burst = base;
    for (std::size_t k = 0; k < length; ++k) {
      const bool set = k == 0 || k + 1 == length || random.below(2) == 1;
      if (set) {
        const std::size_t at = first + k;
        burst[at / 8] = static_cast<std::uint8_t>(burst[at / 8] ^ (1u << (at % 8)));
      }
    }
    EXPECT_NE(crc_of(burst), crc) << "burst of " << length << " bits at " << first;
  }
}

}  // namespace
}  // namespace hivecal::crc32c_test
