// The FNV-1a 64 digest (core/digest.hpp): the published FNV test vectors, little-endian
// integers and IEEE-754 bits of doubles, column-major Eigen order, and chunking independence.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>
#include <limits>

#include "hivecal/core/digest.hpp"
#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::digest_test {
namespace {

/// Digest of a byte array, hashed in one call.
template <std::size_t N>
std::uint64_t digest_of(const unsigned char (&bytes)[N], std::size_t count = N) {
  Digest digest;
  EXPECT_NO_HEAP(digest.add_bytes(bytes, count));
  return digest.value();
}

// Known answers from the FNV reference test suite (Noll, "FNV hash" test vectors).
TEST(Digest, MatchesThePublishedFnv1a64Vectors) {
  const Digest fresh;
  EXPECT_EQ(fresh.value(), 0xcbf29ce484222325ULL);  // offset basis = hash of ""

  Digest empty;
  EXPECT_NO_HEAP(empty.add_bytes(nullptr, 0));
  EXPECT_EQ(empty.value(), 0xcbf29ce484222325ULL);

  const unsigned char a[] = {'a'};
  EXPECT_EQ(digest_of(a), 0xaf63dc4c8601ec8cULL);

  const unsigned char foobar[] = {'f', 'o', 'o', 'b', 'a', 'r'};
  EXPECT_EQ(digest_of(foobar), 0x85944171f73967e8ULL);
}

TEST(Digest, IsSensitiveToByteOrderAndValue) {
  const unsigned char ab[] = {'a', 'b'};
  const unsigned char ba[] = {'b', 'a'};
  EXPECT_NE(digest_of(ab), digest_of(ba));
  const unsigned char zero[] = {0};
  // FNV-1a multiplies even for a zero byte: hashing it changes the state.
  EXPECT_NE(digest_of(zero), 0xcbf29ce484222325ULL);
  EXPECT_EQ(digest_of(zero), 0xcbf29ce484222325ULL * 0x100000001b3ULL);
}

TEST(Digest, HashesIntegersAsLittleEndianBytes) {
  Digest by_value;
  EXPECT_NO_HEAP(by_value.add_u64(0x0123456789abcdefULL));
  const unsigned char little_endian[] = {0xef, 0xcd, 0xab, 0x89, 0x67, 0x45, 0x23, 0x01};
  EXPECT_EQ(by_value.value(), digest_of(little_endian));
  EXPECT_EQ(by_value.value(), 0x37eb3f3347761c55ULL);  // FNV-1a 64 of those 8 bytes, computed apart
}

TEST(Digest, HashesDoublesAsTheirIeeeBits) {
  Digest one;
  EXPECT_NO_HEAP(one.add(1.0));
  const unsigned char one_bits[] = {0, 0, 0, 0, 0, 0, 0xf0, 0x3f};  // 0x3ff0000000000000
  EXPECT_EQ(one.value(), digest_of(one_bits));
  EXPECT_EQ(one.value(), 0xaab1693229ba1db8ULL);

  // Bits, not values: signed zeros and NaN payloads give different digests.
  Digest plus_zero;
  Digest minus_zero;
  plus_zero.add(0.0);
  minus_zero.add(-0.0);
  EXPECT_NE(plus_zero.value(), minus_zero.value());
  Digest nan_a;
  Digest nan_b;
  nan_a.add(math::from_bits(0x7ff8000000000000ULL));
  nan_b.add(math::from_bits(0x7ff8000000000001ULL));
  EXPECT_NE(nan_a.value(), nan_b.value());

  // A double hashes exactly like the integer of its bits.
  Random random(11);
  for (int i = 0; i < 200; ++i) {
    const double x = random.uniform(-1e6, 1e6);
    Digest as_double;
    Digest as_bits;
    EXPECT_NO_HEAP(as_double.add(x));
    as_bits.add_u64(math::bits_of(x));
    ASSERT_EQ(as_double.value(), as_bits.value()) << x;
  }
}

TEST(Digest, HashesEigenObjectsColumnMajor) {
  Eigen::Matrix<double, 2, 3> m;
  m << 1.0, 2.0, 3.0,  //
      4.0, 5.0, 6.0;
  Digest whole;
  EXPECT_NO_HEAP(whole.add(m));
  Digest by_columns;
  for (double x : {1.0, 4.0, 2.0, 5.0, 3.0, 6.0}) by_columns.add(x);
  EXPECT_EQ(whole.value(), by_columns.value());
  Digest by_rows;
  for (double x : {1.0, 2.0, 3.0, 4.0, 5.0, 6.0}) by_rows.add(x);
  EXPECT_NE(whole.value(), by_rows.value());

  // Integer coefficients are hashed as the doubles they convert to.
  Eigen::Matrix<int, 2, 1> ints(7, -3);
  Digest from_ints;
  EXPECT_NO_HEAP(from_ints.add(ints));
  Digest from_doubles;
  from_doubles.add(7.0);
  from_doubles.add(-3.0);
  EXPECT_EQ(from_ints.value(), from_doubles.value());
}

TEST(Digest, DoesNotDependOnHowTheBytesAreSplit) {
  Random random(5);
  unsigned char bytes[64];
  for (int trial = 0; trial < 100; ++trial) {
    const std::size_t count = static_cast<std::size_t>(random.below(sizeof bytes + 1));
    for (std::size_t i = 0; i < count; ++i) bytes[i] = static_cast<unsigned char>(random.next());
    const std::uint64_t whole = digest_of(bytes, count);
    Digest pieces;
    std::size_t done = 0;
    while (done < count) {
      const std::size_t piece = static_cast<std::size_t>(random.below(count - done + 1));
      EXPECT_NO_HEAP(pieces.add_bytes(bytes + done, piece));
      done += piece;
    }
    ASSERT_EQ(pieces.value(), whole) << "trial " << trial;
    if (count > 0) {
      bytes[random.below(count)] ^= static_cast<unsigned char>(1U << random.below(8));
      EXPECT_NE(digest_of(bytes, count), whole) << "a flipped bit must change the digest";
    }
  }
}

}  // namespace
}  // namespace hivecal::digest_test
