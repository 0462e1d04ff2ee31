#include "hivecal/port/rtde_client.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>

#include "hivecal/port/byte_source.hpp"

namespace hivecal::port {
namespace {

constexpr std::uint16_t kProtocolVersion = 2;
constexpr std::size_t kHeaderBytes = 3;
constexpr std::size_t kMaxPackageBytes = 4096;  // the controller's packages are far smaller

/// The connection; closed on destruction.
class Socket {
 public:
  ~Socket() {
    if (fd >= 0) ::close(fd);
  }
  int fd = -1;
};

/// host:port for messages, an IPv6 address in brackets.
std::string address_text(const std::string& host, int port) {
  const bool v6 = host.find(':') != std::string::npos;
  return (v6 ? "[" + host + "]" : host) + ":" + std::to_string(port);
}

Error connect_to(const std::string& host, int port, int timeout_ms, Socket* socket) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string where = quoted(address_text(host, port), 120);
  const int looked = ::getaddrinfo(host.c_str(), std::to_string(port).c_str(), &hints, &found);
  if (looked != 0) return Error::input("--rtde " + where + ": " + ::gai_strerror(looked));
  Error error = Error::input("--rtde " + where + ": no address");
  for (addrinfo* a = found; a != nullptr; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC | SOCK_NONBLOCK, a->ai_protocol);
    if (fd < 0) continue;
    int result = ::connect(fd, a->ai_addr, a->ai_addrlen);
    if (result != 0 && errno == EINPROGRESS) {
      pollfd wait{fd, POLLOUT, 0};
      result = ::poll(&wait, 1, timeout_ms);
      int problem = 0;
      socklen_t size = sizeof problem;
      if (result == 1 && ::getsockopt(fd, SOL_SOCKET, SO_ERROR, &problem, &size) == 0 && problem == 0) {
        result = 0;
      } else {
        error = Error::input(
            "--rtde " + where + ": " +
            (result == 0 ? "no answer within " + std::to_string(timeout_ms) + " ms" : system_message(problem)));
        result = -1;
      }
    } else if (result != 0) {
      error = Error::input("--rtde " + where + ": " + system_message(errno));
    }
    if (result == 0) {
      socket->fd = fd;
      ::freeaddrinfo(found);
      return Error{};
    }
    ::close(fd);
  }
  ::freeaddrinfo(found);
  return error;
}

/// Sends one package.
Error send_package(int fd, RtdePackage type, const std::vector<std::uint8_t>& payload) {
  const auto size = static_cast<std::uint16_t>(kHeaderBytes + payload.size());
  std::vector<std::uint8_t> bytes = {static_cast<std::uint8_t>(size >> 8), static_cast<std::uint8_t>(size & 0xff),
                                     static_cast<std::uint8_t>(type)};
  bytes.insert(bytes.end(), payload.begin(), payload.end());
  std::size_t done = 0;
  while (done < bytes.size()) {
    const ssize_t put = ::send(fd, bytes.data() + done, bytes.size() - done, MSG_NOSIGNAL);
    if (put < 0 && (errno == EINTR || errno == EAGAIN)) {
      pollfd wait{fd, POLLOUT, 0};
      (void)::poll(&wait, 1, 100);
      continue;
    }
    if (put <= 0) return Error::input("--rtde: send failed: " + system_message(errno));
    done += static_cast<std::size_t>(put);
  }
  return Error{};
}

/// Outcome of waiting for a package.
enum class Received { package, timeout, closed, stopped };

/// The bytes received and not yet handed out as packages. A package the network delivers in
/// parts (a retransmission pauses it mid-way for hundreds of ms) waits here for its rest: a
/// timeout between its parts loses nothing; only a package that stays unfinished for
/// `stall_ms` ends the connection.
class PackageReader {
 public:
  PackageReader(int fd, int stall_ms) : fd_(fd), stall_ms_(stall_ms) {}

