#include "hivecal/solve/gsa.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"
#include "solve/solver_common.hpp"

namespace hivecal {
namespace {

/// One minimisation: the agents in unit-box coordinates, their random stream and budget.
class GsaRun {
 public:
  GsaRun(const GsaSolverBase::Storage& storage, detail::CountedObjective* objective, const SearchBox& box,
         std::size_t dimension, const GsaOptions& options)
      : s_(storage),
        objective_(objective),
        box_(box),
        dimension_(dimension),
        agents_(options.agents),
        options_(options),
        random_(options.seed),
        best_(storage.best, dimension) {}

  /// Uniform positions in the unit box, zero velocities, agents in index order.
  void initialise() {
    for (std::size_t i = 0; i < agents_; ++i) {
      s_.order[i] = i;
      for (std::size_t d = 0; d < dimension_; ++d) {
        position(i)[d] = random_.uniform01();
        velocity(i)[d] = 0.0;
      }
    }
  }

  /// Evaluates every agent at its position; false if the budget ran out first.
  bool evaluate_agents() {
    for (std::size_t i = 0; i < agents_; ++i) {
      if (objective_->exhausted()) return false;
      to_box(position(i), s_.point);
      s_.costs[i] = objective_->evaluate(s_.point);
      best_.offer(s_.point, s_.costs[i]);
    }
    return true;
  }

  /// Masses from the costs, then one move: iteration t of t_max (1-based).
  void move(std::size_t iteration) {
    compute_masses();
    sort_by_cost();
    const double exponent = -options_.beta * static_cast<double>(iteration) / static_cast<double>(options_.iterations);
    const double gravity = options_.g0 * math::exp(exponent);
    const std::size_t attractors = attractor_count(iteration);
    for (std::size_t i = 0; i < agents_; ++i) accelerate(i, gravity, attractors);
    for (std::size_t i = 0; i < agents_; ++i) advance(i);
  }

  /// Iteration t (1-based) of t_max: every agent evaluated, then one move unless this was the
  /// last iteration or the budget ran out (those positions would never be evaluated).
  void iterate(std::size_t iteration) {
    if (evaluate_agents() && iteration != options_.iterations) move(iteration);
  }

  double best_cost() const { return best_.cost(); }  ///< best cost so far

 private:
  double* position(std::size_t i) const { return s_.positions + i * dimension_; }
  double* velocity(std::size_t i) const { return s_.velocities + i * dimension_; }

  void to_box(const double* unit, double* x) const {
    for (std::size_t d = 0; d < dimension_; ++d) x[d] = box_.lower[d] + unit[d] * (box_.upper[d] - box_.lower[d]);
  }

  /// m_i = (f_i - worst) / (best - worst), M_i = m_i / sum m (Rashedi eqs. 15-16) over the
  /// finite costs; agents with an infinite cost weigh nothing; equal masses when best == worst.
  void compute_masses() {
    double best = 0.0;
    double worst = 0.0;
    bool any_finite = false;
    for (std::size_t i = 0; i < agents_; ++i) {
      const double cost = s_.costs[i];
      if (!math::is_finite(cost)) continue;
      if (!any_finite || cost < best) best = cost;
      if (!any_finite || cost > worst) worst = cost;
      any_finite = true;
    }
    double sum = 0.0;
    for (std::size_t i = 0; i < agents_; ++i) {
      const double cost = s_.costs[i];
      s_.masses[i] = math::is_finite(cost) && best < worst ? (cost - worst) / (best - worst) : 0.0;
      sum += s_.masses[i];
    }
    for (std::size_t i = 0; i < agents_; ++i) {
      s_.masses[i] = sum > 0.0 ? s_.masses[i] / sum : 1.0 / static_cast<double>(agents_);
    }
  }

  /// Insertion sort of the agent order by (cost, index): a strict total order, so the result
  /// does not depend on the sort's implementation; cheap as the order changes little.
  void sort_by_cost() {
    for (std::size_t n = 1; n < agents_; ++n) {
      const std::size_t agent = s_.order[n];
      std::size_t slot = n;
      while (slot > 0 && comes_before(agent, s_.order[slot - 1])) {
        s_.order[slot] = s_.order[slot - 1];
        --slot;
      }
      s_.order[slot] = agent;
    }
  }

