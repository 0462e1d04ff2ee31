// Kinematics checks run by both tests/lib/model/test_kinematics.cpp and the firmware image
// (tests/firmware/test_kinematics.cpp): the datasheet point, the two FK paths agreeing, the
// analytic Jacobian against central differences, parameter and UR-delta round trips, names.
#pragma once

#include <cstring>
#include <limits>

#include "hivecal/core/random.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/model/ur_deltas.hpp"
#include "testkit/check_log.hpp"
#include "testkit/test_data.hpp"

namespace hivecal::test {

/// The UR5 at zero joints puts the tool point where the datasheet lengths say.
inline CheckLog ur5_zero_pose_is_the_datasheet_point() {
  CheckLog log;
  const Vec3 p = fk_tool_point(nominal_model(RobotType::ur5), JointVector::Zero());
  log.near(p.x(), -0.425 - 0.39225, 1e-15, "x [m]");
  log.near(p.y(), -(0.10915 + 0.0823), 1e-15, "y [m]");
  log.near(p.z(), 0.089159 - 0.09465, 1e-15, "z [m]");
  return log;
}

/// fk_tool_point (fast path) equals the flange pose applied to the tool, for every UR type,
/// at `poses_per_type` random poses each.
inline CheckLog tool_point_fast_path_agrees_with_pose_chain(int poses_per_type) {
  CheckLog log;
  Random random(11);
  for (RobotType type : {RobotType::ur3, RobotType::ur5, RobotType::ur10, RobotType::ur5e}) {
    RobotModel model = perturbed_model(nominal_model(type), &random, 1e-3, 1e-3);
    model.tool_m << 0.01, -0.02, 0.15;
    for (int i = 0; i < poses_per_type; ++i) {
      const JointVector q = random_joints(&random);
      const RigidTransform flange = fk_flange(model, q);
      const Vec3 fast = fk_tool_point(model, q);
      log.less((flange.apply(model.tool_m) - fast).norm(), 1e-14, "fast path vs pose chain [m]");
      log.near(flange.rotation.determinant(), 1.0, 1e-14, "det(flange rotation)");
    }
  }
  return log;
}

/// The analytic Jacobian of `model` at q equals central finite differences of fk_tool_point for
/// each of its parameters (model_param_count), and is 0 in the columns beyond them; into *log.
inline void jacobian_matches_central_differences_at(const RobotModel& model, const JointVector& q, CheckLog* log) {
  ToolPointJacobian jacobian;
  const Vec3 point = tool_point_jacobian(model, q, &jacobian);
  log->less((point - fk_tool_point(model, q)).norm(), 1e-14, "Jacobian's point vs fk_tool_point [m]");
  const ModelParams params = to_params(model);
  for (int k = 0; k < model_param_count(model); ++k) {
    const double h = 1e-6;
    ModelParams plus = params;
    ModelParams minus = params;
    plus(k) += h;
    minus(k) -= h;
    const Vec3 numeric =
        (fk_tool_point(with_model_params(model, plus), q) - fk_tool_point(with_model_params(model, minus), q)) /
        (2 * h);
    log->less((numeric - jacobian.col(k)).norm(), 1e-8, "Jacobian column vs central difference");
  }
  for (int k = model_param_count(model); k < kMaxModelParamCount; ++k) {
    log->check(jacobian.col(k).isZero(), "Jacobian column beyond the model's is 0");
  }
}

/// Property: the analytic Jacobian equals central finite differences for random geometries
/// and poses (`trials` of them), for all 27 parameters.
inline CheckLog jacobian_matches_central_differences(int trials) {
  CheckLog log;
  Random random(12);
  for (int trial = 0; trial < trials; ++trial) {
    RobotModel model = perturbed_model(nominal_model(RobotType::ur5), &random, 5e-3, 5e-3);
    model.tool_m << random.uniform(-0.05, 0.05), random.uniform(-0.05, 0.05), random.uniform(0.0, 0.2);
    jacobian_matches_central_differences_at(model, random_joints(&random), &log);
  }
  return log;
}

/// to_params / with_model_params round-trip every bit; the index helpers point at the right fields.
inline CheckLog params_round_trip() {
  CheckLog log;
  Random random(13);
  RobotModel model = perturbed_model(nominal_model(RobotType::ur10), &random, 1e-3, 1e-3);
  model.tool_m << 1.0, 2.0, 3.0;
  const RobotModel back = with_model_params(RobotModel{}, to_params(model));
  log.check(std::memcmp(&back, &model, sizeof model) == 0, "with_model_params(to_params(model)) == model, bit for bit");
  log.equal(to_params(model)(model_param_index(2, DhField::a)), model.joints[2].a_m, "a of joint 2");
  log.equal(to_params(model)(tool_param_index(kSixJoints, 2)), 3.0, "tool z");
  return log;
}

/// Robot type names both ways, unknown names rejected.
inline CheckLog robot_type_names() {
  CheckLog log;
  RobotType type = RobotType::ur3;
  log.status(robot_type_from_name("ur10", &type), Status::ok, "\"ur10\"");
  log.check(type == RobotType::ur10, "\"ur10\" is ur10");
  log.status(robot_type_from_name("ur5e", &type), Status::ok, "\"ur5e\"");
  log.check(type == RobotType::ur5e, "\"ur5e\" is ur5e");
  log.status(robot_type_from_name("ur7", &type), Status::invalid_argument, "\"ur7\"");
  log.status(robot_type_from_name(nullptr, &type), Status::invalid_argument, "null name");
  log.same_text(robot_type_name(RobotType::ur5), "ur5", "name of ur5");
  log.same_text(robot_type_name(RobotType::ur5e), "ur5e", "name of ur5e");
  return log;
}

/// UR calibration deltas rebuild the calibrated model; a NaN delta is rejected.
inline CheckLog ur_deltas_round_trip_and_reject_nan() {
  CheckLog log;
  Random random(14);
  const RobotModel nominal = nominal_model(RobotType::ur5e);
  const RobotModel calibrated = perturbed_model(nominal, &random, 1e-3, 1e-3);
  const UrCalibrationDeltas deltas = ur_deltas_between(nominal, calibrated);
  RobotModel rebuilt;
  log.status(apply_ur_deltas(nominal, deltas, &rebuilt), Status::ok, "apply deltas");
  log.less((to_params(rebuilt) - to_params(calibrated)).cwiseAbs().maxCoeff(), 1e-16, "rebuilt vs calibrated");
  UrCalibrationDeltas bad = deltas;
  bad.delta_d_m[3] = std::numeric_limits<double>::quiet_NaN();
  log.status(apply_ur_deltas(nominal, bad, &rebuilt), Status::non_finite_input, "NaN delta");
  return log;
}

}  // namespace hivecal::test
