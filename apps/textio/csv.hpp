// Readers and writers of the CSV formats of docs/formats.md (shared/spec/io-formats.md):
// robot joint log, tracker log, paired samples, poses to predict, predicted positions.
// Every error names the file and line; nothing is half-read silently.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "hivecal/dataset.hpp"
#include "hivecal/types.hpp"
#include "ur_calibration_conf.hpp"  // ParseResult

namespace hivecal::textio {

/// One row of a robot joint log (t on the robot clock).
struct RobotLogRow {
  double t_s = 0.0;                         ///< robot clock [s]
  JointVector q_rad = JointVector::Zero();  ///< joint positions [rad]
};

/// One row of a tracker log (t on the tracker clock).
struct TrackerLogRow {
  double t_s = 0.0;                 ///< tracker clock [s]
  Vec3 point_m = Vec3::Zero();      ///< position in the tracker frame [m] (NaN allowed when not valid)
  std::uint8_t status = 0;          ///< 0 valid, 1 beam lost, 2 unstable, other: not valid
};

/// Streams a robot joint log (`t,q1..q6`, extra columns ignored); timestamps must increase.
ParseResult read_robot_log(const std::string& path, const std::function<void(const RobotLogRow&)>& on_row);
/// Streams a tracker log (`t,x,y,z[,status]`); timestamps must increase.
ParseResult read_tracker_log(const std::string& path, const std::function<void(const TrackerLogRow&)>& on_row);
/// Reads paired static samples (`q1..q6,x,y,z`) into a dataset; reports a full dataset as an error.
ParseResult read_samples_csv(const std::string& path, DatasetBase* dataset);
/// Reads poses to predict (`q1..q6`, optionally preceded by `t`).
ParseResult read_joints_csv(const std::string& path, std::vector<JointVector>* poses);

/// `x,y,z` rows with round-trip precision.
std::string format_points_csv(const std::vector<Vec3>& points_m);
/// `q1..q6,x,y,z` rows with round-trip precision.
std::string format_samples_csv(Span<const Sample> samples);

/// True when the file looks like text CSV (a printable first line), false for binary captures.
bool looks_like_csv(const std::string& path);

}  // namespace hivecal::textio
