// The population stage on the link lengths (solve/population_stage.hpp), ABC and GSA at tiny
// settings: only the lengths move, inside the box; the cost is the training MAE by a plain
// loop; the base is the fit on every training sample; the hooks are forwarded; errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>

#include "hivecal/core/random.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/solve/population_stage.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::population_stage_test {
namespace {

constexpr std::size_t kSamples = 60;
Dataset<kSamples> dataset;
Paper6Cost<kSamples> cost;
AbcSolver<12, kPaper6Dimension> abc;
GsaSolver<12, kPaper6Dimension> gsa;
AbcSolver<12, 5> narrow_abc;  // one length short for a UR arm
Trace<32> trace;
Paper6StageResult result;
Paper6StageResult other;
Sample subset_samples[kSamples];

/// The UR link lengths d1, a2, a3, d4, d5, d6 of `model`, read from the DH table [m].
struct Lengths {
  double v[6];
};
Lengths lengths_of(const RobotModel& m) {
  return Lengths{
      {m.joints[0].d_m, m.joints[1].a_m, m.joints[2].a_m, m.joints[3].d_m, m.joints[4].d_m, m.joints[5].d_m}};
}
/// Their ModelParams indices, in the same order.
const int kLengthIndex[6] = {model_param_index(0, DhField::d), model_param_index(1, DhField::a),
                             model_param_index(2, DhField::a), model_param_index(3, DhField::d),
                             model_param_index(4, DhField::d), model_param_index(5, DhField::d)};

const RobotModel& start() {
  static const RobotModel model = nominal_model(RobotType::ur5);
  return model;
}

/// The truth: the start geometry with its six lengths off by 0.4 .. 1.2 mm (either sign).
RobotModel truth_of(Random* random) {
  RobotModel truth = start();
  ModelParams p = to_params(truth);
  for (int k : kLengthIndex) p(k) += (random->below(2) == 0 ? -1.0 : 1.0) * random->uniform(0.4e-3, 1.2e-3);
  set_model_params(p, &truth);
  return truth;
}

/// Noise-free samples of `truth` seen from the example tracker.
RobotModel fill(std::uint64_t seed) {
  Random random(seed);
  const RobotModel truth = truth_of(&random);
  dataset.clear();
  test::fill_dataset(truth, test::example_base_to_tracker(), kSamples, 0.0, &random, &dataset);
  return truth;
}

/// Mean |base * FK(q) * tool - measured| over `samples`, by a plain loop [m].
double mae_3d(const RobotModel& model, const RigidTransform& base, Span<const Sample> samples) {
  double sum = 0.0;
  for (const Sample& s : samples) {
    const Vec3 e = base.apply(fk_tool_point(model, s.q_rad)) - s.point_m;
    sum += std::sqrt(e.x() * e.x() + e.y() * e.y() + e.z() * e.z());
  }
  return sum / static_cast<double>(samples.size());
}

/// Sum of squared errors [m^2].
double sse(const RobotModel& model, const RigidTransform& base, Span<const Sample> samples) {
  double sum = 0.0;
  for (const Sample& s : samples) sum += (base.apply(fk_tool_point(model, s.q_rad)) - s.point_m).squaredNorm();
  return sum;
}

AbcOptions tiny_abc(std::uint64_t seed) {
  AbcOptions options;
  options.food_sources = 10;
  options.cycles = 15;
  options.seed = seed;
  return options;
}

GsaOptions tiny_gsa(std::uint64_t seed) {
  GsaOptions options;
  options.agents = 10;
  options.iterations = 15;
  options.seed = seed;
  return options;
}

/// What both stages must return on noise-free data of `truth` from the start geometry.
void expect_stage_result(const Paper6StageResult& r, const RobotModel& truth, double half_width_m, const char* what) {
  const Span<const Sample> train = dataset.train();
  // Only the six lengths move, each inside start +/- half width.
  const ModelParams got = to_params(r.model);
  const ModelParams from = to_params(start());
  for (int i = 0; i < model_param_count(kSixJoints); ++i) {
    bool is_length = false;
    for (int k : kLengthIndex) is_length = is_length || k == i;
    if (is_length) {
      EXPECT_LE(std::fabs(got(i) - from(i)), half_width_m * (1.0 + 1e-12)) << what << " " << i;
    } else {
      EXPECT_EQ(got(i), from(i)) << what << " " << i;
    }
  }
  // The cost is the training MAE with the base refitted: the stage's base is that fit.
  EXPECT_NEAR(r.best_cost_m, mae_3d(r.model, r.base_to_tracker, train), 1e-12) << what;
  // Better than the start geometry with its own best base, and the five lengths that the cost
  // sees (d1 only slides the base along z) closer to the truth.
  RigidTransform start_base;
  ASSERT_EQ(fit_base_to_tracker(start(), train, &start_base), Status::ok);
  EXPECT_LT(r.best_cost_m, 0.8 * mae_3d(start(), start_base, train)) << what;
  const Lengths found = lengths_of(r.model);
  const Lengths goal = lengths_of(truth);
  const Lengths nominal = lengths_of(start());
  double error_found = 0.0;
  double error_start = 0.0;
  for (int k = 1; k < 6; ++k) {
    error_found += std::fabs(found.v[k] - goal.v[k]);
    error_start += std::fabs(nominal.v[k] - goal.v[k]);
  }
  EXPECT_LT(error_found, 0.8 * error_start) << what;
  // The base is the least-squares fit on the training samples: no small move lowers the SSE.
  const double best_sse = sse(r.model, r.base_to_tracker, train);
  for (int axis = 0; axis < 3; ++axis) {
    for (const double h : {-1e-6, 1e-6}) {
      RigidTransform moved = r.base_to_tracker;
      moved.translation_m(axis) += h;
      EXPECT_GE(sse(r.model, moved, train), best_sse) << what;
      Vec3 turn = Vec3::Zero();
      turn(axis) = h;
      moved = r.base_to_tracker;
      moved.rotation = rotation_x(turn.x()) * rotation_y(turn.y()) * rotation_z(turn.z()) * moved.rotation;
      EXPECT_GE(sse(r.model, moved, train), best_sse) << what;
    }
  }
  EXPECT_NEAR(r.base_to_tracker.rotation.determinant(), 1.0, 1e-12);
}

TEST(PopulationStage, AbcMovesOnlyTheLengthsTowardTheTruth) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const RobotModel truth = fill(900 + seed);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate_paper6_abc(start(), dataset.train(), {}, tiny_abc(seed),
                                                 kPaper6DefaultHalfWidth_m, &cost, &abc, &result));
    ASSERT_EQ(status, Status::ok) << seed;
    expect_stage_result(result, truth, kPaper6DefaultHalfWidth_m, "ABC");
    // SN to start, then SN employed + SN onlookers per cycle (no scout this early).
    EXPECT_EQ(result.evaluations, 10u + 15u * 20u);
    EXPECT_EQ(result.iterations, 15u);
  }
}

