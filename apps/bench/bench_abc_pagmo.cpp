// Benchmark (not a test): hivecal's ABC against pagmo2's bee_colony on the paper's six-length
// problem, same simulated samples, same cost, same number of cost evaluations, one process.
//
//   hivecal_bench_abc_pagmo [--poses N] [--seed S] [--sources SN] [--cycles C] [--repeat R]
//                           [--seeds K] [--ours-only]
//
// Timed runs: {hivecal ABC, pagmo bee_colony} x {precomputed Paper6Cost, generic evaluate_cost},
// plus hivecal on the float (firmware) layout. The generic cost is what a pagmo user writes with
// this library (FK + Kabsch per candidate); the precomputed one isolates the optimiser's own
// overhead. Then the final MAE of both optimisers over K solver seeds (precomputed cost, so it
// is cheap), compared by median. --ours-only runs just the first row (for callgrind).
// Figures and commands: docs/solvers-abc-gsa.md.
#include <pagmo/algorithms/bee_colony.hpp>
#include <pagmo/population.hpp>
#include <pagmo/problem.hpp>
#include <pagmo/types.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <utility>

#include "hivecal/solve/abc.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/paper6_data.hpp"

namespace {

using hivecal::LinkLengthBox;
using hivecal::Paper6CostBase;

constexpr std::size_t kMaxPoses = 1024;
constexpr std::size_t kMaxSeeds = 101;

struct Settings {
  std::size_t poses = 38;     // the paper's session: 38 poses, 27 for training
  std::uint64_t seed = 1;     // simulation and solver seed
  std::size_t sources = 150;  // the paper's ABC: 150 food sources
  std::size_t cycles = 300;   // and 300 cycles
  int repeat = 3;             // timings keep the fastest of these runs
  std::size_t seeds = 11;     // solver seeds of the final-MAE comparison
  bool ours_only = false;     // just hivecal + precomputed (for callgrind)
};

/// The generic cost as an Objective: FK and a Kabsch fit over every sample per candidate.
class GenericPaper6Cost final : public hivecal::Objective {
 public:
  GenericPaper6Cost(const hivecal::RobotModel& nominal, hivecal::Span<const hivecal::Sample> samples)
      : nominal_(nominal), samples_(samples) {}
  std::size_t dimension() const override { return hivecal::kPaper6Dimension; }
  double evaluate(const double* lengths_m) override { return mae(lengths_m); }
  double mae(const double* lengths_m) const {
    hivecal::RigidTransform base;
    double cost_m = std::numeric_limits<double>::infinity();
    (void)hivecal::evaluate_cost(hivecal::with_link_lengths(nominal_, link_length_set(nominal_), lengths_m), samples_,
                                 hivecal::CostKind::mean_abs_3d, hivecal::BaseFrame::refit, &base, &cost_m);
    return cost_m;
  }

 private:
  hivecal::RobotModel nominal_;
  hivecal::Span<const hivecal::Sample> samples_;
};

/// pagmo user-defined problem over one of the two costs (pointers: pagmo copies UDPs).
struct PagmoPaper6 {
  Paper6CostBase* precomputed = nullptr;       // used when set
  const GenericPaper6Cost* generic = nullptr;  // else this
  LinkLengthBox box;

