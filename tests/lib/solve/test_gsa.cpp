// GSA: sanity on the sphere, its contract (options, errors, counts, budget, trace, progress,
// seeding, no heap) and the paper's six-length problem against the least-squares reference.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "hivecal/core/trace.hpp"
#include "hivecal/solve/gsa.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/paper6_session.hpp"
#include "testkit/paper6_solver_checks.hpp"
#include "testkit/solver_fixture.hpp"
#include "testkit/test_objectives.hpp"

namespace hivecal::gsa_test {
namespace {

using Solver = GsaSolver<150, 8>;

Solver& solver() {
  return test::shared_solver<Solver>();
}

using test::kWithinReference;

TEST(GsaSolver, ConvergesOnTheSphere) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    test::Sphere sphere(5);
    const test::CubeBox box(5, 5.12);
    SolverResult result;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = solver().minimize(sphere, box.view(), test::gsa_options(30, 300, seed), &result));
    ASSERT_EQ(s, Status::ok);
    EXPECT_LT(result.best_cost, 1e-8) << "seed " << seed;
  }
}

TEST(GsaSolver, EvaluatesEveryAgentOncePerIteration) {
  test::Sphere sphere(3);
  const test::CubeBox box(3, 1.0);
  static Trace<32> trace;
  trace.clear();
  SolverResult result;
  ASSERT_EQ(solver().minimize(sphere, box.view(), test::gsa_options(12, 9, 2), &result, &trace), Status::ok);
  EXPECT_EQ(result.evaluations, 12u * 9u);
  EXPECT_EQ(sphere.calls, result.evaluations);
  EXPECT_EQ(result.iterations, 9u);
  ASSERT_EQ(trace.size(), 9u);
  for (std::size_t i = 1; i < trace.size(); ++i) EXPECT_LE(trace.values()[i], trace.values()[i - 1]);
  EXPECT_EQ(trace.values()[8], result.best_cost);
  EXPECT_EQ(result.best_cost, sphere.evaluate(result.best_x.data()));
}

TEST(GsaSolver, StopsAtTheEvaluationBudget) {
  test::Sphere sphere(3);
  const test::CubeBox box(3, 1.0);
  GsaOptions options = test::gsa_options(10, 50, 3);
  options.max_evaluations = 35;
  SolverResult result;
  ASSERT_EQ(solver().minimize(sphere, box.view(), options, &result), Status::ok);
  EXPECT_EQ(result.evaluations, 35u);
  EXPECT_EQ(result.iterations, 4u);  // the fourth one cut short
}

TEST(GsaSolver, ReportsProgressOncePerIteration) {
  test::Rosenbrock rosenbrock(2);
  const test::CubeBox box(2, 2.048);
  test::RecordingObserver observer;
  SolverResult result;
  EXPECT_NO_HEAP(
      (void)solver().minimize(rosenbrock, box.view(), test::gsa_options(20, 40, 4), &result, nullptr, &observer));
  EXPECT_EQ(observer.calls, 40u);
  EXPECT_TRUE(observer.increasing);
  EXPECT_EQ(observer.last.iteration, 40u);
  EXPECT_EQ(observer.last.iteration_count, 40u);
  EXPECT_EQ(observer.last.best_cost, result.best_cost);
  EXPECT_EQ(observer.last.evaluations, 800u);
}

TEST(GsaSolver, SameSeedSameBits) {
  double first_x[4] = {};
  double first_cost = 0.0;
  for (int run = 0; run < 2; ++run) {
    test::Rastrigin rastrigin(4);
    const test::CubeBox box(4, 5.12);
    SolverResult result;
    ASSERT_EQ(solver().minimize(rastrigin, box.view(), test::gsa_options(25, 30, 99), &result), Status::ok);
    for (std::size_t d = 0; d < 4; ++d) {
      if (run == 0) first_x[d] = result.best_x[d];
      EXPECT_EQ(result.best_x[d], first_x[d]);
    }
    if (run == 0) first_cost = result.best_cost;
    EXPECT_EQ(result.best_cost, first_cost);
  }
}

TEST(GsaSolver, NanCostsWeighNothing) {
  test::expect_nan_costs_ignored(solver(), test::gsa_options(40, 100, 5), 1e-3);
}

