// Simulated calibration sessions with a known truth for the Levenberg-Marquardt tests and
// benchmark: parallel-axis truths, tool-down poses, gross outliers, and the identifiable
// combinations a calibrated model is compared on (own PRNG: the same on every target).
#pragma once

#include <cmath>

#include <Eigen/LU>

#include "hivecal/model/dataset.hpp"
#include "hivecal/solve/lm.hpp"
#include "hivecal/solve/normal_equations.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// What an LM test file keeps in static storage (too large for a test's stack): a training
/// and a fresh set of up to `Capacity` samples, the solver's workspace and its result. Each
/// file holds one in a function-local static; each test clears what it fills.
template <std::size_t Capacity, typename Workspace = LmWorkspace>
struct LmTestStorage {
  Dataset<Capacity> train;  ///< the samples a calibration is fitted on
  Dataset<Capacity> fresh;  ///< poses the calibration is judged on
  Workspace workspace;      ///< the solver's memory
  LmResult result;          ///< the last calibration
};

/// Three standard normal deviates, drawn x, y, z in this order (constructor arguments would
/// be evaluated in an unspecified order, so the data would differ between compilers/targets).
inline Vec3 gaussian_vector(Random* random) {
  Vec3 v;
  v << random->normal(), random->normal(), random->normal();  // comma initialiser: sequenced
  return v;
}

/// perturbed_model, but joints 2-4 stay exactly parallel (alpha2 = alpha3 = 0, as standard
/// DH assumes for a UR: a tilt between parallel axes is not a DH parameter), with `tool_m`.
inline RobotModel perturbed_parallel_model(RobotType type, Random* random, double length_sigma_m,
                                           double angle_sigma_rad, const Vec3& tool_m) {
  const RobotModel nominal = nominal_model(type);
  RobotModel model = perturbed_model(nominal, random, length_sigma_m, angle_sigma_rad);
  model.joints[1].alpha_rad = nominal.joints[1].alpha_rad;
  model.joints[2].alpha_rad = nominal.joints[2].alpha_rad;
  model.tool_m = tool_m;
  return model;
}

/// Axis of joint 6 in the base frame: the flange z axis before the last twist alpha6.
inline Vec3 joint6_axis(const RobotModel& model, const JointVector& q_rad) {
  double s = 0.0;
  double c = 0.0;
  math::sincos(model.joints[5].alpha_rad, &s, &c);
  return fk_flange(model, q_rad).rotation * Vec3(0.0, s, c);
}

/// `count` random UR poses with wrist 2 held within +-0.05 rad of -pi/2 (a grid at one tool
/// orientation: d5 and alpha5 move the tool point alike there, told apart only by the tool
/// point's offset from the flange axis), seen by a tracker at example_base_to_tracker() with
/// 10 um noise and an unmodelled deflection of up to `effect_m`, smooth in the joints.
inline void fill_narrow_wrist_dataset(const RobotModel& truth, std::size_t count, double effect_m, Random* random,
                                      DatasetBase* dataset) {
  const RigidTransform base = example_base_to_tracker();
  for (std::size_t i = 0; i < count; ++i) {
    JointVector q = random_joints(random);
    q(4) = -math::kHalfPi + random->uniform(-0.05, 0.05);
    const Vec3 noise = gaussian_vector(random);
    const Vec3 effect =
        effect_m * Vec3(std::sin(3.0 * q(0) + 2.0 * q(1)), std::cos(4.0 * q(2) - q(4)), std::sin(5.0 * q(3)));
    (void)dataset->add(q, base.apply(fk_tool_point(truth, q)) + 10e-6 * noise + effect);
  }
}

/// Random q1, q2, q3, q6 and the q4, q5 (Newton on the true model) that point joint 6's
/// axis straight down; `flipped` picks the other wrist branch (q5 near +pi/2).
inline JointVector tool_down_joints(const RobotModel& truth, bool flipped, Random* random) {
  JointVector q = random_joints(random);
  const double branch = flipped ? math::kHalfPi : -math::kHalfPi;
  q(4) = branch;
  q(3) = branch - q(1) - q(2);
  for (int iteration = 0; iteration < 20; ++iteration) {
    const Vec3 axis = joint6_axis(truth, q);
    Eigen::Matrix2d jacobian;
    for (int k = 0; k < 2; ++k) {
      const double h = 1e-7;
      JointVector plus = q;
      JointVector minus = q;
      plus(3 + k) += h;
      minus(3 + k) -= h;
      const Vec3 slope = (joint6_axis(truth, plus) - joint6_axis(truth, minus)) / (2.0 * h);
      jacobian(0, k) = slope.x();
      jacobian(1, k) = slope.y();
    }
    const Eigen::Vector2d delta = jacobian.inverse() * Eigen::Vector2d(axis.x(), axis.y());
    q(3) -= delta(0);
    q(4) -= delta(1);
  }
  return q;
}

