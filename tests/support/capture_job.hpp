// The whole calibration job of the firmware image, shared with the host test so that both
// run exactly the same code on the same capture bytes and seed:
//   robot + tracker capture bytes -> decode -> clock sync (pass 1) -> quasi-static samples
//   (pass 2) -> 70/30 split -> ABC on the paper-6 cost (float layout) -> LM on the full model
//   -> validation on the test split -> a digest of every result bit.
// Every step is a lib/ entry point the command-line tool uses too (capture_pipeline.hpp,
// hybrid.hpp, lm.hpp). Heap-free: the phases' large objects share one static arena
// (placement new; one phase's objects are dead before the next phase starts).
#pragma once

#include <cstddef>
#include <cstdint>
#include <new>

#include "hivecal/sync/capture_pipeline.hpp"
#include "hivecal/sync/clock_sync.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/core/digest.hpp"
#include "hivecal/solve/population_stage.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/model/metrics.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "hivecal/sync/sample_extraction.hpp"
#include "hivecal/core/trace.hpp"

namespace hivecal::test {

/// Samples the job can hold (the firmware budget: 512).
inline constexpr std::size_t kJobSamples = 512;
/// Clock profiles: 3072 knots x 20 ms = 61 s of robot data, 640 tracker points = 64 s.
/// Longer sessions are fine: the clock fit then rests on their first minute.
inline constexpr std::size_t kJobClockRobotKnots = 3072;
inline constexpr std::size_t kJobClockTrackerPoints = 640;
/// Extractor rings: 256 robot records (2 s at 125 Hz: the 1 s window plus the merge lag),
/// 64 tracker points.
inline constexpr std::size_t kJobRobotHistory = 256;
inline constexpr std::size_t kJobTrackerHistory = 64;
/// ABC capacity: the paper's 150 food sources.
inline constexpr std::size_t kJobFoodSources = 150;
inline constexpr std::size_t kJobTraceCapacity = 300;

using JobClockEstimator = ClockEstimator<kJobClockRobotKnots, kJobClockTrackerPoints>;
using JobExtractor = SampleExtractor<kJobRobotHistory, kJobTrackerHistory>;
using JobCost = Paper6Cost<kJobSamples, float>;
using JobAbc = AbcSolver<kJobFoodSources, kPaper6Dimension>;

/// The stages of a job, in order (a report's `stage` is the last one reached).
enum class JobStage : int { clock = 0, extraction, split, abc, lm, done };

/// Settings of one job run.
struct CaptureJobConfig {
  RobotType robot = RobotType::ur5;              ///< nominal geometry
  Vec3 tool_m = Vec3(0.0, 0.0, 0.1695);          ///< nominal tool point in the flange frame [m]
  std::uint64_t seed = 1;                        ///< split and ABC seed
  double train_fraction = 0.7;                   ///< share of samples for training
  std::size_t food_sources = 150;                ///< ABC SN
  std::size_t cycles = 300;                      ///< ABC cycles
  JobStage stop_after = JobStage::done;          ///< end early after this stage (instruction counts per stage)
};

/// The job's results (static storage: the LmResult alone is ~3 KB).
struct CaptureJobReport {
  JobStage stage = JobStage::clock;      ///< last stage reached (done on success)
  Status status = Status::ok;            ///< status of that stage
  StreamPassStats decoding;              ///< decoder counters of pass 1
  ClockFit clock;                        ///< pass 1 result
  ExtractionCounts counts;               ///< pass 2 result
  std::size_t samples = 0;               ///< samples kept
  std::size_t train = 0;                 ///< of which training
  Paper6StageResult abc;                 ///< ABC stage
  LmResult lm;                           ///< LM stage
  ErrorStats uncalibrated_test;          ///< nominal geometry, nominal base fit, on the test split
  ErrorStats calibrated_test;            ///< the LM result on the test split
  std::uint64_t digest = 0;              ///< hash of all of the above that is a result
};

/// Opens (again) both streams at their first byte. Implemented over files on the host and
/// semihosting in the firmware.
class CaptureSource {
 public:
  /// The two readers, positioned at the start; read_failed if they cannot be (re)opened.
  virtual Status open(ByteReader** robot, ByteReader** tracker) = 0;

 protected:
  ~CaptureSource() = default;
};

namespace detail {
template <typename A, typename B>
constexpr std::size_t max_size() { return sizeof(A) > sizeof(B) ? sizeof(A) : sizeof(B); }
}  // namespace detail

/// The ABC phase's objects, built together in the arena.
struct JobAbcPhase {
  JobCost cost;
  JobAbc abc;
  Trace<kJobTraceCapacity> trace;
};

/// Static storage of a job: the dataset, and one arena for whichever phase runs.
struct CaptureJobWorkspace {
  static constexpr std::size_t kArenaBytes =
      detail::max_size<JobClockEstimator, JobExtractor>() > detail::max_size<JobAbcPhase, LmWorkspace>()
          ? detail::max_size<JobClockEstimator, JobExtractor>()
          : detail::max_size<JobAbcPhase, LmWorkspace>();

