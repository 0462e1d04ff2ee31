// Packet layouts are written once per type (Wire<Record>::payload) and run both ways: a
// PacketWriter serialises a record, a PacketReader fills one. Both move byte by byte,
// little-endian, and refuse to step outside their buffer, so encode and decode cannot
// disagree on a layout and no read goes past the packet.
#include "hivecal/wire/codec.hpp"

#include <cstring>

#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {

static_assert(sizeof(DeviceInfoRecord::name) == kDeviceNameBytes + 1, "name holds 24 chars + NUL");
static_assert(kMaxSpecFrameBytes == 138, "JOINT_STATE: 136-byte packet + COBS code byte + delimiter");
static_assert(kMaxJoints <= 255, "JOINT_STATE version 2 counts its joints in one byte");

/// Whether the target stores integers as the wire does (little-endian): then a field is one copy
/// of its bytes, not a shift per byte.
constexpr bool kWireOrderIsNative =
#if defined(__BYTE_ORDER__) && defined(__ORDER_LITTLE_ENDIAN__)
    __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;
#else
    false;
#endif

/// Little-endian unsigned integer of `bytes` (<= 8) bytes at `data`.
std::uint64_t load_le(const std::uint8_t* data, std::size_t bytes) {
  std::uint64_t value = 0;
  if constexpr (kWireOrderIsNative) {
    std::memcpy(&value, data, bytes);  // the low `bytes` bytes of the value, as on the wire
    return value;
  }
  for (std::size_t i = 0; i < bytes; ++i) value |= static_cast<std::uint64_t>(data[i]) << (8u * i);
  return value;
}

/// DEVICE_INFO names are printable ASCII: no control bytes can reach a log or terminal.
bool is_name_char(std::uint8_t c) {
  return c >= 0x20 && c <= 0x7E;
}

/// Serialises fields in order; ok() turns false instead of writing past the buffer.
class PacketWriter {
 public:
  PacketWriter(std::uint8_t* packet, std::size_t capacity) : packet_(packet), capacity_(capacity) {}

  void u8(std::uint8_t value) { put(value, 1); }
  /// A count in one byte (JOINT_STATE version 2's joints); ok() turns false beyond 255.
  void count8(const int& value) {
    if (value < 0 || value > 255) ok_ = false;
    put(static_cast<std::uint64_t>(value), 1);
  }
  void u16(std::uint16_t value) { put(value, 2); }
  void u32(std::uint32_t value) { put(value, 4); }
  void u64(std::uint64_t value) { put(value, 8); }
  void f32(float value) {
    std::uint32_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);  // bit copy: NaN payloads survive
    put(bits, 4);
  }
  void f64(double value) { put(math::bits_of(value), 8); }
  void zeros(std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) put(0, 1);
  }
  /// Name padded with 0x00; rejects an unterminated or non-printable name.
  void name(const char (&text)[kDeviceNameBytes + 1]) {
    std::size_t length = 0;
    while (length < kDeviceNameBytes && text[length] != '\0') ++length;
    if (text[length] != '\0') ok_ = false;
    for (std::size_t i = 0; i < kDeviceNameBytes; ++i) {
      const auto c = static_cast<std::uint8_t>(i < length ? text[i] : '\0');
      if (i < length && !is_name_char(c)) ok_ = false;
      put(c, 1);
    }
  }

  void refuse() { ok_ = false; }              ///< a field's value cannot be written
  bool ok() const { return ok_; }             ///< every field fitted and was valid
  std::size_t size() const { return size_; }  ///< bytes written [bytes]

 private:
  void put(std::uint64_t value, std::size_t bytes) {
    if (bytes > capacity_ - size_) {
      ok_ = false;
      return;
    }
    if constexpr (kWireOrderIsNative) {
      std::memcpy(packet_ + size_, &value, bytes);  // the low `bytes` bytes, as the wire wants them
      size_ += bytes;
      return;
    }
    for (std::size_t i = 0; i < bytes; ++i) packet_[size_++] = static_cast<std::uint8_t>(value >> (8u * i));
  }

  std::uint8_t* packet_;
  std::size_t capacity_;
  std::size_t size_ = 0;
  bool ok_ = true;
};

/// Parses fields in order; never reads past `size` bytes (in_bounds() turns false and
/// fields read as 0), and well_formed() turns false on non-zero padding or a bad name.
class PacketReader {
 public:
  PacketReader(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}

