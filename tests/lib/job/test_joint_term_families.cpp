// The joint terms as a table of families (job/joint_term_families.hpp): each term kind is one
// family's, each entry builds its terms per joint, the table's order makes the stages, each
// family's level, coverage and blocked-fold rules are its entry's (a test table with a third
// family shows that one entry is all a family needs), and the job admits every term it keeps at
// its family's level, in the table's stages.
#include <gtest/gtest.h>

#include <cmath>

#include "hivecal/calibration.hpp"
#include "hivecal/core/random.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::joint_term_families_test {
namespace {

constexpr JointTermFamilySet kGravity = 1;
constexpr JointTermFamilySet kHarmonics = 2;

/// The default gravity terms of a UR5 under floor gravity, then its harmonics of orders 1 .. 2.
ComplianceModel both_families() {
  ComplianceModel terms;
  const RobotModel ur5 = nominal_model(RobotType::ur5);
  EXPECT_EQ(kJointTermFamilies[0].append_terms(ur5, kJointTermFamilies[0].default_size, &terms), Status::ok);
  EXPECT_EQ(kJointTermFamilies[1].append_terms(ur5, 2, &terms), Status::ok);
  return terms;
}

TEST(JointTermFamilies, EveryTermKindIsOneFamilysAndEachEntryBuildsItsTermsPerJoint) {
  for (JointTermKind kind : {JointTermKind::gravity, JointTermKind::harmonic_sin, JointTermKind::harmonic_cos}) {
    ComplianceTerm term;
    term.kind = kind;
    int holders = 0;
    for (const JointTermFamily& family : kJointTermFamilies) holders += family.holds(term) ? 1 : 0;
    EXPECT_EQ(holders, 1) << static_cast<int>(kind);
  }
  ComplianceModel terms;
  EXPECT_NO_HEAP(terms = both_families());
  if (kMaxComplianceTerms < 4 + 24) return;  // the bare-metal capacity holds the gravity terms only
  ComplianceModel gravity;
  ASSERT_EQ(
      default_compliance_terms(nominal_model(RobotType::ur5), Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &gravity),
      Status::ok);
  ASSERT_EQ(terms.term_count, gravity.term_count + 24);  // a sine and a cosine per joint and order
  for (int t = 0; t < terms.term_count; ++t) {
    const int family = joint_term_family(terms.terms[t]);
    EXPECT_EQ(family, t < gravity.term_count ? 0 : 1) << t;
    if (t < gravity.term_count) {
      EXPECT_EQ(terms.terms[t].frame, gravity.terms[t].frame) << t;
    }
  }
  EXPECT_EQ(joint_term_families_of(terms), kGravity | kHarmonics);
  // The builders are called in the table's order: the gravity family, the first, starts the set.
  ComplianceModel harmonics_first;
  ASSERT_EQ(kJointTermFamilies[1].append_terms(nominal_model(RobotType::ur5), 1, &harmonics_first), Status::ok);
  EXPECT_EQ(kJointTermFamilies[0].append_terms(nominal_model(RobotType::ur5), 1, &harmonics_first),
            Status::invalid_argument);
}

TEST(JointTermFamilies, TheTablesOrderMakesTheStagesEachAddingAFamily) {
  if (kMaxComplianceTerms < 4 + 24) return;
  const ComplianceModel terms = both_families();
  JointTermStages stages;
  EXPECT_NO_HEAP(stages = plan_joint_term_stages(terms));
  ASSERT_EQ(stages.count, 2);
  EXPECT_EQ(stages.families[0], kGravity);
  EXPECT_EQ(stages.families[1], kGravity | kHarmonics);
  EXPECT_STREQ(joint_term_stage_name(stages.families[0]), "LM+compliance");
  EXPECT_STREQ(joint_term_stage_name(stages.families[1]), "LM+compliance+harmonics");
  EXPECT_STREQ(joint_term_stage_name(kHarmonics), "LM+harmonics");
  // Against the table's order (the harmonics first): one stage of every term.
  ComplianceModel reversed;
  ASSERT_EQ(kJointTermFamilies[1].append_terms(nominal_model(RobotType::ur5), 1, &reversed), Status::ok);
  for (int t = 0; t < 4; ++t) reversed.terms[reversed.term_count++] = terms.terms[t];  // the gravity terms
  stages = plan_joint_term_stages(reversed);
  ASSERT_EQ(stages.count, 1);
  EXPECT_EQ(stages.families[0], kGravity | kHarmonics);
  // One family: one stage; no term: none.
  ComplianceModel harmonics;
  ASSERT_EQ(kJointTermFamilies[1].append_terms(nominal_model(RobotType::ur5), 1, &harmonics), Status::ok);
  stages = plan_joint_term_stages(harmonics);
  ASSERT_EQ(stages.count, 1);
  EXPECT_EQ(stages.families[0], kHarmonics);
  EXPECT_EQ(plan_joint_term_stages(ComplianceModel{}).count, 0);
}

// A test table: the harmonics split in two families, the first orders and the higher ones,
// each with a level of its own, the higher orders not checked on the blocked folds nor by their
// period. One entry each: the stages, the levels and the admission rules follow.
bool first_order(const ComplianceTerm& term) {
  return is_harmonic(term) && term.order == 1;
}
bool higher_order(const ComplianceTerm& term) {
  return is_harmonic(term) && term.order > 1;
}
double level_four(double compliance_t, int count, int dof) {
  (void)count;
  (void)dof;
  return compliance_t + 1.0;
}
Status no_terms(const RobotModel& model, int size, ComplianceModel* terms) {
  (void)model;
  (void)size;
  (void)terms;
  return Status::ok;
}
constexpr JointTermFamily kSplitHarmonics[] = {
    kJointTermFamilies[0],
    {"eccentricity", &first_order, &no_terms, 0, &harmonic_term_level, &harmonics_short_of_their_period, true},
    {"gears", &higher_order, &no_terms, 0, &level_four, nullptr, false},
};

/// The UR5's gravity terms, then its first harmonics of every joint, then its second ones.
ComplianceModel gravity_then_orders() {
  ComplianceModel terms;
  const RobotModel ur5 = nominal_model(RobotType::ur5);
  EXPECT_EQ(append_gravity_terms(ur5, 1, &terms), Status::ok);
  for (int order = 1; order <= 2; ++order) {
    for (int j = 0; j < kSixJoints; ++j) {
      for (JointTermKind kind : {JointTermKind::harmonic_sin, JointTermKind::harmonic_cos}) {
        terms.terms[terms.term_count++] = ComplianceTerm{j, 0, kind, order};
      }
    }
  }
  return terms;
}

TEST(JointTermFamilies, ANewFamilyIsOneEntryItsStageLevelAndRulesFollow) {
  if (kMaxComplianceTerms < 4 + 24) return;
  const Span<const JointTermFamily> table(kSplitHarmonics);
  RobotModel model = nominal_model(RobotType::ur5);
  model.compliance = gravity_then_orders();
  const JointTermStages stages = plan_joint_term_stages(model.compliance, table);
  ASSERT_EQ(stages.count, 3);
  EXPECT_EQ(stages.families[0], 1);
  EXPECT_EQ(stages.families[1], 3);
  EXPECT_EQ(stages.families[2], 7);
  // Each family's level from its own rule and its own count of terms.
  const double compliance_t = 3.0;
  const int dof = 400;
  const JointTermLevels levels = joint_term_levels(model, compliance_t, dof, table);
  for (int t = 0; t < model.compliance.term_count; ++t) {
    const int index = compliance_param_index(model, t);
    const ComplianceTerm& term = model.compliance.terms[t];
    const double expected = !is_harmonic(term) ? compliance_t
                            : term.order == 1  ? harmonic_term_level(compliance_t, 12, dof)
                                               : compliance_t + 1.0;
    EXPECT_EQ(levels.of(index), expected) << compliance_term_name(model.compliance, t);
  }
  // The library's table: both orders one family of 24, a level raised for 24 terms.
  const JointTermLevels library = joint_term_levels(model, compliance_t, dof);
  EXPECT_EQ(library.of(compliance_param_index(model, 4)), harmonic_term_level(compliance_t, 24, dof));
  EXPECT_GT(harmonic_term_level(compliance_t, 24, dof), harmonic_term_level(compliance_t, 12, dof));
  EXPECT_EQ(library.of(compliance_param_index(model, 0)), compliance_t);
  EXPECT_EQ(parameter_significance_level(model, compliance_param_index(model, 4), 2.0, compliance_t, dof),
            harmonic_term_level(compliance_t, 24, dof));
  // Coverage and the blocked folds: only the entries that ask for them. Poses that turn no
  // joint through 3/4 of a turn leave every harmonic short of its period.
  Sample narrow[2];
  narrow[1].q_rad = JointVector::Constant(0.5);
  const ParamMask first = joint_term_params_mask(model, 2, table);
  const ParamMask higher = joint_term_params_mask(model, 4, table);
  EXPECT_EQ(uncovered_joint_terms(model, Span<const Sample>(narrow), table), first);
  EXPECT_EQ(uncovered_joint_terms(model, Span<const Sample>(narrow)), first | higher);
  EXPECT_EQ(blocked_fold_terms(model, table), compliance_params_mask(model) & ~higher);
  EXPECT_EQ(blocked_fold_terms(model), compliance_params_mask(model));
}

/// `count` samples of a perturbed UR5 whose shoulder and elbow sag and whose base and elbow are
/// eccentric (true_joints of test_calibration_harmonics.cpp), 15 um tracker noise.
void fill(std::uint64_t seed, std::size_t count, DatasetBase* out) {
  const auto turned = [](const JointVector& q) {
    JointVector t = q;
    const double forearm = std::cos(q(1) + q(2));
    t(1) += 60e-6 * (0.425 * std::cos(q(1)) + 0.392 * forearm) / 0.817;
    t(2) += 30e-6 * forearm + 60e-6 * std::sin(q(2)) + 50e-6 * std::cos(q(2));
    t(0) += 50e-6 * std::sin(q(0)) - 40e-6 * std::cos(q(0));
    return t;
  };
  test::fill_turned(seed, count, 15e-6, turned, out);
}

constexpr std::size_t kSamples = 256;
CalibrationWorkspace<kSamples, double, 20, 300> workspace;
CalibrationResult result;
Dataset<kSamples> dataset;

TEST(JointTermFamilies, TheJobRunsTheTablesStagesAndKeepsATermOnlyAtItsFamilysLevel) {
  if (kMaxComplianceTerms < 4 + 24) return;
  fill(41, kSamples, &dataset);
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.compliance.enabled = true;
  options.compliance.model = both_families();
  const JointTermStages planned = plan_joint_term_stages(options.compliance.model);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result));
  ASSERT_EQ(status, Status::ok);
  ASSERT_EQ(result.stage_count, 1u + static_cast<std::size_t>(planned.count));
  for (int k = 0; k < planned.count; ++k) {  // a stage per family, in the table's order
    const CalibrationStage& stage = result.stages[1 + k];
    EXPECT_TRUE(stage.compliance);
    EXPECT_EQ(joint_term_families_of(stage.model.compliance), planned.families[k]) << k;
    EXPECT_STREQ(result.stage_name(1 + static_cast<std::size_t>(k)), joint_term_stage_name(planned.families[k]));
    // What the period rule rejected is of the families whose entry has one (the harmonics).
    EXPECT_EQ(stage.folds.coverage_rejected & ~joint_term_params_mask(stage.model, kHarmonics), ParamMask{0});
  }
  // The final fit (r.lm: its stage kept its terms): every joint term it estimates is of a
  // family and clears that family's level.
  const CalibrationStage* final_stage = result.final_stage();
  ASSERT_NE(final_stage, nullptr);
  ASSERT_FALSE(final_stage->rigid_kept);
  const RobotModel& fitted = result.lm.model;
  const JointTermLevels levels = joint_term_levels(fitted, options.compliance.significance_t, result.lm.residual_dof);
  int kept = 0;
  for (int t = 0; t < fitted.compliance.term_count; ++t) {
    const int index = compliance_param_index(fitted, t);
    if (!mask_has(result.lm.identifiability.kept_mask, index)) continue;
    ++kept;
    ASSERT_GE(joint_term_family(fitted.compliance.terms[t]), 0);
    const double ratio = std::fabs(fitted.compliance.coefficient[t]) / result.lm.sigma(index);
    EXPECT_GE(ratio, std::fmax(result.significance_t, levels.of(index))) << compliance_term_name(fitted.compliance, t);
  }
  EXPECT_GT(kept, 0);
}

