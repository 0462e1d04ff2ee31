// A stand-in UR controller for the RTDE client's tests (port::record_rtde, `record --rtde`):
// a thread speaking the documented protocol (rtde_client.hpp) to one client on a loopback
// socket (IPv4 or IPv6), scripted to behave well or to misbehave the ways a network or a
// hostile peer does: a package cut by a pause (a TCP retransmission), a controller that only
// chatters, a flood of packages or text messages, NaN values, a timestamp that goes back.
#pragma once

#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "hivecal/port/byte_source.hpp"

namespace hivecal::test {

/// How the stand-in controller behaves.
struct ControllerScript {
  int data_packages = 500;        ///< sent after start
  int data_period_ms = 0;         ///< pause between data packages (0: as fast as the socket takes them)
  bool accept_version = true;     ///< answer V with 1
  std::string unknown_variable;   ///< answered NOT_FOUND
  bool close_mid_stream = false;  ///< close after the data instead of waiting for P
  bool answer = true;             ///< false: never read or answer anything
  bool ipv6 = false;              ///< listen on ::1 instead of 127.0.0.1
  int text_at_package = 10;       ///< a text message before this data package (-1: none)
  /// Data package whose second half comes this long after its first (-1: none) [ms]
  int pause_in_package = -1;
  int pause_ms = 0;               ///< that pause [ms]
  int nan_at_package = -1;        ///< this data package carries a NaN joint (-1: none)
  int backwards_at_package = -1;  ///< this data package's timestamp is before the previous one (-1: none)
  /// Only text messages, as fast as the socket takes them, from the connection on (never a
  /// reply) or, with chatter_after_start, instead of the data; until the client leaves or
  /// chatter_limit_s passes.
  bool chatter_only = false;
  bool chatter_after_start = false;  ///< see chatter_only
  double chatter_limit_s = 30.0;     ///< the chatter's end at the latest [s]
  int chatter_period_ms = 0;         ///< pause between text messages (0: none)
};

/// The value k (0: timestamp [s], 1-6: joints [rad], 7-12: TCP pose) of data package `package`.
inline double rtde_value_of(int package, int k) {
  return k == 0 ? 1000.0 + package * 0.008 : package * 1e-3 + k * 0.1 + 1.0 / 3.0;
}

/// A listening loopback socket and the controller thread serving one client.
class StandInController {
 public:
  explicit StandInController(ControllerScript script) : script_(std::move(script)) {
    listener_ = ::socket(script_.ipv6 ? AF_INET6 : AF_INET, SOCK_STREAM, 0);
    if (script_.ipv6) {
      sockaddr_in6 address{};
      address.sin6_family = AF_INET6;
      address.sin6_addr = in6addr_loopback;
      EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
      socklen_t size = sizeof address;
      ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &size);
      port_ = ntohs(address.sin6_port);
    } else {
      sockaddr_in address{};
      address.sin_family = AF_INET;
      address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
      EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
      socklen_t size = sizeof address;
      ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &size);
      port_ = ntohs(address.sin_port);
    }
    EXPECT_EQ(::listen(listener_, 1), 0);
    if (script_.answer) thread_ = std::thread([this] { serve(); });
  }
  ~StandInController() {
    if (thread_.joinable()) thread_.join();
    ::close(listener_);
  }
  StandInController(const StandInController&) = delete;
  StandInController& operator=(const StandInController&) = delete;

  int port() const { return port_; }                               ///< where it listens
  double requested_frequency() const { return frequency_; }        ///< the recipe's [Hz]
  std::uint64_t texts_sent() const { return texts_sent_.load(); }  ///< text messages sent

 private:
  static bool send_bytes(int fd, const std::uint8_t* bytes, std::size_t count) {
    while (count > 0) {
      const ssize_t put = ::send(fd, bytes, count, MSG_NOSIGNAL);
      if (put <= 0) return false;
      bytes += put;
      count -= static_cast<std::size_t>(put);
    }
    return true;
  }
  static std::vector<std::uint8_t> package(char type, const std::vector<std::uint8_t>& payload) {
    const std::size_t size = 3 + payload.size();
    std::vector<std::uint8_t> bytes = {static_cast<std::uint8_t>(size >> 8), static_cast<std::uint8_t>(size & 0xff),
                                       static_cast<std::uint8_t>(type)};
    bytes.insert(bytes.end(), payload.begin(), payload.end());
    return bytes;
  }
  static bool send_package(int fd, char type, const std::vector<std::uint8_t>& payload) {
    const std::vector<std::uint8_t> bytes = package(type, payload);
    return send_bytes(fd, bytes.data(), bytes.size());
  }
  static void put_be_double(std::vector<std::uint8_t>* out, double value) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &value, sizeof bits);
    for (int k = 7; k >= 0; --k) out->push_back(static_cast<std::uint8_t>(bits >> (8 * k)));
  }
  static bool receive_package(int fd, char* type, std::vector<std::uint8_t>* payload) {
    std::uint8_t header[3];
    if (::recv(fd, header, 3, MSG_WAITALL) != 3) return false;
    const std::size_t size = (static_cast<std::size_t>(header[0]) << 8) | header[1];
    *type = static_cast<char>(header[2]);
    payload->assign(size - 3, 0);
    return payload->empty() ||
           ::recv(fd, payload->data(), payload->size(), MSG_WAITALL) == static_cast<ssize_t>(payload->size());
  }
  static std::vector<std::uint8_t> text_payload(const std::string& message) {
    const std::string source = "stand-in";
    std::vector<std::uint8_t> text = {static_cast<std::uint8_t>(message.size())};
    text.insert(text.end(), message.begin(), message.end());
    text.push_back(static_cast<std::uint8_t>(source.size()));
    text.insert(text.end(), source.begin(), source.end());
    text.push_back(1);
    return text;
  }

  /// Sends text messages until the client leaves (a send fails) or the limit passes.
  void chatter(int fd) {
    const std::int64_t end_ms = port::monotonic_ms() + static_cast<std::int64_t>(script_.chatter_limit_s * 1000.0);
    const std::vector<std::uint8_t> text = package('M', text_payload("all is well"));
    while (port::monotonic_ms() < end_ms && send_bytes(fd, text.data(), text.size())) {
      ++texts_sent_;
      if (script_.chatter_period_ms > 0) port::sleep_ms(script_.chatter_period_ms);
    }
  }

  /// The data packages after 'S'; false when the client left.
  bool send_data(int fd) {
    for (int p = 0; p < script_.data_packages; ++p) {
      if (p == script_.text_at_package && !send_package(fd, 'M', text_payload("safety check passed"))) return false;
      std::vector<std::uint8_t> data = {1};
      for (int k = 0; k < 13; ++k) {
        double value = rtde_value_of(p, k);
        if (p == script_.nan_at_package && k == 3) value = std::numeric_limits<double>::quiet_NaN();
        if (p == script_.backwards_at_package && k == 0) value = rtde_value_of(p - 2, 0);
        put_be_double(&data, value);
      }
      const std::vector<std::uint8_t> bytes = package('U', data);
      if (p == script_.pause_in_package) {  // the first half, a pause, the rest
        const std::size_t half = bytes.size() / 2;
        if (!send_bytes(fd, bytes.data(), half)) return false;
        port::sleep_ms(script_.pause_ms);
        if (!send_bytes(fd, bytes.data() + half, bytes.size() - half)) return false;
      } else if (!send_bytes(fd, bytes.data(), bytes.size())) {
        return false;
      }
      if (script_.data_period_ms > 0) port::sleep_ms(script_.data_period_ms);
    }
    return true;
  }

  void serve() {
    pollfd client{listener_, POLLIN, 0};  // a client that never comes (refused earlier) ends the wait
    if (::poll(&client, 1, 20000) != 1) return;
    const int fd = ::accept(listener_, nullptr, nullptr);
    if (fd < 0) return;
    if (script_.chatter_only && !script_.chatter_after_start) {
      chatter(fd);
      ::close(fd);
      return;
    }
    char type = 0;
    std::vector<std::uint8_t> payload;
    while (receive_package(fd, &type, &payload)) {
      if (type == 'V') {
        send_package(fd, 'V', {static_cast<std::uint8_t>(script_.accept_version ? 1 : 0)});
        if (!script_.accept_version) break;
      } else if (type == 'v') {
        send_package(fd, 'v', {0, 0, 0, 5, 0, 0, 0, 11, 0, 0, 0, 0, 0, 0, 48, 57});  // 5.11.0.12345
      } else if (type == 'O') {
        std::uint64_t bits = 0;
        for (int k = 0; k < 8; ++k) bits = (bits << 8) | payload[static_cast<std::size_t>(k)];
        std::memcpy(&frequency_, &bits, sizeof bits);
        const std::string names(payload.begin() + 8, payload.end());
        std::string types;
        std::size_t at = 0;
        while (at <= names.size()) {
          const std::size_t end = std::min(names.find(',', at), names.size());
          const std::string name = names.substr(at, end - at);
          const char* t = name == script_.unknown_variable ? "NOT_FOUND" : name == "timestamp" ? "DOUBLE" : "VECTOR6D";
          types += (types.empty() ? "" : ",") + std::string(t);
          at = end + 1;
        }
        std::vector<std::uint8_t> reply = {1};
        reply.insert(reply.end(), types.begin(), types.end());
        send_package(fd, 'O', reply);
      } else if (type == 'S') {
        send_package(fd, 'S', {1});
        if (script_.chatter_only) {
          chatter(fd);
          break;
        }
        if (!send_data(fd) || script_.close_mid_stream) break;
      } else if (type == 'P') {
        send_package(fd, 'P', {1});
        break;
      }
    }
    ::close(fd);
  }

  ControllerScript script_;
  int listener_ = -1;
  int port_ = 0;
  double frequency_ = 0.0;
  std::atomic<std::uint64_t> texts_sent_{0};
  std::thread thread_;
};

}  // namespace hivecal::test
