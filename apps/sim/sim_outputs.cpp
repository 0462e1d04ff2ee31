#include "sim/sim_outputs.hpp"

#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <functional>

#include "hivecal/port/output_files.hpp"
#include "hivecal/wire/codec.hpp"
#include "textio/robot_description.hpp"
#include "textio/csv.hpp"
#include "textio/json.hpp"
#include "textio/text_util.hpp"
#include "record/result_json.hpp"

namespace hivecal::sim {
namespace {

constexpr std::size_t kFlushBytes = 1 << 16;  // streamed files are written in 64 kB pieces

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

/// Streams one device's frames into a capture file; false if a record cannot be encoded.
template <typename Stream, typename Record>
bool write_capture(const Session& session, port::StagedFile& file) {
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
  return encoded;
}

/// Streams rows produced by `row(record)` under `header` into a CSV file.
template <typename Stream, typename Record, typename Row>
bool write_csv(const Session& session, const char* header, Row row, port::StagedFile& file) {
  file.write(std::string(header) + "\n");
  Stream stream(session);
  Record record;
  while (stream.next(&record)) file.write(row(record));
  return true;
}

std::string robot_row(const JointStateRecord& r) {
  std::string line = seconds_text(r.timestamp_us);
  for (int j = 0; j < r.joint_count; ++j) line += "," + textio::format_double(r.q_rad[j]);
  return line + "\n";
}

std::string tracker_row(const TrackerPointRecord& r) {
  std::string line = seconds_text(r.timestamp_us);
  for (const double x : r.point_m) line += "," + textio::format_double(x);
  return line + "," + std::to_string(r.status) + "\n";
}

std::string truth_sample_row(const TruthSample& s, int joints) {
  std::string line =
      std::to_string(s.waypoint) + "," + seconds_text(s.tracker_us) + "," + textio::format_double(s.robot_us * 1e-6);
  for (int j = 0; j < joints; ++j) line += "," + textio::format_double(s.q_rad(j));
  for (int a = 0; a < 3; ++a) line += "," + textio::format_double(s.point_m(a));
  return line + "\n";
}

void write_simulation_members(const Session& session, double truth_margin_s, textio::JsonWriter& json) {
  const SimConfig& c = session.config();
  const SimTruth& truth = session.truth();
  json.key("simulation").begin_object();
  json.key("format").value("hivecal-sim-truth/1");
  json.key("seed").value(static_cast<unsigned long long>(c.seed));
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
  for (const JointVector& q : session.waypoints())
    json.inline_array(q.data(), static_cast<std::size_t>(session.truth().model.joint_count));
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

bool write_truth_json(const Session& session, double truth_margin_s, port::StagedFile& out) {
  record::CalibrationFile file;
  file.robot = session.config().robot_name;
  file.convention = session.config().convention;
  file.modified_base = session.config().modified_base;
  file.model = session.truth().model;
  file.base_to_tracker = session.truth().base_to_tracker;
  out.write(record::format_calibration_json(
      file, [&](textio::JsonWriter& json) { write_simulation_members(session, truth_margin_s, json); }));
  return true;
}

bool write_truth_samples(const Session& session, double margin_s, port::StagedFile& file) {
  const int joints = session.truth().model.joint_count;
  file.write("waypoint,t_tracker,t_robot," + textio::joint_header(joints) + ",x,y,z\n");
  for (const TruthSample& s : truth_samples(session, margin_s)) file.write(truth_sample_row(s, joints));
  return true;
}

}  // namespace

bool append_frame(const JointStateRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_joint_state, bytes);
}

bool append_frame(const TrackerPointRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_tracker_point, bytes);
}

bool append_frame(const DeviceInfoRecord& record, std::vector<std::uint8_t>* bytes) {
  return append_with(record, encode_device_info, bytes);
}

std::vector<std::string> output_names(bool with_captures) {
  std::vector<std::string> names;
  if (with_captures) names = {kRobotCaptureName, kTrackerCaptureName};
  for (const char* name : kLogAndTruthNames) names.push_back(name);
  return names;
}

port::Error stage_outputs(const Session& session, bool with_captures, double truth_margin_s, port::OutputSet* outputs,
                          std::size_t folder) {
  using Writer = std::function<bool(port::StagedFile&)>;
  const std::pair<const char*, Writer> jobs[] = {
      {kRobotCaptureName,
       [&](port::StagedFile& f) { return write_capture<RobotStream, JointStateRecord>(session, f); }},
      {kTrackerCaptureName,
       [&](port::StagedFile& f) { return write_capture<TrackerStream, TrackerPointRecord>(session, f); }},
      {kLogAndTruthNames[0],
       [&](port::StagedFile& f) {
         const std::string header = "t," + textio::joint_header(session.truth().model.joint_count);
         return write_csv<RobotStream, JointStateRecord>(session, header.c_str(), robot_row, f);
       }},
      {kLogAndTruthNames[1],
       [&](port::StagedFile& f) {
         return write_csv<TrackerStream, TrackerPointRecord>(session, "t,x,y,z,status", tracker_row, f);
       }},
      {kLogAndTruthNames[2], [&](port::StagedFile& f) { return write_truth_json(session, truth_margin_s, f); }},
      {kLogAndTruthNames[3], [&](port::StagedFile& f) { return write_truth_samples(session, truth_margin_s, f); }},
  };
  for (const auto& [name, job] : jobs) {
    const bool capture = std::string(name) == kRobotCaptureName || std::string(name) == kTrackerCaptureName;
    if (capture && !with_captures) continue;
    port::StagedFile* file = nullptr;
    port::Error error = outputs->stage(folder, name, &file);
    if (!error.ok()) return error;
    if (!job(*file)) return port::Error::failure(std::string(name) + ": a record could not be encoded");
    error = file->finish();
    if (!error.ok()) return error;
  }
  return port::Error{};
}

}  // namespace hivecal::sim
