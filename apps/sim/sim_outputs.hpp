// What `hivecal simulate` writes: the two capture files (wire format), the CSV logs of
// io-formats.md, and the ground truth (docs/streams.md "Outputs and ground truth").
// Every file is streamed (bounded memory whatever the session length) into a file staged in
// a port::OutputSet; the caller commits them together: a failed run leaves no file.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "hivecal/port/error.hpp"
#include "hivecal/port/output_files.hpp"
#include "sim/sim_model.hpp"

namespace hivecal::sim {

/// File names of the captures inside the output folder.
inline constexpr const char* kRobotCaptureName = "robot.cap";
inline constexpr const char* kTrackerCaptureName = "tracker.cap";  ///< see kRobotCaptureName
/// The other outputs, in this order: the two CSV logs, then the ground truth.
inline constexpr const char* kLogAndTruthNames[] = {"robot_joints.csv", "tracker.csv", "truth.json",
                                                    "truth_samples.csv"};

/// Every file name stage_outputs() writes into its folder (the captures only `with_captures`).
std::vector<std::string> output_names(bool with_captures);

/// Encodes one record as a whole frame (COBS + delimiter) appended to *bytes.
bool append_frame(const JointStateRecord& record, std::vector<std::uint8_t>* bytes);
/// Same for a tracker point.
bool append_frame(const TrackerPointRecord& record, std::vector<std::uint8_t>* bytes);
/// Same for a DEVICE_INFO.
bool append_frame(const DeviceInfoRecord& record, std::vector<std::uint8_t>* bytes);

/// Stages every output of `session` (the captures only `with_captures`) as files of output
/// folder `folder` of `outputs`; the caller commits. `truth_margin_s`: how far inside a stop
/// an instant must be to count as an ideal sample.
port::Error stage_outputs(const Session& session, bool with_captures, double truth_margin_s, port::OutputSet* outputs,
                          std::size_t folder);

}  // namespace hivecal::sim
