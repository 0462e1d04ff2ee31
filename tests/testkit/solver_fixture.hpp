// Setup and checks shared by the population-solver tests (ABC and GSA, GoogleTest): one
// static solver per type, options of a given population size, iteration count and seed, a
// progress observer that records, and the checks both solvers must pass alike.
#pragma once

#include <gtest/gtest.h>

#include <cstddef>
#include <cstdint>

#include "hivecal/core/math.hpp"
#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"
#include "testkit/test_objectives.hpp"

namespace hivecal::test {

/// One solver of each type for the whole test binary: a solver holds its population inline,
/// too large for a test's stack.
template <typename Solver>
Solver& shared_solver() {
  static Solver solver;
  return solver;
}

/// Default options but for the population size, iteration count and seed.
template <typename Options, std::size_t Options::*Population, std::size_t Options::*Iterations>
Options sized_options(std::size_t population, std::size_t iterations, std::uint64_t seed) {
  Options options;
  options.*Population = population;
  options.*Iterations = iterations;
  options.seed = seed;
  return options;
}

/// ABC options: SN food sources, MCN cycles, seed; the rest default.
inline AbcOptions abc_options(std::size_t food_sources, std::size_t cycles, std::uint64_t seed) {
  return sized_options<AbcOptions, &AbcOptions::food_sources, &AbcOptions::cycles>(food_sources, cycles, seed);
}

/// GSA options: N agents, t_max iterations, seed; the rest default.
inline GsaOptions gsa_options(std::size_t agents, std::size_t iterations, std::uint64_t seed) {
  return sized_options<GsaOptions, &GsaOptions::agents, &GsaOptions::iterations>(agents, iterations, seed);
}

/// Records the progress reports: how many, the last one, and whether they came numbered 1, 2, ...
struct RecordingObserver final : ProgressObserver {
  std::size_t calls = 0;   ///< reports so far
  SolverProgress last;     ///< the latest report
  bool increasing = true;  ///< every report's iteration was calls + 1
  void on_iteration(const SolverProgress& progress) override {
    increasing = increasing && progress.iteration == calls + 1;
    ++calls;
    last = progress;
  }
};

/// On an objective that is NaN almost everywhere (test::MostlyNan, 2-D box +/-3) the solver
/// still ends on a finite cost below `max_cost`: NaN never wins a comparison.
template <typename Solver, typename Options>
void expect_nan_costs_ignored(Solver& solver, const Options& options, double max_cost) {
  MostlyNan mostly_nan(2);
  const CubeBox box(2, 3.0);
  SolverResult result;
  ASSERT_EQ(solver.minimize(mostly_nan, box.view(), options, &result), Status::ok);
  EXPECT_TRUE(math::is_finite(result.best_cost));
  EXPECT_LT(result.best_cost, max_cost);
}

}  // namespace hivecal::test
