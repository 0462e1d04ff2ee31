// Capacities that are build parameters: the build sets them once for the whole library
// (CMakeLists.txt, as INTERFACE definitions of the library target, so that every consumer sees
// the same sizes). Results do not depend on them (docs/determinism.md).
#pragma once

#ifndef HIVECAL_MAX_JOINT_TERMS
#define HIVECAL_MAX_JOINT_TERMS 4  // the gravity terms alone (the bare-metal default)
#endif

namespace hivecal {

/// Most joint terms (gravity compliance and joint-angle harmonics, model/compliance.hpp) one
/// model holds, each one more parameter: 40 in hosted builds (the 4 gravity terms and three
/// harmonic orders per joint), 4 on bare metal (docs/footprint.md says what each costs) [-].
inline constexpr int kMaxJointTerms = HIVECAL_MAX_JOINT_TERMS;
static_assert(kMaxJointTerms >= 4 && kMaxJointTerms <= 40,
              "the four default gravity terms; at most those and three harmonic orders of six joints");

}  // namespace hivecal