TEST(GsaSolver, AllEqualCostsGiveEqualMassesAndStayInTheBox) {
  // best == worst: the guard gives every agent the same mass; walls stop the agents.
  test::Flat flat(3);
  const double lower[3] = {-1.0, 0.0, 10.0};
  const double upper[3] = {1.0, 0.5, 11.0};
  const SearchBox box{Span<const double>(lower), Span<const double>(upper)};
  SolverResult result;
  ASSERT_EQ(solver().minimize(flat, box, test::gsa_options(10, 20, 6), &result), Status::ok);
  EXPECT_EQ(result.best_cost, 1.0);
  for (std::size_t d = 0; d < 3; ++d) {
    EXPECT_GE(result.best_x[d], lower[d]);
    EXPECT_LE(result.best_x[d], upper[d]);
  }
}

TEST(GsaSolver, RejectsBadOptionsWithoutEvaluating) {
  test::Sphere sphere(3);
  const test::CubeBox box(3, 1.0);
  SolverResult result;
  auto run = [&](const GsaOptions& options) { return solver().minimize(sphere, box.view(), options, &result); };
  EXPECT_EQ(run(test::gsa_options(1, 10, 1)), Status::population_out_of_range);
  EXPECT_EQ(run(test::gsa_options(151, 10, 1)), Status::population_out_of_range);
  EXPECT_EQ(run(test::gsa_options(10, 0, 1)), Status::invalid_argument);
  GsaOptions options = test::gsa_options(10, 10, 1);
  options.g0 = -1.0;
  EXPECT_EQ(run(options), Status::invalid_argument);
  options.g0 = std::numeric_limits<double>::infinity();
  EXPECT_EQ(run(options), Status::invalid_argument);
  options = test::gsa_options(10, 10, 1);
  options.beta = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(run(options), Status::invalid_argument);
  options = test::gsa_options(10, 10, 1);
  options.epsilon = 0.0;
  EXPECT_EQ(run(options), Status::invalid_argument);
  options = test::gsa_options(10, 10, 1);
  options.final_attractors = 0;
  EXPECT_EQ(run(options), Status::invalid_argument);
  options.final_attractors = 11;
  EXPECT_EQ(run(options), Status::invalid_argument);
  options = test::gsa_options(10, 10, 1);
  options.max_evaluations = 5;
  EXPECT_EQ(run(options), Status::invalid_argument);
  const test::CubeBox wrong_box(2, 1.0);
  EXPECT_EQ(solver().minimize(sphere, wrong_box.view(), test::gsa_options(10, 10, 1), &result),
            Status::dimension_out_of_range);
  double lower[3] = {-1.0, -1.0, 2.0};
  const double upper[3] = {1.0, 1.0, 1.0};
  EXPECT_EQ(solver().minimize(sphere, SearchBox{Span<const double>(lower), Span<const double>(upper)},
                              test::gsa_options(10, 10, 1), &result),
            Status::bad_bounds);
  EXPECT_EQ(result.status, Status::bad_bounds);
  EXPECT_EQ(sphere.calls, 0u);
}

using Paper6Solver = GsaSolver<150, kPaper6Dimension>;

Paper6Solver& paper6_solver() {
  return test::shared_solver<Paper6Solver>();
}

TEST(GsaPaper6, PaperConfigReachesTheLeastSquaresMaeOnPaperSizedSessions) {
  test::Paper6Session& session = test::shared_session();
  for (std::uint64_t seed = 11; seed <= 13; ++seed) {
    ASSERT_TRUE(session.simulate(seed, 38, test::Paper6Truth::paper_like));
    GsaOptions options;  // N = 150, t_max = 200
    options.seed = seed;
    static Trace<200> trace;
    trace.clear();
    SolverResult result;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = paper6_solver().minimize(session.cost, session.box.view(), options, &result, &trace));
    ASSERT_EQ(s, Status::ok);
    EXPECT_EQ(result.evaluations, 150u * 200u);
    EXPECT_EQ(trace.size(), 200u);
    EXPECT_LE(result.best_cost, kWithinReference * session.reference_mae_m) << "seed " << seed;
    EXPECT_LT(result.best_cost, 0.75 * session.nominal_mae_m);
    EXPECT_LT(session.test_mae(result.best_x.data()), session.test_mae(link_lengths(session.cell.nominal).data()));
  }
}

TEST(GsaPaper6, ReachesTheLeastSquaresMaeOnAFewHundredPoses) {
  test::expect_least_squares_mae_on_a_few_hundred_poses(paper6_solver(), test::gsa_options(60, 150, 21));
}

}  // namespace
}  // namespace hivecal::gsa_test
