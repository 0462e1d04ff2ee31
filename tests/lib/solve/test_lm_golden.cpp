// Golden digest of the LM calibration: model, base, sigma, singular values, drops and trace
// of a least-squares and a Huber run, hashed over their raw bits. The committed value must
// come out on every preset (host -O0/-O3/-march=native, aarch64, armhf).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

#include "hivecal/calibration.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/solve/lm.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/lm_test_data.hpp"
#include "testkit/other_arms.hpp"
#include "testkit/target_data.hpp"

namespace hivecal::lm_golden_test {
namespace {

constexpr std::uint64_t kLmGoldenDigest = 0x3d085493880f23f8ULL;
/// The same for a non-UR arm (IRB120-like, testkit/other_arms.hpp), least squares only.
constexpr std::uint64_t kLmOtherArmGoldenDigest = 0x7ee155e37a84119dULL;
/// The same for three reflectors on a UR5 (testkit/target_data.hpp): the other targets' tool
/// points eliminated from the normal equations and their sigmas.
constexpr std::uint64_t kLmTargetsGoldenDigest = 0xb4e9be8f76e40505ULL;
// Issue 16: the default point compliance terms estimated with the full model
// (LmParamSet::full_compliance) on a session bent in another form.
constexpr std::uint64_t kLmComplianceGoldenDigest = 0xa7c5fb5f5822f6e1ULL;
// The calibration job with compliance enabled (LM, then LM+compliance).
constexpr std::uint64_t kComplianceJobGoldenDigest = 0xe1a81719554ee0c7ULL;
// The calibration job on a controller's own TCP readings: base and tool points known
// (CalibrationOptions::base_known, tool_known), joint 1 estimated instead, three targets.
constexpr std::uint64_t kKnownFramesJobGoldenDigest = 0x5df87ca3e87c640dULL;

void add_result(const LmResult& r, Status status, const TraceBase& trace, Digest* digest) {
  digest->add_u64(static_cast<std::uint64_t>(status));
  digest->add(to_params(r.model).head(model_param_count(r.model)));
  digest->add(r.base_to_tracker.rotation);
  digest->add(r.base_to_tracker.translation_m);
  // The 33 rigid sigmas, then the model's compliance ones: a rigid result hashes as before.
  digest->add(r.sigma.head(rigid_param_count(kSixJoints) + r.model.compliance.term_count));
  digest->add(r.loss_sum_m2);
  digest->add(r.rms_m);
  digest->add(r.residual_sigma_m);
  digest->add(r.huber_threshold_m);
  digest->add_u64(static_cast<std::uint64_t>(r.iterations));
  digest->add_u64(static_cast<std::uint64_t>(r.termination));
  const IdentifiabilityReport& report = r.identifiability;
  digest->add_mask(report.kept_mask);
  for (int d = 0; d < report.dropped_count; ++d) {
    const DroppedParam& entry = report.dropped[d];
    digest->add_u64(static_cast<std::uint64_t>(entry.index));
    digest->add(entry.singular_ratio);
    for (double c : entry.component) digest->add(c);
  }
  for (int k = 0; k < report.singular_count_before; ++k) digest->add(report.singular_values_before[k]);
  for (int k = 0; k < report.singular_count_after; ++k) digest->add(report.singular_values_after[k]);
  digest->add(report.condition_after);
  for (double v : trace.values()) digest->add(v);
}

/// `joint_trig_storage`: LmWorkspace::joint_trig (empty: recomputed in every pass).
std::uint64_t lm_digest(Span<JointTrig> joint_trig_storage) {
  Random random(20261123);
  const RobotModel truth =
      test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.002, -0.001, 0.1695));
  static Dataset<150> clean;
  static Dataset<150> dirty;
  clean.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), 150, 1e-5, &random, &clean);
  test::copy_with_outliers(clean, 20, 3, 1e-3, 4e-3, &random, &dirty);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.17);
  static LmWorkspace ws;
  ws.joint_trig = joint_trig_storage;
  static LmResult result;
  static Trace<64> trace;
  Digest digest;
  LmOptions options;
  trace.clear();
  add_result(result, calibrate_lm(start, nullptr, clean.samples(), options, &ws, &result, &trace), trace,
             &digest);  // the whole digest runs under EXPECT_NO_HEAP below
  options.loss = LmLoss::huber;
  trace.clear();
  add_result(result, calibrate_lm(start, nullptr, dirty.samples(), options, &ws, &result, &trace), trace, &digest);
  return digest.value();
}

