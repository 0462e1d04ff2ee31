#include "textio/ros2_bag.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <dirent.h>
#include <sys/stat.h>

#include "hivecal/port/input_file.hpp"
#include "textio/log_rows.hpp"
#include "textio/text_util.hpp"

#if HIVECAL_HAVE_SQLITE3
#include <sqlite3.h>
#endif

namespace hivecal::textio {
namespace {

constexpr std::uint32_t kMaxNames = 256;         // joints in one message
constexpr std::uint32_t kMaxStringBytes = 4096;  // one name or frame_id

/// CDR reader: alignment counts from the end of the 4-byte encapsulation header.
class Cdr {
 public:
  Cdr(const std::uint8_t* data, std::size_t size) : data_(data), size_(size) {}
  bool header() {
    if (size_ < 4 || data_[0] != 0) return false;
    big_endian_ = data_[1] == 0;  // 0x0000 CDR_BE, 0x0001 CDR_LE
    if (data_[1] > 1) return false;
    at_ = 4;
    return true;
  }
  bool u32(std::uint32_t* v) {
    std::uint8_t b[4];
    if (!bytes(b, 4)) return false;
    *v = big_endian_ ? (std::uint32_t{b[0]} << 24 | std::uint32_t{b[1]} << 16 | std::uint32_t{b[2]} << 8 | b[3])
                     : (std::uint32_t{b[3]} << 24 | std::uint32_t{b[2]} << 16 | std::uint32_t{b[1]} << 8 | b[0]);
    return true;
  }
  bool f64(double* v) {
    std::uint8_t b[8];
    if (!bytes(b, 8)) return false;
    if (big_endian_) std::reverse(b, b + 8);
    std::memcpy(v, b, 8);  // the message is little endian now, as the hosts hivecal runs on
    return true;
  }
  bool string(std::string_view* s) {
    std::uint32_t length = 0;  // includes the terminating NUL
    if (!u32(&length) || length == 0 || length > kMaxStringBytes || length > size_ - at_) return false;
    if (data_[at_ + length - 1] != 0) return false;
    *s = std::string_view(reinterpret_cast<const char*>(data_ + at_), length - 1);
    at_ += length;
    return true;
  }
  /// A sequence length whose elements of `element_bytes` fit in what is left.
  bool count(std::uint32_t* n, std::size_t element_bytes) {
    return u32(n) && *n <= kMaxNames && std::size_t{*n} * element_bytes <= size_ - at_;
  }

