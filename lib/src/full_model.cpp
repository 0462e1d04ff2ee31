#include "hivecal/full_model.hpp"

#include <cmath>

#include "hivecal/math.hpp"

namespace hivecal {
namespace {

constexpr const char* kParamNames[kFullParamCount] = {
    "theta1", "d1", "a1", "alpha1", "theta2", "d2", "a2", "alpha2", "theta3", "d3", "a3",
    "alpha3", "theta4", "d4", "a4", "alpha4", "theta5", "d5", "a5", "alpha5", "theta6", "d6",
    "a6", "alpha6", "tool_x", "tool_y", "tool_z", "base_rx", "base_ry", "base_rz", "base_tx", "base_ty",
    "base_tz"};

/// Cross-product matrix: skew(v) * x = v x x.
Mat3 skew(const Vec3& v) {
  Mat3 k;
  k << 0.0, -v.z(), v.y(),
       v.z(), 0.0, -v.x(),
       -v.y(), v.x(), 0.0;
  return k;
}

/// The same bits as full_residual_jacobian's residual: tool_point_jacobian chains the flange
/// pose exactly like fk_flange, so trial costs and accumulated costs compare exactly.
Vec3 point_residual(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample) {
  return base_to_tracker.apply(fk_flange(model, sample.q_rad).apply(model.tool_m)) - sample.point_m;
}

/// eq += w J^T J (upper triangle) and w J^T r. Column-major order: contiguous writes.
void add_weighted_sample(const FullJacobian& jacobian, const Vec3& residual_m, double weight,
                         NormalEquations* eq) {
  const FullJacobian weighted = weight * jacobian;
  for (int b = 0; b < kFullParamCount; ++b) {
    eq->jtwr(b) += weighted(0, b) * residual_m(0) + weighted(1, b) * residual_m(1) + weighted(2, b) * residual_m(2);
    for (int a = 0; a <= b; ++a) {
      eq->jtwj(a, b) += weighted(0, a) * jacobian(0, b) + weighted(1, a) * jacobian(1, b) +
                        weighted(2, a) * jacobian(2, b);
    }
  }
}

// Log-spaced bins of the median histogram: 4 per decade from 1e-12 m to 100 m, plus an
// underflow bin (index 0, norms below 1e-12 m, zero included) and an overflow bin.
constexpr int kHistogramBins = 56;
constexpr int kRefineBins = 64;
constexpr double kHistogramFloor_m = 1e-12;
constexpr double kLn10 = 2.302585092994045684;
constexpr double kBinsPerLnUnit = 4.0 / kLn10;

int histogram_bin(double norm_m) {
  if (!(norm_m >= kHistogramFloor_m)) return 0;
  const double position = math::log(norm_m / kHistogramFloor_m) * kBinsPerLnUnit;
  if (position >= static_cast<double>(kHistogramBins)) return kHistogramBins + 1;
  return 1 + static_cast<int>(position);
}

double histogram_bin_lower_m(int bin) {
  return kHistogramFloor_m * math::exp(static_cast<double>(bin - 1) / kBinsPerLnUnit);
}

}  // namespace

int mask_count(ParamMask mask) {
  int count = 0;
  for (int i = 0; i < kFullParamCount; ++i) count += mask_has(mask, i) ? 1 : 0;
  return count;
}

const char* full_param_name(int index) {
  if (index < 0 || index >= kFullParamCount) return "?";
  return kParamNames[index];
}

Mat3 rotation_from_vector(const Vec3& rotation_vector_rad) {
  const double angle2 = rotation_vector_rad.squaredNorm();
  double sin_ratio = 1.0;      // sin(t) / t
  double cos_ratio = 0.5;      // (1 - cos(t)) / t^2
  if (angle2 < 1e-8) {         // t < 1e-4: Taylor terms beyond t^4 are below 1e-24
    sin_ratio = 1.0 - angle2 / 6.0 + angle2 * angle2 / 120.0;
    cos_ratio = 0.5 - angle2 / 24.0 + angle2 * angle2 / 720.0;
  } else {
    const double angle = std::sqrt(angle2);
    double s = 0.0;
    double c = 0.0;
    math::sincos(angle, &s, &c);
    sin_ratio = s / angle;
    cos_ratio = (1.0 - c) / angle2;
  }
  const Mat3 k = skew(rotation_vector_rad);
  return Mat3::Identity() + sin_ratio * k + cos_ratio * (k * k);
}

void apply_full_increment(const FullParams& increment, RobotModel* model, RigidTransform* base_to_tracker) {
  *model = from_params(to_params(*model) + increment.head<kModelParamCount>());
  const Vec3 rotation_rad = increment.segment<3>(base_rotation_param_index(0));
  const Vec3 translation_m = increment.segment<3>(base_translation_param_index(0));
  base_to_tracker->translation_m += base_to_tracker->rotation * translation_m;
  base_to_tracker->rotation = base_to_tracker->rotation * rotation_from_vector(rotation_rad);
}

Vec3 full_residual_jacobian(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample,
                            FullJacobian* jacobian) {
  ToolPointJacobian tool_jacobian;
  const Vec3 point_m = tool_point_jacobian(model, sample.q_rad, &tool_jacobian);
  const Mat3& rotation = base_to_tracker.rotation;
  jacobian->leftCols<kModelParamCount>() = rotation * tool_jacobian;
  // d(R Exp(w) p)/dw at w = 0 is R (e_k x p) = -R skew(p) e_k; d(R tau)/dtau = R.
  jacobian->block<3, 3>(0, base_rotation_param_index(0)) = -(rotation * skew(point_m));
  jacobian->block<3, 3>(0, base_translation_param_index(0)) = rotation;
  return base_to_tracker.apply(point_m) - sample.point_m;
}

void scale_normal_matrix(const NormalMatrix& jtwj, ParamMask mask, double outside_diagonal, NormalMatrix* scaled,
                         FullParams* scale) {
  for (int i = 0; i < kFullParamCount; ++i) (*scale)(i) = mask_has(mask, i) ? 1.0 / std::sqrt(jtwj(i, i)) : 1.0;
  for (int b = 0; b < kFullParamCount; ++b) {
    for (int a = 0; a < kFullParamCount; ++a) {
      if (mask_has(mask, a) && mask_has(mask, b)) {
        (*scaled)(a, b) = jtwj(a, b) * (*scale)(a) * (*scale)(b);
      } else {
        (*scaled)(a, b) = a == b ? outside_diagonal : 0.0;
      }
    }
  }
}

double PointLoss::rho(double norm_m) const {
  const double k = huber_threshold_m;
  if (k <= 0.0 || norm_m <= k) return norm_m * norm_m;
  return 2.0 * k * norm_m - k * k;
}

double PointLoss::weight(double norm_m) const {
  const double k = huber_threshold_m;
  if (k <= 0.0 || norm_m <= k) return 1.0;
  return k / norm_m;
}

Status accumulate_normal_equations(const RobotModel& model, const RigidTransform& base_to_tracker,
                                   Span<const Sample> samples, const PointLoss& loss, NormalEquations* out) {
  if (samples.empty()) return Status::dataset_empty;
  NormalEquations& eq = *out;
  eq.jtwj.setZero();
  eq.jtwr.setZero();
  eq.loss_sum_m2 = 0.0;
  eq.weighted_squares_m2 = 0.0;
  eq.squares_sum_m2 = 0.0;
  eq.count = samples.size();
  FullJacobian jacobian;
  for (const Sample& sample : samples) {
    const Vec3 residual_m = full_residual_jacobian(model, base_to_tracker, sample, &jacobian);
    const double squared = residual_m.squaredNorm();
    const double norm_m = std::sqrt(squared);
    const double weight = loss.weight(norm_m);
    add_weighted_sample(jacobian, residual_m, weight, &eq);
    eq.loss_sum_m2 += loss.rho(norm_m);
    eq.weighted_squares_m2 += weight * squared;
    eq.squares_sum_m2 += squared;
  }
  for (int b = 0; b < kFullParamCount; ++b)
    for (int a = b + 1; a < kFullParamCount; ++a) eq.jtwj(a, b) = eq.jtwj(b, a);
  if (!math::is_finite(eq.loss_sum_m2) || !all_finite(eq.jtwr) || !all_finite(eq.jtwj)) {
    return Status::non_finite_input;
  }
  return Status::ok;
}

Status evaluate_point_loss(const RobotModel& model, const RigidTransform& base_to_tracker,
                           Span<const Sample> samples, const PointLoss& loss, double* loss_sum_m2,
                           double* squares_sum_m2) {
  if (samples.empty()) return Status::dataset_empty;
  double loss_sum = 0.0;
  double squares = 0.0;
  for (const Sample& sample : samples) {
    const double squared = point_residual(model, base_to_tracker, sample).squaredNorm();
    loss_sum += loss.rho(std::sqrt(squared));
    squares += squared;
  }
  if (!math::is_finite(loss_sum) || !math::is_finite(squares)) return Status::non_finite_input;
  *loss_sum_m2 = loss_sum;
  *squares_sum_m2 = squares;
  return Status::ok;
}

Status median_residual_norm(const RobotModel& model, const RigidTransform& base_to_tracker,
                            Span<const Sample> samples, double* median_m) {
  if (samples.empty()) return Status::dataset_empty;
  std::size_t counts[kHistogramBins + 2] = {};
  for (const Sample& sample : samples) {
    const double norm_m = point_residual(model, base_to_tracker, sample).norm();
    if (!math::is_finite(norm_m)) return Status::non_finite_input;
    ++counts[histogram_bin(norm_m)];
  }
  const std::size_t rank = (samples.size() - 1) / 2;  // lower median, 0-based
  std::size_t below = 0;
  int bin = 0;
  while (below + counts[bin] <= rank) below += counts[bin++];
  if (bin == 0) {  // at or below the floor: report the floor
    *median_m = kHistogramFloor_m;
    return Status::ok;
  }
  const double lower_m = histogram_bin_lower_m(bin);
  // The overflow bin has no upper edge: split [100 m, 10 * 100 m) and clamp into it.
  const double upper_m = bin <= kHistogramBins ? histogram_bin_lower_m(bin + 1) : 10.0 * lower_m;
  std::size_t refined[kRefineBins] = {};
  for (const Sample& sample : samples) {
    const double norm_m = point_residual(model, base_to_tracker, sample).norm();
    if (histogram_bin(norm_m) != bin) continue;
    const double position = (norm_m - lower_m) / (upper_m - lower_m) * kRefineBins;
    int sub = position <= 0.0 ? 0 : static_cast<int>(position);
    if (sub >= kRefineBins) sub = kRefineBins - 1;
    ++refined[sub];
  }
  int sub = 0;
  while (sub < kRefineBins - 1 && below + refined[sub] <= rank) below += refined[sub++];
  *median_m = lower_m + (static_cast<double>(sub) + 0.5) / kRefineBins * (upper_m - lower_m);
  return Status::ok;
}

}  // namespace hivecal
