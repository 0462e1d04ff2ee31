#include "sim_outputs.hpp"

#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <functional>

#include "calibration_json.hpp"
#include "csv.hpp"
#include "hivecal/wire/codec.hpp"
#include "json.hpp"
#include "text_util.hpp"

namespace hivecal::sim {
namespace {

constexpr std::size_t kFlushBytes = 1 << 16;  // streamed files are written in 64 kB pieces

/// A file written through a temporary beside it and renamed by commit().
class StreamingFile {
 public:
  StreamingFile(const std::string& path, std::string* error) : path_(path), temp_(path + ".tmp") {
    file_ = std::fopen(temp_.c_str(), "wb");
    if (file_ == nullptr) *error = path + ": cannot create a temporary file beside it: " + std::strerror(errno);
  }
  ~StreamingFile() {
    if (file_ != nullptr) {
      std::fclose(file_);
      std::remove(temp_.c_str());
    }
  }
  StreamingFile(const StreamingFile&) = delete;
  StreamingFile& operator=(const StreamingFile&) = delete;

  bool ok() const { return file_ != nullptr; }
  void write(const void* bytes, std::size_t count) { failed_ = failed_ || std::fwrite(bytes, 1, count, file_) != count; }
  void write(const std::string& text) { write(text.data(), text.size()); }
  /// Flushes, fsyncs and renames onto the target.
  bool commit(std::string* error) {
    bool good = !failed_ && std::fflush(file_) == 0 && ::fsync(fileno(file_)) == 0;
    good = std::fclose(file_) == 0 && good;
    file_ = nullptr;
    if (!good || std::rename(temp_.c_str(), path_.c_str()) != 0) {
      *error = path_ + ": write failed: " + std::strerror(errno);
      std::remove(temp_.c_str());
      return false;
    }
    return true;
  }

 private:
  std::string path_;
  std::string temp_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
};

template <typename Record, typename Encoder>
bool append_with(const Record& record, Encoder encode, std::vector<std::uint8_t>* bytes) {
  std::uint8_t frame[kMaxFrameBytes];
  std::size_t written = 0;
  if (encode(record, Span<std::uint8_t>(frame), &written) != Status::ok) return false;
  bytes->insert(bytes->end(), frame, frame + written);
  return true;
}

/// Seconds on a device clock, exactly as the microsecond timestamp ("12.008000").
std::string seconds_text(std::uint64_t t_us) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%" PRIu64 ".%06" PRIu64, t_us / 1000000, t_us % 1000000);
  return buffer;
}

/// Streams one device's frames into a capture file.
template <typename Stream, typename Record>
bool write_capture(const Session& session, const std::string& path, std::string* error) {
  StreamingFile file(path, error);
  if (!file.ok()) return false;
  Stream stream(session);
  std::vector<std::uint8_t> bytes;
  bool encoded = append_frame(stream.device_info(), &bytes);
  Record record;
  while (encoded && stream.next(&record)) {
    encoded = append_frame(record, &bytes);
    if (bytes.size() >= kFlushBytes) {
      file.write(bytes.data(), bytes.size());
      bytes.clear();
    }
  }
  file.write(bytes.data(), bytes.size());
  if (!encoded) {
    *error = path + ": a record could not be encoded";
    return false;
  }
  return file.commit(error);
}

/// Streams rows produced by `row(record)` under `header` into a CSV file.
template <typename Stream, typename Record, typename Row>
bool write_csv(const Session& session, const std::string& path, const char* header, Row row, std::string* error) {
  StreamingFile file(path, error);
  if (!file.ok()) return false;
  file.write(std::string(header) + "\n");
  Stream stream(session);
  Record record;
  while (stream.next(&record)) file.write(row(record));
  return file.commit(error);
}

std::string robot_row(const JointStateRecord& r) {
  std::string line = seconds_text(r.timestamp_us);
  for (const double q : r.q_rad) line += "," + textio::format_double(q);
  return line + "\n";
}

std::string tracker_row(const TrackerPointRecord& r) {
  std::string line = seconds_text(r.timestamp_us);
  for (const double x : r.point_m) line += "," + textio::format_double(x);
  return line + "," + std::to_string(r.status) + "\n";
}

std::string truth_sample_row(const TruthSample& s) {
  std::string line = std::to_string(s.waypoint) + "," + seconds_text(s.tracker_us) + "," +
                     textio::format_double(s.robot_us * 1e-6);
  for (int j = 0; j < kJointCount; ++j) line += "," + textio::format_double(s.q_rad(j));
  for (int a = 0; a < 3; ++a) line += "," + textio::format_double(s.point_m(a));
  return line + "\n";
}

void write_simulation_members(const Session& session, double truth_margin_s, textio::JsonWriter& json) {
  const SimConfig& c = session.config();
  const SimTruth& truth = session.truth();
  json.key("simulation").begin_object();
  json.key("format").value("hivecal-sim-truth/1");
  json.key("seed").value(static_cast<long long>(c.seed));
  json.key("duration_s").value(session.duration_s());
  json.key("clock").begin_object();
  json.key("relation").value("t_robot_us = offset_us + (1 + drift) * t_tracker_us");
  json.key("offset_us").value(truth.clock_offset_us);
  json.key("drift").value(truth.clock_drift);
  json.end_object();
  json.key("nominal_tool").inline_array(truth.nominal.tool_m.data(), 3);
  json.key("geometry_errors").begin_object();
  if (c.use_deltas) {
    json.key("source").value("calibration.conf deltas");
  } else {
    json.key("length_sigma_m").value(c.length_sigma_m);
    json.key("angle_sigma_rad").value(c.angle_sigma_rad);
  }
  json.key("tool_sigma_m").value(c.tool_sigma_m);
  json.end_object();
  json.key("compliance").begin_object();
  json.key("joint2_rad").value(c.compliance_j2_rad);
  json.key("joint3_rad").value(c.compliance_j3_rad);
  json.end_object();
  json.key("robot_stream").begin_object();
  json.key("period_s").value(c.robot_period_s);
  json.key("jitter_s").value(c.robot_jitter_s);
  json.key("drop_probability").value(c.robot_drop_probability);
  json.key("start_s").value(c.robot_start_s);
  json.end_object();
  json.key("tracker_stream").begin_object();
  json.key("period_s").value(c.tracker_period_s);
  json.key("jitter_s").value(c.tracker_jitter_s);
  json.key("noise_m").value(c.tracker_noise_m);
  json.key("beam_lost_probability").value(c.beam_lost_probability);
  json.key("unstable_probability").value(c.unstable_probability);
  json.key("start_s").value(c.tracker_start_s);
  json.end_object();
  json.key("truth_sample_margin_s").value(truth_margin_s);
  json.key("waypoints").begin_array();
  for (const JointVector& q : session.waypoints()) json.inline_array(q.data(), kJointCount);
  json.end_array();
  json.key("stops").begin_array();
  for (const Segment& s : session.schedule()) {
    if (s.waypoint < 0) continue;
    const double span[2] = {s.start_s, s.start_s + s.duration_s};
    json.inline_array(span, 2);
  }
  json.end_array();
  json.end_object();
}

bool write_truth_json(const Session& session, const std::string& path, double truth_margin_s, std::string* error) {
  textio::CalibrationFile file;
  file.robot = session.config().robot_type;
  file.model = session.truth().model;
  file.base_to_tracker = session.truth().base_to_tracker;
  const std::string text = textio::format_calibration_json(
      file, [&](textio::JsonWriter& json) { write_simulation_members(session, truth_margin_s, json); });
  return textio::write_file_atomically(path, text, error);
}

bool write_truth_samples(const Session& session, const std::string& path, double margin_s, std::string* error) {
  StreamingFile file(path, error);
  if (!file.ok()) return false;
  file.write("waypoint,t_tracker,t_robot,q1,q2,q3,q4,q5,q6,x,y,z\n");
  for (const TruthSample& s : truth_samples(session, margin_s)) file.write(truth_sample_row(s));
  return file.commit(error);
}

}  // namespace

