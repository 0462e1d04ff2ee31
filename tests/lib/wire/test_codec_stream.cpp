// Wire codec on whole streams: chunking invariance, round trips through a noisy channel
// (bit flips, dropped and inserted bytes, garbage), the corruption sweep (the golden digest:
// test_codec_golden.cpp).
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <vector>

#include "hivecal/wire/codec.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/codec_stream.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::codec_stream_test {
namespace {

using test::Corrupted;
using test::feed_chunked;
using test::SentStream;
using test::StreamShape;

/// Checks every delivered record against what was sent (looked up by sequence number: the
/// stream numbers all its frames with one counter) and remembers which sent frames arrived,
/// in arrival order.
class CheckingHandler : public test::DigestHandler {
 public:
  explicit CheckingHandler(const SentStream& sent) : sent_(sent) {
    accepted.reserve(sent.frames.size());  // up front: the callbacks run under the allocation trap
  }
  void on_joint_state(const JointStateRecord& r) override {
    DigestHandler::on_joint_state(r);
    check(0, r, sent_.joint_states);
  }
  void on_tracker_point(const TrackerPointRecord& r) override {
    DigestHandler::on_tracker_point(r);
    check(1, r, sent_.tracker_points);
  }
  void on_device_info(const DeviceInfoRecord& r) override {
    DigestHandler::on_device_info(r);
    check(2, r, sent_.device_infos);
  }

  std::vector<std::size_t> accepted;  ///< indices into sent.frames of the delivered records, arrival order
  std::uint64_t per_type[3] = {};     ///< records delivered per type
  std::uint64_t false_accepts = 0;    ///< delivered records that were never sent

