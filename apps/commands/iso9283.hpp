// The ISO 9283 test: its poses and program (`plan --iso9283 CUBE`) and its analysis
// (`hivecal iso9283`, commands.hpp); docs/iso9283.md.
#pragma once

#include "cli/options.hpp"

namespace hivecal::cli {

/// `plan --iso9283 X,Y,Z,SIDE`: the standard's five positions in the cube (centre X, Y, Z and
/// side in the base frame [m]) with one orientation facing --tracker-position (or tool down
/// with --tool-down), written as a pose list (--out) and a URScript program of --cycles cycles
/// (--urscript), each cycle P1, P5, P4, P3, P2 (every pose approached from one direction).
Error plan_iso9283(const Options& options);

}  // namespace hivecal::cli