/// An IRB120-like arm (joints 2-3 parallel, offsets) calibrated from its nominal table.
std::uint64_t other_arm_digest() {
  Random random(20261125);
  const RobotModel truth = test::other_arm_truth(test::OtherArm::irb120, &random);
  static Dataset<150> samples;
  samples.clear();
  test::fill_other_arm(truth, test::example_base_to_tracker(), 150, 1e-5, &random, &samples);
  RobotModel start = test::other_arm_model(test::OtherArm::irb120);
  start.tool_m = Vec3(0.0, 0.0, 0.1);
  static LmWorkspace ws;
  static LmResult result;
  static Trace<64> trace;
  trace.clear();
  Digest digest;
  add_result(result, calibrate_lm(start, nullptr, samples.samples(), LmOptions{}, &ws, &result, &trace), trace,
             &digest);
  return digest.value();
}

/// A UR5 with three reflectors, 60 poses, calibrated from the nominal table with target 1 on
/// the flange axis and the other two unknown.
std::uint64_t targets_digest() {
  Random random(20261126);
  const Vec3 tool_m(0.012, -0.006, 0.17);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m), tool_m);
  static Dataset<180> samples;
  samples.clear();
  test::fill_target_dataset(truth, test::example_base_to_tracker(), 60, 3, 1e-5, &random, &samples);
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.17);
  static LmWorkspaceWithTargets ws;
  static LmResult result;
  static Trace<64> trace;
  trace.clear();
  Digest digest;
  add_result(result, calibrate_lm(start, nullptr, samples.samples(), LmOptions{}, &ws, &result, &trace), trace,
             &digest);
  for (const Vec3& other_m : result.model.other_tools_m) digest.add(other_m);
  for (const Vec3& sigma_m : result.other_tools_sigma_m) digest.add(sigma_m);
  return digest.value();
}

/// 120 poses of a perturbed UR5 (tool off the flange axis, 10 um noise) whose shoulder bends
/// by upper cos q2 + fore cos(q2 + q3) and elbow by elbow cos(q2 + q3) [rad] (other_session.hpp's
/// form, with the library's cos).
void fill_bent_session(std::uint64_t seed, double upper_rad, double fore_rad, double elbow_rad, Dataset<120>* samples) {
  Random random(seed);
  const RobotModel truth =
      test::perturbed_parallel_model(RobotType::ur5, &random, 3e-4, 3e-4, Vec3(0.015, -0.01, 0.15));
  samples->clear();
  for (int i = 0; i < 120; ++i) {
    const JointVector q = test::random_joints(&random);
    JointVector bent = q;
    bent(1) += upper_rad * math::cos(q(1)) + fore_rad * math::cos(q(1) + q(2));
    bent(2) += elbow_rad * math::cos(q(1) + q(2));
    const Vec3 noise = test::gaussian_vector(&random);
    (void)samples->add(q, test::example_base_to_tracker().apply(fk_tool_point(truth, bent)) + 1e-5 * noise);
  }
}

/// The nominal UR5 with the tool guessed on the flange axis: the bent sessions' start.
RobotModel bent_session_start() {
  RobotModel start = nominal_model(RobotType::ur5);
  start.tool_m = Vec3(0.0, 0.0, 0.15);
  return start;
}

/// A UR5 whose shoulder and elbow bend under gravity in another form than the calibration's
/// basis (other_session.hpp's, with the library's cos), 120 poses, calibrated with the
/// default point compliance terms (LmParamSet::full_compliance) from the nominal table.
std::uint64_t compliance_digest(Span<JointTrig> joint_trig_storage) {
  static Dataset<120> samples;
  fill_bent_session(20261127, 45e-6, 20e-6, 25e-6, &samples);
  RobotModel start = bent_session_start();
  (void)default_compliance_terms(start, Vec3(0.0, 0.0, -1.0), ComplianceLoad::point, &start.compliance);
  static LmWorkspace ws;
  ws.joint_trig = joint_trig_storage;
  static LmResult result;
  static Trace<64> trace;
  trace.clear();
  LmOptions options;
  options.params = LmParamSet::full_compliance;
  Digest digest;
  add_result(result, calibrate_lm(start, nullptr, samples.samples(), options, &ws, &result, &trace), trace, &digest);
  for (int t = 0; t < result.model.compliance.term_count; ++t) digest.add(result.model.compliance.coefficient[t]);
  return digest.value();
}

/// A job's status, stages (geometry, with `compliance` its coefficients, base, test MAE), with
/// `sigma` LM's rigid sigmas, and its kept, pruned and outlier figures, into *digest.
void add_job_result(Status status, const CalibrationResult& result, bool compliance, bool sigma, Digest* digest) {
  digest->add_u64(static_cast<std::uint64_t>(status));
  digest->add_u64(result.stage_count);
  for (const CalibrationStage& stage : result.stage_list()) {
    digest->add(to_params(stage.model).head(model_param_count(stage.model)));
    // The four default point terms' slots (zero in a rigid stage), whatever the build's capacity.
    for (int k = 0; compliance && k < 4; ++k) digest->add(stage.model.compliance.coefficient[k]);
    digest->add(stage.base_to_tracker.rotation);
    digest->add(stage.base_to_tracker.translation_m);
    digest->add(stage.test.mae(ErrorAxis::norm_3d));
  }
  if (sigma) digest->add(result.lm.sigma.head(rigid_param_count(kSixJoints)));
  digest->add_mask(result.lm.identifiability.kept_mask);
  digest->add_mask(result.lm_pruned_mask);
  digest->add_u64(result.outlier_count);
}

