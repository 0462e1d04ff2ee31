// The ISO 9283 test: its poses and program (`plan --iso9283 CUBE`) and its analysis
// (`hivecal iso9283`, commands.hpp); docs/iso9283.md.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
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
/// joints (the arm's `joints`), and a sample compares only with the poses of the cells its
/// tolerance touches (at most 2^joints); *comparisons (optional) counts the same_point calls made.
std::vector<PoseReaches> group_reaches(Span<const Sample> samples, const std::vector<std::size_t>& lines, int joints,
                                       std::size_t* comparisons = nullptr);

/// `plan --iso9283 X,Y,Z,SIDE|auto`: the standard's five positions in the cube (centre X, Y, Z
/// and side in the base frame [m]; auto: the largest cube found whose five positions `model`
/// reaches within `limits` with the one orientation, above --floor-z and outside
/// --keep-out-radius) with one orientation facing --tracker-position (or tool down with
/// --tool-down), written as a pose list (--out) and a URScript program of --cycles cycles
/// (--urscript), each cycle P1, P5, P4, P3, P2 (every pose approached from one direction).
/// `widest`: the joint limits tried when `limits` leave no cube (blame_tool_or_limits).
Error plan_iso9283(const Options& options, const RobotModel& model, const JointLimits& limits,
                   const JointLimits& widest);

/// Why nothing met the plan's constraints when that is the tool or the joint limits, "" when
/// neither: `finds(model, limits)` searches again with the reflector at the flange (the tool is
/// why when that finds something), then with `widest` instead of `limits` (narrower on some
/// joint: the limits are why when that finds something). The text names --tool or the limits'
/// source (--joint-limits FILE, or the description's) and what to do.
std::string blame_tool_or_limits(const Options& options, const RobotModel& model, const JointLimits& limits,
                                 const JointLimits& widest,
                                 const std::function<bool(const RobotModel&, const JointLimits&)>& finds);

}  // namespace hivecal::cli
