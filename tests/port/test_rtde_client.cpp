// The RTDE client against a stand-in UR controller in this test (a thread speaking the
// documented protocol on a loopback socket): every data package it sends arrives as a log row
// with each value exactly as sent; text messages are passed on; an unknown variable
// (NOT_FOUND), a refused protocol version, a host that never answers and a controller that
// closes mid-stream each end as they should.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "hivecal/port/rtde_client.hpp"

namespace hivecal::port::rtde_client_test {
namespace {

/// How the stand-in controller behaves.
struct ControllerScript {
  int data_packages = 500;        ///< sent after start
  bool accept_version = true;     ///< answer V with 1
  std::string unknown_variable;   ///< answered NOT_FOUND
  bool close_mid_stream = false;  ///< close after the data instead of waiting for P
  bool answer = true;             ///< false: never read or answer anything
};

double value_of(int package, int k) {
  return k == 0 ? 1000.0 + package * 0.008 : package * 1e-3 + k * 0.1 + 1.0 / 3.0;
}

void put_be_double(std::vector<std::uint8_t>* out, double value) {
  std::uint64_t bits = 0;
  std::memcpy(&bits, &value, sizeof bits);
  for (int k = 7; k >= 0; --k) out->push_back(static_cast<std::uint8_t>(bits >> (8 * k)));
}

void send_all(int fd, char type, const std::vector<std::uint8_t>& payload) {
  const std::size_t size = 3 + payload.size();
  std::vector<std::uint8_t> bytes = {static_cast<std::uint8_t>(size >> 8), static_cast<std::uint8_t>(size & 0xff),
                                     static_cast<std::uint8_t>(type)};
  bytes.insert(bytes.end(), payload.begin(), payload.end());
  (void)!::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
}

bool receive_package(int fd, char* type, std::vector<std::uint8_t>* payload) {
  std::uint8_t header[3];
  if (::recv(fd, header, 3, MSG_WAITALL) != 3) return false;
  const std::size_t size = (static_cast<std::size_t>(header[0]) << 8) | header[1];
  *type = static_cast<char>(header[2]);
  payload->assign(size - 3, 0);
  return payload->empty() ||
         ::recv(fd, payload->data(), payload->size(), MSG_WAITALL) == static_cast<ssize_t>(payload->size());
}

/// A listening loopback socket and the controller thread serving one client.
class StandInController {
 public:
  explicit StandInController(ControllerScript script) : script_(std::move(script)) {
    listener_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    EXPECT_EQ(::bind(listener_, reinterpret_cast<sockaddr*>(&address), sizeof address), 0);
    EXPECT_EQ(::listen(listener_, 1), 0);
    socklen_t size = sizeof address;
    ::getsockname(listener_, reinterpret_cast<sockaddr*>(&address), &size);
    port_ = ntohs(address.sin_port);
    if (script_.answer) thread_ = std::thread([this] { serve(); });
  }
  ~StandInController() {
    if (thread_.joinable()) thread_.join();
    ::close(listener_);
  }
  int port() const { return port_; }
  double requested_frequency() const { return frequency_; }

 private:
  void serve() {
    const int fd = ::accept(listener_, nullptr, nullptr);
    if (fd < 0) return;
    char type = 0;
    std::vector<std::uint8_t> payload;
    while (receive_package(fd, &type, &payload)) {
      if (type == 'V') {
        send_all(fd, 'V', {static_cast<std::uint8_t>(script_.accept_version ? 1 : 0)});
        if (!script_.accept_version) break;
      } else if (type == 'v') {
        send_all(fd, 'v', {0, 0, 0, 5, 0, 0, 0, 11, 0, 0, 0, 0, 0, 0, 48, 57});  // 5.11.0.12345
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
        send_all(fd, 'O', reply);
      } else if (type == 'S') {
        send_all(fd, 'S', {1});
        for (int p = 0; p < script_.data_packages; ++p) {
          if (p == 10) {
            const std::string message = "safety check passed";
            const std::string source = "stand-in";
            std::vector<std::uint8_t> text = {static_cast<std::uint8_t>(message.size())};
            text.insert(text.end(), message.begin(), message.end());
            text.push_back(static_cast<std::uint8_t>(source.size()));
            text.insert(text.end(), source.begin(), source.end());
            text.push_back(1);
            send_all(fd, 'M', text);
          }
          std::vector<std::uint8_t> data = {1};
          for (int k = 0; k < 13; ++k) put_be_double(&data, value_of(p, k));
          send_all(fd, 'U', data);
        }
        if (script_.close_mid_stream) break;
      } else if (type == 'P') {
        send_all(fd, 'P', {1});
        break;
      }
    }
    ::close(fd);
  }