  /// The next whole package into *type and *payload, waiting until `deadline_ms` (monotonic).
  Received next(std::int64_t deadline_ms, const volatile std::sig_atomic_t* stop, std::uint8_t* type,
                std::vector<std::uint8_t>* payload, Error* error) {
    for (;;) {
      if (take(type, payload, error)) return Received::package;
      if (!error->ok()) return Received::closed;
      if (stop != nullptr && *stop != 0) return Received::stopped;
      const std::int64_t now_ms = monotonic_ms();
      if (!buffer_.empty() && now_ms - started_ms_ > stall_ms_) {
        *error = Error::input("--rtde: a package stayed unfinished for " + std::to_string(stall_ms_) + " ms (" +
                              std::to_string(buffer_.size()) + " bytes of " + std::to_string(expected_size()) +
                              " came): the connection broke off");
        return Received::closed;
      }
      if (now_ms >= deadline_ms) return Received::timeout;  // what came of a package stays
      pollfd wait{fd_, POLLIN, 0};
      const int ready = ::poll(&wait, 1, static_cast<int>(std::min<std::int64_t>(deadline_ms - now_ms, 100)));
      if (ready <= 0) continue;
      std::uint8_t chunk[16384];
      const ssize_t got = ::recv(fd_, chunk, sizeof chunk, 0);
      if (got == 0) return Received::closed;
      if (got < 0) {
        if (errno == EINTR || errno == EAGAIN) continue;
        return Received::closed;
      }
      if (buffer_.empty()) started_ms_ = now_ms;
      buffer_.insert(buffer_.end(), chunk, chunk + got);
    }
  }

 private:
  /// The declared size of the package at the front (its header may be incomplete: 0).
  std::size_t expected_size() const {
    return buffer_.size() < 2 ? 0 : (static_cast<std::size_t>(buffer_[0]) << 8) | buffer_[1];
  }
  /// Hands out the package at the front when it is whole; a size no RTDE package has is an error.
  bool take(std::uint8_t* type, std::vector<std::uint8_t>* payload, Error* error) {
    if (buffer_.size() < kHeaderBytes) return false;
    const std::size_t size = expected_size();
    if (size < kHeaderBytes || size > kMaxPackageBytes) {
      *error = Error::input("--rtde: a package of " + std::to_string(size) + " bytes: not the RTDE protocol");
      return false;
    }
    if (buffer_.size() < size) return false;
    *type = buffer_[2];
    payload->assign(buffer_.begin() + kHeaderBytes, buffer_.begin() + static_cast<std::ptrdiff_t>(size));
    buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(size));
    started_ms_ = monotonic_ms();  // the next package's bytes, if any came, start now
    return true;
  }

  int fd_;
  int stall_ms_;
  std::vector<std::uint8_t> buffer_;
  std::int64_t started_ms_ = 0;
};

/// Refuses traffic far beyond what was asked for: a UR controller sends `frequency_hz` data
/// packages a second and a few text messages, so more than twice that, after a burst of
/// kBurstPackages (a backlog the network delivers at once), is not its RTDE output, and would
/// fill the disk and the terminal.
class TrafficLimit {
 public:
  explicit TrafficLimit(double frequency_hz) : frequency_hz_(frequency_hz), start_ms_(monotonic_ms()) {}
  /// Counts one package; an input error when the traffic passes the limit.
  Error count() {
    ++packages_;
    if (packages_ <= kBurstPackages) return Error{};
    const double elapsed_s = static_cast<double>(monotonic_ms() - start_ms_) * 1e-3;
    if (static_cast<double>(packages_) <= kBurstPackages + 2.0 * frequency_hz_ * elapsed_s) return Error{};
    char rate[64];
    std::snprintf(rate, sizeof rate, "%llu packages in %.3f s", static_cast<unsigned long long>(packages_), elapsed_s);
    char asked[32];
    std::snprintf(asked, sizeof asked, "%g Hz", frequency_hz_);
    return Error::input(std::string("--rtde: the controller sent ") + rate + ", far more than the " + asked +
                        " asked for (at most twice that rate after a burst of " + std::to_string(kBurstPackages) +
                        "): not a UR controller's RTDE output; refusing it");
  }

 private:
  static constexpr std::uint64_t kBurstPackages = 1000;
  double frequency_hz_;
  std::int64_t start_ms_;
  std::uint64_t packages_ = 0;
};

std::uint32_t be32(const std::uint8_t* p) {
  return (static_cast<std::uint32_t>(p[0]) << 24) | (static_cast<std::uint32_t>(p[1]) << 16) |
         (static_cast<std::uint32_t>(p[2]) << 8) | p[3];
}

double be_double(const std::uint8_t* p) {
  std::uint64_t bits = 0;
  for (int k = 0; k < 8; ++k) bits = (bits << 8) | p[k];
  double value = 0.0;
  std::memcpy(&value, &bits, sizeof value);
  return value;
}