/// Fills `dataset` with `count` tool-down samples, alternating the two wrist branches.
inline void fill_tool_down_dataset(const RobotModel& truth, const RigidTransform& base_to_tracker, std::size_t count,
                                   double noise_m, Random* random, DatasetBase* dataset) {
  for (std::size_t i = 0; i < count; ++i) {
    const JointVector q = tool_down_joints(truth, i % 2 == 1, random);
    const Vec3 noise = gaussian_vector(random);
    (void)dataset->add(q, base_to_tracker.apply(fk_tool_point(truth, q)) + noise_m * noise);
  }
}

/// Copies `source` into `target`, moving every `period`-th sample (from `offset`) by a
/// random direction times a length in [min_m, max_m): gross tracker errors.
inline void copy_with_outliers(const DatasetBase& source, std::size_t period, std::size_t offset, double min_m,
                               double max_m, Random* random, DatasetBase* target) {
  target->clear();
  for (std::size_t i = 0; i < source.size(); ++i) {
    Vec3 point = source.samples()[i].point_m;
    if (i % period == offset) {
      const Vec3 direction = gaussian_vector(random);
      point += direction.normalized() * random->uniform(min_m, max_m);
    }
    (void)target->add(source.samples()[i].q_rad, point);
  }
}

/// Largest distance [m] between the tool points two calibrations predict in the tracker.
inline double max_prediction_gap(const RobotModel& a, const RigidTransform& base_a, const RobotModel& b,
                                 const RigidTransform& base_b, Span<const Sample> poses) {
  double gap = 0.0;
  for (const Sample& s : poses) {
    const double d = (base_a.apply(fk_tool_point(a, s.q_rad)) - base_b.apply(fk_tool_point(b, s.q_rad))).norm();
    if (d > gap) gap = d;
  }
  return gap;
}

/// The base frame carried through joint 1's fixed part, base * Rz(theta1) * Tz(d1): what the
/// data determines when theta1 and d1 trade against the base rotation and height.
inline RigidTransform base_through_joint1(const RobotModel& model, const RigidTransform& base_to_tracker) {
  RigidTransform joint1;
  joint1.rotation = rotation_from_vector(Vec3(0.0, 0.0, model.joints[0].theta_offset_rad));
  joint1.translation_m = Vec3(0.0, 0.0, model.joints[0].d_m);
  return base_to_tracker.then_after(joint1);
}

/// The tool point in frame 5 at joint-6 position q6 [m]: what joint 6's DH parameters and
/// the tool point determine together.
inline Vec3 tool_in_frame5(const RobotModel& model, double q6_rad) {
  const DhJoint& j = model.joints[5];
  const Vec3 after_twist = rotation_from_vector(Vec3(j.alpha_rad, 0.0, 0.0)) * model.tool_m + Vec3(j.a_m, 0.0, 0.0);
  return rotation_from_vector(Vec3(0.0, 0.0, q6_rad + j.theta_offset_rad)) * after_twist + Vec3(0.0, 0.0, j.d_m);
}

/// d2 + d3 + d4: the only combination of the parallel joints' offsets the data determines.
inline double parallel_offset_sum_m(const RobotModel& model) {
  return model.joints[1].d_m + model.joints[2].d_m + model.joints[3].d_m;
}

/// `count` samples of a perturbed UR5 at random poses with `noise_m` tracker noise: the arm turns
/// to turned(q) when its joints read q; `reading_step_rad` > 0: the readings rounded to that
/// step, as a pendant shows them; `elbow_half_range_rad` > 0: the elbow drawn within +- it.
template <typename Turned>
void fill_turned(std::uint64_t seed, std::size_t count, double noise_m, Turned turned, DatasetBase* out,
                 double reading_step_rad = 0.0, double elbow_half_range_rad = 0.0) {
  Random model_random(2503);
  RobotModel truth = perturbed_model(nominal_model(RobotType::ur5), &model_random, 1e-3, 1e-3);
  truth.tool_m << 0.02, -0.015, 0.12;
  const RigidTransform base = example_base_to_tracker();
  Random random(seed);
  out->clear();
  for (std::size_t i = 0; i < count; ++i) {
    JointVector q = random_joints(&random);
    if (elbow_half_range_rad > 0.0) q(2) = random.uniform(-elbow_half_range_rad, elbow_half_range_rad);
    JointVector reading = q;
    if (reading_step_rad > 0.0) {
      for (int j = 0; j < kSixJoints; ++j) reading(j) = reading_step_rad * std::round(q(j) / reading_step_rad);
    }
    (void)out->add(reading, base.apply(fk_tool_point(truth, turned(q))) + noise_m * gaussian_vector(&random));
  }
}

}  // namespace hivecal::test