  void u8(std::uint8_t& value) { value = static_cast<std::uint8_t>(get(1)); }
  void count8(int& value) { value = static_cast<int>(get(1)); }
  void u16(std::uint16_t& value) { value = static_cast<std::uint16_t>(get(2)); }
  void u64(std::uint64_t& value) { value = get(8); }
  void f32(float& value) {
    const auto bits = static_cast<std::uint32_t>(get(4));
    std::memcpy(&value, &bits, sizeof value);
  }
  void f64(double& value) { value = math::from_bits(get(8)); }
  void zeros(std::size_t count) {
    for (std::size_t i = 0; i < count; ++i)
      if (get(1) != 0) well_formed_ = false;
  }
  /// Printable ASCII, then only 0x00 up to the field's end; always NUL-terminated.
  void name(char (&text)[kDeviceNameBytes + 1]) {
    bool ended = false;
    for (std::size_t i = 0; i < kDeviceNameBytes; ++i) {
      const auto c = static_cast<std::uint8_t>(get(1));
      ended = ended || c == 0;
      if (c != 0 && (ended || !is_name_char(c))) well_formed_ = false;
      text[i] = ended ? '\0' : static_cast<char>(c);
    }
    text[kDeviceNameBytes] = '\0';
  }

  void refuse() { well_formed_ = false; }            ///< a field's value is not one the layout allows
  bool in_bounds() const { return in_bounds_; }      ///< no field ran past the end
  bool well_formed() const { return well_formed_; }  ///< padding and name as specified

