// Serves a simulated session live: the robot and tracker frames are written, in true-time
// order, into the master sides of two pseudo-terminals, at real time, accelerated, or as
// fast as the readers take them. A SerialPort on the slave paths reads them like real ports.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>

#include "hivecal/port/pty.hpp"
#include "sim/sim_model.hpp"

namespace hivecal::sim {

/// The pacing a live session accepts besides 0 [session seconds per second]: slower would
/// stretch a session over years, faster is "as fast as read" (0) in all but name.
inline constexpr double kMinServeSpeed = 0.01;
inline constexpr double kMaxServeSpeed = 1e4;
/// The longest wait before streaming [s].
inline constexpr double kMaxServeDelay_s = 3600.0;

/// Pacing of a live session.
struct ServeOptions {
  double speed = 1.0;  ///< session seconds per wall-clock second; 0: no pacing (else kMinServeSpeed .. kMaxServeSpeed)
};

/// What was served.
struct ServeStats {
  std::uint64_t robot_bytes = 0;     ///< bytes written to the robot pty
  std::uint64_t tracker_bytes = 0;   ///< bytes written to the tracker pty
  std::uint64_t robot_frames = 0;    ///< frames (DEVICE_INFO included)
  std::uint64_t tracker_frames = 0;  ///< frames (DEVICE_INFO included)
};

/// Writes the whole session into the two ptys' masters (or until *stop is set).
/// Fault::output if a write fails (e.g. the pty was closed).
port::Error serve_session(const Session& session, const port::PtyPair& robot, const port::PtyPair& tracker,
                          const ServeOptions& options, const std::atomic<bool>* stop, ServeStats* stats);

}  // namespace hivecal::sim
