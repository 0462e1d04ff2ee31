#include "sim/sim_server.hpp"

#include <vector>

#include "hivecal/port/byte_source.hpp"
#include "sim/sim_outputs.hpp"

namespace hivecal::sim {
namespace {

/// Sleeps until session time t_s is due at `speed` (nothing when speed is 0) or a stop is
/// requested.
void wait_until_due(double t_s, double speed, std::int64_t start_ms, const std::atomic<bool>* stop) {
  if (speed <= 0.0) return;
  const auto due_ms = start_ms + static_cast<std::int64_t>(t_s / speed * 1000.0);
  if (stop == nullptr) {
    port::sleep_ms(due_ms - port::monotonic_ms());
  } else {
    (void)port::sleep_ms(due_ms - port::monotonic_ms(), *stop);
  }
}

/// Writes one frame; false on failure (*error says it) or on a stop request (*error empty).
bool send(int fd, const std::vector<std::uint8_t>& frame, const std::atomic<bool>* stop, std::uint64_t* bytes,
          std::uint64_t* frames, std::string* error, const char* what) {
  if (!port::write_all(fd, frame.data(), frame.size(), stop)) {
    if (stop == nullptr || !stop->load()) *error = std::string("cannot write to the ") + what + " pty";
    return false;
  }
  *bytes += frame.size();
  ++*frames;
  return true;
}

bool serve_frames(const Session& session, const port::PtyPair& robot, const port::PtyPair& tracker,
                  const ServeOptions& options, const std::atomic<bool>* stop, ServeStats* stats, std::string* error) {
  RobotStream robot_stream(session);
  TrackerStream tracker_stream(session);
  std::vector<std::uint8_t> frame;
  const std::int64_t start_ms = port::monotonic_ms();
  bool ok = append_frame(robot_stream.device_info(), &frame) &&
            send(robot.master_fd, frame, stop, &stats->robot_bytes, &stats->robot_frames, error, "robot");
  frame.clear();
  ok = ok && append_frame(tracker_stream.device_info(), &frame) &&
       send(tracker.master_fd, frame, stop, &stats->tracker_bytes, &stats->tracker_frames, error, "tracker");
  JointStateRecord joint;
  TrackerPointRecord point;
  bool has_joint = robot_stream.next(&joint);
  bool has_point = tracker_stream.next(&point);
  while (ok && (has_joint || has_point) && !(stop != nullptr && stop->load())) {
    frame.clear();
    if (has_point && (!has_joint || tracker_stream.last_true_time_s() < robot_stream.last_true_time_s())) {
      wait_until_due(tracker_stream.last_true_time_s(), options.speed, start_ms, stop);
      ok = append_frame(point, &frame) &&
           send(tracker.master_fd, frame, stop, &stats->tracker_bytes, &stats->tracker_frames, error, "tracker");
      has_point = tracker_stream.next(&point);
    } else {
      wait_until_due(robot_stream.last_true_time_s(), options.speed, start_ms, stop);
      ok = append_frame(joint, &frame) &&
           send(robot.master_fd, frame, stop, &stats->robot_bytes, &stats->robot_frames, error, "robot");
      has_joint = robot_stream.next(&joint);
    }
  }
  return ok;
}

}  // namespace

port::Error serve_session(const Session& session, const port::PtyPair& robot, const port::PtyPair& tracker,
                          const ServeOptions& options, const std::atomic<bool>* stop, ServeStats* stats) {
  std::string error;
  if (serve_frames(session, robot, tracker, options, stop, stats, &error) || error.empty()) return port::Error{};
  return port::Error::output(error);
}

}  // namespace hivecal::sim