TEST(PopulationStage, GsaMovesOnlyTheLengthsTowardTheTruth) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const RobotModel truth = fill(910 + seed);
    Status status = Status::invalid_argument;
    EXPECT_NO_HEAP(status = calibrate_paper6_gsa(start(), dataset.train(), {}, tiny_gsa(seed),
                                                 kPaper6DefaultHalfWidth_m, &cost, &gsa, &result));
    ASSERT_EQ(status, Status::ok) << seed;
    expect_stage_result(result, truth, kPaper6DefaultHalfWidth_m, "GSA");
    EXPECT_EQ(result.evaluations, 10u * 15u);  // every agent once per iteration
    EXPECT_EQ(result.iterations, 15u);
  }
}

TEST(PopulationStage, TheBoxIsStartPlusMinusTheHalfWidth) {
  fill(920);
  const double half_width_m = 1e-5;  // far narrower than the ~1 mm length errors
  ASSERT_EQ(calibrate_paper6_abc(start(), dataset.train(), {}, tiny_abc(3), half_width_m, &cost, &abc, &result),
            Status::ok);
  const Lengths found = lengths_of(result.model);
  const Lengths nominal = lengths_of(start());
  double largest = 0.0;
  for (int k = 0; k < 6; ++k) {
    EXPECT_LE(std::fabs(found.v[k] - nominal.v[k]), half_width_m * (1.0 + 1e-9)) << k;
    largest = std::fmax(largest, std::fabs(found.v[k] - nominal.v[k]));
  }
  EXPECT_GT(largest, 0.1 * half_width_m);  // it did search
  ASSERT_EQ(calibrate_paper6_gsa(start(), dataset.train(), {}, tiny_gsa(3), half_width_m, &cost, &gsa, &result),
            Status::ok);
  const Lengths gsa_found = lengths_of(result.model);
  for (int k = 0; k < 6; ++k) EXPECT_LE(std::fabs(gsa_found.v[k] - nominal.v[k]), half_width_m * (1.0 + 1e-9)) << k;
}

