// The same session in the forms real tools log it (io-formats.md, "Logs written by other
// tools"): hivecal CSV, UR RTDE recorder, rostopic echo -p /joint_states (joints in a
// driver's own order), a tracker export in mm and ms with lost-beam rows absent, and a ROS 2
// bag (sqlite3 storage, CDR JointState). Written as the tools write them, from records.
#pragma once

#include <charconv>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "hivecal/wire/records.hpp"

#if HIVECAL_HAVE_SQLITE3
#include <sqlite3.h>
#endif

namespace hivecal::test {

/// The UR drivers' joint names, joints 1..6.
inline const char* const kUrJoints[kSixJoints] = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
                                                  "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
/// The order ur_robot_driver publishes them in (alphabetical): joint indices 0-based.
inline const int kDriverOrder[kSixJoints] = {2, 1, 0, 3, 4, 5};

/// "%.17g", as the tools print (std::to_chars with a precision is printf's %.*g, several
/// times faster: the ten-minute log test writes 3.6 million of them).
inline std::string g17(double v) {
  char b[40];
  const std::to_chars_result end = std::to_chars(b, b + sizeof b, v, std::chars_format::general, 17);
  return std::string(b, end.ptr);
}

inline std::string seconds(std::uint64_t t_us) {
  char b[40];
  std::snprintf(b, sizeof b, "%" PRIu64 ".%06" PRIu64, t_us / 1000000, t_us % 1000000);
  return b;
}

/// ASCII `text` as an editor saves it in UTF-16 (`width` 2) or UTF-32 (`width` 4), little- or
/// big-endian, with `bom` (its byte order mark, or "") first.
inline std::string wide_text(const std::string& text, int width, bool big_endian, const std::string& bom) {
  std::string out = bom;
  for (const char c : text) {
    std::string unit(static_cast<std::size_t>(width), '\0');
    unit[big_endian ? unit.size() - 1 : 0] = c;
    out += unit;
  }
  return out;
}

/// hivecal's robot log: t,q1..q6.
inline std::string hivecal_robot_csv(const std::vector<JointStateRecord>& records) {
  std::string out = "t,q1,q2,q3,q4,q5,q6\n";
  for (const JointStateRecord& r : records) {
    out += seconds(r.timestamp_us);
    for (int j = 0; j < r.joint_count; ++j) out += "," + g17(r.q_rad[j]);
    out += "\n";
  }
  return out;
}

/// The RTDE recorder's CSV (space-separated by default): target_q first (offset, so that
/// reading it by mistake shows), then actual_q, then the TCP pose.
inline std::string rtde_log(const std::vector<JointStateRecord>& records, char separator = ' ') {
  std::string out = "timestamp";
  for (const char* field : {"target_q_", "actual_q_", "actual_TCP_pose_"}) {
    for (int k = 0; k < kSixJoints; ++k) out += separator + std::string(field) + std::to_string(k);
  }
  out += "\n";
  out.reserve(out.size() + records.size() * 256);  // ~250 bytes a row: one allocation, not ~30
  for (const JointStateRecord& r : records) {
    out += seconds(r.timestamp_us);
    for (int j = 0; j < r.joint_count; ++j) (out += separator) += g17(r.q_rad[j] + 0.01);
    for (int j = 0; j < r.joint_count; ++j) (out += separator) += g17(r.q_rad[j]);
    for (int k = 0; k < kSixJoints; ++k) (out += separator) += "0.5";
    out += "\n";
  }
  return out;
}

/// `rostopic echo -p /joint_states`: ns times, joints in `order` (indices of joints 1..6).
inline std::string rostopic_log(const std::vector<JointStateRecord>& records,
                                const int order[kSixJoints] = kDriverOrder) {
  std::string out = "%time,field.header.seq,field.header.stamp,field.header.frame_id";
  for (const char* field : {"name", "position", "velocity", "effort"}) {
    for (int k = 0; k < kSixJoints; ++k) out += ",field." + std::string(field) + std::to_string(k);
  }
  out += "\n";
  std::uint64_t seq = 0;
  for (const JointStateRecord& r : records) {
    const std::uint64_t stamp_ns = r.timestamp_us * 1000;
    out += std::to_string(stamp_ns + 2345678) + "," + std::to_string(seq++) + "," + std::to_string(stamp_ns) + ",";
    for (int k = 0; k < kSixJoints; ++k) out += std::string(",") + kUrJoints[order[k]];
    for (int k = 0; k < kSixJoints; ++k) out += "," + g17(r.q_rad[order[k]]);
    for (int k = 0; k < 2 * kSixJoints; ++k) out += ",0.0";
    out += "\n";
  }
  return out;
}

/// hivecal's tracker log: t,x,y,z,status.
inline std::string hivecal_tracker_csv(const std::vector<TrackerPointRecord>& records) {
  std::string out = "t,x,y,z,status\n";
  for (const TrackerPointRecord& r : records) {
    out += seconds(r.timestamp_us) + "," + g17(r.point_m[0]) + "," + g17(r.point_m[1]) + "," + g17(r.point_m[2]) + "," +
           std::to_string(r.status) + "\n";
  }
  return out;
}

/// A tracker software's export: `Time [ms];X [mm];Y [mm];Z [mm]`, rows not valid absent.
inline std::string tracker_export(const std::vector<TrackerPointRecord>& records) {
  std::string out = "Time [ms];X [mm];Y [mm];Z [mm]\n";
  for (const TrackerPointRecord& r : records) {
    if (!r.is_valid()) continue;
    char t[40];
    std::snprintf(t, sizeof t, "%" PRIu64 ".%03" PRIu64, r.timestamp_us / 1000, r.timestamp_us % 1000);
    out += std::string(t) + ";" + g17(r.point_m[0] * 1e3) + ";" + g17(r.point_m[1] * 1e3) + ";" +
           g17(r.point_m[2] * 1e3) + "\n";
  }
  return out;
}

/// Little-endian CDR of a sensor_msgs/msg/JointState with `names`/`positions` as given.
inline std::vector<std::uint8_t> joint_state_cdr(std::uint64_t t_us, const std::vector<std::string>& names,
                                                 const std::vector<double>& positions) {
  std::vector<std::uint8_t> out = {0, 1, 0, 0};
  auto align = [&](std::size_t n) {
    while ((out.size() - 4) % n != 0) out.push_back(0);
  };
  auto u32 = [&](std::uint32_t v) {
    align(4);
    for (int b = 0; b < 4; ++b) out.push_back(static_cast<std::uint8_t>(v >> (8 * b)));
  };
  auto str = [&](const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    out.insert(out.end(), s.begin(), s.end());
    out.push_back(0);
  };
  auto doubles = [&](const std::vector<double>& v) {
    u32(static_cast<std::uint32_t>(v.size()));
    for (const double d : v) {
      align(8);
      std::uint8_t b[8];
      std::memcpy(b, &d, 8);
      out.insert(out.end(), b, b + 8);
    }
  };
  u32(static_cast<std::uint32_t>(t_us / 1000000));
  u32(static_cast<std::uint32_t>(t_us % 1000000 * 1000));
  str("base_link");
  u32(static_cast<std::uint32_t>(names.size()));
  for (const std::string& n : names) str(n);
  doubles(positions);
  doubles(std::vector<double>(positions.size(), 0.0));  // velocity
  doubles({});                                          // effort
  return out;
}

#if HIVECAL_HAVE_SQLITE3
/// Writes a rosbag2 folder `dir` (created by the caller): metadata.yaml and dir_0.db3 with
/// /joint_states (message joint k named names[k], its position the record's joint order[k])
/// and an unrelated /tf topic. False on a sqlite error.
inline bool write_ros2_bag_joints(const std::string& dir, const std::vector<JointStateRecord>& records,
                                  const std::vector<std::string>& names, const std::vector<int>& order) {
  std::FILE* yaml = std::fopen((dir + "/metadata.yaml").c_str(), "w");
  if (yaml == nullptr) return false;
  std::fputs(
      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
      "  relative_file_paths:\n    - bag_0.db3\n",
      yaml);
  std::fclose(yaml);
  sqlite3* db = nullptr;
  if (sqlite3_open((dir + "/bag_0.db3").c_str(), &db) != SQLITE_OK) return false;
  bool ok = sqlite3_exec(db,
                         "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
                         "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
                         "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, "
                         "timestamp INTEGER NOT NULL, data BLOB NOT NULL);"
                         "INSERT INTO topics VALUES(1, '/tf', 'tf2_msgs/msg/TFMessage', 'cdr', '');"
                         "INSERT INTO topics VALUES(2, '/joint_states', 'sensor_msgs/msg/JointState', 'cdr', '');"
                         "BEGIN;",
                         nullptr, nullptr, nullptr) == SQLITE_OK;
  sqlite3_stmt* insert = nullptr;
  ok = ok && sqlite3_prepare_v2(db, "INSERT INTO messages(topic_id, timestamp, data) VALUES(?1, ?2, ?3)", -1, &insert,
                                nullptr) == SQLITE_OK;
  for (std::size_t i = 0; ok && i < records.size(); ++i) {
    std::vector<double> positions;
    for (const int k : order) positions.push_back(records[i].q_rad[k]);
    const std::vector<std::uint8_t> data = joint_state_cdr(records[i].timestamp_us, names, positions);
    const std::uint8_t tf[8] = {0, 1, 0, 0, 0, 0, 0, 0};
    for (int topic : {2, 1}) {
      if (topic == 1 && i % 10 != 0) continue;
      sqlite3_bind_int(insert, 1, topic);
      sqlite3_bind_int64(insert, 2, static_cast<sqlite3_int64>(records[i].timestamp_us * 1000 + 1500000));
      if (topic == 2) {
        sqlite3_bind_blob(insert, 3, data.data(), static_cast<int>(data.size()), SQLITE_TRANSIENT);
      } else {
        sqlite3_bind_blob(insert, 3, tf, 8, SQLITE_TRANSIENT);
      }
      ok = sqlite3_step(insert) == SQLITE_DONE && sqlite3_reset(insert) == SQLITE_OK;
    }
  }
  sqlite3_finalize(insert);
  ok = ok && sqlite3_exec(db, "COMMIT;", nullptr, nullptr, nullptr) == SQLITE_OK;
  sqlite3_close(db);
  return ok;
}

/// The same with a UR's six joints named as its driver names them, in `order`.
inline bool write_ros2_bag(const std::string& dir, const std::vector<JointStateRecord>& records,
                           const int order[kSixJoints] = kDriverOrder) {
  std::vector<std::string> names;
  for (int k = 0; k < kSixJoints; ++k) names.push_back(kUrJoints[order[k]]);
  return write_ros2_bag_joints(dir, records, names, std::vector<int>(order, order + kSixJoints));
}
#endif

}  // namespace hivecal::test