  pagmo::vector_double fitness(const pagmo::vector_double& x) const {
    return {precomputed != nullptr ? precomputed->evaluate(x.data()) : generic->mae(x.data())};
  }
  std::pair<pagmo::vector_double, pagmo::vector_double> get_bounds() const {
    return {pagmo::vector_double(box.lower_m, box.lower_m + hivecal::kPaper6Dimension),
            pagmo::vector_double(box.upper_m, box.upper_m + hivecal::kPaper6Dimension)};
  }
};

struct RunFigures {
  double seconds = std::numeric_limits<double>::infinity();  // fastest run [s]
  double best_mae_m = 0.0;                                   // final best cost [m]
  unsigned long long evaluations = 0;                        // cost evaluations per run
};

template <typename Run>
RunFigures fastest_of(int repeat, Run run) {
  RunFigures figures;
  for (int r = 0; r < repeat; ++r) {
    const auto start = std::chrono::steady_clock::now();
    const std::pair<double, unsigned long long> outcome = run();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (seconds < figures.seconds) figures.seconds = seconds;
    figures.best_mae_m = outcome.first;
    figures.evaluations = outcome.second;
  }
  return figures;
}

RunFigures run_hivecal(hivecal::Objective& cost, const LinkLengthBox& box, const Settings& settings) {
  static hivecal::AbcSolver<1000, hivecal::kPaper6Dimension> solver;
  hivecal::AbcOptions options;
  options.food_sources = settings.sources;
  options.cycles = settings.cycles;
  options.seed = settings.seed;
  return fastest_of(settings.repeat, [&] {
    hivecal::SolverResult result;
    if (solver.minimize(cost, box.view(), options, &result) != hivecal::Status::ok) std::exit(1);
    return std::make_pair(result.best_cost, static_cast<unsigned long long>(result.evaluations));
  });
}

RunFigures run_pagmo(const PagmoPaper6& udp, const Settings& settings) {
  // Same limit as ours (SN * D, Karaboga's default); pagmo's own default would be 20.
  const auto limit = static_cast<unsigned>(settings.sources * hivecal::kPaper6Dimension);
  const auto seed = static_cast<unsigned>(settings.seed);
  return fastest_of(settings.repeat, [&] {
    pagmo::problem problem(udp);
    pagmo::population population(problem, settings.sources, seed);  // evaluates the initial sources
    pagmo::algorithm algorithm(pagmo::bee_colony(static_cast<unsigned>(settings.cycles), limit, seed));
    population = algorithm.evolve(population);
    return std::make_pair(population.champion_f()[0],
                          static_cast<unsigned long long>(population.get_problem().get_fevals()));
  });
}

double median(double* values, std::size_t count) {
  std::sort(values, values + count);
  return count % 2 == 1 ? values[count / 2] : 0.5 * (values[count / 2 - 1] + values[count / 2]);
}

/// Final MAE of both optimisers over solver seeds 1..K (one repeat each), medians compared.
void compare_quality(PagmoPaper6 udp, Paper6CostBase& precomputed, const LinkLengthBox& box, Settings settings) {
  double ours_m[kMaxSeeds];
  double pagmo_m[kMaxSeeds];
  std::size_t ours_better = 0;
  const std::size_t seeds = settings.seeds;
  settings.repeat = 1;
  for (std::size_t i = 0; i < seeds; ++i) {
    settings.seed = i + 1;
    ours_m[i] = run_hivecal(precomputed, box, settings).best_mae_m;
    pagmo_m[i] = run_pagmo(udp, settings).best_mae_m;
    if (ours_m[i] <= pagmo_m[i]) ++ours_better;
  }
  std::printf("final MAE over %zu solver seeds: median %.4f um (hivecal) vs %.4f um (pagmo); hivecal <= pagmo in %zu\n",
              seeds, 1e6 * median(ours_m, seeds), 1e6 * median(pagmo_m, seeds), ours_better);
}

void print_row(const char* name, const RunFigures& figures, const RunFigures& reference) {
  std::printf("%-34s %9.4f s %9llu evals %8.3f us/eval   MAE %8.4f um   x%.1f\n", name, figures.seconds,
              figures.evaluations, 1e6 * figures.seconds / static_cast<double>(figures.evaluations),
              1e6 * figures.best_mae_m, figures.seconds / reference.seconds);
}

bool parse(int argc, char** argv, Settings* settings) {
  for (int i = 1; i < argc; ++i) {
    const bool has_value = i + 1 < argc;
    if (std::strcmp(argv[i], "--ours-only") == 0) {
      settings->ours_only = true;
    } else if (has_value && std::strcmp(argv[i], "--poses") == 0) {
      settings->poses = std::strtoul(argv[++i], nullptr, 10);
    } else if (has_value && std::strcmp(argv[i], "--seed") == 0) {
      settings->seed = std::strtoull(argv[++i], nullptr, 10);
    } else if (has_value && std::strcmp(argv[i], "--sources") == 0) {
      settings->sources = std::strtoul(argv[++i], nullptr, 10);
    } else if (has_value && std::strcmp(argv[i], "--cycles") == 0) {
      settings->cycles = std::strtoul(argv[++i], nullptr, 10);
    } else if (has_value && std::strcmp(argv[i], "--repeat") == 0) {
      settings->repeat = std::atoi(argv[++i]);
    } else if (has_value && std::strcmp(argv[i], "--seeds") == 0) {
      settings->seeds = std::strtoul(argv[++i], nullptr, 10);
    } else {
      return false;
    }
  }
  return settings->poses >= 5 && settings->poses <= kMaxPoses && settings->sources >= 2 && settings->sources <= 1000 &&
         settings->cycles >= 1 && settings->repeat >= 1 && settings->seeds >= 1 && settings->seeds <= kMaxSeeds;
}

}  // namespace

