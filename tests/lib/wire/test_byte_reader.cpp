// Byte sources (wire/byte_reader.hpp): MemoryByteReader hands out every byte once, in order,
// in reads of any capacity, returns 0 only at the end (and again after it), never writes past
// `capacity`, reads the caller's bytes in place (not a copy), and rewind() starts over.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/wire/byte_reader.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::byte_reader_test {
namespace {

using Bytes = std::vector<std::uint8_t>;

// The interface: abstract, and not deletable through the base (readers are not owned by it).
static_assert(std::is_abstract_v<ByteReader>, "ByteReader is an interface");
static_assert(!std::is_destructible_v<ByteReader>, "no delete through ByteReader");
static_assert(std::is_base_of_v<ByteReader, MemoryByteReader>, "MemoryByteReader is a ByteReader");

Bytes random_bytes(Random* random, std::size_t size) {
  Bytes bytes(size);
  for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(random->next());
  return bytes;
}

/// One read through the interface, under the allocation trap.
Status read_some(ByteReader& reader, std::uint8_t* out, std::size_t capacity, std::size_t* count) {
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = reader.read(out, capacity, count));
  return status;
}

/// Reads `reader` to its end with capacities 1..max_capacity drawn from `random`; checks each
/// read against the contract and returns the bytes in order.
Bytes read_all(ByteReader& reader, std::size_t expected_total, std::size_t max_capacity, Random* random) {
  Bytes all;
  std::uint8_t buffer[1100];
  for (int reads = 0; reads < 100000; ++reads) {
    const auto capacity = static_cast<std::size_t>(1 + random->below(max_capacity));
    const std::size_t guarded = capacity + 16;  // capacity <= 1024: inside the buffer
    std::fill(buffer, buffer + guarded, std::uint8_t{0xC3});
    std::size_t count = 12345;
    EXPECT_EQ(read_some(reader, buffer, capacity, &count), Status::ok);
    EXPECT_LE(count, capacity);
    if (count > capacity) break;
    // Only buffer[0, count) may change.
    EXPECT_EQ(std::count(buffer + count, buffer + guarded, 0xC3), static_cast<long>(guarded - count));
    if (count == 0) {
      EXPECT_EQ(all.size(), expected_total) << "0 returned before the end";
      return all;
    }
    all.insert(all.end(), buffer, buffer + count);
  }
  ADD_FAILURE() << "the reader never reported the end";
  return all;
}

TEST(MemoryByteReader, HandsOutEveryByteInOrderWhateverTheCapacity) {
  Random random(51);
  for (int trial = 0; trial < 60; ++trial) {
    const Bytes bytes = random_bytes(&random, static_cast<std::size_t>(random.below(3000)));
    MemoryByteReader reader(Span<const std::uint8_t>(bytes.data(), bytes.size()));
    const std::size_t max_capacity = trial % 3 == 0 ? 1 : trial % 3 == 1 ? 16 : 1024;
    EXPECT_EQ(read_all(reader, bytes.size(), max_capacity, &random), bytes) << trial;
  }
}

TEST(MemoryByteReader, EachReadFillsTheCapacityWhileBytesRemain) {
  // All bytes are at hand: each read gives min(capacity, remaining), so a reader of n bytes
  // ends after ceil(n / capacity) reads.
  Bytes bytes(1000);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7 + 3);
  MemoryByteReader reader(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  std::uint8_t buffer[300];
  const std::size_t expected[] = {300, 300, 300, 100, 0};
  std::size_t offset = 0;
  for (const std::size_t n : expected) {
    std::size_t count = 0;
    ASSERT_EQ(read_some(reader, buffer, sizeof buffer, &count), Status::ok);
    ASSERT_EQ(count, n);
    EXPECT_TRUE(std::equal(buffer, buffer + count, bytes.begin() + static_cast<long>(offset)));
    offset += count;
  }
}

