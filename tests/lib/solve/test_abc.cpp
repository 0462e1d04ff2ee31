// ABC on standard benchmark functions (known optima) and its contract: options, errors,
// evaluation counts, scouts, budget, trace, progress hook, seeding, no heap.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hivecal/core/trace.hpp"
#include "hivecal/solve/abc.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/solver_fixture.hpp"
#include "testkit/test_objectives.hpp"

namespace hivecal::abc_test {
namespace {

using Solver = AbcSolver<40, 8>;

Solver& solver() {
  return test::shared_solver<Solver>();
}

TEST(AbcSolver, FindsTheSphereMinimum) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    test::Sphere sphere(5);
    const test::CubeBox box(5, 5.12);
    SolverResult result;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = solver().minimize(sphere, box.view(), test::abc_options(20, 500, seed), &result));
    ASSERT_EQ(s, Status::ok);
    EXPECT_LT(result.best_cost, 1e-20) << "seed " << seed;
    ASSERT_EQ(result.best_x.size(), 5u);
    for (double x : result.best_x) EXPECT_LT(std::fabs(x), 1e-10);
  }
}

TEST(AbcSolver, FindsTheRosenbrockValley) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    test::Rosenbrock rosenbrock(2);
    const test::CubeBox box(2, 2.048);
    SolverResult result;
    EXPECT_NO_HEAP((void)solver().minimize(rosenbrock, box.view(), test::abc_options(20, 1000, seed), &result));
    ASSERT_EQ(result.status, Status::ok);
    EXPECT_LT(result.best_cost, 1e-2) << "seed " << seed;  // ABC creeps along the curved valley
    EXPECT_NEAR(result.best_x[0], 1.0, 0.15);
    EXPECT_NEAR(result.best_x[1], 1.0, 0.3);
  }
}

TEST(AbcSolver, EscapesRastriginLocalMinima) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    test::Rastrigin rastrigin(3);
    const test::CubeBox box(3, 5.12);
    SolverResult result;
    EXPECT_NO_HEAP((void)solver().minimize(rastrigin, box.view(), test::abc_options(20, 500, seed), &result));
    EXPECT_LT(result.best_cost, 1e-10) << "seed " << seed;
    for (double x : result.best_x) EXPECT_LT(std::fabs(x), 1e-6);
  }
}

TEST(AbcSolver, CountsEvaluationsLikeTheReferenceAlgorithm) {
  // SN to start, then SN employed + SN onlooker per cycle; no scout before `limit` failures.
  test::Sphere sphere(4);
  const test::CubeBox box(4, 1.0);
  SolverResult result;
  ASSERT_EQ(solver().minimize(sphere, box.view(), test::abc_options(10, 7, 3), &result), Status::ok);
  EXPECT_EQ(result.evaluations, 10u + 7u * 20u);
  EXPECT_EQ(sphere.calls, result.evaluations);
  EXPECT_EQ(result.iterations, 7u);
  EXPECT_EQ(result.best_cost, sphere.evaluate(result.best_x.data()));
}

TEST(AbcSolver, AbandonsExhaustedSourcesOnePerCycle) {
  // Nothing ever improves on a flat cost: with limit 1 every cycle sends exactly one scout.
  test::Flat flat(3);
  const test::CubeBox box(3, 1.0);
  AbcOptions options = test::abc_options(10, 6, 4);
  options.limit = 1;
  SolverResult result;
  ASSERT_EQ(solver().minimize(flat, box.view(), options, &result), Status::ok);
  EXPECT_EQ(result.evaluations, 10u + 6u * 21u);
  // With the default limit (SN * D = 30) no source fails that often within 6 cycles.
  test::Flat flat_default(3);
  ASSERT_EQ(solver().minimize(flat_default, box.view(), test::abc_options(10, 6, 4), &result), Status::ok);
  EXPECT_EQ(result.evaluations, 10u + 6u * 20u);
}

TEST(AbcSolver, StopsAtTheEvaluationBudget) {
  test::Sphere sphere(4);
  const test::CubeBox box(4, 1.0);
  AbcOptions options = test::abc_options(10, 100, 5);
  options.max_evaluations = 95;
  static Trace<128> trace;
  trace.clear();
  SolverResult result;
  ASSERT_EQ(solver().minimize(sphere, box.view(), options, &result, &trace), Status::ok);
  EXPECT_EQ(result.evaluations, 95u);
  EXPECT_EQ(sphere.calls, 95u);
  EXPECT_EQ(result.iterations, 5u);  // 10 + 4 * 20 = 90, the fifth cycle is cut short
  EXPECT_EQ(trace.size(), 5u);
}

TEST(AbcSolver, TracesTheBestCostAndReportsProgressEachCycle) {
  test::Rastrigin rastrigin(2);
  const test::CubeBox box(2, 5.12);
  static Trace<64> trace;
  trace.clear();
  test::RecordingObserver observer;
  SolverResult result;
  Status s = Status::invalid_argument;
  EXPECT_NO_HEAP(
      s = solver().minimize(rastrigin, box.view(), test::abc_options(12, 50, 6), &result, &trace, &observer));
  ASSERT_EQ(s, Status::ok);
  ASSERT_EQ(trace.size(), 50u);
  for (std::size_t i = 1; i < trace.size(); ++i) EXPECT_LE(trace.values()[i], trace.values()[i - 1]);
  EXPECT_EQ(trace.values()[49], result.best_cost);
  EXPECT_EQ(observer.calls, 50u);
  EXPECT_TRUE(observer.increasing);
  EXPECT_EQ(observer.last.iteration_count, 50u);
  EXPECT_EQ(observer.last.best_cost, result.best_cost);
  EXPECT_EQ(observer.last.evaluations, result.evaluations);
}