int main(int argc, char** argv) {
  Settings settings;
  if (!parse(argc, argv, &settings)) {
    std::fprintf(stderr,
                 "usage: hivecal_bench_abc_pagmo [--poses 5..1024] [--seed S] [--sources 2..1000] [--cycles C]"
                 " [--repeat R] [--seeds 1..101] [--ours-only]\n");
    return 2;
  }
  static hivecal::Dataset<kMaxPoses> dataset;
  static hivecal::Paper6Cost<kMaxPoses> precomputed;
  hivecal::Random random(settings.seed);
  const hivecal::test::Paper6Cell cell = hivecal::test::paper6_cell(&random, hivecal::test::Paper6Truth::paper_like);
  hivecal::test::fill_tool_down(cell, settings.poses, 1e-5, &random, &dataset);
  LinkLengthBox box;
  if (dataset.split(hivecal::kDefaultTrainFraction, settings.seed) != hivecal::Status::ok ||
      precomputed.build(cell.nominal, dataset.train()) != hivecal::Status::ok ||
      hivecal::link_length_box(cell.nominal, hivecal::kPaper6DefaultHalfWidth_m, &box) != hivecal::Status::ok) {
    std::fprintf(stderr, "bench: simulated session could not be prepared\n");
    return 1;
  }
  GenericPaper6Cost generic(cell.nominal, dataset.train());
  const hivecal::LinkLengths nominal_m = hivecal::link_lengths(cell.nominal);
  std::printf("paper-6 ABC benchmark: %zu training poses, %zu food sources x %zu cycles, seed %llu\n",
              dataset.train().size(), settings.sources, settings.cycles,
              static_cast<unsigned long long>(settings.seed));
  std::printf("nominal MAE %.4f um (precomputed) / %.4f um (generic)\n\n", 1e6 * precomputed.evaluate(nominal_m.data()),
              1e6 * generic.mae(nominal_m.data()));

  const RunFigures ours = run_hivecal(precomputed, box, settings);
  print_row("hivecal ABC + precomputed cost", ours, ours);
  if (settings.ours_only) return 0;
  static hivecal::Paper6Cost<kMaxPoses, float> compact;
  if (compact.build(cell.nominal, dataset.train()) != hivecal::Status::ok) return 1;
  print_row("hivecal ABC + float-layout cost", run_hivecal(compact, box, settings), ours);
  print_row("hivecal ABC + generic cost", run_hivecal(generic, box, settings), ours);
  PagmoPaper6 udp;
  udp.box = box;
  udp.precomputed = &precomputed;
  print_row("pagmo bee_colony + precomputed cost", run_pagmo(udp, settings), ours);
  udp.precomputed = nullptr;
  udp.generic = &generic;
  const RunFigures pagmo_generic = run_pagmo(udp, settings);
  print_row("pagmo bee_colony + generic cost", pagmo_generic, ours);
  std::printf("\nspeed-up, ours (precomputed) vs pagmo (generic cost): %.1fx; final MAE %.4f vs %.4f um\n",
              pagmo_generic.seconds / ours.seconds, 1e6 * ours.best_mae_m, 1e6 * pagmo_generic.best_mae_m);
  udp.generic = nullptr;
  udp.precomputed = &precomputed;
  compare_quality(udp, precomputed, box, settings);
  return 0;
}
