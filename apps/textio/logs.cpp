#include "textio/logs.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <sys/stat.h>

#include "hivecal/port/error.hpp"
#include "hivecal/port/input_file.hpp"
#include "textio/delimited.hpp"
#include "textio/log_rows.hpp"
#include "textio/ros2_bag.hpp"
#include "textio/text_util.hpp"

namespace hivecal::textio {
namespace {

constexpr double kMaxTime_us = 1.8e19;  // whole microseconds still fit a u64
constexpr std::uint8_t kBeamLostStatus = 1;
const char* const kTimeNames[] = {"t", "time", "timestamp"};

const char* const kRobotFormats =
    "t,q1..qN (hivecal), timestamp + actual_q_0..actual_q_5 (UR RTDE recorder) or field.header.stamp + "
    "field.nameK + field.positionK (rostopic echo -p /joint_states)";
const char* const kTrackerFormats = "a time column (t, time or timestamp) and x, y, z, units in brackets allowed";

std::string column_name(const char* prefix, int k) {
  return prefix + std::to_string(k);
}

/// "found 'header' (semicolon-separated, 4 columns)" for messages.
std::string found(const DelimitedReader& r) {
  return "found " + port::quoted(r.header_line(), 120) + " (" + delimiter_name(r.delimiter()) + "-separated, " +
         std::to_string(r.columns().size()) + " columns)";
}

int find_time(const DelimitedReader& r) {
  for (const char* name : kTimeNames) {
    const int at = r.find(name);
    if (at >= 0) return at;
  }
  return -1;
}

/// True when the header has the UR's six columns "<prefix><first>" .. "<prefix><first+5>".
bool has_all(const DelimitedReader& r, const char* prefix, int first) {
  for (int k = 0; k < kSixJoints; ++k) {
    if (r.find(column_name(prefix, first + k)) < 0) return false;
  }
  return true;
}

bool looks_like_tracker(const DelimitedReader& r) {
  return find_time(r) >= 0 && r.find("x") >= 0 && r.find("y") >= 0 && r.find("z") >= 0;
}
bool looks_like_robot(const DelimitedReader& r) {
  return r.find("q1") >= 0 || has_all(r, "actual_q_", 0) || has_all(r, "target_q_", 0) ||
         r.find("field.header.stamp") >= 0;
}

/// Factor of column `index` to SI for `quantity`; false with the reader's error set.
bool scale_of(DelimitedReader& r, int index, Quantity quantity, double* scale) {
  return r.column_scale(static_cast<std::size_t>(index), quantity, scale);
}

/// The time column: field -> whole microseconds, checked to increase.
class TimeColumn {
 public:
  /// Uses column `index`, whose unit defaults to `default_unit` when the header gives none.
  bool init(DelimitedReader& r, int index, const char* default_unit) {
    index_ = static_cast<std::size_t>(index);
    const Column& c = r.columns()[index_];
    double scale_s = 1.0;
    if (!si_scale(c.unit.empty() ? default_unit : c.unit, Quantity::time, &scale_s))
      return scale_of(r, index, Quantity::time, &scale_s);
    nanoseconds_ = scale_s == 1e-9;
    scale_us_ = scale_s * 1e6;
    return true;
  }
  /// The row's time into *t_us; *repeated when it equals the previous row's. False with the
  /// reader's error set when it is not a number, out of range or earlier than the previous.
  bool read(DelimitedReader& r, std::uint64_t* t_us, bool* repeated) {
    std::uint64_t ns = 0;
    if (nanoseconds_ && r.whole_number(index_, &ns)) {
      *t_us = ns / 1000 + (ns % 1000 >= 500 ? 1 : 0);  // exact for Unix times in ns (> 2^53)
    } else {
      double us = 0.0;
      if (!r.number(index_, scale_us_, &us)) return false;
      if (!(us >= 0.0 && us <= kMaxTime_us)) {
        return r.fail("timestamp " + format_double(us * 1e-6) + " s outside 0 .. 1.8e13 s");
      }
      *t_us = static_cast<std::uint64_t>(us + 0.5);
    }
    std::string problem;
    if (!order_.accept(*t_us, repeated, &problem)) return r.fail(problem);
    return true;
  }

