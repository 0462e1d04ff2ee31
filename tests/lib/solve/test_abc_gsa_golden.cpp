// Golden digest of the population solvers: ABC (canonical and the paper's variant) and GSA on
// a simulated paper-6 session (exact and float term layouts), and ABC on Rosenbrock, hashed
// over the raw bits of the traces, best parameters, best costs and counts. The committed value must come out on every
// target and optimisation level (host -O0/-O3/-march=native, aarch64, armhf).
#include <gtest/gtest.h>

#include <cstdio>

#include "hivecal/core/digest.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "testkit/alloc_trap.hpp"
#include "testkit/paper6_session.hpp"
#include "testkit/test_objectives.hpp"

namespace hivecal::abc_gsa_golden_test {
namespace {

constexpr std::uint64_t kSolverGoldenDigest = 0xe2806b9f86ac933fULL;

/// Hashes one run into *digest; prints the run's own digest so a mismatch points at a solver.
void add_run(const char* name, const SolverResult& result, const TraceBase& trace, Digest* digest) {
  Digest run;
  run.add_u64(static_cast<std::uint64_t>(result.status));
  for (double value : trace.values()) run.add(value);
  for (double x : result.best_x) run.add(x);
  run.add(result.best_cost);
  run.add_u64(result.evaluations);
  run.add_u64(result.iterations);
  std::printf("  %-14s 0x%016llx (best %.17g)\n", name, static_cast<unsigned long long>(run.value()), result.best_cost);
  digest->add_u64(run.value());
}

std::uint64_t solver_digest() {
  static AbcSolver<30, kPaper6Dimension> abc;
  static GsaSolver<30, kPaper6Dimension> gsa;
  static Trace<64> trace;
  test::Paper6Session& session = test::shared_session();
  Digest digest;
  digest.add_u64(session.simulate(5, 38, test::Paper6Truth::paper_like) ? 1U : 0U);
  const LinkLengths nominal_m = link_lengths(session.cell.nominal);
  Digest setup;
  setup.add(session.cost.evaluate(nominal_m.data()));
  std::printf("  %-14s 0x%016llx\n", "cost setup", static_cast<unsigned long long>(setup.value()));
  digest.add_u64(setup.value());
  for (AbcVariant variant : {AbcVariant::canonical, AbcVariant::paper_as_written}) {
    AbcOptions options;
    options.food_sources = 30;
    options.cycles = 40;
    options.seed = 17;
    options.variant = variant;
    trace.clear();
    SolverResult result;
    (void)abc.minimize(session.cost, session.box.view(), options, &result, &trace);
    add_run(variant == AbcVariant::canonical ? "abc canonical" : "abc paper", result, trace, &digest);
  }
  GsaOptions options;
  options.agents = 30;
  options.iterations = 40;
  options.seed = 17;
  trace.clear();
  SolverResult result;
  (void)gsa.minimize(session.cost, session.box.view(), options, &result, &trace);
  add_run("gsa", result, trace, &digest);

  static Paper6Cost<64, float> compact;
  digest.add_u64(static_cast<std::uint64_t>(compact.build(session.cell.nominal, session.dataset.train())));
  AbcOptions compact_options;
  compact_options.food_sources = 30;
  compact_options.cycles = 40;
  compact_options.seed = 17;
  trace.clear();
  (void)abc.minimize(compact, session.box.view(), compact_options, &result, &trace);
  add_run("abc compact", result, trace, &digest);

  test::Rosenbrock rosenbrock(2);
  const test::CubeBox box(2, 2.048);
  AbcOptions rosenbrock_options;
  rosenbrock_options.food_sources = 10;
  rosenbrock_options.cycles = 50;
  rosenbrock_options.seed = 18;
  trace.clear();
  (void)abc.minimize(rosenbrock, box.view(), rosenbrock_options, &result, &trace);
  add_run("abc rosenbrock", result, trace, &digest);
  return digest.value();
}

TEST(Golden, SolverDigestIsTheSameOnEveryTarget) {
  std::uint64_t digest = 0;
  solver_digest();  // builds the session's statics outside the trap
  EXPECT_NO_HEAP(digest = solver_digest());
  std::printf("solver digest: 0x%016llx\n", static_cast<unsigned long long>(digest));
  EXPECT_EQ(digest, kSolverGoldenDigest);
}

}  // namespace
}  // namespace hivecal::abc_gsa_golden_test