  ControllerScript script_;
  int listener_ = -1;
  int port_ = 0;
  double frequency_ = 0.0;
  std::thread thread_;
};

TEST(RtdeClient, EveryPackageArrivesAsSent) {
  ControllerScript script;
  script.close_mid_stream = true;  // the controller ends the session: the client keeps all it got
  StandInController controller(script);
  std::vector<std::string> rows;
  std::vector<std::string> texts;
  RtdeRecordOptions options;
  options.frequency_hz = 500.0;
  options.on_text = [&](const std::string& t) { texts.push_back(t); };
  RtdeStats stats;
  const Error error = record_rtde(
      "127.0.0.1", controller.port(), options, nullptr,
      [&](const std::string& row) {
        rows.push_back(row);
        return Error{};
      },
      &stats);
  ASSERT_TRUE(error.ok()) << error.message;
  EXPECT_TRUE(stats.ended_by_controller);
  EXPECT_EQ(controller.requested_frequency(), 500.0);
  EXPECT_EQ(stats.controller_version[0], 5u);
  EXPECT_EQ(stats.controller_version[1], 11u);
  EXPECT_EQ(stats.controller_version[3], 12345u);
  ASSERT_EQ(stats.data_packages, 500u);  // loopback: every one (the issue asks >= 90 %)
  ASSERT_EQ(rows.size(), 501u);
  EXPECT_EQ(rows[0], rtde_log_header());
  for (int p = 0; p < 500; ++p) {
    const char* at = rows[static_cast<std::size_t>(p) + 1].c_str();
    for (int k = 0; k < 13; ++k) {
      char* end = nullptr;
      const double value = std::strtod(at, &end);
      ASSERT_EQ(value, value_of(p, k)) << "package " << p << " value " << k;  // exactly as sent
      at = end;
    }
  }
  ASSERT_EQ(texts.size(), 1u);
  EXPECT_EQ(texts[0], "stand-in: safety check passed");
}

TEST(RtdeClient, AVariableTheControllerDoesNotKnowIsNamed) {
  ControllerScript script;
  script.unknown_variable = "actual_TCP_pose";
  StandInController controller(script);
  RtdeStats stats;
  bool wrote = false;
  const Error error = record_rtde(
      "127.0.0.1", controller.port(), RtdeRecordOptions(), nullptr,
      [&](const std::string&) {
        wrote = true;
        return Error{};
      },
      &stats);
  EXPECT_EQ(error.fault, Fault::input);
  EXPECT_NE(error.message.find("it does not know actual_TCP_pose"), std::string::npos) << error.message;
  EXPECT_FALSE(wrote) << "nothing written before the controller accepted the recipe";
}

TEST(RtdeClient, ARefusedVersionAndASilentHostEndWithAReason) {
  ControllerScript refusing;
  refusing.accept_version = false;
  StandInController old_controller(refusing);
  RtdeStats stats;
  const auto nothing = [](const std::string&) { return Error{}; };
  Error error = record_rtde("127.0.0.1", old_controller.port(), RtdeRecordOptions(), nullptr, nothing, &stats);
  EXPECT_NE(error.message.find("refuses protocol version 2"), std::string::npos) << error.message;
  ControllerScript silent;
  silent.answer = false;  // the connection is taken (listen backlog) but nothing ever answers
  StandInController mute(silent);
  RtdeRecordOptions quick;
  quick.reply_timeout_ms = 300;
  error = record_rtde("127.0.0.1", mute.port(), quick, nullptr, nothing, &stats);
  EXPECT_NE(error.message.find("no reply to 'V' within 300 ms"), std::string::npos) << error.message;
}

}  // namespace
}  // namespace hivecal::port::rtde_client_test
