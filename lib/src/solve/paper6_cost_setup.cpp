// The paper-6 cost's setup (solve/paper6_cost.hpp): the link lengths of a model, the samples
// stored with their link-length directions, the precomputed sums. Run once per cost: compiled
// for size on bare metal, apart from the hot evaluation in paper6_cost.cpp.
#include "hivecal/solve/paper6_cost.hpp"

#include "hivecal/model/rigid_fit.hpp"
#include "solve/paper6_layout.hpp"

namespace hivecal {

LinkLengthSet link_length_set(const RobotModel& nominal) {
  const ModelParams params = to_params(nominal);
  LinkLengthSet set;
  for (int j = 0; j < nominal.joint_count; ++j) {
    for (DhField field : {DhField::d, DhField::a}) {
      const int index = model_param_index(j, field);
      if (params(index) != 0.0) set.param_index[set.count++] = index;
    }
  }
  return set;
}

LinkLengths link_lengths(const RobotModel& model, const LinkLengthSet& set) {
  const ModelParams params = to_params(model);
  LinkLengths lengths_m;
  lengths_m.count = set.count;
  for (std::size_t k = 0; k < set.count; ++k) lengths_m.data()[k] = params(set.param_index[k]);
  return lengths_m;
}

LinkLengths link_lengths(const RobotModel& model) {
  return link_lengths(model, link_length_set(model));
}

RobotModel with_link_lengths(const RobotModel& model, const LinkLengthSet& set, const double* lengths_m) {
  ModelParams params = to_params(model);
  for (std::size_t k = 0; k < set.count; ++k) params(set.param_index[k]) = lengths_m[k];
  RobotModel out;  // rigid: the compliance is not the lengths' (with_link_lengths' contract)
  out.joint_count = model.joint_count;
  out.prismatic_joints = model.prismatic_joints;
  set_model_params(params, &out);
  for (int k = 0; k < kMaxTargets - 1; ++k) out.other_tools_m[k] = model.other_tools_m[k];  // not among the parameters
  return out;
}

Status link_length_box(const RobotModel& nominal, double half_width_m, LinkLengthBox* box) {
  if (!(math::is_finite(half_width_m) && half_width_m > 0.0)) return Status::invalid_argument;
  const LinkLengthSet set = link_length_set(nominal);
  if (set.count == 0) return Status::invalid_argument;
  const LinkLengths lengths_m = link_lengths(nominal, set);
  if (!all_finite(lengths_m.values_m)) return Status::non_finite_input;
  box->count = set.count;
  for (std::size_t k = 0; k < set.count; ++k) {
    box->lower_m[k] = lengths_m.data()[k] - half_width_m;
    box->upper_m[k] = lengths_m.data()[k] + half_width_m;
  }
  return Status::ok;
}

Paper6CostView::Paper6CostView(Span<double> values, std::size_t max_lengths)
    : Paper6CostBase(values.data(), paper6_capacity_of(values.size(), max_lengths), max_lengths) {
  for (double& value : values) value = 0.0;
}

Status Paper6CostBase::reset(const RobotModel& nominal, const RigidTransform& reference_base_to_tracker) {
  if (!all_finite(to_params(nominal)) || !all_finite(reference_base_to_tracker.rotation) ||
      !all_finite(reference_base_to_tracker.translation_m)) {
    return Status::non_finite_input;
  }
  const LinkLengthSet set = link_length_set(nominal);
  const std::size_t stored = set.has_d1() ? set.count - 1 : set.count;
  const std::size_t per_sample = paper6_layout::kDirectionValue + 3 * stored;
  if (set.count == 0 || per_sample > max_values_per_sample_) return Status::dimension_out_of_range;
  nominal_ = nominal;
  reference_ = reference_base_to_tracker;
  set_ = set;
  stored_count_ = stored;
  values_per_sample_ = per_sample;
  const LinkLengths lengths_m = link_lengths(nominal, set);
  for (std::size_t k = 0; k < set.count; ++k) nominal_lengths_m_[k] = lengths_m.data()[k];
  size_ = 0;
  ready_ = false;
  return Status::ok;
}

template <typename Scalar>
void Paper6CostBase::store(const Vec3& predicted_m, const Vec3& measured_m, const ToolPointJacobian& jacobian,
                           Scalar* values) const {
  const Vec3 measured_in_base_m = reference_.rotation.transpose() * (measured_m - reference_.translation_m);
  const Vec3 point_m = predicted_m - point_origin_m_;
  const Vec3 error_m = measured_in_base_m - predicted_m;
  const std::size_t first = set_.count - stored_count_;  // d1 (not stored) comes first
  for (int r = 0; r < 3; ++r) {
    const auto row = static_cast<std::size_t>(r);
    values[paper6_layout::value_index(paper6_layout::kPointValue + row, size_, values_per_sample_)] =
        static_cast<Scalar>(point_m(r));
    values[paper6_layout::value_index(paper6_layout::kErrorValue + row, size_, values_per_sample_)] =
        static_cast<Scalar>(error_m(r));
    for (std::size_t k = 0; k < stored_count_; ++k) {
      values[paper6_layout::value_index(paper6_layout::kDirectionValue + 3 * k + row, size_, values_per_sample_)] =
          static_cast<Scalar>(jacobian(r, set_.param_index[first + k]));
    }
  }
}

Status Paper6CostBase::add(const JointVector& q_rad, const Vec3& point_m, int target) {
  if (!all_finite(q_rad) || !all_finite(point_m)) return Status::non_finite_input;
  if (target < 0 || target >= kMaxTargets) return Status::invalid_argument;
  if (size_ == capacity_) return Status::dataset_full;
  // The point is affine in the link lengths for any tool point: the target's own one.
  RobotModel target_model = nominal_;
  target_model.tool_m = target_tool(nominal_, target);
  ToolPointJacobian jacobian;
  (void)tool_point_jacobian(target_model, q_rad, &jacobian);
  const Vec3 predicted_m = fk_tool_point(target_model, q_rad);  // as evaluate_cost computes it
  if (size_ == 0) point_origin_m_ = predicted_m;
  scalar_.store(*this, predicted_m, point_m, jacobian);
  ++size_;
  ready_ = false;
  return Status::ok;
}

template <typename Scalar>
Status Paper6CostBase::precompute(const Scalar* values) {
  const auto count = static_cast<double>(size_);
  Vec3 point_sum_m = Vec3::Zero();
  Vec3 measured_sum_m = Vec3::Zero();
  const auto stored = static_cast<int>(stored_count_);
  paper6_layout::StoredDirections direction_sum = paper6_layout::StoredDirections::Zero();
  for (std::size_t i = 0; i < size_; ++i) {
    const paper6_layout::WideTerm term = paper6_layout::widen(values, i, values_per_sample_, stored);
    point_sum_m += term.point_m;
    measured_sum_m += term.measured_m;
    direction_sum += term.directions;
  }
  point_mean_m_ = point_sum_m / count;
  measured_mean_m_ = measured_sum_m / count;
  const paper6_layout::StoredDirections stored_direction_mean = direction_sum / count;
  // All K columns: d1 (when a link length) slides along the base z axis for every pose.
  const int first = set_.has_d1() ? 1 : 0;
  direction_mean_.setZero();
  if (first == 1) direction_mean_.col(0) = Vec3::UnitZ();
  for (int k = 0; k < stored; ++k) direction_mean_.col(first + k) = stored_direction_mean.col(k);

  // Second pass on centred values (the terms stay as they are, so add() may follow).
  Mat3 point_scatter_m2 = Mat3::Zero();
  Mat3 measured_scatter_m2 = Mat3::Zero();
  cross_nominal_m2_.setZero();
  for (Mat3& cross : cross_per_length_m_) cross.setZero();
  for (std::size_t i = 0; i < size_; ++i) {
    const paper6_layout::WideTerm term = paper6_layout::widen(values, i, values_per_sample_, stored);
    const Vec3 point_m = term.point_m - point_mean_m_;
    const Vec3 measured_m = term.measured_m - measured_mean_m_;
    point_scatter_m2 += point_m * point_m.transpose();
    measured_scatter_m2 += measured_m * measured_m.transpose();
    cross_nominal_m2_ += point_m * measured_m.transpose();
    for (int k = 0; k < stored; ++k) {
      const Vec3 direction = term.directions.col(k) - stored_direction_mean.col(k);
      cross_per_length_m_[k] += direction * measured_m.transpose();
    }
  }
  if (!scatter_spans_plane(point_scatter_m2) || !scatter_spans_plane(measured_scatter_m2)) {
    return Status::degenerate_geometry;
  }
  return Status::ok;
}

Status Paper6CostBase::finalize() {
  ready_ = false;
  if (size_ < 3) return Status::too_few_samples;
  const Status status = scalar_.precompute(*this);
  ready_ = status == Status::ok;
  return status;
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples) {
  return build(nominal, samples, Span<const std::uint32_t>());
}

Status Paper6CostBase::build(const RobotModel& nominal, Span<const Sample> samples,
                             Span<const std::uint32_t> selection) {
  if (samples.empty()) return Status::dataset_empty;
  for (const std::uint32_t position : selection) {
    if (position >= samples.size()) return Status::invalid_argument;
  }
  RigidTransform reference;
  const Status fitted = fit_base_to_tracker(nominal, samples, &reference);
  if (fitted != Status::ok) return fitted;
  const Status reset_status = reset(nominal, reference);
  if (reset_status != Status::ok) return reset_status;
  const std::size_t count = selection.empty() ? samples.size() : selection.size();
  for (std::size_t k = 0; k < count; ++k) {
    const Sample& sample = samples[selection.empty() ? k : selection[k]];
    const Status added = add(sample.q_rad, sample.point_m, sample.target);
    if (added != Status::ok) return added;
  }
  return finalize();
}

template <typename Scalar>
void Paper6CostBase::store_on(Paper6CostBase& cost, const Vec3& predicted_m, const Vec3& measured_m,
                              const ToolPointJacobian& jacobian) {
  cost.store(predicted_m, measured_m, jacobian, paper6_layout::storage_of<Scalar>(cost.values_, cost.compact_values_));
}

template <typename Scalar>
Status Paper6CostBase::precompute_on(Paper6CostBase& cost) {
  return cost.precompute(paper6_layout::storage_of<Scalar>(cost.values_, cost.compact_values_));
}

// The instantiations the constructors name (an image links those its costs use).
template void Paper6CostBase::store_on<double>(Paper6CostBase&, const Vec3&, const Vec3&, const ToolPointJacobian&);
template void Paper6CostBase::store_on<float>(Paper6CostBase&, const Vec3&, const Vec3&, const ToolPointJacobian&);
template Status Paper6CostBase::precompute_on<double>(Paper6CostBase&);
template Status Paper6CostBase::precompute_on<float>(Paper6CostBase&);

}  // namespace hivecal