/// A text message's words: "source: message" (warning level kept out).
std::string text_of(const std::vector<std::uint8_t>& payload) {
  if (payload.empty()) return "";
  const std::size_t message_size = payload[0];
  if (1 + message_size > payload.size()) return printable(std::string(payload.begin(), payload.end()), 200);
  const std::string message(payload.begin() + 1, payload.begin() + 1 + static_cast<std::ptrdiff_t>(message_size));
  std::string source;
  if (2 + message_size <= payload.size()) {
    const std::size_t source_size = payload[1 + message_size];
    const std::size_t at = 2 + message_size;
    if (at + source_size <= payload.size()) {
      source.assign(payload.begin() + static_cast<std::ptrdiff_t>(at),
                    payload.begin() + static_cast<std::ptrdiff_t>(at + source_size));
    }
  }
  return printable(source.empty() ? message : source + ": " + message, 300);
}

/// The connection being recorded: the socket's package reader, the traffic limit, the
/// options, the stop request and the moment after which nothing more is waited for.
struct Session {
  int fd;
  PackageReader reader;
  TrafficLimit traffic;
  const RtdeRecordOptions& options;
  const volatile std::sig_atomic_t* stop;
  std::int64_t end_ms;  ///< --duration-s passes (INT64_MAX without one)
  RtdeStats* stats;
};

/// Passes a text message on.
void pass_text(Session& session, const std::vector<std::uint8_t>& payload) {
  ++session.stats->text_messages;
  if (session.options.on_text) session.options.on_text(text_of(payload));
}

/// Sends `type` with `payload` and waits for the reply of the same type (text messages on
/// the way are passed on; they do not extend the wait: the reply is due reply_timeout_ms
/// after the request, and within --duration-s).
Error request(Session& session, RtdePackage type, const std::vector<std::uint8_t>& payload,
              std::vector<std::uint8_t>* reply) {
  Error error = send_package(session.fd, type, payload);
  if (!error.ok()) return error;
  const char name = static_cast<char>(type);
  const std::int64_t reply_due_ms = monotonic_ms() + session.options.reply_timeout_ms;
  const std::int64_t deadline_ms = std::min(reply_due_ms, session.end_ms);
  for (;;) {
    std::uint8_t got = 0;
    const Received r = session.reader.next(deadline_ms, session.stop, &got, reply, &error);
    if (error.ok() && r == Received::package) error = session.traffic.count();
    if (!error.ok()) return error;
    if (r == Received::timeout && deadline_ms < reply_due_ms) {
      return Error::input(std::string("--rtde: --duration-s passed before the controller answered '") + name + "' (" +
                          std::to_string(session.stats->text_messages) +
                          " text messages came meanwhile): nothing recorded");
    }
    if (r == Received::timeout) {
      return Error::input(std::string("--rtde: no reply to '") + name + "' within " +
                          std::to_string(session.options.reply_timeout_ms) + " ms" +
                          (session.stats->text_messages == 0
                               ? std::string()
                               : " (" + std::to_string(session.stats->text_messages) + " text messages came instead)"));
    }
    if (r == Received::closed)
      return Error::input(std::string("--rtde: the controller closed the connection after '") + name + "'");
    if (r == Received::stopped) return Error::input("--rtde: stopped during the setup");
    if (got == static_cast<std::uint8_t>(type)) return Error{};
    if (got == static_cast<std::uint8_t>(RtdePackage::text_message)) pass_text(session, *reply);
  }
}

constexpr std::size_t kValues = 13;  // timestamp + actual_q (6) + actual_TCP_pose (6)

/// The log column of value k of a data package (rtde_log_header's names).
std::string column_name(std::size_t k) {
  if (k == 0) return "timestamp";
  return (k <= 6 ? "actual_q_" : "actual_TCP_pose_") + std::to_string((k - 1) % 6);
}

