// Setup shared by the population-solver tests (ABC and GSA): one static solver per type and
// options of a given population size, iteration count and seed.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/gsa.hpp"

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

}  // namespace hivecal::test
