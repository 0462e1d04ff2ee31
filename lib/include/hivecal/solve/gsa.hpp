// Gravitational search algorithm (GSA, Rashedi, Nezamabadi-pour & Saryazdi 2009) over a box,
// as in Khanesar et al. section II-D. Agents move in box-normalised coordinates u in [0, 1]^D
// (x = lower + u (upper - lower)), so G is in box widths per iteration^2 and one G0 suits any
// box. No heap: the agents live in GsaSolver<MaxAgents, MaxDimension>.
#pragma once

#include <cstddef>
#include <cstdint>

#include "hivecal/solve/objective.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/trace.hpp"

namespace hivecal {

/// GSA settings; the defaults are the paper's (N = 150, t_max = 200, beta = 20, eps = 2.22e-16).
/// The distance power r_p is 1 (force ~ 1 / R), as in the paper. The paper gives no G0; 5 box
/// widths works on the six-length problem where Rashedi's 100 on a 200-wide box (0.5) stalls
/// (docs/solvers-abc-gsa.md).
struct GsaOptions {
  std::size_t agents = 150;           ///< N: agents, >= 2 [-]
  std::size_t iterations = 200;       ///< t_max: iterations, each evaluates every agent once, >= 1 [-]
  double g0 = 5.0;                    ///< G0: initial gravitational constant [box widths / iteration^2]
  double beta = 20.0;                 ///< decay of G(t) = G0 exp(-beta t / t_max) [-]
  double epsilon = 2.22e-16;          ///< added to agent distances [box widths]
  std::size_t final_attractors = 1;   ///< k_best at t_max; k_best falls linearly from N, >= 1 [-]
  std::uint64_t max_evaluations = 0;  ///< stop once this many costs were evaluated; 0 = no cap, else >= N [-]
  std::uint64_t seed = 1;             ///< seed of the hivecal::Random stream [-]
};

/// The GSA algorithm over caller-sized storage (see GsaSolver for the owning type).
class GsaSolverBase {
 public:
  GsaSolverBase(const GsaSolverBase&) = delete;
  GsaSolverBase& operator=(const GsaSolverBase&) = delete;

  /// Minimises `objective` over `box`. Writes the best cost per iteration into *trace and
  /// calls *progress after each iteration (either may be null). Errors (nothing evaluated):
  /// population_out_of_range (N < 2 or above capacity), dimension_out_of_range, bad_bounds,
  /// invalid_argument (iterations 0, g0 or beta not finite and >= 0, epsilon not finite and > 0,
  /// final_attractors not in [1, N], max_evaluations below N). *result is always written.
  Status minimize(Objective& objective, const SearchBox& box, const GsaOptions& options, SolverResult* result,
                  TraceBase* trace = nullptr, ProgressObserver* progress = nullptr);

  std::size_t max_agents() const { return storage_.max_agents; }        ///< N capacity [-]
  std::size_t max_dimension() const { return storage_.max_dimension; }  ///< D capacity [-]

  /// Arrays sized by the owning class: positions and velocities [N x D], one entry per agent or dimension.
  struct Storage {
    double* positions;          ///< agent positions, agent-major [box widths, in 0..1]
    double* velocities;         ///< agent velocities, agent-major [box widths / iteration]
    double* costs;              ///< cost of each agent at its current position
    double* masses;             ///< normalised inertial masses M_i, summing to 1 [-]
    std::size_t* order;         ///< agent indices by increasing cost (k_best are the first)
    double* point;              ///< position being evaluated [objective's units]
    double* best;               ///< best position so far [objective's units]
    std::size_t max_agents;     ///< capacity of the per-agent arrays
    std::size_t max_dimension;  ///< capacity of the per-dimension arrays
  };

 protected:
  explicit GsaSolverBase(const Storage& storage) : storage_(storage) {}
  ~GsaSolverBase() = default;

 private:
  Storage storage_;
};

/// A GSA solver owning room for `MaxAgents` agents of `MaxDimension` parameters:
/// (MaxAgents * (2 MaxDimension + 2) + 2 MaxDimension) doubles plus one size_t per agent.
/// Big for a stack at the paper's size (150 x 6: ~16 KiB): give it static storage.
template <std::size_t MaxAgents, std::size_t MaxDimension>
class GsaSolver final : public GsaSolverBase {
  static_assert(MaxAgents >= 2 && MaxDimension >= 1, "GSA needs two agents and one dimension");

 public:
  GsaSolver()
      : GsaSolverBase(
            Storage{positions_, velocities_, costs_, masses_, order_, point_, best_, MaxAgents, MaxDimension}) {}

 private:
  double positions_[MaxAgents * MaxDimension] = {};
  double velocities_[MaxAgents * MaxDimension] = {};
  double costs_[MaxAgents] = {};
  double masses_[MaxAgents] = {};
  std::size_t order_[MaxAgents] = {};
  double point_[MaxDimension] = {};
  double best_[MaxDimension] = {};
};

}  // namespace hivecal
