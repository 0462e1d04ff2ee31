// A small subset of samples that spans the poses of a large set: the start a global search
// needs (the population stage of a hybrid runs on it; LM refines on every sample). Greedy
// farthest-point sampling in joint space, deterministic (ties: the lower position), no heap:
// the caller gives one scratch value per sample and room for the chosen positions.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/core/span.hpp"
#include "hivecal/model/dataset.hpp"

namespace hivecal {

/// Squared distance of two samples' poses over their first `joint_count` joints: joint
/// differences wrapped to (-pi, pi] (q and q + 2 pi are one pose; a prismatic joint's metres
/// count as radians), plus pi^2 when they measure different targets (another reflector is
/// another point, whatever the joints) [rad^2].
double pose_distance_sq(const Sample& a, const Sample& b, int joint_count);

/// Chooses min(samples.size(), chosen.size()) samples spreading over the poses: the first
/// sample, then each time the one farthest (pose_distance_sq over `joint_count` joints) from
/// every one chosen so far.
/// Writes their positions in `samples`, ascending, to chosen[0, count) and returns count.
/// `scratch` holds each sample's distance to the chosen set while it runs; it needs
/// samples.size() values, else nothing is chosen and 0 is returned. Cost: samples x count
/// distances.
std::size_t spanning_subset(Span<const Sample> samples, int joint_count, Span<double> scratch,
                            Span<std::uint32_t> chosen);

}  // namespace hivecal