TEST(PopulationStage, ASubsetIsSearchedButTheBaseFitsEveryTrainingSample) {
  fill(930);
  std::uint32_t subset[kSamples / 3] = {};
  for (std::size_t k = 0; k < kSamples / 3; ++k) {
    subset[k] = static_cast<std::uint32_t>(3 * k + 1);
    subset_samples[k] = dataset.train()[3 * k + 1];
  }
  const Span<const Sample> picked(subset_samples, kSamples / 3);
  Status status = Status::invalid_argument;
  EXPECT_NO_HEAP(status = calibrate_paper6_abc(start(), dataset.train(), Span<const std::uint32_t>(subset), tiny_abc(4),
                                               kPaper6DefaultHalfWidth_m, &cost, &abc, &result));
  ASSERT_EQ(status, Status::ok);
  // The cost is the MAE on the subset with the base refitted on the subset ...
  RigidTransform subset_base;
  ASSERT_EQ(fit_base_to_tracker(result.model, picked, &subset_base), Status::ok);
  EXPECT_NEAR(result.best_cost_m, mae_3d(result.model, subset_base, picked), 1e-12);
  EXPECT_GT(std::fabs(result.best_cost_m - mae_3d(result.model, subset_base, dataset.train())), 1e-9);
  // ... while the base returned is the fit on every training sample, not on the subset.
  RigidTransform all_base;
  ASSERT_EQ(fit_base_to_tracker(result.model, dataset.train(), &all_base), Status::ok);
  EXPECT_LT((result.base_to_tracker.translation_m - all_base.translation_m).norm(), 1e-12);
  EXPECT_LT((result.base_to_tracker.rotation - all_base.rotation).norm(), 1e-12);
  EXPECT_GT((subset_base.translation_m - all_base.translation_m).norm(), 1e-9);
  // GSA takes the subset the same way.
  ASSERT_EQ(calibrate_paper6_gsa(start(), dataset.train(), Span<const std::uint32_t>(subset), tiny_gsa(4),
                                 kPaper6DefaultHalfWidth_m, &cost, &gsa, &other),
            Status::ok);
  ASSERT_EQ(fit_base_to_tracker(other.model, picked, &subset_base), Status::ok);
  EXPECT_NEAR(other.best_cost_m, mae_3d(other.model, subset_base, picked), 1e-12);
}

TEST(PopulationStage, ForwardsTraceAndProgressAndRepeatsItsBits) {
  fill(940);
  struct Counter final : ProgressObserver {
    std::size_t calls = 0;
    SolverProgress last;
    void on_iteration(const SolverProgress& progress) override {
      ++calls;
      last = progress;
    }
  };
  Counter counter;
  trace.clear();
  ASSERT_EQ(calibrate_paper6_abc(start(), dataset.train(), {}, tiny_abc(5), kPaper6DefaultHalfWidth_m, &cost, &abc,
                                 &result, &trace, &counter),
            Status::ok);
  EXPECT_EQ(trace.size(), 15u);
  EXPECT_EQ(trace.values()[14], result.best_cost_m);
  EXPECT_EQ(counter.calls, 15u);
  EXPECT_EQ(counter.last.iteration, 15u);
  EXPECT_EQ(counter.last.evaluations, result.evaluations);
  // Same inputs, same bits (the hooks only watch); another seed, another answer.
  ASSERT_EQ(
      calibrate_paper6_abc(start(), dataset.train(), {}, tiny_abc(5), kPaper6DefaultHalfWidth_m, &cost, &abc, &other),
      Status::ok);
  EXPECT_EQ(to_params(other.model), to_params(result.model));
  EXPECT_EQ(other.best_cost_m, result.best_cost_m);
  EXPECT_EQ(other.base_to_tracker.translation_m, result.base_to_tracker.translation_m);
  ASSERT_EQ(
      calibrate_paper6_abc(start(), dataset.train(), {}, tiny_abc(6), kPaper6DefaultHalfWidth_m, &cost, &abc, &other),
      Status::ok);
  EXPECT_NE(other.best_cost_m, result.best_cost_m);

  trace.clear();
  counter = Counter();
  ASSERT_EQ(calibrate_paper6_gsa(start(), dataset.train(), {}, tiny_gsa(5), kPaper6DefaultHalfWidth_m, &cost, &gsa,
                                 &result, &trace, &counter),
            Status::ok);
  EXPECT_EQ(trace.size(), 15u);
  EXPECT_EQ(counter.calls, 15u);
  EXPECT_EQ(counter.last.best_cost, result.best_cost_m);
}