/// The job (calibration.hpp) with compliance enabled on the same kind of session: split,
/// blunder test, rigid LM, then LM+compliance with the significance test.
std::uint64_t compliance_job_digest() {
  static Dataset<120> samples;
  fill_bent_session(20261128, 60e-6, 30e-6, 40e-6, &samples);
  const RobotModel start = bent_session_start();
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.compliance.enabled = true;
  static CalibrationWorkspace<120, double, 20, 64> ws;
  static CalibrationResult result;
  Digest digest;
  const Status status = calibrate(start, &samples, options, &ws, &result);
  EXPECT_EQ(status, Status::ok);
  EXPECT_EQ(result.stage_count, 2u);  // LM, LM+compliance
  add_job_result(status, result, true, false, &digest);
  return digest.value();
}

TEST(LmGolden, ComplianceJobDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = compliance_job_digest());
  std::printf("job digest (LM + LM+compliance): 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kComplianceJobGoldenDigest);
}

/// A perturbed UR5 read as its controller reports the TCP (identity base, three points of the
/// tool frame known), 40 poses with 10 um noise, the job with a 70/30 split and the
/// significance test, base and tool known.
std::uint64_t known_frames_job_digest() {
  static Dataset<120> samples;
  samples.clear();
  Random random(20261126);
  const Vec3 tool_m(0.0, 0.0, 0.05);
  const RobotModel truth =
      test::with_plate(test::perturbed_parallel_model(RobotType::ur5, &random, 1e-3, 1e-3, tool_m), tool_m);
  test::fill_target_dataset(truth, RigidTransform(), 40, 3, 1e-5, &random, &samples);
  RobotModel start = nominal_model(RobotType::ur5);
  for (int t = 0; t < kMaxTargets; ++t) target_tool(&start, t) = target_tool(truth, t);
  CalibrationOptions options;
  options.method = CalibrationMethod::lm;
  options.base_known = true;
  options.tool_known = true;
  static CalibrationWorkspace<120, double, 20, 64> ws;
  static CalibrationResult result;
  Digest digest;
  const Status status = calibrate(start, &samples, options, &ws, &result);
  EXPECT_EQ(status, Status::ok);
  add_job_result(status, result, false, true, &digest);
  return digest.value();
}

TEST(LmGolden, KnownFramesJobDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = known_frames_job_digest());
  std::printf("job digest (base and tool known): 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kKnownFramesJobGoldenDigest);
}

TEST(LmGolden, ComplianceDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  static JointTrig storage[120];
  EXPECT_NO_HEAP(digest = compliance_digest({}));
  std::printf("lm digest (full+compliance): 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kLmComplianceGoldenDigest);
  std::uint64_t stored = 0;  // the stored trig is of the readings: a compliant model does not use it
  EXPECT_NO_HEAP(stored = compliance_digest(storage));
  EXPECT_EQ(stored, digest);
}

TEST(LmGolden, SeveralTargetsDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = targets_digest());
  std::printf("lm digest (three reflectors): 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kLmTargetsGoldenDigest);
}

TEST(LmGolden, NonUrArmDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = other_arm_digest());
  std::printf("lm digest (IRB120-like arm): 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kLmOtherArmGoldenDigest);
}

TEST(LmGolden, DigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  EXPECT_NO_HEAP(digest = lm_digest({}));
  std::printf("lm digest: 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kLmGoldenDigest);
}

// Stored joint trig saves work, not bits; storage smaller than the dataset is ignored.
TEST(LmGolden, StoredJointTrigGivesTheSameBits) {
  static JointTrig storage[150];
  const auto poison = [] {
    for (JointTrig& t : storage) t.sin_q[0] = std::numeric_limits<double>::quiet_NaN();
  };
  std::uint64_t stored = 0;
  std::uint64_t too_small = 0;
  poison();
  EXPECT_NO_HEAP(too_small = lm_digest(Span<JointTrig>(storage, 149)));
  EXPECT_TRUE(std::isnan(storage[0].sin_q[0])) << "storage too small for the samples: left alone";
  EXPECT_NO_HEAP(stored = lm_digest(storage));
  EXPECT_FALSE(std::isnan(storage[149].sin_q[0])) << "the solver filled and read the storage";
  EXPECT_EQ(stored, kLmGoldenDigest);
  EXPECT_EQ(too_small, kLmGoldenDigest);
}

}  // namespace
}  // namespace hivecal::lm_golden_test
