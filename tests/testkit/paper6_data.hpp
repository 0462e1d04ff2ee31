// Paper-like simulated sessions for the six-length calibration (Khanesar et al.): a UR5 whose
// d1, a2, a3, d4, d5, d6 differ from nominal, tool pointing roughly down, a tracker ~3 m away,
// ~10 um noise; plus an independent least-squares reference built on the generic kinematics.
#pragma once

#include <Eigen/Cholesky>

#include "hivecal/core/random.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/solve/cost.hpp"
#include "hivecal/solve/paper6_cost.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// Joint positions of a UR with the tool axis within ~20 degrees of straight down [rad]:
/// q2 + q3 + q4 near -pi/2 and q5 near -pi/2 point the flange z axis at -z.
inline JointVector random_joints_tool_down(Random* random) {
  JointVector q;
  q(0) = random->uniform(-3.0, 3.0);
  q(1) = random->uniform(-2.0, -0.8);
  q(2) = random->uniform(0.6, 2.2);
  q(3) = -math::kHalfPi - q(1) - q(2) + random->uniform(-0.35, 0.35);
  q(4) = -math::kHalfPi + random->uniform(-0.35, 0.35);
  q(5) = random->uniform(-3.0, 3.0);
  return q;
}

/// The simulated cell: nominal geometry (with the known tool), the true one, the tracker pose.
struct Paper6Cell {
  RobotModel nominal;              ///< datasheet UR5 plus the tool
  RobotModel truth;                ///< what the simulated arm really is
  RigidTransform base_to_tracker;  ///< where the tracker sees the base
};

/// What differs between the true arm and the nominal one.
enum class Paper6Truth {
  six_lengths,  ///< only d1, a2, a3, d4, d5, d6, by 0.3 mm rms: the truth is in the calibrated family
  paper_like,   ///< every DH value by 50 um / 50 urad rms: unmodelled errors remain (paper: 75 -> 60 um)
};

/// A UR5 (tool 105 mm out) whose geometry is off as `kind` says.
inline Paper6Cell paper6_cell(Random* random, Paper6Truth kind) {
  Paper6Cell cell;
  cell.nominal = nominal_model(RobotType::ur5);
  cell.nominal.tool_m << 0.0012, -0.0008, 0.105;
  if (kind == Paper6Truth::paper_like) {
    cell.truth = perturbed_model(cell.nominal, random, 5e-5, 5e-5);
  } else {
    LinkLengths lengths_m = link_lengths(cell.nominal);
    for (std::size_t k = 0; k < lengths_m.count; ++k) lengths_m.data()[k] += 3e-4 * random->normal();
    cell.truth = with_link_lengths(cell.nominal, link_length_set(cell.nominal), lengths_m.data());
  }
  cell.base_to_tracker = example_base_to_tracker();
  return cell;
}

/// Adds `count` tool-down poses of the true arm, seen with isotropic noise_m per axis.
inline void fill_tool_down(const Paper6Cell& cell, std::size_t count, double noise_m, Random* random,
                           DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = random_joints_tool_down(random);
    Vec3 noise;
    noise << random->normal(), random->normal(), random->normal();  // comma: drawn in order
    (void)dataset->add(q, cell.base_to_tracker.apply(fk_tool_point(cell.truth, q)) + noise_m * noise);
  }
}

/// Least-squares link lengths (link_length_set(nominal): for UR the paper's six), independent
/// of Paper6Cost: alternate a Kabsch base fit with the exact linear least-squares step in the
/// lengths (the tool point is affine in them).
/// Fixed-size storage for every possible length; the unused rows and columns stay zero and
/// the step is solved on the first K only.
inline LinkLengths least_squares_lengths(const RobotModel& nominal, Span<const Sample> samples, int max_rounds = 500) {
  constexpr int kMax = static_cast<int>(kMaxLinkLengths);
  using MatK = Eigen::Matrix<double, kMax, kMax>;
  using Mat3K = Eigen::Matrix<double, 3, kMax>;
  const LinkLengthSet set = link_length_set(nominal);
  const auto count = static_cast<Eigen::Index>(set.count);
  LinkLengths lengths_m = link_lengths(nominal, set);
  for (int round = 0; round < max_rounds; ++round) {
    const RobotModel model = with_link_lengths(nominal, set, lengths_m.data());
    RigidTransform base;
    if (fit_base_to_tracker(model, samples, &base) != Status::ok) break;
    MatK normal = MatK::Zero();
    LinkLengths::Values rhs = LinkLengths::Values::Zero();
    for (const Sample& sample : samples) {
      ToolPointJacobian jacobian;
      const Vec3 point_m = tool_point_jacobian(model, sample.q_rad, &jacobian);
      Mat3K columns = Mat3K::Zero();
      for (Eigen::Index k = 0; k < count; ++k) columns.col(k) = jacobian.col(set.param_index[k]);
      const Vec3 residual_base_m = base.rotation.transpose() * (base.apply(point_m) - sample.point_m);
      normal += columns.transpose() * columns;
      rhs -= columns.transpose() * residual_base_m;
    }
    LinkLengths::Values step_m = LinkLengths::Values::Zero();
    step_m.head(count) = normal.topLeftCorner(count, count).ldlt().solve(rhs.head(count));
    lengths_m.values_m += step_m;
    if (step_m.norm() < 1e-14) break;
  }
  return lengths_m;
}

/// MAE [m] of the six lengths through the generic cost (refit base, mean |r|).
inline double generic_mae(const RobotModel& nominal, const double* lengths_m, Span<const Sample> samples) {
  RigidTransform base;
  double mae_m = -1.0;
  (void)evaluate_cost(with_link_lengths(nominal, link_length_set(nominal), lengths_m), samples, CostKind::mean_abs_3d,
                      BaseFrame::refit, &base, &mae_m);
  return mae_m;
}

}  // namespace hivecal::test