  bool comes_before(std::size_t a, std::size_t b) const {
    return s_.costs[a] < s_.costs[b] || (!(s_.costs[b] < s_.costs[a]) && a < b);
  }

  /// k_best falls linearly from N (t = 0) to final_attractors (t = t_max), rounded half up,
  /// in integers so that every target rounds alike.
  std::size_t attractor_count(std::size_t iteration) const {
    const std::size_t span = agents_ - options_.final_attractors;
    const std::size_t remaining = options_.iterations - iteration;
    return options_.final_attractors + (span * remaining + options_.iterations / 2) / options_.iterations;
  }

  /// v_i = rand * v_i + a_i with a_i = sum over the k_best heaviest j != i of
  /// rand_j G M_j (x_j - x_i) / (R_ij + eps) (Rashedi eqs. 7-11, r_p = 1; M_i cancels).
  /// Only velocities change here, so every agent sees the same positions.
  void accelerate(std::size_t i, double gravity, std::size_t attractors) {
    const double* xi = position(i);
    double* vi = velocity(i);
    for (std::size_t d = 0; d < dimension_; ++d) vi[d] *= random_.uniform01();
    for (std::size_t rank = 0; rank < attractors; ++rank) {
      const std::size_t j = s_.order[rank];
      if (j == i) continue;
      const double* xj = position(j);
      double distance_squared = 0.0;
      for (std::size_t d = 0; d < dimension_; ++d) distance_squared += (xj[d] - xi[d]) * (xj[d] - xi[d]);
      const double pull =
          random_.uniform01() * gravity * s_.masses[j] / (std::sqrt(distance_squared) + options_.epsilon);
      for (std::size_t d = 0; d < dimension_; ++d) vi[d] += pull * (xj[d] - xi[d]);
    }
  }

  /// x_i += v_i, clamped to the unit box; a wall stops the velocity across it.
  void advance(std::size_t i) {
    double* xi = position(i);
    double* vi = velocity(i);
    for (std::size_t d = 0; d < dimension_; ++d) {
      xi[d] += vi[d];
      if (xi[d] < 0.0 || xi[d] > 1.0) {
        xi[d] = xi[d] < 0.0 ? 0.0 : 1.0;
        vi[d] = 0.0;
      }
    }
  }

  const GsaSolverBase::Storage& s_;
  detail::CountedObjective* objective_;
  const SearchBox& box_;
  std::size_t dimension_;
  std::size_t agents_;
  const GsaOptions& options_;
  Random random_;
  detail::BestSoFar best_;
};

bool finite_at_least(double value, double minimum) {
  return math::is_finite(value) && value >= minimum;
}

Status validate(const GsaOptions& options, const SearchBox& box, std::size_t dimension, std::size_t max_agents,
                std::size_t max_dimension) {
  const Status common = detail::validate_population_and_box(options.agents, max_agents, options.max_evaluations, box,
                                                            dimension, max_dimension);
  if (common != Status::ok) return common;
  if (options.iterations == 0 || !finite_at_least(options.g0, 0.0) || !finite_at_least(options.beta, 0.0)) {
    return Status::invalid_argument;
  }
  if (!(math::is_finite(options.epsilon) && options.epsilon > 0.0)) return Status::invalid_argument;
  if (options.final_attractors < 1 || options.final_attractors > options.agents) return Status::invalid_argument;
  return Status::ok;
}

}  // namespace

Status GsaSolverBase::minimize(Objective& objective, const SearchBox& box, const GsaOptions& options,
                               SolverResult* result, TraceBase* trace, ProgressObserver* progress) {
  const std::size_t dimension = objective.dimension();
  const Status valid = validate(options, box, dimension, storage_.max_agents, storage_.max_dimension);
  return detail::run_population<GsaRun>(valid, objective, box, dimension, storage_, options, options.iterations, result,
                                        trace, progress);
}

}  // namespace hivecal
