// The model's joint terms as one table of families (docs/compliance.md, "Families"): per
// family, which terms are its own (their basis, model/compliance.hpp) and how they are built
// per joint, the level its terms must clear in the significance test, the order in which the
// job admits it (the table's order: a stage per family, each adding to the previous stage's
// model) and what admits a term beyond the significance test (the period its joint turns
// through, the blocked folds). The next family (cable stretch, backlash) is one more entry, its
// JointTermKind and its basis in compliance.cpp. No heap: the table is constexpr, its rules
// function pointers.
#pragma once

#include <cstdint>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/model/compliance.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

/// Chance that a stage keeps any of its harmonic terms on an arm without harmonics
/// (Bonferroni over the terms; harmonic_term_level) [-].
inline constexpr double kHarmonicFamilyAlpha = 0.01;

/// A harmonic is admitted only when the training poses turn its joint through at least this
/// share of its period (2 pi / order): over less, it is a polynomial the geometry holds too, and
/// nothing ties it down beyond the poses' range [-].
inline constexpr double kHarmonicMinPeriodShare = 0.75;

/// One family of joint terms: an entry of kJointTermFamilies.
struct JointTermFamily {
  /// Its part of a joint-term stage's name ("LM+compliance", "LM+compliance+harmonics").
  const char* name;
  /// Whether `term` is of the family (its JointTermKind: the basis compliance_basis evaluates).
  bool (*holds)(const ComplianceTerm& term);
  /// Appends the family's terms for the joints of `model` to *terms, zero coefficients (their
  /// basis per joint), after those of the families before it in the table (called in the
  /// table's order, the builders make a set the job admits a family at a time); `size` is the
  /// family's own (the harmonics' highest order; the gravity terms read terms->load and
  /// terms->gravity_direction instead). Errors: the builder's.
  Status (*append_terms)(const RobotModel& model, int size, ComplianceModel* terms);
  /// The size the job appends when the options give no term at all (0: none by default).
  int default_size;
  /// The level in the significance test each of the family's `count` terms in a fit with `dof`
  /// residual degrees of freedom must clear, from CalibrationCompliance::significance_t [-].
  double (*level)(double compliance_t, int count, int dof);
  /// The family's terms of `model` that the training poses cannot admit: fixed at their start
  /// values before the fit (BlockedFoldCheck::coverage_rejected). Null: every term may be.
  ParamMask (*uncovered)(const RobotModel& model, Span<const Sample> train);
  /// Its added terms must predict each joint's range ends no worse than the fit without them
  /// (the blocked folds, BlockedFoldCheck).
  bool blocked_folds;
};

/// True for a gravity term (JointTermKind::gravity).
constexpr bool is_gravity_term(const ComplianceTerm& term) {
  return term.kind == JointTermKind::gravity;
}

/// The gravity family's terms: default_compliance_terms of terms->load and
/// terms->gravity_direction for `model` into *terms, which holds no term yet (the first family
/// of the table starts the set; `size` unused). Errors: default_compliance_terms's;
/// invalid_argument when *terms holds terms already.
Status append_gravity_terms(const RobotModel& model, int size, ComplianceModel* terms);
/// The harmonics' terms: append_harmonic_terms of orders 1 .. `orders`.
Status append_harmonics_of_orders(const RobotModel& model, int orders, ComplianceModel* terms);

/// A gravity term's level: compliance_t itself (`count` and `dof` unused) [-].
double gravity_term_level(double compliance_t, int count, int dof);
/// The level a family of `count` harmonic terms must clear with `dof` residual degrees of
/// freedom: `compliance_t`, raised so that an arm without any of them keeps one by chance at
/// most kHarmonicFamilyAlpha of the time (Bonferroni: each term two-sided at alpha / count, from
/// Student's t with the fit's dof, as its sigma is estimated from the residuals: 24 harmonics,
/// many samples: 3.53; a fit that leaves no redundancy cannot test a term: infinite) [-].
double harmonic_term_level(double compliance_t, int count, int dof);
/// The harmonic terms of `model` whose joint the training samples turn through less than
/// kHarmonicMinPeriodShare of the term's period.
ParamMask harmonics_short_of_their_period(const RobotModel& model, Span<const Sample> train);