  Dataset<kJobSamples> dataset;
  alignas(alignof(std::max_align_t)) unsigned char arena[kArenaBytes];
};

/// Hashes every result bit of a report (what host and firmware must agree on).
inline std::uint64_t capture_job_digest(const CaptureJobReport& r) {
  Digest d;
  d.add_u64(static_cast<std::uint64_t>(r.stage));
  d.add_u64(static_cast<std::uint64_t>(r.status));
  d.add(r.clock.offset_us);
  d.add(r.clock.drift);
  d.add(r.clock.offset_at_reference_us);
  d.add(r.clock.sigma_offset_at_reference_us);
  d.add_u64(r.counts.tracker_points);
  d.add_u64(r.counts.kept);
  for (std::uint64_t n : r.counts.dropped) d.add_u64(n);
  d.add_u64(r.samples);
  d.add_u64(r.train);
  d.add(to_params(r.abc.model));
  d.add(r.abc.base_to_tracker.rotation);
  d.add(r.abc.base_to_tracker.translation_m);
  d.add(r.abc.best_cost_m);
  d.add_u64(r.abc.evaluations);
  d.add(to_params(r.lm.model));
  d.add(r.lm.base_to_tracker.rotation);
  d.add(r.lm.base_to_tracker.translation_m);
  d.add(r.lm.sigma);
  d.add(r.lm.rms_m);
  d.add_u64(static_cast<std::uint64_t>(r.lm.iterations));
  d.add_u64(r.lm.identifiability.kept_mask);
  for (const ErrorStats* s : {&r.uncalibrated_test, &r.calibrated_test}) {
    d.add_u64(s->count);
    for (double v : s->mae_m) d.add(v);
  }
  return d.value();
}

/// Runs the job; *report gets every result and its digest. Returns the failing status, or
/// ok (LM's not_converged counts as a result: the last point is used).
inline Status run_capture_job(CaptureSource& source, const CaptureJobConfig& config, CaptureJobWorkspace* ws,
                              CaptureJobReport* report) {
  report->~CaptureJobReport();
  CaptureJobReport& r = *new (report) CaptureJobReport();  // in place: no 4 KB temporary on the stack
  RobotModel nominal = nominal_model(config.robot);
  nominal.tool_m = config.tool_m;
  auto finish = [&](JobStage stage, Status status) {
    r.stage = stage;
    r.status = status;
    r.digest = capture_job_digest(r);
    return status;
  };
  ByteReader* robot = nullptr;
  ByteReader* tracker = nullptr;

  // Pass 1: clock relation.
  Status s = source.open(&robot, &tracker);
  if (s != Status::ok) return finish(JobStage::clock, s);
  {
    JobClockEstimator* estimator = new (ws->arena) JobClockEstimator(make_clock_sync_config(nominal));
    s = estimate_clock_from_streams(*robot, *tracker, estimator, &r.clock, &r.decoding);
    estimator->~JobClockEstimator();
  }
  if (s != Status::ok || config.stop_after == JobStage::clock) return finish(JobStage::clock, s);

  // Pass 2: quasi-static samples.
  s = source.open(&robot, &tracker);
  if (s != Status::ok) return finish(JobStage::extraction, s);
  ws->dataset.clear();
  {
    JobExtractor* extractor = new (ws->arena) JobExtractor(make_extraction_config(nominal), r.clock, &ws->dataset);
    s = extract_samples_from_streams(*robot, *tracker, extractor, nullptr);
    r.counts = extractor->counts();
    extractor->~JobExtractor();
  }
  r.samples = ws->dataset.size();
  if (s != Status::ok || config.stop_after == JobStage::extraction) return finish(JobStage::extraction, s);

  s = ws->dataset.split(config.train_fraction, config.seed);
  r.train = ws->dataset.train().size();
  if (s != Status::ok || config.stop_after == JobStage::split) return finish(JobStage::split, s);
  const Span<const Sample> train = ws->dataset.train();

  // ABC on the paper's six lengths (float terms: 84 B per sample).
  {
    JobAbcPhase* phase = new (ws->arena) JobAbcPhase();
    AbcOptions options;
    options.food_sources = config.food_sources;
    options.cycles = config.cycles;
    options.seed = config.seed;
    s = calibrate_paper6_abc(nominal, train, options, kPaper6DefaultHalfWidth_m, &phase->cost, &phase->abc, &r.abc,
                             &phase->trace);
    phase->~JobAbcPhase();
  }
  if (s != Status::ok || config.stop_after == JobStage::abc) return finish(JobStage::abc, s);

  // LM on the full model from the ABC result.
  {
    LmWorkspace* lm = new (ws->arena) LmWorkspace();
    s = calibrate_lm(r.abc.model, &r.abc.base_to_tracker, train, LmOptions{}, lm, &r.lm);
    lm->~LmWorkspace();
  }
  if (s != Status::ok && s != Status::not_converged) return finish(JobStage::lm, s);

  RigidTransform nominal_base;
  if (fit_base_to_tracker(nominal, train, &nominal_base) == Status::ok) {
    r.uncalibrated_test = position_error_stats(nominal, nominal_base, ws->dataset.test());
  }
  r.calibrated_test = position_error_stats(r.lm.model, r.lm.base_to_tracker, ws->dataset.test());
  finish(JobStage::done, s);
  return Status::ok;
}

}  // namespace hivecal::test