OutputPaths output_paths_in(const std::string& dir) {
  const std::string prefix = dir.empty() || dir.back() == '/' ? dir : dir + "/";
  return OutputPaths{prefix + "robot.cap",  prefix + "tracker.cap", prefix + "robot_joints.csv",
                     prefix + "tracker.csv", prefix + "truth.json",  prefix + "truth_samples.csv"};
}

bool append_frame(const JointStateRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_joint_state, bytes);
}

bool append_frame(const TrackerPointRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_tracker_point, bytes);
}

bool append_frame(const DeviceInfoRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_device_info, bytes);
}

bool write_outputs(const Session& session, const OutputPaths& paths, double truth_margin_s, std::string* error) {
  const std::pair<const std::string*, std::function<bool()>> jobs[] = {
      {&paths.robot_capture, [&] { return write_capture<RobotStream, JointStateRecord>(session, paths.robot_capture, error); }},
      {&paths.tracker_capture,
       [&] { return write_capture<TrackerStream, TrackerPointRecord>(session, paths.tracker_capture, error); }},
      {&paths.robot_csv,
       [&] { return write_csv<RobotStream, JointStateRecord>(session, paths.robot_csv, "t,q1,q2,q3,q4,q5,q6", robot_row, error); }},
      {&paths.tracker_csv,
       [&] { return write_csv<TrackerStream, TrackerPointRecord>(session, paths.tracker_csv, "t,x,y,z,status", tracker_row, error); }},
      {&paths.truth_json, [&] { return write_truth_json(session, paths.truth_json, truth_margin_s, error); }},
      {&paths.truth_samples_csv, [&] { return write_truth_samples(session, paths.truth_samples_csv, truth_margin_s, error); }},
  };
  for (const auto& [path, job] : jobs)
    if (!path->empty() && !job()) return false;
  return true;
}

}  // namespace hivecal::sim
