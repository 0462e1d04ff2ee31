// ABC on the paper's six-length problem (simulated UR5 sessions with known truth): reaches the
// least-squares reference MAE, improves clearly on nominal, and the paper's variant as written
// does worse than the canonical algorithm.
#include <gtest/gtest.h>

#include "hivecal/solve/abc.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/paper6_session.hpp"
#include "testkit/paper6_solver_checks.hpp"
#include "testkit/solver_fixture.hpp"
#include "testkit/test_objectives.hpp"

namespace hivecal::abc_paper6_test {
namespace {

using Solver = AbcSolver<150, kPaper6Dimension>;

Solver& solver() {
  return test::shared_solver<Solver>();
}

using test::kWithinReference;

TEST(AbcPaper6, PaperConfigReachesTheLeastSquaresMaeOnPaperSizedSessions) {
  // The paper: 38 poses, 27 for training; ABC with 150 food sources and 300 cycles; the arm
  // has errors beyond the six lengths, as a real one does.
  test::Paper6Session& session = test::shared_session();
  for (std::uint64_t seed = 11; seed <= 13; ++seed) {
    ASSERT_TRUE(session.simulate(seed, 38, test::Paper6Truth::paper_like));
    ASSERT_EQ(session.cost.size(), 27u);
    AbcOptions options;  // 150 x 300 by default
    options.seed = seed;
    SolverResult result;
    Status s = Status::invalid_argument;
    EXPECT_NO_HEAP(s = solver().minimize(session.cost, session.box.view(), options, &result));
    ASSERT_EQ(s, Status::ok);
    EXPECT_EQ(result.evaluations, 150u + 300u * 300u);
    EXPECT_LE(result.best_cost, kWithinReference * session.reference_mae_m) << "seed " << seed;
    EXPECT_LT(result.best_cost, 0.75 * session.nominal_mae_m);
    // The cost really is the paper's: the generic path gives the same MAE at the optimum.
    const double generic_m = test::generic_mae(session.cell.nominal, result.best_x.data(), session.dataset.train());
    EXPECT_NEAR(result.best_cost, generic_m, 1e-11 * generic_m);
    // And it generalises: the held-out poses improve too.
    EXPECT_LT(session.test_mae(result.best_x.data()), session.test_mae(link_lengths(session.cell.nominal).data()));
  }
}

TEST(AbcPaper6, FirmwareFloatLayoutReachesTheSameMae) {
  // The 84-byte-per-sample layout (docs/solvers-abc-gsa.md, memory) on a paper-sized session.
  static Paper6Cost<test::kMaxSessionSamples, float> compact;
  test::Paper6Session& session = test::shared_session();
  ASSERT_TRUE(session.simulate(14, 38, test::Paper6Truth::paper_like));
  ASSERT_EQ(compact.build(session.cell.nominal, session.dataset.train()), Status::ok);
  AbcOptions options = test::abc_options(60, 200, 14);
  SolverResult result;
  EXPECT_NO_HEAP((void)solver().minimize(compact, session.box.view(), options, &result));
  ASSERT_EQ(result.status, Status::ok);
  EXPECT_LE(result.best_cost, kWithinReference * session.reference_mae_m);
  const double generic_m = test::generic_mae(session.cell.nominal, result.best_x.data(), session.dataset.train());
  EXPECT_NEAR(result.best_cost, generic_m, 1e-6 * generic_m);
}

TEST(AbcPaper6, ReachesTheLeastSquaresMaeOnAFewHundredPoses) {
  test::expect_least_squares_mae_on_a_few_hundred_poses(solver(), test::abc_options(60, 150, 21));
}

TEST(AbcPaper6, PaperVariantAsWrittenConvergesWorseThanCanonical) {
  // One session, the same small budget, several solver seeds: compare medians, not one lucky run.
  constexpr std::size_t kSeeds = 5;
  test::Paper6Session& session = test::shared_session();
  ASSERT_TRUE(session.simulate(31, 38, test::Paper6Truth::paper_like));
  double canonical_excess[kSeeds];
  double paper_excess[kSeeds];
  for (std::size_t i = 0; i < kSeeds; ++i) {
    for (AbcVariant variant : {AbcVariant::canonical, AbcVariant::paper_as_written}) {
      AbcOptions options = test::abc_options(40, 200, 100 + i);
      options.variant = variant;
      SolverResult result;
      EXPECT_NO_HEAP((void)solver().minimize(session.cost, session.box.view(), options, &result));
      ASSERT_EQ(result.status, Status::ok);
      const double excess = result.best_cost / session.reference_mae_m - 1.0;
      (variant == AbcVariant::canonical ? canonical_excess : paper_excess)[i] = excess;
    }
  }
  const double canonical_median = test::median_of(canonical_excess, kSeeds);
  const double paper_median = test::median_of(paper_excess, kSeeds);
  std::printf("median excess over the least-squares MAE: canonical %.4f, paper as written %.4f\n", canonical_median,
              paper_median);
  // At this budget canonical ABC meets the 2 % goal and the variant as written does not.
  EXPECT_LT(canonical_median, 0.02);
  EXPECT_GT(paper_median, 0.02);
  EXPECT_GT(paper_median, canonical_median);
}

TEST(AbcPaper6, PaperVariantAsWrittenCannotContractOnTheSphere) {
  // phi in [0, 1] only ever steps away from the neighbour: no fine convergence.
  static AbcSolver<20, 5> small;
  double canonical[5];
  double paper[5];
  for (std::size_t i = 0; i < 5; ++i) {
    for (AbcVariant variant : {AbcVariant::canonical, AbcVariant::paper_as_written}) {
      test::Sphere sphere(5);
      const test::CubeBox box(5, 5.12);
      AbcOptions options = test::abc_options(20, 500, 200 + i);
      options.variant = variant;
      SolverResult result;
      ASSERT_EQ(small.minimize(sphere, box.view(), options, &result), Status::ok);
      (variant == AbcVariant::canonical ? canonical : paper)[i] = result.best_cost;
    }
  }
  EXPECT_LT(test::median_of(canonical, 5), 1e-20);
  EXPECT_GT(test::median_of(paper, 5), 1e-8);
}

}  // namespace
}  // namespace hivecal::abc_paper6_test