 private:
  bool bytes(std::uint8_t* out, std::size_t n) {
    const std::size_t aligned = 4 + (at_ - 4 + n - 1) / n * n;
    if (aligned > size_ || n > size_ - aligned) return false;
    std::memcpy(out, data_ + aligned, n);
    at_ = aligned + n;
    return true;
  }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t at_ = 0;
  bool big_endian_ = false;
};

bool is_folder(const std::string& path) {
  struct stat info {};
  return ::stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode);
}

bool ends_with(const std::string& s, const char* suffix) {
  const std::size_t n = std::strlen(suffix);
  return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

/// The bag's .db3 files in name order (split bags are numbered _0, _1, ...); false with
/// *error set when there is none or the bag is MCAP.
bool bag_files(const std::string& path, std::vector<std::string>* files, std::string* error) {
  if (!is_folder(path)) {
    files->push_back(path);
    return true;
  }
  std::string metadata;
  if (!port::read_whole_file(path + "/metadata.yaml", port::kMaxTextInputBytes, &metadata).ok()) {
    *error = path + ": a folder without metadata.yaml: not a ROS 2 bag";
    return false;
  }
  if (metadata.find("storage_identifier: mcap") != std::string::npos) {
    *error = path + ": " + kMcapRefusal;
    return false;
  }
  DIR* dir = ::opendir(path.c_str());
  if (dir != nullptr) {
    while (const dirent* entry = ::readdir(dir)) {
      const std::string name = entry->d_name;
      if (ends_with(name, ".db3")) files->push_back(path + "/" + name);
      if (ends_with(name, ".mcap")) *error = path + ": " + kMcapRefusal;
    }
    ::closedir(dir);
  }
  std::sort(files->begin(), files->end());
  if (files->empty() && error->empty()) *error = path + ": no .db3 file (sqlite3 storage) in the bag";
  return !files->empty();
}

}  // namespace

bool decode_joint_state_cdr(const std::uint8_t* data, std::size_t size, JointStateMessage* message,
                            std::string* error) {
  Cdr cdr(data, size);
  std::uint32_t sec = 0, nanosec = 0, names = 0, positions = 0;
  std::string_view frame_id;
  message->names.clear();
  message->positions_rad.clear();
  bool ok = cdr.header() && cdr.u32(&sec) && cdr.u32(&nanosec) && cdr.string(&frame_id) && cdr.count(&names, 5);
  for (std::uint32_t k = 0; ok && k < names; ++k) {
    std::string_view name;
    ok = cdr.string(&name);
    message->names.push_back(name);
  }
  ok = ok && cdr.count(&positions, 8);
  for (std::uint32_t k = 0; ok && k < positions; ++k) {
    double q = 0.0;
    ok = cdr.f64(&q);
    message->positions_rad.push_back(q);
  }
  if (!ok) {
    *error = "not a CDR sensor_msgs/msg/JointState (truncated or malformed)";
    return false;
  }
  if (static_cast<std::int32_t>(sec) < 0 || nanosec >= 1000000000u) {
    *error = "header.stamp out of range";
    return false;
  }
  if (positions != names) {
    *error = std::to_string(names) + " names but " + std::to_string(positions) + " positions";
    return false;
  }
  message->stamp_us = std::uint64_t{sec} * 1000000u + (nanosec + 500u) / 1000u;
  return true;
}

#if HIVECAL_HAVE_SQLITE3

namespace {

/// Reads /joint_states of one .db3 into *log; false with log->error set.
class BagFile {
 public:
  ~BagFile() {
    sqlite3_finalize(statement_);
    sqlite3_close(db_);
  }
  bool read(const std::string& file, const RobotLogOptions& options, TimeOrder* order, RobotLog* log,
            std::string* first_names) {
    file_ = file;
    if (sqlite3_open_v2(file.c_str(), &db_, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) return fail("cannot open");
    std::int64_t topic = 0;
    if (!find_topic(&topic, log)) return false;
    if (!prepare("SELECT data FROM messages WHERE topic_id = ?1 ORDER BY timestamp, id")) return false;
    sqlite3_bind_int64(statement_, 1, topic);
    JointStateMessage message;
    std::string problem;
    int step = SQLITE_ROW;
    while ((step = sqlite3_step(statement_)) == SQLITE_ROW) {
      ++log->counters.rows;
      const auto* data = static_cast<const std::uint8_t*>(sqlite3_column_blob(statement_, 0));
      const auto size = static_cast<std::size_t>(sqlite3_column_bytes(statement_, 0));
      if (!decode_joint_state_cdr(data, size, &message, &problem)) return fail_message(log, problem);
      int source[kMaxJoints];
      const JointMatch match = match_joints(message.names, options, source);
      if (match == JointMatch::other_count) {
        return fail_message(log, other_joint_count_message(message.names, options.units.joints));
      }
      if (match == JointMatch::missing) {
        if (first_names->empty()) *first_names = join_names(message.names);
        ++log->counters.missing_joints;
        continue;
      }
      const InputJoints& joints = options.units.joints;
      JointStateRecord record;
      record.timestamp_us = message.stamp_us;
      record.joint_count = joints.count;
      bool repeated = false;
      if (!order->accept(record.timestamp_us, &repeated, &problem)) return fail_message(log, problem);
      for (int j = 0; j < joints.count; ++j) {
        record.q_rad[j] = message.positions_rad[static_cast<std::size_t>(source[j])];
        if (!std::isfinite(record.q_rad[j]))
          return fail_message(log, "joint " + std::to_string(j + 1) + ": NaN or Inf");
        if (joints.slides(j)) {
          if (std::fabs(record.q_rad[j]) > kMaxJointTravel_m) {
            return fail_message(log, "prismatic joint q" + std::to_string(j + 1) + " = " +
                                         format_double(record.q_rad[j]) +
                                         " m is beyond any slide: not a joint position (JointState is in m)");
          }
        } else if (std::fabs(record.q_rad[j]) > kMaxJointMagnitude_rad) {
          return fail_message(log, "joint q" + std::to_string(j + 1) + " = " + format_double(record.q_rad[j]) +
                                       " rad is more than one turn: not a joint position (JointState is in rad)");
        }
      }
      if (repeated) {
        ++log->counters.repeated_time;
        continue;
      }
      record.sequence = static_cast<std::uint16_t>(log->records.size());
      log->records.push_back(record);
    }
    return step == SQLITE_DONE || fail(sqlite3_errmsg(db_));
  }
  const std::string& error() const { return error_; }

 private:
  bool fail(const std::string& problem) {
    error_ = file_ + ": " + problem;
    return false;
  }
  bool fail_message(const RobotLog* log, const std::string& problem) {
    return fail("/joint_states message " + std::to_string(log->counters.rows) + ": " + problem);
  }
  bool prepare(const char* sql) {
    sqlite3_finalize(statement_);
    statement_ = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &statement_, nullptr) == SQLITE_OK) return true;
    return fail(std::string("not a rosbag2 sqlite3 file (") + sqlite3_errmsg(db_) + ")");
  }
  bool find_topic(std::int64_t* topic, RobotLog* log) {
    if (!prepare("SELECT id, name, type, serialization_format FROM topics")) return false;
    std::string names;
    bool found = false;
    while (sqlite3_step(statement_) == SQLITE_ROW) {
      const auto text = [this](int column) {
        const unsigned char* t = sqlite3_column_text(statement_, column);
        return t == nullptr ? std::string() : std::string(reinterpret_cast<const char*>(t));
      };
      names += (names.empty() ? "" : ", ") + text(1);
      if (text(1) != "/joint_states") continue;
      if (text(2) != "sensor_msgs/msg/JointState" || text(3) != "cdr") {
        return fail("/joint_states is " + text(2) + " (" + text(3) + "), expected sensor_msgs/msg/JointState (cdr)");
      }
      *topic = sqlite3_column_int64(statement_, 0);
      found = true;
    }
    if (!found) return fail("no /joint_states topic (topics: " + (names.empty() ? std::string("none") : names) + ")");
    if (!prepare("SELECT COUNT(*) FROM messages WHERE topic_id != ?1")) return false;
    sqlite3_bind_int64(statement_, 1, *topic);
    if (sqlite3_step(statement_) == SQLITE_ROW) {
      log->counters.other_messages += static_cast<std::uint64_t>(sqlite3_column_int64(statement_, 0));
    }
    return true;
  }