// Every method's stages and the terms' stages within the result's kMaxCalibrationStages: 'all'
// (GSA, ABC, LM) with both families asks for five, which the hosted result holds; a build that
// holds fewer refuses the job at the input step instead of writing past its stages.
TEST(JointTermFamilies, AJobOfMoreStagesThanTheResultHoldsIsRefusedAtTheInputStep) {
  if (kMaxComplianceTerms < 4 + 24) return;
  fill(43, 120, &dataset);
  CalibrationOptions options;
  options.method = CalibrationMethod::all;
  options.abc_food_sources = options.gsa_agents = 20;  // the workspace's population capacity
  options.abc_cycles = options.gsa_iterations = 30;
  options.compliance.enabled = true;
  options.compliance.model = both_families();
  const std::size_t needed = 3 + static_cast<std::size_t>(plan_joint_term_stages(options.compliance.model).count);
  ASSERT_EQ(needed, 5u);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate(nominal_model(RobotType::ur5), &dataset, options, &workspace, &result));
  if (needed > kMaxCalibrationStages) {
    EXPECT_EQ(status, Status::invalid_argument);
    EXPECT_EQ(result.step, CalibrationStep::input);
  } else {
    ASSERT_EQ(status, Status::ok);
    EXPECT_EQ(result.stage_count, needed);
    EXPECT_STREQ(result.stage_name(4), "LM+compliance+harmonics");
  }
}

}  // namespace
}  // namespace hivecal::joint_term_families_test
