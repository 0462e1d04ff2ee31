// The joint-term families' rules and the questions the job asks of the table
// (job/joint_term_families.hpp).
#include "hivecal/job/joint_term_families.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hivecal/core/distributions.hpp"
#include "hivecal/core/math.hpp"

namespace hivecal {
namespace {

/// Longest name of a joint-term stage, its terminating zero included [B].
constexpr int kMaxStageNameBytes = 32;

/// A stage's name in static storage.
struct StageName {
  char text[kMaxStageNameBytes] = {};
};

/// Every set's name: "LM" and "+name" of each family in the set, in the table's order.
struct StageNames {
  StageName name[1 << kJointTermFamilyCount];
};

constexpr StageNames stage_names() {
  StageNames names;
  for (int set = 0; set < (1 << kJointTermFamilyCount); ++set) {
    char* out = names.name[set].text;
    int length = 0;
    const auto append = [&](const char* text) {
      for (int i = 0; text[i] != '\0' && length + 1 < kMaxStageNameBytes; ++i) out[length++] = text[i];
    };
    append("LM");
    for (int f = 0; f < kJointTermFamilyCount; ++f) {
      if (((set >> f) & 1) == 0 && !(set == 0 && f == 0)) continue;  // an empty set: the first family's
      append("+");
      append(kJointTermFamilies[f].name);
    }
  }
  return names;
}
constexpr StageNames kStageNames = stage_names();

/// Whether every family's name fits a stage's name with all the others.
constexpr bool stage_names_fit() {
  int length = 2;  // "LM"
  for (const JointTermFamily& family : kJointTermFamilies) {
    length += 1;  // "+"
    for (int i = 0; family.name[i] != '\0'; ++i) ++length;
  }
  return length < kMaxStageNameBytes;
}
static_assert(stage_names_fit(), "a stage's name holds every family's");

}  // namespace

Status append_gravity_terms(const RobotModel& model, int size, ComplianceModel* terms) {
  (void)size;
  if (terms->term_count != 0) return Status::invalid_argument;  // the first family: it starts the set
  return default_compliance_terms(model, terms->gravity_direction, terms->load, terms);
}

Status append_harmonics_of_orders(const RobotModel& model, int orders, ComplianceModel* terms) {
  return append_harmonic_terms(orders, model, terms);
}

double gravity_term_level(double compliance_t, int count, int dof) {
  (void)count;
  (void)dof;
  return compliance_t;
}

double harmonic_term_level(double compliance_t, int count, int dof) {
  if (count <= 0) return compliance_t;
  if (dof < 1) return std::numeric_limits<double>::infinity();
  const double per_term_tail = kHarmonicFamilyAlpha / static_cast<double>(count);
  const double t_squared = math::f_upper_quantile(per_term_tail, 1.0, static_cast<double>(dof));
  return math::is_finite(t_squared) ? std::fmax(compliance_t, std::sqrt(t_squared))
                                    : std::numeric_limits<double>::infinity();
}

ParamMask harmonics_short_of_their_period(const RobotModel& model, Span<const Sample> train) {
  ParamMask short_of = 0;
  if (train.empty()) return short_of;
  for (int t = 0; t < model.compliance.term_count; ++t) {
    const ComplianceTerm& term = model.compliance.terms[t];
    if (!is_harmonic(term)) continue;
    double lowest = train[0].q_rad(term.joint);
    double highest = lowest;
    for (const Sample& s : train) {
      lowest = std::fmin(lowest, s.q_rad(term.joint));
      highest = std::fmax(highest, s.q_rad(term.joint));
    }
    const double period_rad = 2.0 * math::kPi / static_cast<double>(term.order);
    if (highest - lowest < kHarmonicMinPeriodShare * period_rad)
      short_of |= param_bit(compliance_param_index(model, t));
  }
  return short_of;
}

int joint_term_family(const ComplianceTerm& term, Span<const JointTermFamily> families) {
  const std::size_t count = std::min(families.size(), static_cast<std::size_t>(kMaxJointTermFamilies));
  for (std::size_t f = 0; f < count; ++f)
    if (families[f].holds(term)) return static_cast<int>(f);
  return -1;
}

JointTermFamilySet joint_term_families_of(const ComplianceModel& terms, Span<const JointTermFamily> families) {
  unsigned set = 0;
  for (int t = 0; t < terms.term_count; ++t) {
    const int family = joint_term_family(terms.terms[t], families);
    if (family >= 0) set |= 1u << family;
  }
  return static_cast<JointTermFamilySet>(set);
}

ParamMask joint_term_params_mask(const RobotModel& model, JointTermFamilySet set,
                                 Span<const JointTermFamily> families) {
  ParamMask mask = 0;
  for (int t = 0; t < model.compliance.term_count; ++t) {
    const int family = joint_term_family(model.compliance.terms[t], families);
    if (family >= 0 && ((set >> family) & 1) != 0) mask |= param_bit(compliance_param_index(model, t));
  }
  return mask;
}

JointTermStages plan_joint_term_stages(const ComplianceModel& terms, Span<const JointTermFamily> families) {
  JointTermStages stages;
  if (terms.term_count <= 0) return stages;
  // The families in the order their terms come; one stage per family when that is the table's
  // order and no family comes back.
  int order[kMaxJointTermFamilies];
  int seen = 0;
  bool in_table_order = true;
  for (int t = 0; t < terms.term_count; ++t) {
    const int family = joint_term_family(terms.terms[t], families);
    if (seen > 0 && family == order[seen - 1]) continue;
    in_table_order = in_table_order && family >= 0 && (seen == 0 || family > order[seen - 1]);
    if (!in_table_order) break;
    order[seen++] = family;
  }
  if (!in_table_order || seen < 2) {
    stages.count = 1;
    stages.families[0] = joint_term_families_of(terms, families);
    return stages;
  }
  unsigned held = 0;
  for (int k = 0; k < seen; ++k) {
    held |= 1u << order[k];
    stages.families[stages.count++] = static_cast<JointTermFamilySet>(held);
  }
  return stages;
}

JointTermLevels joint_term_levels(const RobotModel& model, double compliance_t, int dof,
                                  Span<const JointTermFamily> families) {
  JointTermLevels levels;
  levels.unknown_t = compliance_t;
  levels.family_count = static_cast<int>(std::min(families.size(), static_cast<std::size_t>(kMaxJointTermFamilies)));
  for (int f = 0; f < levels.family_count; ++f) {
    levels.members[f] = joint_term_params_mask(model, static_cast<JointTermFamilySet>(1u << f), families);
    levels.level_t[f] = families[static_cast<std::size_t>(f)].level(compliance_t, mask_count(levels.members[f]), dof);
  }
  return levels;
}

ParamMask uncovered_joint_terms(const RobotModel& model, Span<const Sample> train,
                                Span<const JointTermFamily> families) {
  ParamMask mask = 0;
  for (std::size_t f = 0; f < families.size() && f < kMaxJointTermFamilies; ++f) {
    if (families[f].uncovered == nullptr) continue;
    const auto own = static_cast<JointTermFamilySet>(1u << f);
    mask |= families[f].uncovered(model, train) & joint_term_params_mask(model, own, families);
  }
  return mask;
}

ParamMask blocked_fold_terms(const RobotModel& model, Span<const JointTermFamily> families) {
  unsigned set = 0;
  for (std::size_t f = 0; f < families.size() && f < kMaxJointTermFamilies; ++f)
    if (families[f].blocked_folds) set |= 1u << f;
  return joint_term_params_mask(model, static_cast<JointTermFamilySet>(set), families);
}

const char* joint_term_stage_name(JointTermFamilySet set) {
  return kStageNames.name[set & all_joint_term_families(kJointTermFamilyCount)].text;
}

}  // namespace hivecal
