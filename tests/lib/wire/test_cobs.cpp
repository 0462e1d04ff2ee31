// COBS framing (wire/cobs.hpp): Cheshire & Baker's examples, byte equality with the paper's
// reference encoder and the exact encoded size on random buffers, no 0x00 in any encoding,
// the size bound, in-place decoding, and every rejection and short-buffer path.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "hivecal/core/random.hpp"
#include "hivecal/wire/cobs.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::cobs_test {
namespace {

using Bytes = std::vector<std::uint8_t>;

Status encode(const Bytes& packet, Bytes* out, std::size_t* written) {
  return test::no_heap([&] {
    return cobs_encode(Span<const std::uint8_t>(packet.data(), packet.size()),
                       Span<std::uint8_t>(out->data(), out->size()), written);
  });
}

Status decode(const Bytes& encoded, Bytes* out, std::size_t* written) {
  return test::no_heap([&] {
    return cobs_decode(Span<const std::uint8_t>(encoded.data(), encoded.size()),
                       Span<std::uint8_t>(out->data(), out->size()), written);
  });
}

/// StuffData() of Cheshire & Baker (1999), figure 2, transcribed: the reference encoder.
Bytes reference_stuff(const Bytes& packet) {
  Bytes dst(packet.size() + packet.size() / 254 + 2);
  std::size_t code_ptr = 0;
  std::size_t next = 1;
  std::uint8_t code = 0x01;
  auto finish_block = [&] {
    dst[code_ptr] = code;
    code_ptr = next++;
    code = 0x01;
  };
  for (const std::uint8_t byte : packet) {
    if (byte == 0) {
      finish_block();
    } else {
      dst[next++] = byte;
      ++code;
      if (code == 0xFF) finish_block();
    }
  }
  finish_block();
  dst.resize(next - 1);  // the last finish_block reserved a code slot that is not used
  return dst;
}

/// A random packet: no zeros, all zeros, sparse or dense zeros, long nonzero runs.
Bytes random_packet(Random* random, std::size_t size) {
  Bytes packet(size);
  const std::uint64_t shape = random->below(5);
  for (std::uint8_t& b : packet) {
    switch (shape) {
      case 0: b = static_cast<std::uint8_t>(1 + random->below(255)); break;
      case 1: b = 0; break;
      case 2: b = static_cast<std::uint8_t>(random->below(300) == 0 ? 0 : 1 + random->below(255)); break;
      case 3: b = static_cast<std::uint8_t>(random->below(3)); break;
      default: b = static_cast<std::uint8_t>(random->next()); break;
    }
  }
  return packet;
}

TEST(Cobs, KnownEncodings) {
  struct Case {
    const char* packet;
    const char* encoded;
  };
  // Cheshire & Baker examples (delimiter excluded).
  const Case cases[] = {{"00", "0101"},
                        {"0000", "010101"},
                        {"11220033", "0311220233"},
                        {"11223344", "0511223344"},
                        {"11000000", "0211010101"},
                        {"", "01"}};
  for (const Case& c : cases) {
    const Bytes packet = test::from_hex(c.packet);
    Bytes out(cobs_max_encoded_bytes(packet.size()));
    std::size_t written = 0;
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = cobs_encode(Span<const std::uint8_t>(packet.data(), packet.size()),
                                        Span<std::uint8_t>(out.data(), out.size()), &written));
    ASSERT_EQ(status, Status::ok);
    out.resize(written);
    EXPECT_EQ(out, test::from_hex(c.encoded)) << c.packet;
    Bytes back(out.size());
    EXPECT_NO_HEAP(status = cobs_decode(Span<const std::uint8_t>(out.data(), out.size()),
                                        Span<std::uint8_t>(back.data(), back.size()), &written));
    ASSERT_EQ(status, Status::ok);
    back.resize(written);
    EXPECT_EQ(back, packet);
  }
}

TEST(Cobs, LongRunsRoundTripInPlace) {
  Random random(4);
  for (std::size_t size = 0; size < 800; size += 1 + static_cast<std::size_t>(random.below(7))) {
    Bytes packet(size);
    const bool sparse_zeros = random.below(2) == 0;
    for (auto& b : packet) b = static_cast<std::uint8_t>(sparse_zeros ? 1 + random.below(255) : random.below(3));
    Bytes buffer(cobs_max_encoded_bytes(size));
    std::size_t encoded = 0;
    ASSERT_EQ(test::no_heap([&] {
                return cobs_encode(Span<const std::uint8_t>(packet.data(), size),
                                   Span<std::uint8_t>(buffer.data(), buffer.size()), &encoded);
              }),
              Status::ok);
    EXPECT_EQ(std::count(buffer.begin(), buffer.begin() + static_cast<long>(encoded), 0), 0);
    std::size_t decoded = 0;
    ASSERT_EQ(test::no_heap([&] {
                return cobs_decode(Span<const std::uint8_t>(buffer.data(), encoded),
                                   Span<std::uint8_t>(buffer.data(), encoded), &decoded);
              }),
              Status::ok);  // in place
    ASSERT_EQ(decoded, size);
    EXPECT_TRUE(std::equal(packet.begin(), packet.end(), buffer.begin()));
  }
  // A full 254-byte run at the end decodes with or without the final empty run ("01").
  Bytes full(255, 0xAB);
  full[0] = 0xFF;
  Bytes out(300);
  std::size_t decoded = 0;
  ASSERT_EQ(test::no_heap([&] {
              return cobs_decode(Span<const std::uint8_t>(full.data(), full.size()),
                                 Span<std::uint8_t>(out.data(), out.size()), &decoded);
            }),
            Status::ok);
  EXPECT_EQ(decoded, 254u);
}

