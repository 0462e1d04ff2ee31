// A client of Universal Robots' Real-Time Data Exchange (RTDE, TCP port 30004, protocol
// version 2; docs/streams.md "Live UR link"). Every package is `uint16 size (header included),
// uint8 type, payload`, big-endian:
//   V (86) request protocol version: uint16 version -> uint8 accepted
//   v (118) get URControl version -> 4 x uint32 (major, minor, bugfix, build)
//   O (79) setup outputs: double frequency [Hz], names "a,b,..." -> uint8 recipe id, types
//          "DOUBLE,VECTOR6D,..." ("NOT_FOUND" for an unknown variable)
//   S (83) start -> uint8 accepted;  P (80) pause -> uint8 accepted
//   U (85) data: uint8 recipe id, the values in recipe order
//   M (77) text message: uint8 length, message, uint8 length, source, uint8 warning level
// Bytes and numbers only: no kinematics here (port/ knows nothing of the math).
#pragma once

#include <csignal>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hivecal/port/error.hpp"

namespace hivecal::port {

/// Package types of the protocol.
enum class RtdePackage : std::uint8_t {
  protocol_version = 86,     ///< 'V'
  controller_version = 118,  ///< 'v'
  text_message = 77,         ///< 'M'
  data = 85,                 ///< 'U'
  setup_outputs = 79,        ///< 'O'
  start = 83,                ///< 'S'
  pause = 80,                ///< 'P'
};

/// What a recording received.
struct RtdeStats {
  std::uint32_t controller_version[4] = {};  ///< major, minor, bugfix, build
  std::uint64_t data_packages = 0;           ///< data packages received [-]
  std::uint64_t rows_written = 0;            ///< log rows handed to the writer [-]
  std::uint64_t text_messages = 0;           ///< text messages received (each also passed to on_text) [-]
  bool ended_by_controller = false;          ///< the controller closed the connection
};

/// How to record.
struct RtdeRecordOptions {
  double frequency_hz = 125.0;    ///< requested output rate (CB-series: 125, e-Series: up to 500) [Hz]
  double duration_s = 0.0;        ///< stop after this long [s]; 0: until stopped or closed
  int connect_timeout_ms = 5000;  ///< a host that never answers fails after this [ms]
  int reply_timeout_ms = 5000;    ///< each setup reply must come within this [ms]
  std::function<void(const std::string&)> on_text;  ///< controller text messages (optional)
};

/// The variables recorded, in order, and the log's header (the RTDE recorder's, space-separated).
const std::vector<std::string>& rtde_recorded_variables();
std::string rtde_log_header();

/// The default RTDE port.
inline constexpr int kRtdePort = 30004;

/// Reads --rtde's value: HOST, HOST:PORT, an IPv6 address (`::1`, bare: no port) or
/// [IPv6]:PORT; *port is kRtdePort when none is given. Fault::usage naming the forms otherwise.
Error parse_rtde_address(const std::string& text, std::string* host, int* port);

/// Connects to `host`:`port`, negotiates protocol version 2, reads the controller version,
/// sets up the recipe `timestamp,actual_q,actual_TCP_pose` at `frequency_hz`, starts, and
/// hands one log row per data package to `write_row` (text ending in '\n', the header first)
/// until *stop is set, `duration_s` passes (counted from the call: the connection and the
/// setup take part of it) or the controller closes; then pauses. Each setup reply is due
/// `reply_timeout_ms` after its request (text messages meanwhile do not extend it); a package
/// the network delivers in parts is put together whatever the pauses between them, unless it
/// stays unfinished for `reply_timeout_ms`. Errors: input (no answer, refused version, a
/// variable the controller does not know, a malformed or stalled package, no data package
/// for `reply_timeout_ms`, traffic beyond twice `frequency_hz` after a burst of 1000
/// packages, a row with a value that is not finite or a timestamp before the previous one:
/// the rows before it are kept), output (write_row's).
Error record_rtde(const std::string& host, int port, const RtdeRecordOptions& options,
                  const volatile std::sig_atomic_t* stop, const std::function<Error(const std::string&)>& write_row,
                  RtdeStats* stats);

}  // namespace hivecal::port