 private:
  std::uint64_t get(std::size_t bytes) {
    if (bytes > size_ - at_) {
      in_bounds_ = false;
      return 0;
    }
    const std::uint64_t value = load_le(data_ + at_, bytes);
    at_ += bytes;
    return value;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
  bool in_bounds_ = true;
  bool well_formed_ = true;
};

/// Sequence and timestamp (packet offsets 2..11); version and type are handled by the caller.
template <typename Io, typename Record>
void transfer_header(Io& io, Record& record) {
  io.u16(record.sequence);
  io.u64(record.timestamp_us);
}

/// The header fields every version-1 packet has, whatever its type.
struct PacketHeader {
  std::uint16_t sequence = 0;      ///< sequence number of the stream
  std::uint64_t timestamp_us = 0;  ///< sender's clock [us]
};

/// Per packet layout: its record, version and type bytes, payload size, payload layout, counter
/// and handler callback. The layouts are the record types, but for the two of JointStateRecord.
template <typename Layout>
struct Wire;

/// The constants of a Wire<Layout>; each specialisation adds its payload layout and size.
template <typename RecordType, PacketType Type, std::uint64_t DecoderStats::*Counter,
          void (FrameHandler::*Callback)(const RecordType&), std::uint8_t Version = kProtocolVersion>
struct WireTraits {
  using Record = RecordType;
  static constexpr std::uint8_t kVersion = Version;
  static constexpr PacketType kType = Type;
  static constexpr std::uint64_t DecoderStats::*kCounter = Counter;
  static void notify(FrameHandler& handler, const Record& record) { (handler.*Callback)(record); }
};

// GCC: no constant-propagated clones of it either (each one a copy in flash); clang has no
// such attribute and makes none here.
#if defined(__clang__)
#define HIVECAL_NOINLINE_NOCLONE [[gnu::noinline]]
#else
#define HIVECAL_NOINLINE_NOCLONE [[gnu::noinline, gnu::noclone]]
#endif

/// The joints' values of a joint record: positions, then velocities, then currents. One copy,
/// its loops over the joints not unrolled (a field's bytes are), serves both versions' layouts
/// (the firmware's flash).
template <typename Io, typename Record>
HIVECAL_NOINLINE_NOCLONE void joint_values(Io& io, Record& record, int joints) {
#pragma GCC unroll 1
  for (int j = 0; j < joints; ++j) io.f64(record.q_rad[j]);
#pragma GCC unroll 1
  for (int j = 0; j < joints; ++j) io.f64(record.qd_rad_s[j]);
#pragma GCC unroll 1
  for (int j = 0; j < joints; ++j) io.f32(record.current_a[j]);
}

/// JOINT_STATE version 1: six joints, no count (the spec's layout).
struct SixJointState;
template <>
struct Wire<SixJointState> : WireTraits<JointStateRecord, PacketType::joint_state, &DecoderStats::joint_states,
                                        &FrameHandler::on_joint_state> {
  static constexpr std::size_t payload_bytes(const JointStateRecord&) { return kJointStatePayloadBytes; }
  static constexpr std::size_t payload_bytes(const std::uint8_t*) { return kJointStatePayloadBytes; }
  template <typename Io, typename Record>
  static void payload(Io& io, Record& record) {
    record.joint_count = kSixJoints;
    joint_values(io, record, kSixJoints);
  }
};

/// JOINT_STATE version 2: the joint count (one byte, 3 zero bytes), then as many joints' values.
struct CountedJointState;
template <>
struct Wire<CountedJointState> : WireTraits<JointStateRecord, PacketType::joint_state, &DecoderStats::joint_states,
                                            &FrameHandler::on_joint_state, kCountedJointsVersion> {
  static constexpr std::size_t payload_bytes(const JointStateRecord& record) {
    return counted_joint_state_payload_bytes(record.joint_count);
  }
  /// The size the count byte of a received payload announces.
  static constexpr std::size_t payload_bytes(const std::uint8_t* payload) {
    return counted_joint_state_payload_bytes(payload[0]);
  }
  template <typename Io, typename Record>
  static void payload(Io& io, Record& record) {
    io.count8(record.joint_count);
    io.zeros(3);
    if (record.joint_count < 1 || record.joint_count > kMaxJoints) {  // more than the record holds: not read
      io.refuse();
      return;
    }
    joint_values(io, record, record.joint_count);
  }
};

template <>
struct Wire<TrackerPointRecord> : WireTraits<TrackerPointRecord, PacketType::tracker_point,
                                             &DecoderStats::tracker_points, &FrameHandler::on_tracker_point> {
  static constexpr std::size_t payload_bytes(const TrackerPointRecord&) { return kTrackerPointPayloadBytes; }
  static constexpr std::size_t payload_bytes(const std::uint8_t*) { return kTrackerPointPayloadBytes; }
  template <typename Io, typename Record>
  static void payload(Io& io, Record& record) {
    for (auto& coordinate : record.point_m) io.f64(coordinate);
    io.u8(record.status);
    io.zeros(3);
  }
};

template <>
struct Wire<DeviceInfoRecord> : WireTraits<DeviceInfoRecord, PacketType::device_info, &DecoderStats::device_infos,
                                           &FrameHandler::on_device_info> {
  static constexpr std::size_t payload_bytes(const DeviceInfoRecord&) { return kDeviceInfoPayloadBytes; }
  static constexpr std::size_t payload_bytes(const std::uint8_t*) { return kDeviceInfoPayloadBytes; }
  template <typename Io, typename Record>
  static void payload(Io& io, Record& record) {
    io.u8(record.device_kind);
    io.zeros(3);
    io.f32(record.nominal_rate_hz);
    io.name(record.name);
  }
};

template <typename Layout, typename Payload>
constexpr std::size_t packet_bytes_of(const Payload& payload) {
  return kPacketHeaderBytes + Wire<Layout>::payload_bytes(payload) + kPacketCrcBytes;
}

template <typename Layout>
Status encode_record(const typename Wire<Layout>::Record& record, Span<std::uint8_t> out, std::size_t* written) {
  if (written == nullptr) return Status::invalid_argument;
  *written = 0;
  const std::size_t packet_bytes = packet_bytes_of<Layout>(record);
  std::uint8_t packet[kMaxPacketBytes];
  PacketWriter writer(packet, packet_bytes <= kMaxPacketBytes ? packet_bytes : 0);
  writer.u8(Wire<Layout>::kVersion);
  writer.u8(static_cast<std::uint8_t>(Wire<Layout>::kType));
  transfer_header(writer, record);
  typename Wire<Layout>::Record copy = record;  // the layouts run both ways on a writable record
  Wire<Layout>::payload(writer, copy);
  writer.u32(crc32c(packet, writer.size()));
  if (!writer.ok() || writer.size() != packet_bytes) return Status::invalid_argument;
  if (out.size() < cobs_max_encoded_bytes(packet_bytes) + 1) return Status::buffer_too_small;
  std::size_t encoded = 0;
  const Status status = cobs_encode(Span<const std::uint8_t>(packet, packet_bytes), out, &encoded);
  if (status != Status::ok) return status;
  out[encoded] = 0;  // the delimiter; the size check above left room for it
  *written = encoded + 1;
  return Status::ok;
}

/// Forward jumps of half the sequence space or more are read as a restart, not as loss.
constexpr std::uint16_t kRestartJump = 0x8000;

/// Failures that a frame cut at the start of a capture produces by itself.
bool is_truncation_symptom(Status status) {
  return status == Status::cobs_error || status == Status::bad_crc || status == Status::bad_length ||
         status == Status::frame_too_long;
}

}  // namespace