TEST(Cobs, RejectsMalformedFrames) {
  Bytes out(64);
  std::size_t written = 7;
  const Span<std::uint8_t> o(out.data(), out.size());
  const Bytes past_end = test::from_hex("051122");
  EXPECT_EQ(test::no_heap(
                [&] { return cobs_decode(Span<const std::uint8_t>(past_end.data(), past_end.size()), o, &written); }),
            Status::cobs_error);
  EXPECT_EQ(written, 0u);
  const Bytes inner_zero = test::from_hex("03110022");
  EXPECT_EQ(test::no_heap([&] {
              return cobs_decode(Span<const std::uint8_t>(inner_zero.data(), inner_zero.size()), o, &written);
            }),
            Status::cobs_error);
  const Bytes zero_code = test::from_hex("0211002233");
  EXPECT_EQ(test::no_heap(
                [&] { return cobs_decode(Span<const std::uint8_t>(zero_code.data(), zero_code.size()), o, &written); }),
            Status::cobs_error);
  EXPECT_EQ(test::no_heap([&] { return cobs_decode(Span<const std::uint8_t>(), o, &written); }), Status::cobs_error);
  const Bytes fine = test::from_hex("0311220233");
  EXPECT_EQ(test::no_heap([&] {
              return cobs_decode(Span<const std::uint8_t>(fine.data(), fine.size()), o.subspan(0, 3), &written);
            }),
            Status::buffer_too_small);
  EXPECT_EQ(test::no_heap([&] {
              return cobs_encode(Span<const std::uint8_t>(fine.data(), fine.size()), o.subspan(0, 5), &written);
            }),
            Status::buffer_too_small);
  EXPECT_EQ(test::no_heap([&] { return cobs_encode(Span<const std::uint8_t>(fine.data(), fine.size()), o, nullptr); }),
            Status::invalid_argument);
}

TEST(Cobs, MaxEncodedBytesByHand) {
  // One code byte per started run of 254 data bytes, plus the final code (n + n / 254 + 1).
  static_assert(cobs_max_encoded_bytes(0) == 1, "empty packet: one code byte");
  EXPECT_EQ(cobs_max_encoded_bytes(1), 2u);
  EXPECT_EQ(cobs_max_encoded_bytes(253), 254u);
  EXPECT_EQ(cobs_max_encoded_bytes(254), 256u);  // FF + 254 bytes + the final empty run 01
  EXPECT_EQ(cobs_max_encoded_bytes(508), 511u);
  EXPECT_EQ(cobs_max_encoded_bytes(136), 137u);  // the largest wire packet (JOINT_STATE)
}

TEST(Cobs, RandomBuffersRoundTripWithoutZerosAndWithinTheBound) {
  Random random(41);
  // First the run-length edges without zeros (a full 254-byte run at the end gets a final
  // empty run "01"), then random lengths 0..600 and shapes.
  const std::size_t edges[] = {0, 1, 253, 254, 255, 507, 508, 509, 600};
  const std::size_t edge_count = sizeof edges / sizeof edges[0];
  for (std::size_t trial = 0; trial < 400; ++trial) {
    const auto size = trial < edge_count ? edges[trial] : static_cast<std::size_t>(random.below(601));
    Bytes packet = random_packet(&random, size);
    if (trial < edge_count) {
      for (std::uint8_t& b : packet) b = static_cast<std::uint8_t>(1 + random.below(255));
    }
    Bytes encoded(cobs_max_encoded_bytes(size));  // exactly the stated bound
    std::size_t written = 0;
    ASSERT_EQ(encode(packet, &encoded, &written), Status::ok) << size;
    ASSERT_LE(written, encoded.size()) << size;
    encoded.resize(written);
    EXPECT_EQ(std::count(encoded.begin(), encoded.end(), 0), 0) << size;
    // Byte for byte the paper's encoder, hence its size: n + 1 + one extra code byte per
    // 254 nonzero bytes in each zero-delimited piece.
    EXPECT_EQ(encoded, reference_stuff(packet)) << size;
    std::size_t expected_size = size + 1;
    std::size_t piece = 0;
    for (std::size_t i = 0; i <= size; ++i) {
      if (i == size || packet[i] == 0) {
        expected_size += piece / 254;
        piece = 0;
      } else {
        ++piece;
      }
    }
    EXPECT_EQ(written, expected_size) << size;
    if (std::count(packet.begin(), packet.end(), 0) == 0) {
      EXPECT_EQ(written, cobs_max_encoded_bytes(size)) << size;  // the bound is reached without zeros
    }
    // Out of place into exactly the packet's size.
    Bytes decoded(size);
    std::size_t decoded_size = 99;
    ASSERT_EQ(decode(encoded, &decoded, &decoded_size), Status::ok) << size;
    EXPECT_EQ(decoded_size, size);
    EXPECT_EQ(decoded, packet) << size;
  }
}