/// Refuses a data package no log reader would take: a value that is not finite, or a
/// timestamp before the previous one (*last_timestamp_s, updated when the row is good).
Error check_row(const std::vector<std::uint8_t>& payload, std::uint64_t package, double* last_timestamp_s) {
  std::string problem;
  for (std::size_t k = 0; k < kValues && problem.empty(); ++k) {
    const double value = be_double(payload.data() + 1 + 8 * k);
    if (!std::isfinite(value)) problem = column_name(k) + " is " + (value != value ? "NaN" : "infinite");
  }
  const double timestamp_s = be_double(payload.data() + 1);
  char text[160];
  if (problem.empty() && timestamp_s < *last_timestamp_s) {
    std::snprintf(text, sizeof text, "timestamp %.6f s is before the previous package's %.6f s", timestamp_s,
                  *last_timestamp_s);
    problem = text;
  } else if (problem.empty() && timestamp_s < 0.0) {
    std::snprintf(text, sizeof text, "timestamp %.6f s is negative", timestamp_s);
    problem = text;
  }
  if (problem.empty()) {
    *last_timestamp_s = timestamp_s;
    return Error{};
  }
  return Error::input("--rtde: data package " + std::to_string(package) + ": " + problem +
                      "; no robot log reader takes such a row: the recording ends here (the " +
                      std::to_string(package - 1) + " rows before it are kept)");
}

std::string format_row(const std::vector<std::uint8_t>& payload) {
  std::string row;
  char number[32];
  for (std::size_t k = 0; k < kValues; ++k) {
    std::snprintf(number, sizeof number, "%.17g", be_double(payload.data() + 1 + 8 * k));
    row += (k == 0 ? "" : " ") + std::string(number);
  }
  return row + "\n";
}

}  // namespace

Error parse_rtde_address(const std::string& text, std::string* host, int* port) {
  const Error refused = Error::usage(
      "--rtde must be HOST, HOST:PORT, an IPv6 address or [IPv6]:PORT (PORT 1 .. 65535), not " + quoted(text));
  *port = kRtdePort;
  std::string port_text;
  if (!text.empty() && text[0] == '[') {  // [IPv6] or [IPv6]:PORT
    const std::size_t close = text.find(']');
    if (close == std::string::npos || (close + 1 < text.size() && text[close + 1] != ':')) return refused;
    *host = text.substr(1, close - 1);
    if (close + 1 < text.size()) port_text = text.substr(close + 2);
    if (close + 1 < text.size() && port_text.empty()) return refused;
  } else if (std::count(text.begin(), text.end(), ':') == 1) {  // HOST:PORT
    const std::size_t colon = text.find(':');
    *host = text.substr(0, colon);
    port_text = text.substr(colon + 1);
    if (port_text.empty()) return refused;
  } else {  // HOST, or an IPv6 address without a port
    *host = text;
  }
  if (!port_text.empty()) {
    if (port_text.size() > 5 || port_text.find_first_not_of("0123456789") != std::string::npos) return refused;
    *port = std::stoi(port_text);
    if (*port < 1 || *port > 65535) return refused;
  }
  if (host->empty()) return Error::usage("--rtde needs a host name or address, not " + quoted(text));
  return Error{};
}

const std::vector<std::string>& rtde_recorded_variables() {
  static const std::vector<std::string> names = {"timestamp", "actual_q", "actual_TCP_pose"};
  return names;
}

std::string rtde_log_header() {
  std::string header = "timestamp";
  for (const char* vector : {"actual_q", "actual_TCP_pose"})
    for (int k = 0; k < 6; ++k) header += " " + std::string(vector) + "_" + std::to_string(k);
  return header + "\n";
}

