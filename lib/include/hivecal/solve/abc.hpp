// Artificial bee colony (ABC) minimiser over a box: the canonical algorithm of Karaboga &
// Basturk (2008), or the variant as written in Khanesar et al. section II-C (see
// docs/solvers-abc-gsa.md for where and why they differ). No heap: the colony lives in
// AbcSolver<MaxFoodSources, MaxDimension>; the algorithm works on the size-erased base.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/solve/objective.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"

namespace hivecal {

/// Which ABC rules the solver follows.
enum class AbcVariant : int {
  canonical,         ///< Karaboga & Basturk 2008: phi in [-1, 1], onlookers pick p_i = fit_i / sum fit
  paper_as_written,  ///< Khanesar et al. II-C: phi in [0, 1], onlookers pick p_i = cost_i / sum cost
};

/// ABC settings; the defaults are the paper's configuration (150 food sources, 300 cycles).
struct AbcOptions {
  std::size_t food_sources = 150;              ///< SN: food sources = employed bees = onlooker bees, >= 2 [-]
  std::size_t cycles = 300;                    ///< MCN: iterations of employed, onlooker and scout phases, >= 1 [-]
  std::size_t limit = 0;                       ///< failed trials before a source is abandoned; 0 means SN * D [-]
  std::uint64_t max_evaluations = 0;           ///< stop once this many costs were evaluated; 0 = no cap, else >= SN [-]
  std::uint64_t seed = 1;                      ///< seed of the hivecal::Random stream [-]
  AbcVariant variant = AbcVariant::canonical;  ///< rule set
};

/// The ABC algorithm over caller-sized storage (see AbcSolver for the owning type).
class AbcSolverBase {
 public:
  AbcSolverBase(const AbcSolverBase&) = delete;
  AbcSolverBase& operator=(const AbcSolverBase&) = delete;

  /// Minimises `objective` over `box`. Writes the best cost per cycle into *trace and calls
  /// *progress after each cycle (either may be null). Errors (nothing evaluated):
  /// population_out_of_range (SN < 2 or above capacity), dimension_out_of_range, bad_bounds,
  /// invalid_argument (cycles 0, max_evaluations below SN). *result is always written.
  Status minimize(Objective& objective, const SearchBox& box, const AbcOptions& options, SolverResult* result,
                  TraceBase* trace = nullptr, ProgressObserver* progress = nullptr);

  std::size_t max_food_sources() const { return storage_.max_food_sources; }  ///< SN capacity [-]
  std::size_t max_dimension() const { return storage_.max_dimension; }        ///< D capacity [-]

  /// Arrays sized by the owning class: positions [SN x D], and one entry per source or dimension.
  struct Storage {
    double* positions;             ///< food source positions, source-major [objective's units]
    double* costs;                 ///< cost of each source
    double* roulette;              ///< cumulative selection weights of the onlooker phase
    std::size_t* trials;           ///< failed improvement trials per source
    double* candidate;             ///< neighbour being evaluated [objective's units]
    double* best;                  ///< best position so far [objective's units]
    std::size_t max_food_sources;  ///< capacity of the per-source arrays
    std::size_t max_dimension;     ///< capacity of the per-dimension arrays
  };

 protected:
  explicit AbcSolverBase(const Storage& storage) : storage_(storage) {}
  ~AbcSolverBase() = default;

 private:
  Storage storage_;
};

/// An ABC solver owning room for `MaxFoodSources` sources of `MaxDimension` parameters:
/// (MaxFoodSources * (MaxDimension + 2) + 2 * MaxDimension) doubles plus one size_t per source.
/// Big for a stack at the paper's size (150 x 6: ~9 KiB): give it static storage.
template <std::size_t MaxFoodSources, std::size_t MaxDimension>
class AbcSolver final : public AbcSolverBase {
  static_assert(MaxFoodSources >= 2 && MaxDimension >= 1, "ABC needs two sources and one dimension");

 public:
  AbcSolver()
      : AbcSolverBase(
            Storage{positions_, costs_, roulette_, trials_, candidate_, best_, MaxFoodSources, MaxDimension}) {}

 private:
  double positions_[MaxFoodSources * MaxDimension] = {};
  double costs_[MaxFoodSources] = {};
  double roulette_[MaxFoodSources] = {};
  std::size_t trials_[MaxFoodSources] = {};
  double candidate_[MaxDimension] = {};
  double best_[MaxDimension] = {};
};

}  // namespace hivecal
