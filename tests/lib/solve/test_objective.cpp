// The population solvers' common contract (solve/objective.hpp): validate_search_box's errors
// and their order against an independent predicate on random boxes, the result's defaults,
// NaN costs as +Inf in both solvers, and the progress hook's reports (after the trace).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "hivecal/core/trace.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "hivecal/solve/objective.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::objective_test {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

AbcSolver<8, 4> abc;
GsaSolver<8, 4> gsa;
Trace<32> trace;

AbcOptions tiny_abc(std::uint64_t seed) {
  AbcOptions options;
  options.food_sources = 6;
  options.cycles = 10;
  options.seed = seed;
  return options;
}

GsaOptions tiny_gsa(std::uint64_t seed) {
  GsaOptions options;
  options.agents = 6;
  options.iterations = 10;
  options.seed = seed;
  return options;
}

/// x[0] over the box, NaN where x[0] < 0: lower costs lie only where the cost is NaN.
class NanBelowZero final : public Objective {
 public:
  explicit NanBelowZero(std::size_t dimension) : dimension_(dimension) {}
  std::size_t dimension() const override { return dimension_; }
  double evaluate(const double* x) override {
    ++calls;
    return x[0] < 0.0 ? kNan : x[0];
  }
  std::uint64_t calls = 0;  ///< evaluations so far

 private:
  std::size_t dimension_;
};

/// NaN everywhere.
class AlwaysNan final : public Objective {
 public:
  std::size_t dimension() const override { return 2; }
  double evaluate(const double*) override { return kNan; }
};

/// sum (x_d - 0.3)^2.
class Bowl final : public Objective {
 public:
  std::size_t dimension() const override { return 3; }
  double evaluate(const double* x) override {
    double sum = 0.0;
    for (int d = 0; d < 3; ++d) sum += (x[d] - 0.3) * (x[d] - 0.3);
    return sum;
  }
};

/// Checks each report against the trace as it stands when the report arrives.
struct CheckingObserver final : ProgressObserver {
  const TraceBase* watched = nullptr;
  std::size_t calls = 0;
  bool numbered = true;          // iteration == calls + 1 each time
  bool trace_updated = true;     // the trace holds `iteration` values, the last the best cost
  bool cost_monotone = true;     // best cost never rises
  bool evaluations_grow = true;  // evaluations strictly increase
  std::size_t planned = 0;
  SolverProgress last;
  void on_iteration(const SolverProgress& progress) override {
    numbered = numbered && progress.iteration == calls + 1;
    if (calls == 0) planned = progress.iteration_count;
    numbered = numbered && progress.iteration_count == planned;
    if (watched != nullptr) {
      trace_updated = trace_updated && watched->size() == progress.iteration &&
                      watched->values()[watched->size() - 1] == progress.best_cost;
    }
    if (calls > 0) {
      cost_monotone = cost_monotone && progress.best_cost <= last.best_cost;
      evaluations_grow = evaluations_grow && progress.evaluations > last.evaluations;
    }
    last = progress;
    ++calls;
  }
};

/// Whether a box of `count_lower`/`count_upper` bounds is valid for `dimension` <= `max`: the
/// contract restated: sizes first, then every pair finite with lower < upper.
Status expected_status(const double* lower, std::size_t count_lower, const double* upper, std::size_t count_upper,
                       std::size_t dimension, std::size_t max) {
  if (dimension == 0 || dimension > max || count_lower != dimension || count_upper != dimension) {
    return Status::dimension_out_of_range;
  }
  for (std::size_t d = 0; d < dimension; ++d) {
    if (std::isnan(lower[d]) || std::isnan(upper[d]) || std::isinf(lower[d]) || std::isinf(upper[d])) {
      return Status::bad_bounds;
    }
    if (!(lower[d] < upper[d])) return Status::bad_bounds;
  }
  return Status::ok;
}