Status encode_joint_state(const JointStateRecord& record, Span<std::uint8_t> out, std::size_t* written) {
  if (record.joint_count < 1 || record.joint_count > kMaxJoints) {
    if (written != nullptr) *written = 0;
    return Status::invalid_argument;
  }
  return record.joint_count == kSixJoints ? encode_record<SixJointState>(record, out, written)
                                          : encode_record<CountedJointState>(record, out, written);
}

Status encode_tracker_point(const TrackerPointRecord& record, Span<std::uint8_t> out, std::size_t* written) {
  return encode_record<TrackerPointRecord>(record, out, written);
}

Status encode_device_info(const DeviceInfoRecord& record, Span<std::uint8_t> out, std::size_t* written) {
  return encode_record<DeviceInfoRecord>(record, out, written);
}

void StreamDecoder::reset() {
  *this = StreamDecoder();
}

void StreamDecoder::feed(const std::uint8_t* bytes, std::size_t count, FrameHandler& handler) {
  if (bytes == nullptr) return;
  stats_.bytes_total += count;
  const std::uint8_t* const end = bytes + count;
  // memchr finds delimiters a word at a time; the bytes between are copied in one go.
  while (bytes != end) {
    const void* zero = std::memchr(bytes, 0, static_cast<std::size_t>(end - bytes));
    const std::uint8_t* stop = zero != nullptr ? static_cast<const std::uint8_t*>(zero) : end;
    take_frame_bytes(bytes, static_cast<std::size_t>(stop - bytes));
    if (stop == end) break;
    close_frame(handler);
    bytes = stop + 1;
  }
  stats_.bytes_pending = frame_bytes_;
}

bool StreamDecoder::oversized() const {
  // Frame bytes 1 and 2 are the packet's version and type (after the COBS code byte; neither is
  // 0): only a version-2 JOINT_STATE may be longer than the spec's frames, so a stream of those
  // is judged as it always was.
  const bool counted_joints = frame_bytes_ >= 3 && frame_[1] == kCountedJointsVersion &&
                              frame_[2] == static_cast<std::uint8_t>(PacketType::joint_state);
  return frame_bytes_ > (counted_joints ? sizeof frame_ : kMaxSpecFrameBytes - 1);
}

void StreamDecoder::take_frame_bytes(const std::uint8_t* bytes, std::size_t count) {
  if (discarding_) {
    stats_.bytes_discarded += count;
    return;
  }
  if (count <= sizeof frame_ - frame_bytes_) {
    if (count != 0) std::memcpy(frame_ + frame_bytes_, bytes, count);
    frame_bytes_ += count;
    if (!oversized()) return;
    count = 0;  // the bytes are all in the frame, which is too long for its type
  }
  // Longer than any valid frame: drop what we have and everything up to the next delimiter.
  count_rejection(Status::frame_too_long);
  stats_.bytes_discarded += frame_bytes_ + count;
  frame_bytes_ = 0;
  discarding_ = true;
}

void StreamDecoder::close_frame(FrameHandler& handler) {
  if (discarding_) {
    ++stats_.bytes_discarded;  // the oversized frame's delimiter
    discarding_ = false;
  } else if (frame_bytes_ == 0) {
    ++stats_.bytes_idle;
  } else {
    const Status status = decode_frame(handler);
    if (status != Status::ok) {
      stats_.bytes_discarded += frame_bytes_ + 1;
      count_rejection(status);
    }
    frame_bytes_ = 0;
  }
  synchronised_ = true;
}

