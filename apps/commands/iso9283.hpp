// The ISO 9283 test: its poses and program (`plan --iso9283 CUBE`) and its analysis
// (`hivecal iso9283`, commands.hpp); docs/iso9283.md.
#pragma once

#include <cstddef>
#include <vector>

#include "cli/options.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/plan/pose_plan.hpp"

namespace hivecal::cli {

/// The reaches of one commanded pose.
struct PoseReaches {
  Sample first;                  ///< the first reach (its joints: the command; its target)
  std::size_t line = 0;          ///< file line of the first reach (0: unknown)
  std::vector<Vec3> measured_m;  ///< every reach's measured point [m]
};

/// `samples` grouped by pose and target, in the order of their first reach: a sample joins the
/// latest pose whose first reach is the same point (same_point: joints within
/// kSamePoseTolerance_rad, same target), else starts a pose. `lines[s.index]` is the file line
/// of sample s. Linear in the samples: the poses are hashed by cells of their first reach's
/// joints, and a sample compares only with the poses of the cells its tolerance touches (at
/// most 2^6); *comparisons (optional) counts the same_point calls made.
std::vector<PoseReaches> group_reaches(Span<const Sample> samples, const std::vector<std::size_t>& lines,
                                       std::size_t* comparisons = nullptr);

/// `plan --iso9283 X,Y,Z,SIDE|auto`: the standard's five positions in the cube (centre X, Y, Z
/// and side in the base frame [m]; auto: the largest cube found whose five positions `model`
/// reaches within `limits` with the one orientation, above --floor-z and outside
/// --keep-out-radius) with one orientation facing --tracker-position (or tool down with
/// --tool-down), written as a pose list (--out) and a URScript program of --cycles cycles
/// (--urscript), each cycle P1, P5, P4, P3, P2 (every pose approached from one direction).
Error plan_iso9283(const Options& options, const RobotModel& model, const JointLimits& limits);

}  // namespace hivecal::cli
