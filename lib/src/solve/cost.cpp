#include "hivecal/solve/cost.hpp"

#include <cmath>

#include "hivecal/model/rigid_fit.hpp"

namespace hivecal {

Status evaluate_cost(const RobotModel& model, Span<const Sample> samples, CostKind kind, BaseFrame base_frame,
                     RigidTransform* base_to_tracker, double* cost) {
  if (base_to_tracker == nullptr || cost == nullptr) return Status::invalid_argument;
  if (samples.empty()) return Status::dataset_empty;
  if (base_frame == BaseFrame::refit) {
    const Status fit = fit_base_to_tracker(model, samples, base_to_tracker);
    if (fit != Status::ok) return fit;
  }
  double sum = 0.0;
  for (const Sample& sample : samples) {
    const Vec3 residual_m = base_to_tracker->apply(fk_sample_point(model, sample)) - sample.point_m;
    const double squared = residual_m.squaredNorm();
    sum += kind == CostKind::sum_squares ? squared : std::sqrt(squared);
  }
  const double value = kind == CostKind::sum_squares ? sum : sum / static_cast<double>(samples.size());
  if (!math::is_finite(value)) return Status::non_finite_input;
  *cost = value;
  return Status::ok;
}

}  // namespace hivecal
