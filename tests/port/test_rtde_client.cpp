// The RTDE client against a stand-in UR controller (testkit/rtde_controller.hpp: a thread
// speaking the documented protocol on a loopback socket): every data package it sends arrives
// as a log row with each value exactly as sent; text messages are passed on; an unknown
// variable (NOT_FOUND), a refused protocol version, a host that never answers and a controller
// that closes mid-stream each end as they should; and the hostile ones (issue 54): a package
// cut by a pause is put together, a controller that only chatters is timed out, a flood is
// refused, a row no reader takes ends the recording with the rows before it kept.
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "hivecal/port/byte_source.hpp"
#include "hivecal/port/rtde_client.hpp"
#include "testkit/rtde_controller.hpp"

namespace hivecal::port::rtde_client_test {
namespace {

using test::ControllerScript;
using test::rtde_value_of;
using test::StandInController;

/// What one recording against a stand-in controller gave.
struct Recording {
  Error error;                     ///< record_rtde's outcome
  std::vector<std::string> rows;   ///< what it handed to write_row (the header first)
  std::vector<std::string> texts;  ///< the text messages passed on
  RtdeStats stats;                 ///< its counts
  std::int64_t took_ms = 0;        ///< how long it ran [ms]
};

/// The recording ended as refused input, its message holding `part`.
void expect_refused(const Recording& r, const std::string& part) {
  EXPECT_EQ(r.error.fault, Fault::input) << r.error.message;
  EXPECT_NE(r.error.message.find(part), std::string::npos) << r.error.message;
}

Recording record_from(const StandInController& controller, RtdeRecordOptions options,
                      const std::string& host = "127.0.0.1") {
  Recording out;
  options.on_text = [&out](const std::string& t) { out.texts.push_back(t); };
  const std::int64_t start_ms = monotonic_ms();
  out.error = record_rtde(
      host, controller.port(), options, nullptr,
      [&out](const std::string& row) {
        out.rows.push_back(row);
        return Error{};
      },
      &out.stats);
  out.took_ms = monotonic_ms() - start_ms;
  return out;
}

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
      ASSERT_EQ(value, rtde_value_of(p, k)) << "package " << p << " value " << k;  // exactly as sent
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

TEST(RtdeClient, APackageCutByAPauseIsPutTogether) {
  // One TCP retransmission pauses a package mid-way for over 200 ms: the bytes read are kept
  // and the rest completes it (it ended the recording as "a package of N bytes").
  ControllerScript script;
  script.data_packages = 300;
  script.pause_in_package = 100;
  script.pause_ms = 700;
  script.close_mid_stream = true;
  const StandInController controller(script);
  const Recording r = record_from(controller, RtdeRecordOptions());
  ASSERT_TRUE(r.error.ok()) << r.error.message;
  EXPECT_EQ(r.stats.data_packages, 300u);
  ASSERT_EQ(r.rows.size(), 301u);
  EXPECT_EQ(std::strtod(r.rows[101].c_str(), nullptr), rtde_value_of(100, 0));
  EXPECT_GE(r.took_ms, 600);
}

TEST(RtdeClient, AControllerThatOnlyChattersIsTimedOut) {
  // Text messages, never the reply: each reset the reply timer, so it waited forever.
  ControllerScript script;
  script.chatter_only = true;
  script.chatter_period_ms = 5;  // 200 a second: a chatty controller, not a flood
  script.chatter_limit_s = 6.0;
  const StandInController controller(script);
  RtdeRecordOptions options;
  options.reply_timeout_ms = 500;
  const Recording r = record_from(controller, options);
  expect_refused(r, "no reply to 'V' within 500 ms");
  EXPECT_LT(r.took_ms, 2500);
  EXPECT_TRUE(r.rows.empty());
}

TEST(RtdeClient, TheDurationBoundsTheSetup) {
  ControllerScript script;
  script.chatter_only = true;
  script.chatter_period_ms = 5;  // 200 a second: a chatty controller, not a flood
  script.chatter_limit_s = 6.0;
  const StandInController controller(script);
  RtdeRecordOptions options;
  options.duration_s = 0.5;  // the 5 s reply timeout would come later
  const Recording r = record_from(controller, options);
  expect_refused(r, "--duration-s passed before the controller answered 'V'");
  EXPECT_LT(r.took_ms, 2500);
}

TEST(RtdeClient, AControllerThatStopsSendingDataEndsTheRecording) {
  ControllerScript script;
  script.data_packages = 20;
  script.data_period_ms = 8;
  const StandInController controller(script);
  RtdeRecordOptions options;
  options.reply_timeout_ms = 500;
  options.duration_s = 10.0;
  const Recording r = record_from(controller, options);
  expect_refused(r, "no data package for 500 ms");
  EXPECT_EQ(r.rows.size(), 21u);
  EXPECT_LT(r.took_ms, 3000);
}

TEST(RtdeClient, TrafficFarBeyondTheFrequencyIsRefused) {
  // 87k packages/s at a requested 125 Hz were taken, to the disk and the terminal.
  ControllerScript flood;
  flood.data_packages = 100000;
  const StandInController data(flood);
  RtdeRecordOptions options;
  options.frequency_hz = 125.0;
  options.duration_s = 5.0;
  Recording r = record_from(data, options);
  expect_refused(r, "far more than the 125 Hz asked for");
  EXPECT_LT(r.rows.size(), 1200u);
  EXPECT_LT(r.took_ms, 2500);
  ControllerScript chatter;
  chatter.chatter_only = true;
  chatter.chatter_after_start = true;
  chatter.chatter_limit_s = 6.0;
  const StandInController texts(chatter);
  r = record_from(texts, options);
  expect_refused(r, "far more than the 125 Hz asked for");
  EXPECT_LT(r.texts.size(), 1200u);
  EXPECT_LT(r.took_ms, 2500);
}

TEST(RtdeClient, ARowNoReaderTakesEndsTheRecordingKeepingTheRowsBefore) {
  // NaN joints and timestamps that go back were written with success; every reader then
  // refused the whole log.
  ControllerScript nan;
  nan.nan_at_package = 50;
  nan.close_mid_stream = true;
  const StandInController first(nan);
  Recording r = record_from(first, RtdeRecordOptions());
  expect_refused(r, "data package 51: actual_q_2 is NaN");
  EXPECT_NE(r.error.message.find("the 50 rows before it are kept"), std::string::npos) << r.error.message;
  EXPECT_EQ(r.rows.size(), 51u);
  ControllerScript back;
  back.backwards_at_package = 60;
  back.close_mid_stream = true;
  const StandInController second(back);
  r = record_from(second, RtdeRecordOptions());
  expect_refused(r,
                 "data package 61: timestamp 1000.464000 s is before the previous package's "
                 "1000.472000 s");
  EXPECT_EQ(r.rows.size(), 61u);
}

TEST(RtdeClient, AnIpv6AddressIsTakenWithOrWithoutAPort) {
  std::string host;
  int port = 0;
  ASSERT_TRUE(parse_rtde_address("[::1]:30005", &host, &port).ok());
  EXPECT_EQ(host, "::1");
  EXPECT_EQ(port, 30005);
  ASSERT_TRUE(parse_rtde_address("::1", &host, &port).ok());
  EXPECT_EQ(host, "::1");
  EXPECT_EQ(port, kRtdePort);
  ASSERT_TRUE(parse_rtde_address("[fe80::1%eth0]", &host, &port).ok());
  EXPECT_EQ(host, "fe80::1%eth0");
  ASSERT_TRUE(parse_rtde_address("ur5.local:30004", &host, &port).ok());
  EXPECT_EQ(host, "ur5.local");
  ASSERT_TRUE(parse_rtde_address("192.168.1.10", &host, &port).ok());
  EXPECT_EQ(port, kRtdePort);
  for (const char* bad : {"ur5:99999", "ur5:", ":30004", "[::1", "[::1]30004", "[::1]:", "[]:1", "ur5:3e4", ""}) {
    EXPECT_EQ(parse_rtde_address(bad, &host, &port).fault, Fault::usage) << bad;
  }
  ControllerScript script;
  script.ipv6 = true;
  script.data_packages = 20;
  script.close_mid_stream = true;
  const StandInController controller(script);
  const Recording r = record_from(controller, RtdeRecordOptions(), "::1");
  ASSERT_TRUE(r.error.ok()) << r.error.message;
  EXPECT_EQ(r.rows.size(), 21u);
}

}  // namespace
}  // namespace hivecal::port::rtde_client_test