 private:
  template <typename Record>
  void check(int type, const Record& record, const std::vector<Record>& sent) {
    ++per_type[type];
    const std::size_t position = static_cast<std::uint16_t>(record.sequence - sent_.first_sequence);
    const bool known = position < sent_.frames.size() && sent_.frames[position].type == type + 1 &&
                       test::same_bits(sent[sent_.frames[position].index], record);
    if (!known || accepted.size() == accepted.capacity()) {
      ++false_accepts;
      return;
    }
    accepted.push_back(position);
  }
  const SentStream& sent_;
};

/// Indices into sent.frames of the frames that reach the reader unchanged, in arrival order:
/// the pieces of `received` between 0x00s that equal a sent frame byte for byte (valid and
/// unknown-type frames alike; found by comparison, not by decoding).
std::vector<std::size_t> intact_arrivals(const SentStream& sent, const std::vector<std::uint8_t>& received) {
  std::map<std::vector<std::uint8_t>, std::size_t> frame_of_bytes;
  for (std::size_t k = 0; k < sent.frames.size(); ++k) {
    const auto begin = sent.bytes.begin() + static_cast<std::ptrdiff_t>(sent.frames[k].begin);
    const auto end = sent.bytes.begin() + static_cast<std::ptrdiff_t>(sent.frames[k].end) - 1;  // delimiter excluded
    frame_of_bytes.emplace(std::vector<std::uint8_t>(begin, end), k);
  }
  std::vector<std::size_t> arrivals;
  std::vector<std::uint8_t> piece;
  for (const std::uint8_t byte : received) {
    if (byte != 0) {
      piece.push_back(byte);
      continue;
    }
    const auto found = frame_of_bytes.find(piece);
    if (found != frame_of_bytes.end()) arrivals.push_back(found->second);
    piece.clear();
  }
  return arrivals;
}

/// Counter identities that hold for any input.
void expect_consistent(const DecoderStats& s, std::size_t fed_bytes, const CheckingHandler& handler) {
  EXPECT_EQ(s.bytes_total, fed_bytes);
  EXPECT_EQ(s.bytes_accepted + s.bytes_idle + s.bytes_discarded + s.bytes_pending, s.bytes_total);
  EXPECT_LE(s.bytes_pending, kMaxFrameBytes - 1);
  EXPECT_EQ(s.frames_ok, handler.count);
  EXPECT_EQ(s.joint_states, handler.per_type[0]);
  EXPECT_EQ(s.tracker_points, handler.per_type[1]);
  EXPECT_EQ(s.device_infos, handler.per_type[2]);
  EXPECT_EQ(s.frames_ok, s.joint_states + s.tracker_points + s.device_infos);
  EXPECT_LE(s.leading_fragments, 1u);
}

/// Gaps, losses and restarts implied by the arrival order of the stream's frames (their
/// positions in the stream are their sequence numbers; timestamps grow with them).
struct ExpectedSequence {
  std::uint64_t gaps = 0;
  std::uint64_t lost = 0;
  std::uint64_t resets = 0;
};
ExpectedSequence expected_sequence(const std::vector<std::size_t>& arrivals) {
  ExpectedSequence e;
  for (std::size_t k = 1; k < arrivals.size(); ++k) {
    if (arrivals[k] <= arrivals[k - 1]) {
      ++e.resets;
    } else if (arrivals[k] > arrivals[k - 1] + 1) {
      ++e.gaps;
      e.lost += arrivals[k] - arrivals[k - 1] - 1;
    }
  }
  return e;
}

/// Outcome of one stream through the channel.
struct ChannelResult {
  DecoderStats stats;
  std::size_t sent_valid = 0;
  std::size_t errors = 0;
  std::uint64_t false_accepts = 0;
  std::size_t sent_numbered = 0;      ///< valid + unknown-type frames: each took a sequence number
  std::size_t untouched_missed = 0;   ///< undamaged frames that did not arrive intact
  std::size_t garbage_fragments = 0;  ///< deliberate garbage pieces in the sent stream
};

ChannelResult run_channel(std::uint64_t seed, std::size_t frames, double byte_error_rate, std::size_t max_chunk) {
  StreamShape shape;
  shape.frames = frames;
  static SentStream sent;  // static: large streams stay off the test's stack
  test::make_stream(seed, shape, &sent);
  EXPECT_EQ(sent.library_allocations, 0u);
  Random channel(seed ^ 0x5EED);
  static Corrupted received;
  test::corrupt(sent, byte_error_rate, &channel, &received);

  StreamDecoder decoder;
  CheckingHandler handler(sent);
  feed_chunked(received.bytes, max_chunk, seed + 1, &decoder, handler);
  const DecoderStats& s = decoder.stats();
  expect_consistent(s, received.bytes.size(), handler);

  // The decoder must deliver exactly the intact valid frames, skip exactly the intact
  // unknown-type ones, and count as lost only the sequence numbers of frames that did not
  // arrive intact: skipped unknown-type frames are not lost.
  const std::vector<std::size_t> arrivals = intact_arrivals(sent, received.bytes);
  std::vector<std::size_t> known_arrivals;
  std::uint64_t unknown_arrivals = 0;
  for (std::size_t k : arrivals) {
    if (sent.frames[k].type == test::kUnknownTypeMarker)
      ++unknown_arrivals;
    else
      known_arrivals.push_back(k);
  }
  EXPECT_TRUE(handler.accepted == known_arrivals);
  EXPECT_EQ(s.unknown_types, unknown_arrivals);
  const ExpectedSequence e = expected_sequence(arrivals);
  EXPECT_EQ(s.sequence_gaps, e.gaps);
  EXPECT_EQ(s.packets_lost, e.lost);
  EXPECT_EQ(s.sequence_resets, e.resets);

  ChannelResult result;
  result.stats = s;
  result.sent_valid = sent.valid_frames();
  result.sent_numbered = sent.frames.size();
  result.errors = received.errors;
  result.garbage_fragments = sent.garbage_fragments;
  result.false_accepts = handler.false_accepts;
  std::vector<char> arrived(sent.frames.size());
  for (std::size_t k : arrivals) arrived[k] = 1;
  for (std::size_t f = 0; f < sent.frames.size(); ++f)
    if (!received.frame_touched[f] && !arrived[f]) ++result.untouched_missed;
  EXPECT_LE(s.unknown_types, sent.unknown_frames);
  if (byte_error_rate == 0.0) {
    EXPECT_EQ(s.frames_ok, sent.valid_frames());
    EXPECT_EQ(s.unknown_types, sent.unknown_frames);
    EXPECT_EQ(s.frames_rejected() - s.unknown_types, sent.garbage_fragments);
    EXPECT_EQ(s.sequence_gaps + s.packets_lost + s.sequence_resets + s.leading_fragments, 0u);
  }
  return result;
}

TEST(CodecStream, ChunkingDoesNotChangeAnything) {
  StreamShape shape;
  shape.frames = 1500;
  static SentStream sent;
  test::make_stream(77, shape, &sent);
  Random channel(78);
  static Corrupted received;
  test::corrupt(sent, 1e-3, &channel, &received);
  received.bytes.erase(received.bytes.begin(), received.bytes.begin() + 9);  // start mid-frame

  StreamDecoder whole;
  test::DigestHandler reference;
  EXPECT_NO_HEAP(whole.feed(received.bytes.data(), received.bytes.size(), reference));
  EXPECT_EQ(whole.stats().leading_fragments, 1u);
  EXPECT_GT(whole.stats().frames_ok, 1000u);
  EXPECT_GT(whole.stats().crc_failures, 0u);

  for (std::size_t max_chunk : {1, 2, 3, 16, 137, 138, 139, 1000, 100000}) {
    for (std::uint64_t chunk_seed : {1, 2}) {
      StreamDecoder decoder;
      test::DigestHandler handler;
      feed_chunked(received.bytes, max_chunk, chunk_seed, &decoder, handler);
      EXPECT_EQ(handler.count, reference.count) << max_chunk;
      EXPECT_EQ(handler.digest.value(), reference.digest.value()) << max_chunk;
      EXPECT_TRUE(test::same_stats(decoder.stats(), whole.stats())) << max_chunk;
    }
  }
}

TEST(CodecStream, CleanStreamRoundTripsExactly) {
  for (std::uint64_t seed : {1, 2, 3}) {
    const ChannelResult r = run_channel(seed, 3000, 0.0, 300);
    EXPECT_EQ(r.false_accepts, 0u);
    EXPECT_EQ(r.untouched_missed, 0u);
    EXPECT_EQ(r.stats.frames_ok, r.sent_valid);
  }
}

TEST(CodecStream, NoisyChannelRoundTripProperty) {
  for (std::uint64_t seed = 10; seed < 16; ++seed) {
    const double rate = seed % 2 == 0 ? 1e-3 : 5e-3;
    const ChannelResult r = run_channel(seed, 2000, rate, static_cast<std::size_t>(1 + seed * 40));
    EXPECT_GT(r.errors, 0u);
    EXPECT_EQ(r.false_accepts, 0u) << seed;
    EXPECT_EQ(r.untouched_missed, 0u) << seed;
    EXPECT_LT(r.stats.frames_ok, r.sent_valid) << seed;
    EXPECT_GT(r.stats.crc_failures + r.stats.cobs_errors + r.stats.bad_lengths, 0u) << seed;
  }
}

TEST(CodecStream, CorruptionSweepHasNoFalseAccepts) {
  constexpr std::size_t kFrames = 20000;
  std::printf(
      "  byte error rate | errors | frames sent (valid) | accepted | lost (gaps)    | garbage | crc  | cobs | "
      "length | oversized | false accepts\n");
  for (double rate : {1e-5, 1e-4, 1e-3, 1e-2}) {
    const ChannelResult r = run_channel(2026, kFrames, rate, 4096);
    // accepted: of the valid frames; lost: of all frames, as unknown-type ones take numbers too.
    std::printf(
        "  %15.0e | %6zu | %11zu (%5zu) | %7.3f%% | %7.3f%% (%4llu) | %7zu | %4llu | %4llu | %6llu | %9llu | %llu\n",
        rate, r.errors, r.sent_numbered, r.sent_valid,
        100.0 * static_cast<double>(r.stats.frames_ok) / static_cast<double>(r.sent_valid),
        100.0 * static_cast<double>(r.stats.packets_lost) / static_cast<double>(r.sent_numbered),
        static_cast<unsigned long long>(r.stats.sequence_gaps), r.garbage_fragments,
        static_cast<unsigned long long>(r.stats.crc_failures), static_cast<unsigned long long>(r.stats.cobs_errors),
        static_cast<unsigned long long>(r.stats.bad_lengths), static_cast<unsigned long long>(r.stats.oversized_frames),
        static_cast<unsigned long long>(r.false_accepts));
    EXPECT_EQ(r.false_accepts, 0u) << rate;
    EXPECT_EQ(r.untouched_missed, 0u) << rate;
    EXPECT_EQ(r.stats.bad_versions + r.stats.bad_payloads, 0u) << rate;  // only intact packets reach these checks
  }
}

}  // namespace
}  // namespace hivecal::codec_stream_test
