// The kept-set output of the identifiability analysis (the LM's analysis at its start): a
// shifted Cholesky factorisation may stand in for the eigen-decomposition that confirms a drop.
// It must decide exactly as the decomposition does: the same kept set and the same drops, bit
// for bit, over many random sessions; it must refuse where a kept direction lies near the
// threshold or the threshold is too small to certify; and an LM run that never steps still
// reports the whole analysis.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

#include "hivecal/solve/identifiability.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"

namespace hivecal::identifiability_certificate_test {
namespace {

bool same_bits(double a, double b) {
  return std::memcmp(&a, &b, sizeof a) == 0;
}

/// The parts of a report both outputs fill: the kept set, the drops and the first spectrum.
void expect_same_decisions(const IdentifiabilityReport& full, const IdentifiabilityReport& kept_set) {
  EXPECT_EQ(full.free_mask, kept_set.free_mask);
  EXPECT_EQ(full.kept_mask, kept_set.kept_mask);
  ASSERT_EQ(full.dropped_count, kept_set.dropped_count);
  for (int d = 0; d < full.dropped_count; ++d) {
    const DroppedParam& a = full.dropped[d];
    const DroppedParam& b = kept_set.dropped[d];
    EXPECT_EQ(a.index, b.index);
    EXPECT_EQ(a.reason, b.reason);
    EXPECT_TRUE(same_bits(a.singular_ratio, b.singular_ratio));
    for (int c = 0; c < kNullComponentCount; ++c) {
      EXPECT_EQ(a.component_index[c], b.component_index[c]);
      EXPECT_TRUE(same_bits(a.component[c], b.component[c]));
    }
  }
  ASSERT_EQ(full.singular_count_before, kept_set.singular_count_before);
  for (int k = 0; k < full.singular_count_before; ++k) {
    EXPECT_TRUE(same_bits(full.singular_values_before[k], kept_set.singular_values_before[k]));
  }
  EXPECT_TRUE(same_bits(full.condition_before, kept_set.condition_before));
}

/// Whether the kept-set report is the full one entirely (the decomposition ran).
bool same_after_spectrum(const IdentifiabilityReport& full, const IdentifiabilityReport& kept_set) {
  if (full.singular_count_after != kept_set.singular_count_after) return false;
  for (int k = 0; k < full.singular_count_after; ++k) {
    if (!same_bits(full.singular_values_after[k], kept_set.singular_values_after[k])) return false;
  }
  return same_bits(full.condition_after, kept_set.condition_after);
}

struct Analyses {
  IdentifiabilityWorkspace workspace;
  IdentifiabilityReport full;
  IdentifiabilityReport kept_set;
};

Analyses& analyses() {
  static Analyses storage;
  return storage;
}

/// Both analyses of `jtwj`; true when the kept-set one was certified (no spectrum after).
bool analyse_both(const NormalMatrix& jtwj, ParamMask free_mask, double threshold) {
  Analyses& a = analyses();
  Status full = Status::ok;
  Status kept_set = Status::ok;
  EXPECT_NO_HEAP(full = analyze_identifiability(jtwj, free_mask, threshold, &a.workspace, &a.full));
  EXPECT_NO_HEAP(kept_set = analyze_identifiability(jtwj, free_mask, threshold, &a.workspace, &a.kept_set, 0,
                                                    IdentifiabilityOutput::kept_set));
  EXPECT_EQ(full, kept_set);
  if (full != Status::ok) return false;
  expect_same_decisions(a.full, a.kept_set);
  const bool certified = a.kept_set.singular_count_after == 0;
  // Certified only after a drop (without one there is nothing to confirm); else the whole report.
  if (certified) {
    EXPECT_GT(a.full.dropped_count, 0);
  } else {
    EXPECT_TRUE(same_after_spectrum(a.full, a.kept_set));
  }
  return certified;
}

// Random UR5 / UR10 / UR5e sessions of 4 to 200 poses, with and without noise, several
// parameter sets and thresholds: the same decisions every time, and the certificate used on
// most of them (a test that could pass without it ever applying would prove nothing).
TEST(IdentifiabilityCertificate, DecidesAsTheEigenDecompositionOnRandomSessions) {
  static Dataset<200> dataset;
  static NormalEquations eq;
  const RobotType types[] = {RobotType::ur5, RobotType::ur10, RobotType::ur5e};
  const std::size_t sizes[] = {4, 7, 12, 30, 200};
  const double thresholds[] = {kDefaultIdentifiabilityThreshold, 1e-3, 1e-2};
  int cases = 0;
  int certified = 0;
  for (std::uint64_t seed = 1; seed <= 24; ++seed) {
    Random random(seed);
    const RobotType type = types[seed % 3];
    RobotModel truth = test::perturbed_model(nominal_model(type), &random, 3e-4, 3e-4);
    truth.tool_m = Vec3(random.uniform(-0.05, 0.05), random.uniform(-0.05, 0.05), random.uniform(0.0, 0.2));
    dataset.clear();
    test::fill_dataset(truth, test::example_base_to_tracker(), sizes[seed % 5], seed % 2 == 0 ? 0.0 : 1e-5, &random,
                       &dataset);
    Status status = Status::ok;
    EXPECT_NO_HEAP(status = accumulate_normal_equations(truth, test::example_base_to_tracker(), dataset.samples(),
                                                        PointLoss{}, &eq));
    ASSERT_EQ(status, Status::ok);
    const ParamMask masks[] = {rigid_params_mask(kSixJoints), lm_param_mask(LmParamSet::link_lengths, 0, truth)};
    for (ParamMask mask : masks) {
      for (double threshold : thresholds) {
        SCOPED_TRACE(::testing::Message() << "seed " << seed << " threshold " << threshold);
        certified += analyse_both(eq.jtwj, mask, threshold) ? 1 : 0;
        ++cases;
      }
    }
  }
  EXPECT_EQ(cases, 24 * 2 * 3);
  EXPECT_GE(certified, cases / 2) << certified << " of " << cases;
}

/// J^T J of five columns: e0 twice (an exact null pair), then e1 and cos(t) e1 + sin(t) e2
/// with 1 - cos t = gap (a weak but identifiable pair), then e3.
const NormalMatrix& weak_pair(double gap) {
  static NormalMatrix jtj;
  jtj.setZero();
  jtj(0, 0) = jtj(1, 1) = jtj(0, 1) = jtj(1, 0) = 1.0;
  jtj(2, 2) = jtj(3, 3) = 1.0;
  jtj(2, 3) = jtj(3, 2) = 1.0 - gap;
  jtj(4, 4) = 1.0;
  return jtj;
}

ParamMask first_five() {
  ParamMask mask = 0;
  for (int i = 0; i < 5; ++i) mask |= param_bit(i);
  return mask;
}

// After the null pair's drop, the weak pair's small eigenvalue (1 - c against 1 + c) is
// what the confirming round decides on. Far above the threshold's eigenvalue the certificate
// stands in; within the factor-2 margin it must refuse, and the decomposition (which keeps the
// pair) runs. Below the smallest threshold it certifies, it always decomposes.
TEST(IdentifiabilityCertificate, RefusesNearTheThresholdAndForTinyThresholds) {
  const double threshold = 1e-3;
  const double threshold_eigen = threshold * threshold * 2.0;  // (threshold sigma_max)^2, sigma_max^2 = 2
  EXPECT_TRUE(analyse_both(weak_pair(10.0 * threshold_eigen), first_five(), threshold));
  EXPECT_EQ(analyses().kept_set.kept_mask, first_five() & ~param_bit(0));
  EXPECT_FALSE(analyse_both(weak_pair(1.5 * threshold_eigen), first_five(), threshold));
  EXPECT_EQ(analyses().kept_set.kept_mask, first_five() & ~param_bit(0));  // kept: above the threshold
  EXPECT_EQ(analyses().kept_set.singular_count_after, 4);
  // Below the threshold the first round drops the weak pair's lower index too; what is left
  // is certified again.
  EXPECT_TRUE(analyse_both(weak_pair(0.5 * threshold_eigen), first_five(), threshold));
  EXPECT_EQ(analyses().kept_set.kept_mask, first_five() & ~param_bit(0) & ~param_bit(2));
  // A threshold whose square is near the rounding of the factorisation is never certified.
  EXPECT_FALSE(analyse_both(weak_pair(0.1), first_five(), 1e-6));
}

/// Counts the accepted steps of a run.
class AcceptedSteps : public LmObserver {
 public:
  bool on_iteration(const LmIterationInfo& info) override {
    count += info.accepted ? 1 : 0;
    return true;
  }
  int count = 0;
};

// A run that stops before its first accepted step (started at the solution of noise-free
// data) keeps the start's analysis: it is completed, so the report has both spectra.
TEST(IdentifiabilityCertificate, AnLmRunThatNeverStepsReportsTheWholeAnalysis) {
  static test::LmTestStorage<150> lm;
  Random random(31);
  const RobotModel truth =
      test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.012, -0.018, 0.15));
  const RigidTransform base = test::example_base_to_tracker();
  test::fill_dataset(truth, base, 150, 0.0, &random, &lm.train);
  Status status = Status::ok;
  AcceptedSteps accepted;
  EXPECT_NO_HEAP(status = calibrate_lm(truth, &base, lm.train.samples(), LmOptions{}, &lm.workspace, &lm.result,
                                       nullptr, &accepted));
  ASSERT_EQ(status, Status::ok) << status_message(status);
  ASSERT_EQ(accepted.count, 0) << "the run stepped: this test needs one that does not";
  const IdentifiabilityReport& report = lm.result.identifiability;
  EXPECT_EQ(report.kept_count(), 25);
  ASSERT_EQ(report.singular_count_after, report.kept_count());
  for (int k = 1; k < report.singular_count_after; ++k) {
    EXPECT_LE(report.singular_values_after[k], report.singular_values_after[k - 1]);
  }
  EXPECT_GT(report.singular_values_after[report.singular_count_after - 1], 0.0);
  EXPECT_GT(report.condition_after, 1.0);
}

}  // namespace
}  // namespace hivecal::identifiability_certificate_test