TEST(MemoryByteReader, EndIsRepeatedAndAnEmptyReaderEndsAtOnce) {
  std::uint8_t buffer[8] = {9, 9, 9, 9, 9, 9, 9, 9};
  std::size_t count = 77;
  MemoryByteReader empty{Span<const std::uint8_t>()};
  EXPECT_EQ(read_some(empty, buffer, sizeof buffer, &count), Status::ok);
  EXPECT_EQ(count, 0u);

  const Bytes bytes = {1, 2, 3};
  MemoryByteReader reader(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  ASSERT_EQ(read_some(reader, buffer, sizeof buffer, &count), Status::ok);
  ASSERT_EQ(count, 3u);
  for (int again = 0; again < 3; ++again) {
    count = 77;
    EXPECT_EQ(read_some(reader, buffer + 3, 5, &count), Status::ok);
    EXPECT_EQ(count, 0u) << again;
  }
  EXPECT_EQ(Bytes(buffer, buffer + 8), (Bytes{1, 2, 3, 9, 9, 9, 9, 9}));  // nothing written at the end
}

TEST(MemoryByteReader, RewindStartsOverFromAnyPosition) {
  Random random(52);
  const Bytes bytes = random_bytes(&random, 2500);
  MemoryByteReader reader(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  std::uint8_t buffer[100];
  std::size_t count = 0;
  // Part way in, then back to the first byte.
  ASSERT_EQ(read_some(reader, buffer, 37, &count), Status::ok);
  ASSERT_EQ(read_some(reader, buffer, 100, &count), Status::ok);
  EXPECT_NO_HEAP(reader.rewind());
  ASSERT_EQ(read_some(reader, buffer, 5, &count), Status::ok);
  ASSERT_EQ(count, 5u);
  EXPECT_TRUE(std::equal(buffer, buffer + 5, bytes.begin()));
  // Rewound at the start or after the end: the whole stream again, every time.
  EXPECT_NO_HEAP(reader.rewind());
  for (int pass = 0; pass < 3; ++pass) {
    EXPECT_EQ(read_all(reader, bytes.size(), 700, &random), bytes) << pass;
    EXPECT_NO_HEAP(reader.rewind());
  }
}

TEST(MemoryByteReader, ReadsTheCallersBytesInPlace) {
  // "Not owned": the reader sees the caller's buffer as it is when read, not a copy made at
  // construction.
  Bytes bytes = {10, 20, 30, 40, 50, 60};
  MemoryByteReader reader(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  bytes[0] = 11;
  bytes[4] = 55;
  std::uint8_t buffer[4] = {};
  std::size_t count = 0;
  ASSERT_EQ(read_some(reader, buffer, 2, &count), Status::ok);
  EXPECT_EQ(Bytes(buffer, buffer + count), (Bytes{11, 20}));
  bytes[2] = 33;  // not read yet
  bytes[1] = 99;  // already read: not given again
  ASSERT_EQ(read_some(reader, buffer, 4, &count), Status::ok);
  EXPECT_EQ(Bytes(buffer, buffer + count), (Bytes{33, 40, 55, 60}));
  // A view of part of a buffer ends where the view ends.
  MemoryByteReader middle(Span<const std::uint8_t>(bytes.data() + 2, 3));
  std::uint8_t more[8] = {};
  ASSERT_EQ(read_some(middle, more, sizeof more, &count), Status::ok);
  EXPECT_EQ(Bytes(more, more + count), (Bytes{33, 40, 55}));
  ASSERT_EQ(read_some(middle, more, sizeof more, &count), Status::ok);
  EXPECT_EQ(count, 0u);
}

TEST(MemoryByteReader, IndependentReadersOverOneBufferKeepTheirOwnPositions) {
  Random random(53);
  const Bytes bytes = random_bytes(&random, 900);
  MemoryByteReader a(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  MemoryByteReader b(Span<const std::uint8_t>(bytes.data(), bytes.size()));
  Bytes from_a;
  Bytes from_b;
  std::uint8_t buffer[64];
  for (bool a_done = false, b_done = false; !a_done || !b_done;) {
    std::size_t count = 0;
    ByteReader& reader = random.below(2) == 0 ? static_cast<ByteReader&>(a) : static_cast<ByteReader&>(b);
    Bytes& into = &reader == &a ? from_a : from_b;
    ASSERT_EQ(read_some(reader, buffer, 1 + static_cast<std::size_t>(random.below(64)), &count), Status::ok);
    into.insert(into.end(), buffer, buffer + count);
    if (count == 0) {
      (&reader == &a ? a_done : b_done) = true;
    }
  }
  EXPECT_EQ(from_a, bytes);
  EXPECT_EQ(from_b, bytes);
}

}  // namespace
}  // namespace hivecal::byte_reader_test
