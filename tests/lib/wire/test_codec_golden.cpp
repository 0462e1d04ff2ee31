// The codec's golden digest: the same bits on every target and -O level (the golden scope,
// tests/CMakeLists.txt, builds only the test_*golden*.cpp files).
#include <gtest/gtest.h>

#include <cstdio>

#include "hivecal/wire/codec.hpp"
#include "testkit/codec_stream.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::codec_golden_test {
namespace {

using test::Corrupted;
using test::feed_chunked;
using test::SentStream;
using test::StreamShape;

// Golden digest of the codec: encoded bytes of a seeded stream through a seeded channel,
// every decoded record's bits and every counter. Same value on every target and -O level.
constexpr std::uint64_t kCodecGoldenDigest = 0xad8406a5186fd209ULL;

std::uint64_t codec_digest() {
  StreamShape shape;
  shape.frames = 4000;
  static SentStream sent;
  test::make_stream(20261122, shape, &sent);
  EXPECT_EQ(sent.library_allocations, 0u);
  Random channel(20261123);
  static Corrupted received;
  test::corrupt(sent, 2e-3, &channel, &received);
  Digest digest;
  digest.add_bytes(sent.bytes.data(), sent.bytes.size());
  digest.add_bytes(received.bytes.data(), received.bytes.size());
  StreamDecoder decoder;
  test::DigestHandler handler;
  feed_chunked(received.bytes, 200, 20261124, &decoder, handler);
  digest.add_u64(handler.digest.value());
  digest.add_u64(handler.count);
  test::add_stats(&digest, decoder.stats());
  return digest.value();
}

TEST(CodecGolden, DigestIsTheSameOnEveryTarget) {
  const std::uint64_t digest = codec_digest();
  std::printf("codec digest: 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kCodecGoldenDigest);
}

}  // namespace
}  // namespace hivecal::codec_golden_test
