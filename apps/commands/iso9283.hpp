// The ISO 9283 test: its poses and program (`plan --iso9283 CUBE`) and its analysis
// (`hivecal iso9283`, commands.hpp); docs/iso9283.md.
#pragma once

#include "cli/options.hpp"
#include "hivecal/plan/pose_plan.hpp"

namespace hivecal::cli {

/// `plan --iso9283 X,Y,Z,SIDE|auto`: the standard's five positions in the cube (centre X, Y, Z
/// and side in the base frame [m]; auto: the largest cube found whose five positions `model`
/// reaches within `limits` with the one orientation, above --floor-z and outside
/// --keep-out-radius) with one orientation facing --tracker-position (or tool down with
/// --tool-down), written as a pose list (--out) and a URScript program of --cycles cycles
/// (--urscript), each cycle P1, P5, P4, P3, P2 (every pose approached from one direction).
Error plan_iso9283(const Options& options, const RobotModel& model, const JointLimits& limits);

}  // namespace hivecal::cli