TEST(AbcSolver, SameSeedSameBitsOtherSeedOtherPath) {
  static Trace<64> first;
  static Trace<64> second;
  double first_x[3] = {};
  double first_cost = 0.0;
  for (Trace<64>* trace : {&first, &second}) {
    trace->clear();
    test::Rastrigin rastrigin(3);
    const test::CubeBox box(3, 5.12);
    SolverResult result;
    ASSERT_EQ(solver().minimize(rastrigin, box.view(), test::abc_options(15, 40, 77), &result, trace), Status::ok);
    if (trace == &first) {
      for (int d = 0; d < 3; ++d) first_x[d] = result.best_x[d];
      first_cost = result.best_cost;
    } else {
      for (int d = 0; d < 3; ++d) EXPECT_EQ(result.best_x[d], first_x[d]);
      EXPECT_EQ(result.best_cost, first_cost);
    }
  }
  for (std::size_t i = 0; i < first.size(); ++i) EXPECT_EQ(first.values()[i], second.values()[i]);
  test::Rastrigin rastrigin(3);
  const test::CubeBox box(3, 5.12);
  SolverResult other;
  second.clear();
  ASSERT_EQ(solver().minimize(rastrigin, box.view(), test::abc_options(15, 40, 78), &other, &second), Status::ok);
  EXPECT_NE(second.values()[0], first.values()[0]);
}

TEST(AbcSolver, NanCostsCountAsWorst) {
  test::expect_nan_costs_ignored(solver(), test::abc_options(20, 200, 8), 1e-6);
}

TEST(AbcSolver, StaysInsideTheBox) {
  // The sphere's minimum is outside this box: the best point sits on the nearest corner.
  test::Sphere sphere(2);
  const double lower[2] = {1.0, -3.0};
  const double upper[2] = {2.0, -2.0};
  const SearchBox box{Span<const double>(lower), Span<const double>(upper)};
  SolverResult result;
  ASSERT_EQ(solver().minimize(sphere, box, test::abc_options(10, 100, 9), &result), Status::ok);
  EXPECT_EQ(result.best_x[0], 1.0);
  EXPECT_EQ(result.best_x[1], -2.0);
}

TEST(AbcSolver, RejectsBadOptionsWithoutEvaluating) {
  test::Sphere sphere(3);
  const test::CubeBox box(3, 1.0);
  SolverResult result;
  auto run = [&](const AbcOptions& options, const SearchBox& search_box) {
    return solver().minimize(sphere, search_box, options, &result);
  };
  EXPECT_EQ(run(test::abc_options(1, 10, 1), box.view()), Status::population_out_of_range);
  EXPECT_EQ(run(test::abc_options(0, 10, 1), box.view()), Status::population_out_of_range);
  EXPECT_EQ(run(test::abc_options(41, 10, 1), box.view()), Status::population_out_of_range);
  EXPECT_EQ(result.status, Status::population_out_of_range);
  EXPECT_EQ(run(test::abc_options(10, 0, 1), box.view()), Status::invalid_argument);
  AbcOptions tight = test::abc_options(10, 10, 1);
  tight.max_evaluations = 9;
  EXPECT_EQ(run(tight, box.view()), Status::invalid_argument);
  AbcOptions bad_variant = test::abc_options(10, 10, 1);
  bad_variant.variant = static_cast<AbcVariant>(7);
  EXPECT_EQ(run(bad_variant, box.view()), Status::invalid_argument);

  const test::CubeBox short_box(2, 1.0);
  EXPECT_EQ(run(test::abc_options(10, 10, 1), short_box.view()), Status::dimension_out_of_range);
  test::Sphere too_wide(9);
  const test::CubeBox wide_box(9, 1.0);
  EXPECT_EQ(solver().minimize(too_wide, wide_box.view(), test::abc_options(10, 10, 1), &result),
            Status::dimension_out_of_range);
  test::Sphere nothing(0);
  EXPECT_EQ(solver().minimize(nothing, SearchBox{}, test::abc_options(10, 10, 1), &result),
            Status::dimension_out_of_range);

  double lower[3] = {-1.0, -1.0, -1.0};
  double upper[3] = {1.0, 1.0, 1.0};
  const SearchBox own_box{Span<const double>(lower), Span<const double>(upper)};
  lower[1] = 1.0;  // empty interval
  EXPECT_EQ(run(test::abc_options(10, 10, 1), own_box), Status::bad_bounds);
  lower[1] = -std::numeric_limits<double>::infinity();
  EXPECT_EQ(run(test::abc_options(10, 10, 1), own_box), Status::bad_bounds);
  lower[1] = -1.0;
  upper[2] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(run(test::abc_options(10, 10, 1), own_box), Status::bad_bounds);
  EXPECT_EQ(sphere.calls, 0u);
}

TEST(SolverStatus, NewCodesHaveMessages) {
  for (Status status : {Status::population_out_of_range, Status::dimension_out_of_range, Status::bad_bounds}) {
    EXPECT_STRNE(status_message(status), "unknown status");
  }
}

}  // namespace
}  // namespace hivecal::abc_test
