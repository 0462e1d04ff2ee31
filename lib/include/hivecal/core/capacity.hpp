// Capacities that are build parameters: the build sets them once for the whole library
// (CMakeLists.txt, as INTERFACE definitions of the library target, so that every consumer sees
// the same sizes). Results do not depend on them (docs/determinism.md).
#pragma once

#ifndef HIVECAL_MAX_JOINTS
#define HIVECAL_MAX_JOINTS 6  // a 6-axis arm (the bare-metal default)
#endif

#ifndef HIVECAL_MAX_JOINT_TERMS
#define HIVECAL_MAX_JOINT_TERMS 4  // the gravity terms alone (the bare-metal default)
#endif

namespace hivecal {

/// Most joints one robot model holds (RobotModel::joint_count is 1 .. this): 8 in hosted builds
/// (a 7-axis arm on a linear rail), 6 on bare metal (docs/footprint.md says what each costs) [-].
inline constexpr int kMaxJoints = HIVECAL_MAX_JOINTS;
static_assert(kMaxJoints >= 6 && kMaxJoints <= 16,
              "the built-in arms have six joints; a model's joints, base, tool and terms fit a 128-bit mask");

/// Most joint terms (gravity compliance and joint-angle harmonics, model/compliance.hpp) one
/// model holds, each one more parameter: 40 in hosted builds (the 4 gravity terms and three
/// harmonic orders per joint of a 6-axis arm), 4 on bare metal (docs/footprint.md says what each
/// costs) [-].
inline constexpr int kMaxJointTerms = HIVECAL_MAX_JOINT_TERMS;
static_assert(kMaxJointTerms >= 4 && kMaxJointTerms <= 4 + 6 * kMaxJoints,
              "the four default gravity terms; at most those and three harmonic orders of every joint");

}  // namespace hivecal
