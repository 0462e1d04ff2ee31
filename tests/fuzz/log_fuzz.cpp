// libFuzzer target for the log readers of apps/textio (delimited text, hivecal CSV, UR RTDE,
// rostopic, tracker exports, CDR JointState). Input: byte 0 picks the reader (robot log,
// tracker log, CDR message), the rest is the file. Invariants, any breach traps: ok and
// error exclusive; records non-empty, strictly increasing in time, finite where valid; an
// error is one bounded line of printable text (control bytes of the input and what is no UTF-8
// escaped).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

#include "hivecal/port/error.hpp"
#include "textio/logs.hpp"
#include "textio/ros2_bag.hpp"

namespace {

using namespace hivecal;

void require(bool condition) {
  if (!condition) __builtin_trap();
}

void check_error(const std::string& error) {
  require(error.size() < 1024);
  for (std::size_t i = 0; i < error.size();) {  // printable ASCII, or whole UTF-8 characters beyond C1
    const std::size_t length = port::utf8_sequence_bytes(error, i);
    const auto c = static_cast<unsigned char>(error[i]);
    require(length == 1 ? c >= 0x20 && c < 0x7f
                        : length > 1 && !(c == 0xC2 && static_cast<unsigned char>(error[i + 1]) < 0xA0));
    i += length;
  }
}

template <typename Log, typename Valid>
void check_log(const Log& log, Valid valid) {
  require(log.ok == log.error.empty());
  if (!log.ok) {
    check_error(log.error);
    return;
  }
  require(!log.records.empty() && log.records.size() == log.counters.records);
  require(log.counters.records + log.counters.repeated_time + log.counters.missing_joints == log.counters.rows);
  for (std::size_t i = 0; i < log.records.size(); ++i) {
    require(i == 0 || log.records[i].timestamp_us > log.records[i - 1].timestamp_us);
    require(valid(log.records[i]));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::string_view text(reinterpret_cast<const char*>(data + 1), size - 1);
  switch (data[0] % 3) {
    case 0:
      check_log(textio::parse_robot_log(text, "fuzz.csv"), [](const JointStateRecord& r) {
        for (int j = 0; j < r.joint_count; ++j) {
          if (!std::isfinite(r.q_rad[j])) return false;
        }
        return true;
      });
      break;
    case 1:
      check_log(textio::parse_tracker_log(text, "fuzz.csv"), [](const TrackerPointRecord& r) {
        return !r.is_valid() ||
               (std::isfinite(r.point_m[0]) && std::isfinite(r.point_m[1]) && std::isfinite(r.point_m[2]));
      });
      break;
    default: {
      textio::JointStateMessage message;
      std::string error;
      if (textio::decode_joint_state_cdr(data + 1, size - 1, &message, &error)) {
        require(message.names.size() == message.positions_rad.size());
        for (const std::string_view name : message.names) {
          require(name.data() >= reinterpret_cast<const char*>(data) &&
                  name.data() + name.size() <= reinterpret_cast<const char*>(data + size));
        }
      } else {
        check_error(error);
      }
    }
  }
  return 0;
}