 private:
  std::size_t index_ = 0;
  double scale_us_ = 1e6;
  bool nanoseconds_ = false;
  TimeOrder order_;
};

/// Columns of a robot log once its format is known: time and where each joint comes from.
struct RobotLayout {
  TimeColumn time;
  InputJoints joints;                  ///< joints per record and which slide: the arm's (RTDE: a UR's six)
  int q[kMaxJoints] = {};              ///< hivecal / RTDE: column of joint j
  double q_scale[kMaxJoints] = {};     ///< its factor to rad (a prismatic joint's to m)
  std::vector<int> names;              ///< rostopic: field.nameK columns
  std::vector<int> positions;          ///< rostopic: field.positionK columns
  std::vector<double> position_scale;  ///< their factors to rad
};

/// Columns "<prefix><first+j>" as the layout's joints (a prismatic one a length).
bool fixed_joints(DelimitedReader& r, const char* prefix, int first, RobotLayout* layout) {
  for (int j = 0; j < layout->joints.count; ++j) {
    layout->q[j] = r.find(column_name(prefix, first + j));
    const Quantity quantity = layout->joints.slides(j) ? Quantity::length : Quantity::angle;
    if (!scale_of(r, layout->q[j], quantity, &layout->q_scale[j])) return false;
  }
  return true;
}

/// A hivecal log's joints: q1 .. qN for the arm's N (`joints`); another count is refused naming both.
bool hivecal_joints(DelimitedReader& r, const InputJoints& joints, RobotLayout* layout) {
  int count = 0;
  while (count < 99 && r.find(column_name("q", count + 1)) >= 0) ++count;
  if (count != joints.count) {
    return r.fail("its header has joint columns q1..q" + std::to_string(count) + ", but the robot model has " +
                  std::to_string(joints.count) + " joints (" + joint_names(joints.count) +
                  "): the joints of another arm? (--robot-model names the arm)");
  }
  layout->joints = joints;
  return fixed_joints(r, "q", 1, layout);
}

/// Recognises the robot format from the header; false with a message naming what was
/// expected and what was found.
bool robot_layout(DelimitedReader& r, const RobotLogOptions& options, LogFormat* format, RobotLayout* layout) {
  const InputJoints& joints = options.units.joints;
  const int stamp = r.find("field.header.stamp");
  if (stamp >= 0 && r.find("field.name0") >= 0) {
    *format = LogFormat::rostopic;
    for (int k = 0;; ++k) {
      const int name = r.find(column_name("field.name", k));
      const int position = r.find(column_name("field.position", k));
      if (name < 0 || position < 0) break;
      double scale = 1.0;
      if (!scale_of(r, position, Quantity::angle, &scale)) return false;
      layout->names.push_back(name);
      layout->positions.push_back(position);
      layout->position_scale.push_back(scale);
    }
    layout->joints = joints;
    if (layout->names.size() < static_cast<std::size_t>(joints.count)) {
      return r.fail("rostopic log with " + std::to_string(layout->names.size()) +
                    " joints (field.nameK with field.positionK), but the robot model has " +
                    std::to_string(joints.count) + " joints (" + joint_names(joints.count) +
                    "): the joints of another arm? (--robot-model names the arm)");
    }
    return layout->time.init(r, stamp, "ns");
  }
  const int time = find_time(r);
  if (has_all(r, "actual_q_", 0) && r.find("timestamp") >= 0) {
    *format = LogFormat::ur_rtde;
    if (!ur_joints(joints)) {
      const std::string arm = options.arm_name.empty() ? "" : " " + port::quoted(options.arm_name, 60);
      return r.fail(
          "a UR RTDE log (actual_q_0..actual_q_5: a UR controller's six revolute joints), but the robot model" + arm +
          " has " + std::to_string(joints.count) + " joints (" + joint_names(joints.count) +
          (joints.prismatic != 0 ? ", a prismatic one among them" : "") +
          "): RTDE is UR's alone; give the arm's joints as t,q1..q" + std::to_string(joints.count) +
          " (docs/formats.md) or --robot-model the UR that recorded it");
    }
    return fixed_joints(r, "actual_q_", 0, layout) && layout->time.init(r, r.find("timestamp"), "s");
  }
  if (r.find("q1") >= 0 && time >= 0) {
    *format = LogFormat::hivecal_robot;
    return hivecal_joints(r, joints, layout) && layout->time.init(r, time, "s");
  }
  if (has_all(r, "target_q_", 0)) {
    return r.fail(
        "UR RTDE log without timestamp and actual_q_0..actual_q_5: target_q_k are the commanded "
        "positions, not the measured ones; record timestamp and actual_q");
  }
  if (looks_like_tracker(r)) {
    return r.fail("a tracker log (time, x, y, z), not a robot joint log: --robot and --tracker swapped?");
  }
  return r.fail("not a robot joint log: expected " + std::string(kRobotFormats) + "; " + found(r));
}

/// Appends a row's record numbered in reading order, or counts it once more at a time
/// already read (repeated_time) and drops it.
template <typename Log, typename Record>
void keep_record(Record record, bool repeated, Log* log) {
  if (repeated) {
    ++log->counters.repeated_time;
    return;
  }
  record.sequence = static_cast<std::uint16_t>(log->records.size());
  log->records.push_back(record);
}

/// After the last row: the record count, the bytes read, the reader's error, or "no data
/// rows" for a log without any.
template <typename Log>
void finish_rows(DelimitedReader& r, Log* log) {
  log->counters.records = log->records.size();
  log->bytes_read = r.bytes_read();
  log->error = r.error();
  if (log->error.empty() && log->counters.rows == 0) log->error = r.name() + ": no data rows";
}

/// Reads the rows of an opened robot log.
RobotLog read_robot_rows(DelimitedReader& r, const RobotLogOptions& options) {
  RobotLog log;
  r.set_units(options.units);
  RobotLayout layout;
  std::string first_names;  // rostopic: the names of the first row, for a message
  bool good = r.read_header() && robot_layout(r, options, &log.format, &layout);
  std::vector<std::string_view> names;
  while (good && r.next_row()) {
    ++log.counters.rows;
    JointStateRecord record;
    int source[kMaxJoints] = {};  // rostopic: which field.positionK holds joint j
    if (!layout.names.empty()) {
      names.clear();
      for (const int k : layout.names) names.push_back(r.fields()[static_cast<std::size_t>(k)]);
      const JointMatch match = match_joints(names, options, source);
      if (match == JointMatch::other_count) {
        good = r.fail(other_joint_count_message(names, options.units.joints));
        break;
      }
      if (match == JointMatch::missing) {
        if (first_names.empty()) first_names = join_names(names);
        ++log.counters.missing_joints;
        continue;
      }
    }
    bool repeated = false;
    if (!layout.time.read(r, &record.timestamp_us, &repeated)) break;
    record.joint_count = layout.joints.count;
    for (int j = 0; j < layout.joints.count; ++j) {
      if (layout.names.empty()) {
        good = good && r.number(static_cast<std::size_t>(layout.q[j]), layout.q_scale[j], &record.q_rad[j]);
      } else {
        const auto k = static_cast<std::size_t>(source[j]);
        good =
            good && r.number(static_cast<std::size_t>(layout.positions[k]), layout.position_scale[k], &record.q_rad[j]);
      }
    }
    for (int j = 0; good && j < layout.joints.count; ++j) {
      if (!std::isfinite(record.q_rad[j])) good = r.fail("joint " + std::to_string(j + 1) + ": NaN or Inf");
      const int column = layout.names.empty() ? layout.q[j] : layout.positions[static_cast<std::size_t>(source[j])];
      good =
          good && (layout.joints.slides(j) ? r.check_slide(j + 1, static_cast<std::size_t>(column), record.q_rad[j])
                                           : r.check_joint(j + 1, static_cast<std::size_t>(column), record.q_rad[j]));
    }
    if (!good) break;
    keep_record(record, repeated, &log);
  }
  finish_rows(r, &log);
  if (log.error.empty() && log.records.empty() && log.counters.missing_joints > 0) {
    log.error = missing_joints_message(r.name(), expected_joint_names(options), first_names);
  }
  log.ok = log.error.empty();
  return log;
}

/// Columns of a tracker log.
struct TrackerLayout {
  TimeColumn time;
  int xyz[3] = {};
  double scale[3] = {};
  int status = -1;  ///< -1 when absent
};

bool tracker_layout(DelimitedReader& r, LogFormat* format, TrackerLayout* layout) {
  if (!looks_like_tracker(r)) {
    if (looks_like_robot(r)) return r.fail("a robot joint log, not a tracker log: --robot and --tracker swapped?");
    return r.fail("not a tracker log: expected " + std::string(kTrackerFormats) + "; " + found(r));
  }
  static const char* const kAxes[] = {"x", "y", "z"};
  bool units = false;
  for (int k = 0; k < 3; ++k) {
    layout->xyz[k] = r.find(kAxes[k]);
    units = units || !r.columns()[static_cast<std::size_t>(layout->xyz[k])].unit.empty();
    if (!scale_of(r, layout->xyz[k], Quantity::length, &layout->scale[k])) return false;
  }
  layout->status = r.find("status");
  *format = r.find("t") >= 0 && !units ? LogFormat::hivecal_tracker : LogFormat::tracker_export;
  return layout->time.init(r, find_time(r), "s");
}

/// x, y, z and status of a tracker row into *record; false with the reader's error set.
bool tracker_point(DelimitedReader& r, const TrackerLayout& layout, TrackerPointRecord* record) {
  record->status = 0;
  bool all_empty = true;
  for (const int k : layout.xyz) all_empty = all_empty && r.fields()[static_cast<std::size_t>(k)].empty();
  if (layout.status >= 0) {
    double status = 0.0;
    if (!r.number(static_cast<std::size_t>(layout.status), 1.0, &status)) return false;
    if (!(status >= 0.0 && status <= 255.0) || status != std::floor(status))
      return r.fail("status must be an integer 0..255");
    record->status = static_cast<std::uint8_t>(status);
  }
  if (all_empty) {  // an export's lost beam: no coordinates
    for (double& c : record->point_m) c = std::nan("");
    if (record->status == 0) record->status = kBeamLostStatus;
    return true;
  }
  int nan_count = 0;
  for (int k = 0; k < 3; ++k) {
    if (!r.number(static_cast<std::size_t>(layout.xyz[k]), layout.scale[k], &record->point_m[k])) return false;
    nan_count += std::isnan(record->point_m[k]) ? 1 : 0;
  }
  // No status column: three NaN is a lost beam, the wire format's mark.
  if (layout.status < 0 && nan_count == 3) record->status = kBeamLostStatus;
  if (record->status != 0) return true;  // not valid: NaN allowed
  for (const double c : record->point_m) {
    if (!std::isfinite(c)) return r.fail("NaN or Inf in x, y or z of a valid point");
  }
  const std::size_t xyz[3] = {static_cast<std::size_t>(layout.xyz[0]), static_cast<std::size_t>(layout.xyz[1]),
                              static_cast<std::size_t>(layout.xyz[2])};
  return r.check_point(xyz, record->point_m);
}

TrackerLog read_tracker_rows(DelimitedReader& r, const InputUnits& units) {
  TrackerLog log;
  r.set_units(units);
  TrackerLayout layout;
  bool good = r.read_header() && tracker_layout(r, &log.format, &layout);
  while (good && r.next_row()) {
    ++log.counters.rows;
    TrackerPointRecord record;
    bool repeated = false;
    good = layout.time.read(r, &record.timestamp_us, &repeated) && tracker_point(r, layout, &record);
    if (!good) break;
    if (!repeated) log.counters.not_valid += record.is_valid() ? 0u : 1u;
    keep_record(record, repeated, &log);
  }
  finish_rows(r, &log);
  log.ok = log.error.empty();
  return log;
}

template <typename Log>
Log failed(std::string error) {
  Log log;
  log.error = std::move(error);
  return log;
}

constexpr char kMcapMagic[] = "\x89MCAP0\r\n";
constexpr char kSqliteMagic[] = "SQLite format 3";  // followed by a NUL

}  // namespace

const char* log_format_name(LogFormat format) {
  switch (format) {
    case LogFormat::unknown: return "unknown";
    case LogFormat::hivecal_robot: return "hivecal robot log";
    case LogFormat::ur_rtde: return "UR RTDE log";
    case LogFormat::rostopic: return "rostopic joint_states log";
    case LogFormat::ros2_bag: return "ROS 2 bag";
    case LogFormat::hivecal_tracker: return "hivecal tracker log";
    case LogFormat::tracker_export: return "tracker export";
  }
  return "unknown";
}

bool parse_joint_names(std::string_view text, RobotLogOptions* options) {
  std::vector<std::string> names;
  for (std::size_t start = 0;;) {
    const std::size_t comma = std::min(text.find(',', start), text.size());
    const std::string_view name = trim(text.substr(start, comma - start));
    if (name.empty() || names.size() == static_cast<std::size_t>(kMaxJoints)) return false;
    // A joint named twice: two columns would be read as one.
    if (std::find(names.begin(), names.end(), name) != names.end()) return false;
    names.emplace_back(name);
    if (comma == text.size()) break;
    start = comma + 1;
  }
  options->joint_names = std::move(names);
  return true;
}

bool ur_joints(const InputJoints& joints) {
  return joints.count == kSixJoints && joints.prismatic == 0;
}

std::string describe_log(LogFormat format, const LogCounters& c) {
  std::string out = std::string(log_format_name(format)) + ": " + std::to_string(c.rows) + " rows, " +
                    std::to_string(c.records) + " records";
  const struct {
    std::uint64_t count;
    const char* what;
  } notes[] = {{c.repeated_time, "dropped (repeated time)"},
               {c.missing_joints, "dropped (not all joints named)"},
               {c.not_valid, "not valid (beam lost or status != 0)"},
               {c.other_messages, "messages of other topics"}};
  for (const auto& n : notes) {
    if (n.count > 0) out += ", " + std::to_string(n.count) + " " + n.what;
  }
  return out;
}

namespace {

/// True when `head` (a file's first bytes) starts with a line of text that names columns: a letter
/// and a delimiter in 3+ bytes of printable ASCII or whole UTF-8 characters ("(°)", "[µm]").
bool header_line(std::string_view head) {
  bool delimiter = false;
  bool letter = false;
  std::size_t at = 0;
  for (; at < head.size() && head[at] != '\n'; ++at) {
    const auto c = static_cast<unsigned char>(head[at]);
    const std::size_t length = port::utf8_sequence_bytes(head, at);
    if (length > 1) {
      at += length - 1;
      continue;
    }
    // A capture's frames end in 0x00 and are mostly bytes outside printable ASCII.
    if (!((c >= 0x20 && c < 0x7f) || c == '\t' || c == '\r')) return false;
    delimiter = delimiter || c == ',' || c == ';' || c == '\t' || c == ' ';
    letter = letter || (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z');
  }
  return delimiter && letter && at >= 3;
}

}  // namespace

StreamFileKind detect_stream_file(const std::string& path) {
  struct stat info {};
  if (::stat(path.c_str(), &info) == 0 && S_ISDIR(info.st_mode)) return StreamFileKind::ros2_bag;
  port::InputFile file;  // regular files only: a device or FIFO is left to the capture reader to refuse
  if (!file.open(path, port::kMaxStreamInputBytes).ok() || file.is_stdin()) return StreamFileKind::capture;
  char bytes[4096];
  std::size_t got = 0;
  if (file.read(reinterpret_cast<unsigned char*>(bytes), sizeof bytes, &got) != Status::ok) {
    return StreamFileKind::capture;
  }
  const std::string_view head(bytes, got);
  if (got >= 8 && std::memcmp(bytes, kMcapMagic, 8) == 0) return StreamFileKind::mcap;
  if (got >= 16 && std::memcmp(bytes, kSqliteMagic, 16) == 0) return StreamFileKind::ros2_bag;
  std::string_view body;
  if (utf8_text(head, path, &body).ok()) return header_line(body) ? StreamFileKind::text_log : StreamFileKind::capture;
  // UTF-16 or UTF-32 by its first bytes (utf8_text). A capture may start so too (an idle 0x00
  // before a frame): a log only when its first line, without the byte order mark and the NUL
  // bytes (a character beyond ASCII as one '?'), is a header; the text reader then says to save
  // it as UTF-8.
  std::string narrow;
  for (const char c : head) {
    if (c != '\0') narrow += c;
  }
  if (narrow.rfind("\xFF\xFE", 0) == 0 || narrow.rfind("\xFE\xFF", 0) == 0) narrow.erase(0, 2);  // the mark
  for (char& c : narrow) c = static_cast<unsigned char>(c) < 0x80 ? c : '?';
  return header_line(narrow) ? StreamFileKind::text_log : StreamFileKind::capture;
}

RobotLog read_robot_log(const std::string& path, const RobotLogOptions& options) {
  switch (detect_stream_file(path)) {
    case StreamFileKind::ros2_bag: return read_ros2_bag_joint_states(path, options);
    case StreamFileKind::mcap: return failed<RobotLog>(path + ": " + kMcapRefusal);
    case StreamFileKind::capture:
    case StreamFileKind::text_log: break;
  }
  DelimitedReader r;
  if (!r.open(path)) return failed<RobotLog>(r.error());
  return read_robot_rows(r, options);
}

TrackerLog read_tracker_log(const std::string& path, const InputUnits& units) {
  switch (detect_stream_file(path)) {
    case StreamFileKind::ros2_bag:
      return failed<TrackerLog>(path +
                                ": a ROS 2 bag (robot joints), not a tracker log: --robot and --tracker swapped?");
    case StreamFileKind::mcap: return failed<TrackerLog>(path + ": " + kMcapRefusal);
    case StreamFileKind::capture:
    case StreamFileKind::text_log: break;
  }
  DelimitedReader r;
  if (!r.open(path)) return failed<TrackerLog>(r.error());
  return read_tracker_rows(r, units);
}

RobotLog parse_robot_log(std::string_view text, const std::string& name, const RobotLogOptions& options) {
  DelimitedReader r;
  r.open_memory(text, name);
  return read_robot_rows(r, options);
}

TrackerLog parse_tracker_log(std::string_view text, const std::string& name, const InputUnits& units) {
  DelimitedReader r;
  r.open_memory(text, name);
  return read_tracker_rows(r, units);
}

}  // namespace hivecal::textio
