// A simulated capture pair as the devices put it on the wire, for the tests of the capture
// passes: the session's records and their framed bytes (DEVICE_INFO first). Hosted tests only
// (std::vector; encoded under the allocation trap).
#pragma once

#include <cstdint>
#include <vector>

#include "hivecal/wire/codec.hpp"
#include "sim/sim_model.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/sim_feed.hpp"

namespace hivecal::test {

/// Framed wire bytes.
using Bytes = std::vector<std::uint8_t>;

/// One record framed and appended to *out (the encoder checked, and without heap).
template <typename Record>
void append_frame(const Record& record, Status (*encoder)(const Record&, Span<std::uint8_t>, std::size_t*),
                  Bytes* out) {
  std::uint8_t frame[kMaxFrameBytes];
  std::size_t size = 0;
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = encoder(record, Span<std::uint8_t>(frame, sizeof frame), &size));
  EXPECT_EQ(status, Status::ok);
  out->insert(out->end(), frame, frame + size);
}

/// A session's two streams, as records and as wire bytes.
struct SimCapture {
  std::vector<JointStateRecord> joints;    ///< every joint state, in order
  std::vector<TrackerPointRecord> points;  ///< every tracker point, in order
  Bytes robot_bytes;                       ///< DEVICE_INFO, then every joint state, framed
  Bytes tracker_bytes;                     ///< DEVICE_INFO, then every tracker point, framed
};

/// 6 waypoints in 40 s, large geometry errors (the 1 mm tool the clock tests use).
inline const sim::Session& capture_session() {
  static const sim::Session s(large_error_config(25, 6, 40.0));
  return s;
}

/// capture_session()'s streams, built once.
inline const SimCapture& sim_capture() {
  static const SimCapture c = [] {
    SimCapture built;
    sim::RobotStream robot(capture_session());
    append_frame(robot.device_info(), encode_device_info, &built.robot_bytes);
    for (JointStateRecord joint; robot.next(&joint);) {
      built.joints.push_back(joint);
      append_frame(joint, encode_joint_state, &built.robot_bytes);
    }
    sim::TrackerStream tracker(capture_session());
    append_frame(tracker.device_info(), encode_device_info, &built.tracker_bytes);
    for (TrackerPointRecord point; tracker.next(&point);) {
      built.points.push_back(point);
      append_frame(point, encode_tracker_point, &built.tracker_bytes);
    }
    return built;
  }();
  return c;
}

}  // namespace hivecal::test