TEST(Cobs, ShortOutputBuffersAreRefusedWithoutWritingPastThem) {
  Random random(42);
  for (int trial = 0; trial < 200; ++trial) {
    const auto size = static_cast<std::size_t>(1 + random.below(600));
    const Bytes packet = random_packet(&random, size);
    // Encoding: one byte less than the bound is refused and nothing is written, even when the
    // actual encoding would fit.
    Bytes short_out(cobs_max_encoded_bytes(size) - 1, 0x5A);
    std::size_t written = 77;
    EXPECT_EQ(encode(packet, &short_out, &written), Status::buffer_too_small) << size;
    EXPECT_EQ(written, 0u);
    EXPECT_EQ(std::count(short_out.begin(), short_out.end(), 0x5A), static_cast<long>(short_out.size())) << size;
    // Decoding: one byte short of the packet is refused; the output span is never overrun.
    Bytes encoded(cobs_max_encoded_bytes(size));
    ASSERT_EQ(encode(packet, &encoded, &written), Status::ok);
    encoded.resize(written);
    Bytes guarded(size + 8, 0xA5);  // the decoder gets the first size - 1 bytes
    std::size_t decoded = 77;
    EXPECT_EQ(test::no_heap([&] {
                return cobs_decode(Span<const std::uint8_t>(encoded.data(), encoded.size()),
                                   Span<std::uint8_t>(guarded.data(), size - 1), &decoded);
              }),
              Status::buffer_too_small)
        << size;
    EXPECT_EQ(decoded, 0u);
    EXPECT_EQ(std::count(guarded.begin() + static_cast<long>(size - 1), guarded.end(), 0xA5), 9) << size;
  }
  Bytes out(4);
  const Bytes fine = test::from_hex("0311220233");
  EXPECT_EQ(test::no_heap([&] {
              return cobs_decode(Span<const std::uint8_t>(fine.data(), fine.size()),
                                 Span<std::uint8_t>(out.data(), out.size()), nullptr);
            }),
            Status::invalid_argument);
}

TEST(Cobs, DamagedEncodingsAreRejected) {
  Random random(43);
  int truncations = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const Bytes packet = random_packet(&random, static_cast<std::size_t>(random.below(601)));
    Bytes encoded(cobs_max_encoded_bytes(packet.size()));
    std::size_t written = 0;
    ASSERT_EQ(encode(packet, &encoded, &written), Status::ok);
    encoded.resize(written);
    Bytes out(packet.size() + 8);
    std::size_t decoded = 0;
    // A 0x00 anywhere inside the frame (replacing or inserted before a byte) is a COBS error.
    const auto at = static_cast<std::size_t>(random.below(encoded.size()));
    Bytes with_zero = encoded;
    with_zero[at] = 0;
    EXPECT_EQ(decode(with_zero, &out, &decoded), Status::cobs_error) << at;
    Bytes inserted = encoded;
    inserted.insert(inserted.begin() + static_cast<long>(at), std::uint8_t{0});
    EXPECT_EQ(decode(inserted, &out, &decoded), Status::cobs_error) << at;
    // Cut inside a run: the run's code byte points past the new end.
    std::vector<std::size_t> inside_run;
    for (std::size_t code_at = 0; code_at < encoded.size(); code_at += encoded[code_at]) {
      for (std::size_t k = code_at + 1; k < code_at + encoded[code_at]; ++k) inside_run.push_back(k);
    }
    if (!inside_run.empty()) {
      const std::size_t cut = inside_run[static_cast<std::size_t>(random.below(inside_run.size()))];
      const Bytes truncated(encoded.begin(), encoded.begin() + static_cast<long>(cut));
      EXPECT_EQ(decode(truncated, &out, &decoded), Status::cobs_error) << "cut at " << cut;
      ++truncations;
    }
  }
  EXPECT_GT(truncations, 100);
}

}  // namespace
}  // namespace hivecal::cobs_test