  std::string file_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* statement_ = nullptr;
  std::string error_;
};

}  // namespace

RobotLog read_ros2_bag_joint_states(const std::string& path, const RobotLogOptions& options) {
  RobotLog log;
  log.format = LogFormat::ros2_bag;
  if (!options.units.angle.empty() && options.units.angle != "rad") {
    log.error = path + ": a ROS 2 bag's joint positions are in rad (sensor_msgs/JointState): --angle-unit " +
                options.units.angle + " does not apply";
    return log;
  }
  std::vector<std::string> files;
  if (!bag_files(path, &files, &log.error)) return log;
  log.error.clear();
  TimeOrder order;
  std::string first_names;
  for (const std::string& file : files) {
    BagFile bag;
    if (!bag.read(file, options, &order, &log, &first_names)) {
      log.error = bag.error();
      return log;
    }
    struct stat info {};
    if (::stat(file.c_str(), &info) == 0) log.bytes_read += static_cast<std::uint64_t>(info.st_size);
  }
  log.counters.records = log.records.size();
  if (log.counters.rows == 0) log.error = path + ": no /joint_states message";
  if (log.error.empty() && log.records.empty())
    log.error = missing_joints_message(path, expected_joint_names(options), first_names);
  log.ok = log.error.empty();
  return log;
}

#else

RobotLog read_ros2_bag_joint_states(const std::string& path, const RobotLogOptions&) {
  RobotLog log;
  log.format = LogFormat::ros2_bag;
  std::vector<std::string> files;
  if (bag_files(path, &files, &log.error)) log.error = path + ": ROS 2 bags need sqlite3, which this build has not";
  return log;
}

#endif

}  // namespace hivecal::textio
