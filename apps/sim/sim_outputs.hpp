// What `hivecal simulate` writes: the two capture files (wire format), the CSV logs of
// io-formats.md, and the ground truth (docs/streams.md "Outputs and ground truth").
// Every file is streamed (bounded memory whatever the session length) into a temporary
// beside its target, fsynced and renamed: a failed run leaves no partial file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/sim_model.hpp"

namespace hivecal::sim {

/// Output files; an empty path is not written.
struct OutputPaths {
  std::string robot_capture;      ///< robot stream bytes (DEVICE_INFO + JOINT_STATE frames)
  std::string tracker_capture;    ///< tracker stream bytes (DEVICE_INFO + TRACKER_POINT frames)
  std::string robot_csv;          ///< t,q1..q6 on the robot clock
  std::string tracker_csv;        ///< t,x,y,z,status on the tracker clock
  std::string truth_json;         ///< true model (robot-calibration/1) + "simulation" details
  std::string truth_samples_csv;  ///< ideal paired static samples
};

/// The standard file names inside `dir`: robot.cap, tracker.cap, robot_joints.csv,
/// tracker.csv, truth.json, truth_samples.csv.
OutputPaths output_paths_in(const std::string& dir);

/// Encodes one record as a whole frame (COBS + delimiter) appended to *bytes.
bool append_frame(const JointStateRecord& record, std::vector<std::uint8_t>* bytes);
/// Same for a tracker point.
bool append_frame(const TrackerPointRecord& record, std::vector<std::uint8_t>* bytes);
/// Same for a DEVICE_INFO.
bool append_frame(const DeviceInfoRecord& record, std::vector<std::uint8_t>* bytes);

/// Writes every requested output of `session`; false with a message at the first failure.
/// `truth_margin_s`: how far inside a stop an instant must be to count as an ideal sample.
bool write_outputs(const Session& session, const OutputPaths& paths, double truth_margin_s, std::string* error);

}  // namespace hivecal::sim