TEST(PopulationStage, ErrorsLeaveTheResultAlone) {
  fill(950);
  const Span<const Sample> train = dataset.train();
  Paper6StageResult sentinel;
  sentinel.best_cost_m = 123.0;
  sentinel.evaluations = 77;
  sentinel.iterations = 5;
  const auto unchanged = [&](const char* what) {
    EXPECT_EQ(result.best_cost_m, 123.0) << what;
    EXPECT_EQ(result.evaluations, 77u) << what;
    EXPECT_EQ(result.iterations, 5u) << what;
  };
  const auto run_abc = [&](const RobotModel& model, Span<const Sample> samples, Span<const std::uint32_t> subset,
                           const AbcOptions& options, double half_width_m) {
    result = sentinel;
    Status s = Status::ok;
    EXPECT_NO_HEAP(s = calibrate_paper6_abc(model, samples, subset, options, half_width_m, &cost, &abc, &result));
    return s;
  };
  const auto run_gsa = [&](const GsaOptions& options, double half_width_m) {
    result = sentinel;
    return calibrate_paper6_gsa(start(), train, {}, options, half_width_m, &cost, &gsa, &result);
  };
  const double h = kPaper6DefaultHalfWidth_m;
  const double nan = std::numeric_limits<double>::quiet_NaN();

  result = sentinel;
  EXPECT_EQ(calibrate_paper6_abc(start(), train, {}, tiny_abc(1), h, nullptr, &abc, &result), Status::invalid_argument);
  unchanged("null cost");
  EXPECT_EQ(calibrate_paper6_abc(start(), train, {}, tiny_abc(1), h, &cost, nullptr, &result),
            Status::invalid_argument);
  unchanged("null ABC solver");
  EXPECT_EQ(calibrate_paper6_gsa(start(), train, {}, tiny_gsa(1), h, &cost, nullptr, &result),
            Status::invalid_argument);
  unchanged("null GSA solver");
  EXPECT_EQ(calibrate_paper6_abc(start(), train, {}, tiny_abc(1), h, &cost, &abc, nullptr), Status::invalid_argument);
  EXPECT_EQ(calibrate_paper6_gsa(start(), train, {}, tiny_gsa(1), h, &cost, &gsa, nullptr), Status::invalid_argument);

  EXPECT_EQ(run_abc(start(), Span<const Sample>(), {}, tiny_abc(1), h), Status::dataset_empty);
  unchanged("no samples");
  EXPECT_EQ(run_abc(start(), train.subspan(0, 2), {}, tiny_abc(1), h), Status::too_few_samples);
  unchanged("two samples");
  Sample same_pose[4];
  for (Sample& s : same_pose) s = train[0];
  EXPECT_EQ(run_abc(start(), Span<const Sample>(same_pose), {}, tiny_abc(1), h), Status::degenerate_geometry);
  unchanged("one pose");
  const std::uint32_t outside[] = {3, static_cast<std::uint32_t>(kSamples)};
  EXPECT_EQ(run_abc(start(), train, Span<const std::uint32_t>(outside), tiny_abc(1), h), Status::invalid_argument);
  unchanged("subset position outside");
  RobotModel broken = start();
  broken.joints[2].a_m = nan;
  EXPECT_EQ(run_abc(broken, train, {}, tiny_abc(1), h), Status::non_finite_input);
  unchanged("NaN length");

  EXPECT_EQ(run_abc(start(), train, {}, tiny_abc(1), 0.0), Status::invalid_argument);
  unchanged("zero half width");
  EXPECT_EQ(run_abc(start(), train, {}, tiny_abc(1), -1e-3), Status::invalid_argument);
  EXPECT_EQ(run_gsa(tiny_gsa(1), nan), Status::invalid_argument);
  unchanged("NaN half width");

  AbcOptions lonely = tiny_abc(1);
  lonely.food_sources = 1;
  EXPECT_EQ(run_abc(start(), train, {}, lonely, h), Status::population_out_of_range);
  unchanged("one food source");
  AbcOptions idle = tiny_abc(1);
  idle.cycles = 0;
  EXPECT_EQ(run_abc(start(), train, {}, idle, h), Status::invalid_argument);
  GsaOptions crowd = tiny_gsa(1);
  crowd.agents = 13;  // capacity 12
  EXPECT_EQ(run_gsa(crowd, h), Status::population_out_of_range);
  unchanged("too many agents");

  result = sentinel;
  EXPECT_EQ(calibrate_paper6_abc(start(), train, {}, tiny_abc(1), h, &cost, &narrow_abc, &result),
            Status::dimension_out_of_range);
  unchanged("five-length solver for six lengths");
}

}  // namespace
}  // namespace hivecal::population_stage_test
