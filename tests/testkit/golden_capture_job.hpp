// The firmware's calibration job from captures, shared by the firmware image
// (tests/firmware/capture_job_main.cpp, CTest firmware.capture_job[_lm|_compliance]) and the host test
// (tests/lib/job/test_capture_job_golden.cpp), so that both run the same code on the same committed
// capture pair tests/data/fw-session/{robot,tracker}.cap and compare the same digests:
//   captures -> extract_dataset_from_captures (capture_dataset.hpp) -> calibrate()
//   (calibration.hpp) -> a digest of every result bit.
// Heap-free: the capture workspace and the calibration workspace are never alive together
// and share one static arena (placement new).
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/calibration.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/sync/capture_dataset.hpp"

namespace hivecal::test {

/// Samples the job can hold (the firmware budget: 512).
inline constexpr std::size_t kJobSamples = 512;
/// Clock profiles: 3072 knots x 20 ms = 61 s of robot data, 640 tracker points = 64 s; extractor
/// rings: 256 robot records (2 s at 125 Hz: the 1 s window plus the merge lag), 64 tracker points.
using JobCaptureWorkspace = CaptureWorkspace<3072, 640, 256, 64>;
/// Values per stage trace: the traces are views for reports (CalibrationStage::trace_m), no
/// result depends on them and the firmware prints none, so each keeps its first value and
/// counts the rest (TraceBase::dropped); 300 would cost 7.2 kB of static RAM.
inline constexpr std::size_t kJobTraceCapacity = 1;
/// Float paper-6 terms (84 B per sample), the paper's 150 food sources, one-value traces; no GSA
/// phase (the firmware's jobs are ABC+LM and LM; GSA's solver would be the largest phase).
using JobCalibrationWorkspace = CalibrationWorkspace<kJobSamples, float, 150, kJobTraceCapacity, 0, kPaper6Dimension, 1,
                                                     0, 0>;  // one reflector, no subset room, no GSA (RAM)

/// Where a run ends (earlier ends serve the per-stage instruction counts of scripts/footprint.sh).
enum class JobStop : int { clock, extraction, done };

/// Settings of one job run.
struct CaptureJobConfig {
  RobotType robot = RobotType::ur5;      ///< nominal geometry
  Vec3 tool_m = Vec3(0.0, 0.0, 0.1695);  ///< nominal tool point in the flange frame [m]
  CalibrationOptions calibration;        ///< the job (method, split, seed, ABC budget)
  JobStop stop_after = JobStop::done;    ///< end after this pass
};

/// The paper's job with the budget reduced so that the Cortex-M4 run under QEMU stays short
/// (the footprint report measures the paper's 150 x 300 separately): ABC 20 x 30 then LM.
inline CaptureJobConfig golden_capture_job_config() {
  CaptureJobConfig config;
  config.calibration.method = CalibrationMethod::abc_lm;
  config.calibration.seed = 1;
  config.calibration.abc_food_sources = 20;
  config.calibration.abc_cycles = 30;
  return config;
}

/// The LM-only job (the better calibration for ~1 % of the instructions).
inline CaptureJobConfig golden_lm_job_config() {
  CaptureJobConfig config;
  config.calibration.method = CalibrationMethod::lm;
  config.calibration.seed = 1;
  return config;
}

/// The LM-only job with joint compliance (issue 16): the rigid LM, then "LM+compliance" with
/// default_compliance_terms (point loads, floor gravity); the session is simulated compliant.
inline CaptureJobConfig golden_compliance_job_config() {
  CaptureJobConfig config = golden_lm_job_config();
  config.calibration.compliance.enabled = true;
  return config;
}

/// The committed digests: every target must reproduce them.
inline constexpr std::uint64_t kCaptureJobGoldenDigest = 0x8cd7dbfaf4874615ULL;
inline constexpr std::uint64_t kLmJobGoldenDigest = 0xaaca46d548438fdeULL;
inline constexpr std::uint64_t kComplianceJobGoldenDigest = 0xe2882a8274aca303ULL;

/// Static storage of a job: the dataset, and one arena for the capture passes, then the job.
struct CaptureJobWorkspace {
  static constexpr std::size_t kArenaBytes = sizeof(JobCaptureWorkspace) > sizeof(JobCalibrationWorkspace)
                                                 ? sizeof(JobCaptureWorkspace)
                                                 : sizeof(JobCalibrationWorkspace);
  Dataset<kJobSamples> dataset;                                         ///< the samples of the captures
  alignas(alignof(std::max_align_t)) unsigned char arena[kArenaBytes];  ///< capture, then calibration workspace
  RobotModel nominal;  ///< the job's start model (here, not on the stack the job runs on)
};

/// ws->nominal: `config`'s robot and tool. Not inlined: the table's copy stays off the stack of
/// the job that follows.
[[gnu::noinline]] inline void set_job_nominal(const CaptureJobConfig& config, CaptureJobWorkspace* ws) {
  ws->nominal = nominal_model(config.robot);
  ws->nominal.tool_m = config.tool_m;
}

/// The results of a run (static storage: the CalibrationResult alone is ~5 KB).
struct CaptureJobReport {
  CaptureExtraction capture;      ///< the two passes
  std::size_t samples = 0;        ///< samples extracted
  CalibrationResult calibration;  ///< the job (default when the passes failed or stopped it)
  std::uint64_t digest = 0;       ///< hash of every result bit above
};

/// The stage numbers of the digest: 0 clock, 1 extraction, 2 split, 3 ABC, 4 LM, 5 done
/// (the numbering the golden digest was made with).
inline std::uint64_t job_stage_code(const CaptureJobReport& r, bool calibrated) {
  if (!calibrated) return r.capture.pass == CapturePass::clock ? 0 : 1;
  switch (r.calibration.step) {
    case CalibrationStep::input:
    case CalibrationStep::split:
    case CalibrationStep::baseline: return 2;
    case CalibrationStep::gsa:
    case CalibrationStep::abc: return 3;
    case CalibrationStep::lm: return 4;
    case CalibrationStep::done: return 5;
  }
  return 6;
}

/// The stage of `solver` in a result, or null.
inline const CalibrationStage* find_stage(const CalibrationResult& r, CalibrationSolver solver) {
  for (const CalibrationStage& s : r.stage_list())
    if (s.solver == solver) return &s;
  return nullptr;
}

/// Hashes every result bit of a report (what host and firmware must agree on).
inline std::uint64_t capture_job_digest(const CaptureJobReport& r, bool calibrated) {
  const CalibrationResult& c = r.calibration;
  const CalibrationStage* final_stage = c.final_stage();
  Digest d;
  d.add_u64(job_stage_code(r, calibrated));
  d.add_u64(static_cast<std::uint64_t>(!calibrated                                        ? r.capture.status
                                       : c.status != Status::ok || final_stage == nullptr ? c.status
                                                                                          : final_stage->status));
  d.add(r.capture.clock.offset_us);
  d.add(r.capture.clock.drift);
  d.add(r.capture.clock.offset_at_reference_us);
  d.add(r.capture.clock.sigma_offset_at_reference_us);
  d.add_u64(r.capture.counts.tracker_points);
  d.add_u64(r.capture.counts.kept);
  for (std::uint64_t n : r.capture.counts.dropped) d.add_u64(n);
  d.add_u64(r.samples);
  d.add_u64(c.train_count);
  if (const CalibrationStage* abc = find_stage(c, CalibrationSolver::abc)) {
    d.add(to_params(abc->model).head(model_param_count(abc->model)));
    d.add(abc->base_to_tracker.rotation);
    d.add(abc->base_to_tracker.translation_m);
    d.add(abc->best_cost_m);
    d.add_u64(abc->evaluations);
  }
  if (c.has_lm) {
    d.add(to_params(c.lm.model).head(model_param_count(c.lm.model)));
    d.add(c.lm.base_to_tracker.rotation);
    d.add(c.lm.base_to_tracker.translation_m);
    // The 33 rigid sigmas, then the model's compliance ones: a rigid result hashes as before.
    d.add(c.lm.sigma.head(rigid_param_count(kSixJoints) + c.lm.model.compliance.term_count));
    d.add(c.lm.rms_m);
    d.add_u64(static_cast<std::uint64_t>(c.lm.iterations));
    d.add_mask(c.lm.identifiability.kept_mask);
  }
  // Issue 11: the baseline's fitted tool and base, what LM fixed as not significant, the blunders.
  d.add(to_params(c.baseline.model).head(model_param_count(c.baseline.model)));
  d.add(c.baseline.base_to_tracker.translation_m);
  d.add_mask(c.lm_pruned_mask);
  d.add_u64(c.outlier_count);
  d.add_u64(c.outlier_rounds);
  d.add(c.blunder_test.sigma_m);
  d.add_u64(static_cast<std::uint64_t>(c.blunder_verdict));
  for (const CalibrationOutlier& o : c.outlier_list()) {
    d.add_u64(o.index);
    d.add(o.residual_m);
  }
  const ErrorStats none;
  for (const ErrorStats* s : {&c.baseline.test, final_stage != nullptr ? &final_stage->test : &none}) {
    d.add_u64(s->count);
    for (double v : s->mae_m) d.add(v);
  }
  return d.value();
}

/// Runs the job: the capture passes, then calibrate(). *report gets every result and its
/// digest. Returns the failing status, or ok.
inline Status run_capture_job(CaptureSource& source, const CaptureJobConfig& config, CaptureJobWorkspace* ws,
                              CaptureJobReport* report) {
  report->~CaptureJobReport();
  CaptureJobReport& r = *new (report) CaptureJobReport();  // in place: no 5 KB temporary on the stack
  set_job_nominal(config, ws);
  const RobotModel& nominal = ws->nominal;
  JobCaptureWorkspace* capture = new (ws->arena) JobCaptureWorkspace();
  Status status = config.stop_after == JobStop::clock
                      ? estimate_capture_clock(nominal, source, capture, &r.capture)
                      : extract_dataset_from_captures(nominal, source, capture, &ws->dataset, &r.capture);
  capture->~JobCaptureWorkspace();
  r.samples = r.capture.pass == CapturePass::clock ? 0 : ws->dataset.size();
  if (status != Status::ok || config.stop_after != JobStop::done) {
    r.digest = capture_job_digest(r, false);
    return status;
  }
  JobCalibrationWorkspace* calibration = new (ws->arena) JobCalibrationWorkspace();
  status = calibrate(nominal, &ws->dataset, config.calibration, calibration, &r.calibration);
  calibration->~JobCalibrationWorkspace();
  r.digest = capture_job_digest(r, true);
  return status;
}

}  // namespace hivecal::test
