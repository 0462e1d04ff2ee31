// Readers and writers of the fixed-column CSV formats of docs/formats.md
// (shared/spec/io-formats.md): paired samples, poses to predict, predicted positions. The
// robot and tracker logs (hivecal's and other tools') are read by textio/logs.hpp; both read
// text through textio/delimited.hpp (port::InputFile underneath). Every error names the file
// and line; nothing is half-read silently.
#pragma once

#include <string>
#include <vector>

#include "hivecal/core/types.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/port/error.hpp"
#include "textio/delimited.hpp"

namespace hivecal::textio {

/// Reads paired static samples (`q1..q6,x,y,z`, optionally `target` after z: the reflector,
/// 1 .. kMaxTargets, 1 when absent) into a dataset; reports a full dataset as an error. Columns without a bracket unit are in `units` (SI when not declared); joints beyond
/// one turn and points beyond 100 m are refused with the likely cause (delimited.hpp).
/// `lines`, when given, receives the 1-based file line of each sample added, in order.
port::Error read_samples_csv(const std::string& path, DatasetBase* dataset, const InputUnits& units = {},
                             std::vector<std::size_t>* lines = nullptr);
/// Reads poses to predict (`q1..q6`, optionally preceded by `t`), units and checks as above.
port::Error read_joints_csv(const std::string& path, std::vector<JointVector>* poses, const InputUnits& units = {});

/// Reads joint limits: header `lower,upper` [rad], exactly six rows (joint 1 .. 6), lower < upper.
port::Error read_joint_limits_csv(const std::string& path, JointVector* lower_rad, JointVector* upper_rad);

/// `q1..q6` rows with round-trip precision (the poses-to-predict format).
std::string format_joints_csv(Span<const JointVector> poses_rad);
/// `x,y,z` rows with round-trip precision, in metres; with `length_unit` "mm" the header is
/// `x [mm],y [mm],z [mm]` and the values are in millimetres (read back by the same reader).
std::string format_points_csv(const std::vector<Vec3>& points_m, const std::string& length_unit = "m");
/// `q1..q6,x,y,z` rows with round-trip precision (`,target` 1-based when several targets).
std::string format_samples_csv(Span<const Sample> samples);

}  // namespace hivecal::textio