TEST(SearchBox, ValidBoxesPassAndEachFlawHasItsError) {
  const double lower[3] = {-1.0, 0.0, 5.0};
  const double upper[3] = {1.0, 1e-300, 5.000000000000001};  // tiny but non-empty intervals
  const SearchBox box{Span<const double>(lower), Span<const double>(upper)};
  Status s = Status::invalid_argument;
  EXPECT_NO_HEAP(s = validate_search_box(box, 3, 3));
  EXPECT_EQ(s, Status::ok);
  EXPECT_EQ(validate_search_box(box, 3, 8), Status::ok);
  EXPECT_EQ(validate_search_box(box, 0, 8), Status::dimension_out_of_range);
  EXPECT_EQ(validate_search_box(box, 3, 2), Status::dimension_out_of_range);  // above capacity
  EXPECT_EQ(validate_search_box(box, 2, 8), Status::dimension_out_of_range);  // 3 bounds, dimension 2
  EXPECT_EQ(validate_search_box(SearchBox{Span<const double>(lower), Span<const double>(upper, 2)}, 3, 8),
            Status::dimension_out_of_range);
  EXPECT_EQ(validate_search_box(SearchBox{Span<const double>(lower, 2), Span<const double>(upper)}, 3, 8),
            Status::dimension_out_of_range);
  EXPECT_EQ(validate_search_box(SearchBox{}, 1, 8), Status::dimension_out_of_range);
  for (const double bad : {kNan, kInf, -kInf}) {
    double l[3] = {-1.0, -1.0, -1.0};
    double u[3] = {1.0, 1.0, 1.0};
    const SearchBox b{Span<const double>(l), Span<const double>(u)};
    l[2] = bad;
    EXPECT_EQ(validate_search_box(b, 3, 3), Status::bad_bounds) << bad;
    l[2] = -1.0;
    u[0] = bad;
    EXPECT_EQ(validate_search_box(b, 3, 3), Status::bad_bounds) << bad;
    // A size mismatch is reported before a bad bound.
    EXPECT_EQ(validate_search_box(b, 2, 3), Status::dimension_out_of_range) << bad;
  }
  double l[2] = {0.5, 0.0};
  double u[2] = {0.5, 1.0};  // empty interval
  const SearchBox empty{Span<const double>(l), Span<const double>(u)};
  EXPECT_EQ(validate_search_box(empty, 2, 2), Status::bad_bounds);
  u[0] = 0.25;  // reversed
  EXPECT_EQ(validate_search_box(empty, 2, 2), Status::bad_bounds);
}

TEST(SearchBox, AgreesWithTheContractOnRandomBoxes) {
  Random random(801);
  double lower[6] = {};
  double upper[6] = {};
  int flawed = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const std::size_t dimension = static_cast<std::size_t>(random.below(6)) + (trial % 10 == 0 ? 0 : 1);
    const std::size_t max = static_cast<std::size_t>(random.below(7));
    std::size_t count_lower = dimension;
    std::size_t count_upper = dimension;
    if (random.below(8) == 0) count_lower = static_cast<std::size_t>(random.below(7));
    if (random.below(8) == 0) count_upper = static_cast<std::size_t>(random.below(7));
    for (int d = 0; d < 6; ++d) {
      lower[d] = random.uniform(-10.0, 10.0);
      upper[d] = lower[d] + random.uniform(1e-9, 5.0);
      switch (random.below(40)) {  // now and then one flaw
        case 0: lower[d] = kNan; break;
        case 1: upper[d] = kInf; break;
        case 2: lower[d] = -kInf; break;
        case 3: upper[d] = lower[d]; break;
        case 4: upper[d] = lower[d] - 1.0; break;
        default: break;
      }
    }
    const SearchBox box{Span<const double>(lower, count_lower), Span<const double>(upper, count_upper)};
    const Status expected = expected_status(lower, count_lower, upper, count_upper, dimension, max);
    flawed += expected == Status::bad_bounds ? 1 : 0;
    EXPECT_EQ(validate_search_box(box, dimension, max), expected) << "trial " << trial;
  }
  EXPECT_GT(flawed, 100);  // the cases do cover bad bounds
}

TEST(SolverResult, DefaultsSayNothingWasRun) {
  const SolverResult result;
  EXPECT_EQ(result.status, Status::invalid_argument);
  EXPECT_TRUE(result.best_x.empty());
  EXPECT_EQ(result.best_cost, 0.0);
  EXPECT_EQ(result.evaluations, 0u);
  EXPECT_EQ(result.iterations, 0u);
  const SolverProgress progress;
  EXPECT_EQ(progress.iteration, 0u);
  EXPECT_EQ(progress.iteration_count, 0u);
  EXPECT_EQ(progress.evaluations, 0u);
}