Error record_rtde(const std::string& host, int port, const RtdeRecordOptions& options,
                  const volatile std::sig_atomic_t* stop, const std::function<Error(const std::string&)>& write_row,
                  RtdeStats* stats) {
  *stats = RtdeStats();
  // --duration-s bounds the whole run, the connection and the setup included.
  const std::int64_t begin_ms = monotonic_ms();
  const std::int64_t end_ms = options.duration_s > 0.0
                                  ? begin_ms + static_cast<std::int64_t>(options.duration_s * 1000.0)
                                  : std::numeric_limits<std::int64_t>::max();
  Socket socket;
  const auto connect_ms = static_cast<int>(std::min<std::int64_t>(options.connect_timeout_ms, end_ms - begin_ms));
  Error error = connect_to(host, port, connect_ms, &socket);
  if (!error.ok()) return error;
  Session session{socket.fd,
                  PackageReader(socket.fd, options.reply_timeout_ms),
                  TrafficLimit(options.frequency_hz),
                  options,
                  stop,
                  end_ms,
                  stats};
  std::vector<std::uint8_t> reply;
  error = request(session, RtdePackage::protocol_version, {0, kProtocolVersion}, &reply);
  if (error.ok() && (reply.size() != 1 || reply[0] != 1)) {
    error = Error::input("--rtde: the controller refuses protocol version 2 (URControl 3.2 or later speaks it)");
  }
  if (error.ok()) error = request(session, RtdePackage::controller_version, {}, &reply);
  if (error.ok() && reply.size() >= 16) {
    for (int k = 0; k < 4; ++k) stats->controller_version[k] = be32(reply.data() + 4 * k);
  }
  // The output recipe: frequency (double), then the variable names.
  std::vector<std::uint8_t> setup(8);
  std::uint64_t bits = 0;
  std::memcpy(&bits, &options.frequency_hz, sizeof bits);
  for (int k = 0; k < 8; ++k) setup[static_cast<std::size_t>(k)] = static_cast<std::uint8_t>(bits >> (56 - 8 * k));
  std::string names;
  for (const std::string& name : rtde_recorded_variables()) names += (names.empty() ? "" : ",") + name;
  setup.insert(setup.end(), names.begin(), names.end());
  if (error.ok()) error = request(session, RtdePackage::setup_outputs, setup, &reply);
  if (!error.ok()) return error;
  const std::string types(reply.begin() + (reply.empty() ? 0 : 1), reply.end());
  if (types.find("NOT_FOUND") != std::string::npos || types != "DOUBLE,VECTOR6D,VECTOR6D") {
    std::string unknown;
    std::size_t at = 0;
    for (const std::string& name : rtde_recorded_variables()) {
      const std::size_t end = std::min(types.find(',', at), types.size());
      if (types.compare(at, end - at, "NOT_FOUND") == 0) unknown += (unknown.empty() ? "" : ", ") + name;
      at = end + 1;
    }
    return Error::input("--rtde: the controller refuses the recipe (" + printable(types, 120) + ")" +
                        (unknown.empty() ? "" : ": it does not know " + unknown));
  }
  const std::uint8_t recipe = reply[0];
  error = request(session, RtdePackage::start, {}, &reply);
  if (error.ok() && (reply.size() != 1 || reply[0] != 1))
    error = Error::input("--rtde: the controller refuses to start");
  if (error.ok()) error = write_row(rtde_log_header());
  double last_timestamp_s = -std::numeric_limits<double>::infinity();
  std::int64_t last_data_ms = monotonic_ms();
  while (error.ok()) {
    const std::int64_t now_ms = monotonic_ms();
    if (now_ms >= end_ms) break;
    if (now_ms - last_data_ms > options.reply_timeout_ms) {
      error = Error::input("--rtde: no data package for " + std::to_string(options.reply_timeout_ms) + " ms (" +
                           std::to_string(stats->text_messages) +
                           " text messages in all): the controller stopped sending; the recording ends (the " +
                           std::to_string(stats->rows_written) + " rows before are kept)");
      break;
    }
    std::uint8_t type = 0;
    // Wakes at least every 200 ms to check the duration and the stop request.
    const Received r = session.reader.next(std::min(now_ms + 200, end_ms), stop, &type, &reply, &error);
    if (error.ok() && r == Received::package) error = session.traffic.count();
    if (!error.ok() || r == Received::stopped) break;
    if (r == Received::timeout) continue;
    if (r == Received::closed) {
      stats->ended_by_controller = true;
      break;
    }
    if (type == static_cast<std::uint8_t>(RtdePackage::text_message)) {
      pass_text(session, reply);
      continue;
    }
    if (type != static_cast<std::uint8_t>(RtdePackage::data)) continue;
    if (reply.size() != 1 + 8 * kValues || reply[0] != recipe) {
      error = Error::input("--rtde: a data package of " + std::to_string(reply.size()) + " bytes for recipe " +
                           std::to_string(reply.empty() ? 0 : reply[0]) + ": not the recipe set up");
      break;
    }
    ++stats->data_packages;
    last_data_ms = monotonic_ms();
    error = check_row(reply, stats->data_packages, &last_timestamp_s);
    if (error.ok()) error = write_row(format_row(reply));
    if (error.ok()) ++stats->rows_written;
  }
  if (!stats->ended_by_controller) (void)send_package(socket.fd, RtdePackage::pause, {});  // best effort: leaving
  return error;
}

}  // namespace hivecal::port