Status StreamDecoder::decode_frame(FrameHandler& handler) {
  std::size_t packet_bytes = 0;
  // In place: the packet is never longer than its encoding (cobs_decode contract).
  if (cobs_decode(Span<const std::uint8_t>(frame_, frame_bytes_), Span<std::uint8_t>(frame_, frame_bytes_),
                  &packet_bytes) != Status::ok)
    return Status::cobs_error;
  const std::uint8_t* const packet = frame_;
  if (packet_bytes < kPacketHeaderBytes + kPacketCrcBytes) return Status::bad_length;
  // CRC first: a frame damaged in transit is a CRC failure whatever byte was hit, so
  // bad_version / bad_length / unknown_type only ever count intact packets.
  const std::size_t covered_bytes = packet_bytes - kPacketCrcBytes;
  if (crc32c(packet, covered_bytes) != load_le(packet + covered_bytes, kPacketCrcBytes)) return Status::bad_crc;
  if (packet[0] != kProtocolVersion && packet[0] != kCountedJointsVersion) return Status::bad_version;
  // Intact version-1 or 2 header: this packet was sent and took the stream's next sequence
  // number, whether it is then delivered or rejected for its type, length or payload.
  PacketHeader header;
  PacketReader header_reader(packet + 2, covered_bytes - 2);  // after version and type
  transfer_header(header_reader, header);
  track_sequence(header.sequence, header.timestamp_us);
  if (packet[0] == kCountedJointsVersion) {  // version 2 defines the counted JOINT_STATE only
    return static_cast<PacketType>(packet[1]) == PacketType::joint_state
               ? deliver<CountedJointState>(packet, packet_bytes, handler)
               : Status::unknown_type;
  }
  switch (static_cast<PacketType>(packet[1])) {
    case PacketType::joint_state: return deliver<SixJointState>(packet, packet_bytes, handler);
    case PacketType::tracker_point: return deliver<TrackerPointRecord>(packet, packet_bytes, handler);
    case PacketType::device_info: return deliver<DeviceInfoRecord>(packet, packet_bytes, handler);
  }
  return Status::unknown_type;
}

template <typename Layout>
Status StreamDecoder::deliver(const std::uint8_t* packet, std::size_t packet_bytes, FrameHandler& handler) {
  const std::uint8_t* payload = packet + kPacketHeaderBytes;  // one byte at least: the CRC follows the header
  if (packet_bytes != packet_bytes_of<Layout>(payload)) return Status::bad_length;
  typename Wire<Layout>::Record record;
  PacketReader reader(packet + 2, packet_bytes - 2 - kPacketCrcBytes);  // after version and type
  transfer_header(reader, record);
  Wire<Layout>::payload(reader, record);
  if (!reader.in_bounds()) return Status::bad_length;
  if (!reader.well_formed()) return Status::bad_payload;
  ++stats_.frames_ok;
  ++(stats_.*Wire<Layout>::kCounter);
  stats_.bytes_accepted += frame_bytes_ + 1;  // counted before the callback so it sees final stats
  Wire<Layout>::notify(handler, record);
  return Status::ok;
}

void StreamDecoder::track_sequence(std::uint16_t sequence, std::uint64_t timestamp_us) {
  SequenceState& last = sequence_;  // the one counter of the stream, whatever the packet type
  if (last.seen) {
    const auto expected = static_cast<std::uint16_t>(last.sequence + 1u);  // 65535 + 1 -> 0: no gap
    const auto skipped = static_cast<std::uint16_t>(sequence - expected);  // modulo 2^16
    if (timestamp_us < last.timestamp_us || skipped >= kRestartJump) {
      ++stats_.sequence_resets;
    } else if (skipped != 0) {
      ++stats_.sequence_gaps;
      stats_.packets_lost += skipped;
    }
  }
  last = SequenceState{timestamp_us, sequence, true};
}

void StreamDecoder::count_rejection(Status status) {
  if (!synchronised_ && is_truncation_symptom(status)) {
    ++stats_.leading_fragments;  // the capture began inside a frame: expected, not an error
    return;
  }
  switch (status) {
    case Status::bad_crc: ++stats_.crc_failures; break;
    case Status::bad_length: ++stats_.bad_lengths; break;
    case Status::bad_version: ++stats_.bad_versions; break;
    case Status::unknown_type: ++stats_.unknown_types; break;
    case Status::bad_payload: ++stats_.bad_payloads; break;
    case Status::cobs_error: ++stats_.cobs_errors; break;
    case Status::frame_too_long: ++stats_.oversized_frames; break;
    default: break;  // decode_frame returns no other failure
  }
}

}  // namespace hivecal