TEST(Objective, NanCostsAreWorstInBothSolvers) {
  const double lower[2] = {-1.0, -1.0};
  const double upper[2] = {1.0, 1.0};
  const SearchBox box{Span<const double>(lower), Span<const double>(upper)};
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    NanBelowZero objective(2);
    SolverResult result;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = abc.minimize(objective, box, tiny_abc(seed), &result));
    ASSERT_EQ(s, Status::ok);
    EXPECT_TRUE(math::is_finite(result.best_cost)) << "ABC seed " << seed;
    EXPECT_GE(result.best_x[0], 0.0) << "ABC seed " << seed;
    EXPECT_EQ(result.best_cost, result.best_x[0]);
    EXPECT_EQ(objective.calls, result.evaluations);

    NanBelowZero other(2);
    EXPECT_NO_HEAP(s = gsa.minimize(other, box, tiny_gsa(seed), &result));
    ASSERT_EQ(s, Status::ok);
    EXPECT_TRUE(math::is_finite(result.best_cost)) << "GSA seed " << seed;
    EXPECT_GE(result.best_x[0], 0.0) << "GSA seed " << seed;
    EXPECT_EQ(result.best_cost, result.best_x[0]);
  }
  // Nothing but NaN: the best cost is +Inf, the run still completes.
  AlwaysNan nan;
  SolverResult result;
  ASSERT_EQ(abc.minimize(nan, box, tiny_abc(5), &result), Status::ok);
  EXPECT_EQ(result.best_cost, kInf);
  EXPECT_EQ(result.iterations, 10u);
  ASSERT_EQ(gsa.minimize(nan, box, tiny_gsa(5), &result), Status::ok);
  EXPECT_EQ(result.best_cost, kInf);
  EXPECT_EQ(result.iterations, 10u);
}

TEST(ProgressObserver, ReportsEachIterationAfterTheTrace) {
  const double lower[3] = {-1.0, -1.0, -1.0};
  const double upper[3] = {1.0, 1.0, 1.0};
  const SearchBox box{Span<const double>(lower), Span<const double>(upper)};
  for (int solver = 0; solver < 2; ++solver) {
    Bowl bowl;
    trace.clear();
    CheckingObserver observer;
    observer.watched = &trace;
    SolverResult result;
    Status s = Status::invalid_argument;
    if (solver == 0) {
      EXPECT_NO_HEAP(s = abc.minimize(bowl, box, tiny_abc(7), &result, &trace, &observer));
    } else {
      EXPECT_NO_HEAP(s = gsa.minimize(bowl, box, tiny_gsa(7), &result, &trace, &observer));
    }
    ASSERT_EQ(s, Status::ok) << solver;
    EXPECT_EQ(result.status, Status::ok);
    EXPECT_EQ(observer.calls, 10u) << solver;
    EXPECT_TRUE(observer.numbered) << solver;
    EXPECT_EQ(observer.planned, 10u);
    EXPECT_TRUE(observer.trace_updated) << solver;
    EXPECT_TRUE(observer.cost_monotone) << solver;
    EXPECT_TRUE(observer.evaluations_grow) << solver;
    EXPECT_EQ(observer.last.best_cost, result.best_cost);
    EXPECT_EQ(observer.last.evaluations, result.evaluations);
    EXPECT_EQ(result.iterations, 10u);
    // best_x is the point of best_cost, viewed inside the solver (not a copy of its own).
    ASSERT_EQ(result.best_x.size(), 3u);
    Bowl check;
    EXPECT_EQ(check.evaluate(result.best_x.data()), result.best_cost);
    const char* begin = solver == 0 ? reinterpret_cast<const char*>(&abc) : reinterpret_cast<const char*>(&gsa);
    const std::size_t size = solver == 0 ? sizeof abc : sizeof gsa;
    const char* x = reinterpret_cast<const char*>(result.best_x.data());
    EXPECT_TRUE(x >= begin && x < begin + size) << solver;
  }
  // Without an observer or a trace the run is the same (the hooks only watch).
  Bowl bowl;
  SolverResult watched;
  SolverResult bare;
  CheckingObserver observer;
  trace.clear();
  ASSERT_EQ(gsa.minimize(bowl, box, tiny_gsa(9), &watched, &trace, &observer), Status::ok);
  const double watched_cost = watched.best_cost;
  ASSERT_EQ(gsa.minimize(bowl, box, tiny_gsa(9), &bare), Status::ok);
  EXPECT_EQ(bare.best_cost, watched_cost);
  EXPECT_EQ(bare.evaluations, watched.evaluations);
}

}  // namespace
}  // namespace hivecal::objective_test
