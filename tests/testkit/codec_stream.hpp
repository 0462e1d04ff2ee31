// Seeded random wire streams for the codec tests: valid frames of every type, unknown-type
// frames, garbage and idle bytes, and a channel model that flips, drops and inserts bytes.
// Hosted test code (std::vector), deterministic on every target (hivecal::Random only).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <vector>

#include "testkit/alloc_trap.hpp"
#include "testkit/codec_support.hpp"

namespace hivecal::test {

/// SentFrame::type of a CRC-valid frame of an unknown type.
inline constexpr std::uint8_t kUnknownTypeMarker = 0;

/// One frame put on the wire by make_stream; each takes the stream's next sequence number.
struct SentFrame {
  std::uint8_t type = 0;  ///< packet type byte 1..3, or kUnknownTypeMarker
  std::size_t begin = 0;  ///< first byte in SentStream::bytes
  std::size_t end = 0;    ///< one past its delimiter
  std::size_t index = 0;  ///< index into the per-type record array (known types)
};

/// What make_stream produced.
struct SentStream {
  std::vector<std::uint8_t> bytes;                 ///< the wire
  std::vector<JointStateRecord> joint_states;      ///< sent in this order
  std::vector<TrackerPointRecord> tracker_points;  ///< sent in this order
  std::vector<DeviceInfoRecord> device_infos;      ///< sent in this order
  std::vector<SentFrame> frames;                   ///< valid and unknown-type frames, in order
  std::uint16_t first_sequence = 0;                ///< sequence of frames[0]; frames[k] has first_sequence + k
  std::size_t unknown_frames = 0;                  ///< CRC-valid frames of unknown type
  std::size_t garbage_fragments = 0;               ///< non-empty garbage pieces between 0x00s
  std::size_t library_allocations = 0;             ///< heap allocations inside codec calls (must be 0)
  std::size_t valid_frames() const { return joint_states.size() + tracker_points.size() + device_infos.size(); }
};

/// Mix of the stream.
struct StreamShape {
  std::size_t frames = 1000;     ///< valid + unknown frames
  double unknown_chance = 0.03;  ///< share of unknown-type frames
  double garbage_chance = 0.05;  ///< chance of a garbage burst (ended by 0x00) after a frame
  double idle_chance = 0.1;      ///< chance of 1..3 extra 0x00 after a frame
};

inline void append_frame(const std::uint8_t* frame, std::size_t size, std::uint8_t type, std::size_t index,
                         SentStream* out) {
  SentFrame sent;
  sent.type = type;
  sent.begin = out->bytes.size();
  out->bytes.insert(out->bytes.end(), frame, frame + size);
  sent.end = out->bytes.size();
  sent.index = index;
  out->frames.push_back(sent);
}

/// A CRC-valid version-1 packet of an unknown type and random length and payload, with the
/// stream's sequence number and timestamp in its header, framed.
inline std::size_t make_unknown_frame(Random* random, std::uint16_t sequence, std::uint64_t timestamp_us,
                                      std::uint8_t* frame) {
  std::uint8_t packet[kMaxSpecPacketBytes];
  const std::size_t size =
      kPacketHeaderBytes + kPacketCrcBytes + static_cast<std::size_t>(random->below(kMaxSpecPacketBytes - 15));
  packet[0] = kProtocolVersion;
  const std::uint64_t pick = random->below(253);
  packet[1] = static_cast<std::uint8_t>(pick == 0 ? 0 : pick + 3);  // 0x00 or 0x04..0xFF
  for (std::size_t i = 0; i < 2; ++i) packet[2 + i] = static_cast<std::uint8_t>(sequence >> (8 * i));
  for (std::size_t i = 0; i < 8; ++i) packet[4 + i] = static_cast<std::uint8_t>(timestamp_us >> (8 * i));
  for (std::size_t i = kPacketHeaderBytes; i < size - kPacketCrcBytes; ++i)
    packet[i] = static_cast<std::uint8_t>(random->next());
  const std::uint32_t crc = crc32c(packet, size - kPacketCrcBytes);
  for (std::size_t i = 0; i < kPacketCrcBytes; ++i)
    packet[size - kPacketCrcBytes + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  std::size_t encoded = 0;
  (void)cobs_encode(Span<const std::uint8_t>(packet, size), Span<std::uint8_t>(frame, kMaxFrameBytes - 1), &encoded);
  frame[encoded] = 0;
  return encoded + 1;
}

/// A seeded stream from one device: every frame, whatever its type (unknown ones included),
/// takes the stream's next sequence number (starting near 65535, so it wraps) and a later
/// timestamp. At most 65536 frames, so that a sequence number names one frame.
inline void make_stream(std::uint64_t seed, const StreamShape& shape, SentStream* out) {
  *out = SentStream();
  if (shape.frames > 65536) return;  // every caller's checks then fail loudly
  Random random(seed);
  std::uint16_t sequence = static_cast<std::uint16_t>(65535 - random.below(400));
  out->first_sequence = sequence;
  std::uint64_t time_us = random.below(1ULL << 40);
  std::uint8_t frame[kMaxFrameBytes];
  for (std::size_t f = 0; f < shape.frames; ++f) {
    std::size_t size = 0;
    const std::uint16_t seq = sequence++;
    time_us += 1 + random.below(200000);
    if (f > 0 && random.uniform01() < shape.unknown_chance) {
      out->library_allocations += count_allocations([&] { size = make_unknown_frame(&random, seq, time_us, frame); });
      append_frame(frame, size, kUnknownTypeMarker, 0, out);
      ++out->unknown_frames;
    } else {
      const std::uint64_t pick = random.below(10);
      const int t = pick < 6 ? 0 : pick < 9 ? 1 : 2;
      Status status = Status::ok;
      if (t == 0) {
        out->joint_states.push_back(random_joint_state(&random, seq, time_us));
        out->library_allocations +=
            count_allocations([&] { status = encode_joint_state(out->joint_states.back(), frame, &size); });
        append_frame(frame, size, 1, out->joint_states.size() - 1, out);
      } else if (t == 1) {
        out->tracker_points.push_back(random_tracker_point(&random, seq, time_us));
        out->library_allocations +=
            count_allocations([&] { status = encode_tracker_point(out->tracker_points.back(), frame, &size); });
        append_frame(frame, size, 2, out->tracker_points.size() - 1, out);
      } else {
        out->device_infos.push_back(random_device_info(&random, seq, time_us));
        out->library_allocations +=
            count_allocations([&] { status = encode_device_info(out->device_infos.back(), frame, &size); });
        append_frame(frame, size, 3, out->device_infos.size() - 1, out);
      }
      if (status != Status::ok) out->bytes.clear();  // makes every caller's checks fail loudly
    }
    if (random.uniform01() < shape.idle_chance)
      out->bytes.insert(out->bytes.end(), 1 + static_cast<std::size_t>(random.below(3)), 0);
    if (random.uniform01() < shape.garbage_chance) {
      const std::uint64_t length = 1 + random.below(300);
      std::size_t run = 0;
      for (std::uint64_t i = 0; i <= length; ++i) {
        const auto byte = i == length ? std::uint8_t{0} : static_cast<std::uint8_t>(random.next());
        out->bytes.push_back(byte);
        if (byte != 0) {
          ++run;
        } else {
          out->garbage_fragments += run != 0 ? 1 : 0;
          run = 0;
        }
      }
    }
  }
}

/// Channel errors applied to a stream.
struct Corrupted {
  std::vector<std::uint8_t> bytes;  ///< what the reader receives
  std::vector<char> frame_touched;  ///< per SentStream::frames: an error hit it or its leading delimiter
  std::size_t errors = 0;           ///< bit flips + drops + insertions
};

/// round(rate * size) errors at uniform positions, each a bit flip, a dropped byte or an inserted random byte.
inline void corrupt(const SentStream& sent, double byte_error_rate, Random* random, Corrupted* out) {
  const std::size_t n = sent.bytes.size();
  std::vector<std::size_t> positions(static_cast<std::size_t>(byte_error_rate * static_cast<double>(n) + 0.5));
  for (std::size_t& p : positions) p = static_cast<std::size_t>(random->below(n));
  std::sort(positions.begin(), positions.end());
  out->errors = positions.size();
  // Which frame owns each byte, so that an error can be charged to the frame it damages.
  std::vector<std::size_t> owner(n + 1, SIZE_MAX);
  for (std::size_t f = 0; f < sent.frames.size(); ++f)
    for (std::size_t i = sent.frames[f].begin; i < sent.frames[f].end; ++i) owner[i] = f;
  out->frame_touched.assign(sent.frames.size(), 0);
  out->bytes.clear();
  out->bytes.reserve(n + positions.size());
  std::size_t next_error = 0;
  for (std::size_t i = 0; i < n; ++i) {
    std::uint8_t byte = sent.bytes[i];
    bool keep = true;
    for (; next_error < positions.size() && positions[next_error] == i; ++next_error) {
      if (owner[i] != SIZE_MAX) out->frame_touched[owner[i]] = 1;
      if (owner[i + 1] != SIZE_MAX && sent.frames[owner[i + 1]].begin == i + 1) out->frame_touched[owner[i + 1]] = 1;
      switch (random->below(3)) {
        case 0: byte = static_cast<std::uint8_t>(byte ^ (1u << random->below(8))); break;
        case 1: keep = false; break;
        default: out->bytes.push_back(static_cast<std::uint8_t>(random->next())); break;
      }
    }
    if (keep) out->bytes.push_back(byte);
  }
}

/// Feeds `stream` in chunks of 1..max_chunk bytes (sizes from `chunk_seed`); max_chunk 0 = all at once.
inline void feed_chunked(const std::vector<std::uint8_t>& stream, std::size_t max_chunk, std::uint64_t chunk_seed,
                         StreamDecoder* decoder, FrameHandler& handler) {
  Random random(chunk_seed);
  std::size_t at = 0;
  while (at < stream.size()) {
    std::size_t chunk = max_chunk == 0 ? stream.size() : 1 + static_cast<std::size_t>(random.below(max_chunk));
    if (chunk > stream.size() - at) chunk = stream.size() - at;
    EXPECT_NO_HEAP(decoder->feed(stream.data() + at, chunk, handler));
    at += chunk;
  }
}

}  // namespace hivecal::test