/// The families, in the order the job admits them: the gravity terms ("compliance": the
/// joints bending under the arm's weight), then the joint-angle harmonics (encoder
/// eccentricity, transmission error), which must clear a level raised for their number and
/// turn their joint through most of their period. Both are checked on the blocked folds.
inline constexpr JointTermFamily kJointTermFamilies[] = {
    {"compliance", &is_gravity_term, &append_gravity_terms, 1, &gravity_term_level, nullptr, true},
    {"harmonics", &is_harmonic, &append_harmonics_of_orders, 0, &harmonic_term_level, &harmonics_short_of_their_period,
     true},
};
/// Families in kJointTermFamilies [-].
inline constexpr int kJointTermFamilyCount = static_cast<int>(sizeof(kJointTermFamilies) / sizeof(JointTermFamily));
/// Most families a table may hold (JointTermLevels and JointTermStages hold this many) [-].
inline constexpr int kMaxJointTermFamilies = 4;
static_assert(kJointTermFamilyCount <= kMaxJointTermFamilies, "the table holds more families than a set");

/// A set of a table's families: bit f for its entry f (kMaxJointTermFamilies bits used).
using JointTermFamilySet = std::uint8_t;
/// Every family of a table of `count`.
constexpr JointTermFamilySet all_joint_term_families(int count) {
  return static_cast<JointTermFamilySet>((1u << count) - 1u);
}

/// The family of `term` in `families`: the first entry that holds it; -1 when none does (the
/// entries beyond kMaxJointTermFamilies are not read, here and below).
int joint_term_family(const ComplianceTerm& term, Span<const JointTermFamily> families = kJointTermFamilies);
/// The families the terms of `terms` belong to.
JointTermFamilySet joint_term_families_of(const ComplianceModel& terms,
                                          Span<const JointTermFamily> families = kJointTermFamilies);
/// The parameters (full_params.hpp) of `model`'s terms of the families in `set`.
ParamMask joint_term_params_mask(const RobotModel& model, JointTermFamilySet set,
                                 Span<const JointTermFamily> families = kJointTermFamilies);

/// The joint-term stages of `terms`, each the set of families its model holds.
struct JointTermStages {
  int count = 0;                                            ///< stages [-]
  JointTermFamilySet families[kMaxJointTermFamilies] = {};  ///< per stage, in order
};
/// The stages that admit `terms`: when they hold more than one family, each family's terms
/// after those of the families before it in the table (as the command line builds
/// --compliance --harmonics), one stage per family in the table's order, each holding the
/// previous stage's families and its own, so that Table 1 shows what each family bought;
/// otherwise one stage of every term (none without terms).
JointTermStages plan_joint_term_stages(const ComplianceModel& terms,
                                       Span<const JointTermFamily> families = kJointTermFamilies);

/// The level each family of `model`'s terms must clear in a fit with `dof` residual degrees of
/// freedom (JointTermFamily::level over the family's count of terms in the model).
struct JointTermLevels {
  double level_t[kMaxJointTermFamilies] = {};     ///< per family of the table [-]
  ParamMask members[kMaxJointTermFamilies] = {};  ///< per family, its terms' parameters
  int family_count = 0;                           ///< entries used [-]
  double unknown_t = 0.0;                         ///< a term of no family: compliance_t [-]
  /// The level of full-model parameter `index`, a joint term's [-].
  double of(int index) const {
    for (int f = 0; f < family_count; ++f)
      if (mask_has(members[f], index)) return level_t[f];
    return unknown_t;
  }
};
/// The levels of `model`'s joint terms from `compliance_t` (CalibrationCompliance::significance_t).
JointTermLevels joint_term_levels(const RobotModel& model, double compliance_t, int dof,
                                  Span<const JointTermFamily> families = kJointTermFamilies);

/// The terms of `model` the training poses cannot admit (every family's `uncovered`).
ParamMask uncovered_joint_terms(const RobotModel& model, Span<const Sample> train,
                                Span<const JointTermFamily> families = kJointTermFamilies);
/// The terms of `model` whose family the blocked folds admit.
ParamMask blocked_fold_terms(const RobotModel& model, Span<const JointTermFamily> families = kJointTermFamilies);

/// Name of a joint-term stage whose model holds the families `set` of kJointTermFamilies:
/// "LM+" and their names in the table's order joined by "+" ("LM+compliance",
/// "LM+harmonics", "LM+compliance+harmonics"); an empty set is named after the first family.
const char* joint_term_stage_name(JointTermFamilySet set);

}  // namespace hivecal
