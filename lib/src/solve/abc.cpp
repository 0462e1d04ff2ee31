#include "hivecal/solve/abc.hpp"

#include "hivecal/core/random.hpp"
#include "solve/solver_common.hpp"

namespace hivecal {
namespace {

/// Canonical ABC fitness: 1 / (1 + f) for f >= 0, 1 + |f| below; 0 for an infinite cost.
double canonical_fitness(double cost) {
  return cost >= 0.0 ? 1.0 / (1.0 + cost) : 1.0 - cost;
}

/// One minimisation: the colony, its random stream and its evaluation budget.
class AbcRun {
 public:
  AbcRun(const AbcSolverBase::Storage& storage, detail::CountedObjective* objective, const SearchBox& box,
         std::size_t dimension, const AbcOptions& options)
      : s_(storage),
        objective_(objective),
        box_(box),
        dimension_(dimension),
        sources_(options.food_sources),
        limit_(options.limit != 0 ? options.limit : options.food_sources * dimension),
        variant_(options.variant),
        random_(options.seed),
        best_(storage.best, dimension) {}

  /// Places every source at random (one evaluation each, SN in all: the budget allows it).
  void initialise() {
    for (std::size_t i = 0; i < sources_; ++i) place_randomly(i);
  }

  /// Each employed bee tries one neighbour of its own source.
  void employed_phase() {
    for (std::size_t i = 0; i < sources_ && !objective_->exhausted(); ++i) try_neighbour(i);
  }

  /// SN onlookers each pick a source by roulette (weights fixed at the start of the phase)
  /// and try one neighbour of it.
  void onlooker_phase() {
    const double total = prepare_roulette();
    for (std::size_t t = 0; t < sources_ && !objective_->exhausted(); ++t) try_neighbour(roulette_pick(total));
  }

  /// The most-tried source is abandoned for a random one once it failed `limit` times
  /// (at most one scout per cycle, as in Karaboga's reference code).
  void scout_phase() {
    std::size_t most_tried = 0;
    for (std::size_t i = 1; i < sources_; ++i) {
      if (s_.trials[i] > s_.trials[most_tried]) most_tried = i;
    }
    if (s_.trials[most_tried] >= limit_ && !objective_->exhausted()) place_randomly(most_tried);
  }

  /// One cycle: employed bees, onlookers, then at most one scout.
  void iterate(std::size_t /*cycle*/) {
    employed_phase();
    onlooker_phase();
    scout_phase();
  }

  double best_cost() const { return best_.cost(); }  ///< best cost so far

 private:
  double* source(std::size_t i) const { return s_.positions + i * dimension_; }

  void place_randomly(std::size_t i) {
    double* x = source(i);
    detail::random_point_in_box(box_, dimension_, &random_, x);
    s_.costs[i] = objective_->evaluate(x);
    s_.trials[i] = 0;
    best_.offer(x, s_.costs[i]);
  }

  /// v_ij = x_ij + phi (x_ij - x_kj) on one random dimension j, k != i, clamped to the box;
  /// greedy: the source moves only if the neighbour is strictly cheaper.
  void try_neighbour(std::size_t i) {
    const double* x = source(i);
    const auto j = static_cast<std::size_t>(random_.below(dimension_));
    auto k = static_cast<std::size_t>(random_.below(sources_ - 1));
    if (k >= i) ++k;
    const double phi = variant_ == AbcVariant::canonical ? random_.uniform(-1.0, 1.0) : random_.uniform01();
    double v = x[j] + phi * (x[j] - source(k)[j]);
    if (v < box_.lower[j]) v = box_.lower[j];
    if (v > box_.upper[j]) v = box_.upper[j];
    for (std::size_t d = 0; d < dimension_; ++d) s_.candidate[d] = x[d];
    s_.candidate[j] = v;
    const double cost = objective_->evaluate(s_.candidate);
    best_.offer(s_.candidate, cost);
    // Comparing costs is comparing canonical fitness (strictly monotone), without its
    // rounding: 1 / (1 + f) cannot tell apart costs that differ by less than ~1e-16.
    if (cost < s_.costs[i]) {
      source(i)[j] = v;
      s_.costs[i] = cost;
      s_.trials[i] = 0;
    } else {
      ++s_.trials[i];
    }
  }

  /// Selection weight of a source: canonical fitness, or the paper's raw cost (assumed >= 0).
  double selection_weight(double cost) const {
    if (variant_ == AbcVariant::canonical) return canonical_fitness(cost);
    return cost > 0.0 ? cost : 0.0;
  }

  /// Fills the cumulative weights; returns their total.
  double prepare_roulette() {
    double total = 0.0;
    for (std::size_t i = 0; i < sources_; ++i) {
      total += selection_weight(s_.costs[i]);
      s_.roulette[i] = total;
    }
    return total;
  }

  /// Source i with probability weight_i / total (binary search of u * total in the cumulative
  /// weights); uniform when the weights cannot be normalised (total 0 or Inf).
  std::size_t roulette_pick(double total) {
    if (!(total > 0.0 && math::is_finite(total))) return static_cast<std::size_t>(random_.below(sources_));
    double target = random_.uniform01() * total;
    const double last = s_.roulette[sources_ - 1];
    if (target >= last) target = last * (1.0 - 1e-16);  // u * total may round up to the total
    std::size_t lo = 0;
    std::size_t hi = sources_ - 1;
    while (lo < hi) {  // first i with roulette[i] > target: it has a positive weight
      const std::size_t mid = lo + (hi - lo) / 2;
      if (s_.roulette[mid] > target) {
        hi = mid;
      } else {
        lo = mid + 1;
      }
    }
    return lo;
  }

  const AbcSolverBase::Storage& s_;
  detail::CountedObjective* objective_;
  const SearchBox& box_;
  std::size_t dimension_;
  std::size_t sources_;
  std::size_t limit_;
  AbcVariant variant_;
  Random random_;
  detail::BestSoFar best_;
};

Status validate(const AbcOptions& options, const SearchBox& box, std::size_t dimension, std::size_t max_sources,
                std::size_t max_dimension) {
  const Status common = detail::validate_population_and_box(options.food_sources, max_sources, options.max_evaluations,
                                                            box, dimension, max_dimension);
  if (common != Status::ok) return common;
  if (options.cycles == 0) return Status::invalid_argument;
  if (options.variant != AbcVariant::canonical && options.variant != AbcVariant::paper_as_written) {
    return Status::invalid_argument;
  }
  return Status::ok;
}

}  // namespace

Status AbcSolverBase::minimize(Objective& objective, const SearchBox& box, const AbcOptions& options,
                               SolverResult* result, TraceBase* trace, ProgressObserver* progress) {
  const std::size_t dimension = objective.dimension();
  const Status valid = validate(options, box, dimension, storage_.max_food_sources, storage_.max_dimension);
  return detail::run_population<AbcRun>(valid, objective, box, dimension, storage_, options, options.cycles, result,
                                        trace, progress);
}

}  // namespace hivecal
