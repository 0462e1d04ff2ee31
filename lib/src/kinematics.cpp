#include "hivecal/kinematics.hpp"

#include "hivecal/math.hpp"

namespace hivecal {
namespace {

/// One DH link: rotation Rz(theta) Rx(alpha) and translation [a cos, a sin, d].
struct Link {
  Mat3 rotation;
  Vec3 translation_m;
};

/// The link of joint j with its twist's sin and cos taken from `twist`.
Link dh_link(const DhJoint& joint, double sa, double ca, double q_rad) {
  double st = 0.0;
  double ct = 0.0;
  math::sincos(q_rad + joint.theta_offset_rad, &st, &ct);
  Link link;
  link.rotation << ct, -st * ca, st * sa,
                   st, ct * ca, -ct * sa,
                   0.0, sa, ca;
  link.translation_m << joint.a_m * ct, joint.a_m * st, joint.d_m;
  return link;
}

Link dh_link(const DhJoint& joint, double q_rad) {
  double sa = 0.0;
  double ca = 0.0;
  math::sincos(joint.alpha_rad, &sa, &ca);
  return dh_link(joint, sa, ca, q_rad);
}

struct NominalTable {
  double d_m[kJointCount];
  double a_m[kJointCount];
};

// Datasheet values of Universal Robots (standard DH), alpha = [pi/2, 0, 0, pi/2, -pi/2, 0].
constexpr NominalTable kUr3 = {{0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819},
                               {0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr5 = {{0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823},
                               {0.0, -0.425, -0.39225, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr10 = {{0.1273, 0.0, 0.0, 0.163941, 0.1157, 0.0922},
                                {0.0, -0.612, -0.5723, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr5e = {{0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996},
                                {0.0, -0.425, -0.3922, 0.0, 0.0, 0.0}};
constexpr double kUrAlpha_rad[kJointCount] = {math::kHalfPi, 0.0, 0.0, math::kHalfPi, -math::kHalfPi, 0.0};

const NominalTable& table_of(RobotType type) {
  switch (type) {
    case RobotType::ur3: return kUr3;
    case RobotType::ur10: return kUr10;
    case RobotType::ur5e: return kUr5e;
    case RobotType::ur5: break;
  }
  return kUr5;
}

bool names_equal(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {
    ++a;
    ++b;
  }
  return *a == *b;
}

}  // namespace

ModelParams to_params(const RobotModel& model) {
  ModelParams p;
  for (int j = 0; j < kJointCount; ++j) {
    const DhJoint& joint = model.joints[j];
    p(model_param_index(j, DhField::theta_offset)) = joint.theta_offset_rad;
    p(model_param_index(j, DhField::d)) = joint.d_m;
    p(model_param_index(j, DhField::a)) = joint.a_m;
    p(model_param_index(j, DhField::alpha)) = joint.alpha_rad;
  }
  for (int axis = 0; axis < 3; ++axis) p(tool_param_index(axis)) = model.tool_m(axis);
  return p;
}

RobotModel from_params(const ModelParams& p) {
  RobotModel model;
  for (int j = 0; j < kJointCount; ++j) {
    DhJoint& joint = model.joints[j];
    joint.theta_offset_rad = p(model_param_index(j, DhField::theta_offset));
    joint.d_m = p(model_param_index(j, DhField::d));
    joint.a_m = p(model_param_index(j, DhField::a));
    joint.alpha_rad = p(model_param_index(j, DhField::alpha));
  }
  for (int axis = 0; axis < 3; ++axis) model.tool_m(axis) = p(tool_param_index(axis));
  return model;
}

RobotModel nominal_model(RobotType type) {
  const NominalTable& table = table_of(type);
  RobotModel model;
  for (int j = 0; j < kJointCount; ++j) {
    model.joints[j] = DhJoint{0.0, table.d_m[j], table.a_m[j], kUrAlpha_rad[j]};
  }
  return model;
}

const char* robot_type_name(RobotType type) {
  switch (type) {
    case RobotType::ur3: return "ur3";
    case RobotType::ur10: return "ur10";
    case RobotType::ur5e: return "ur5e";
    case RobotType::ur5: break;
  }
  return "ur5";
}

Status robot_type_from_name(const char* name, RobotType* type) {
  constexpr RobotType kAll[] = {RobotType::ur3, RobotType::ur5, RobotType::ur10, RobotType::ur5e};
  if (name == nullptr) return Status::invalid_argument;
  for (RobotType candidate : kAll) {
    if (names_equal(name, robot_type_name(candidate))) {
      *type = candidate;
      return Status::ok;
    }
  }
  return Status::invalid_argument;
}

Status apply_ur_deltas(const RobotModel& nominal, const UrCalibrationDeltas& deltas, RobotModel* calibrated) {
  RobotModel out = nominal;
  for (int j = 0; j < kJointCount; ++j) {
    const double values[] = {deltas.delta_theta_rad[j], deltas.delta_a_m[j], deltas.delta_d_m[j],
                             deltas.delta_alpha_rad[j]};
    for (double v : values) {
      if (!math::is_finite(v)) return Status::non_finite_input;
    }
    out.joints[j].theta_offset_rad += deltas.delta_theta_rad[j];
    out.joints[j].a_m += deltas.delta_a_m[j];
    out.joints[j].d_m += deltas.delta_d_m[j];
    out.joints[j].alpha_rad += deltas.delta_alpha_rad[j];
  }
  *calibrated = out;
  return Status::ok;
}

UrCalibrationDeltas ur_deltas_between(const RobotModel& nominal, const RobotModel& calibrated) {
  UrCalibrationDeltas deltas;
  for (int j = 0; j < kJointCount; ++j) {
    deltas.delta_theta_rad[j] = calibrated.joints[j].theta_offset_rad - nominal.joints[j].theta_offset_rad;
    deltas.delta_a_m[j] = calibrated.joints[j].a_m - nominal.joints[j].a_m;
    deltas.delta_d_m[j] = calibrated.joints[j].d_m - nominal.joints[j].d_m;
    deltas.delta_alpha_rad[j] = calibrated.joints[j].alpha_rad - nominal.joints[j].alpha_rad;
  }
  return deltas;
}

RigidTransform fk_flange(const RobotModel& model, const JointVector& q_rad) {
  RigidTransform pose;
  for (int j = 0; j < kJointCount; ++j) {
    const Link link = dh_link(model.joints[j], q_rad(j));
    pose.translation_m = pose.rotation * link.translation_m + pose.translation_m;
    pose.rotation = pose.rotation * link.rotation;
  }
  return pose;
}

TwistTrig twist_trig(const RobotModel& model) {
  TwistTrig trig;
  for (int j = 0; j < kJointCount; ++j) math::sincos(model.joints[j].alpha_rad, &trig.sin_alpha[j], &trig.cos_alpha[j]);
  return trig;
}

Vec3 fk_tool_point(const RobotModel& model, const JointVector& q_rad) {
  return fk_tool_point(model, twist_trig(model), q_rad);
}

Vec3 fk_tool_point(const RobotModel& model, const TwistTrig& trig, const JointVector& q_rad) {
  // Innermost first: p <- R_j p + t_j needs only matrix-vector products.
  Vec3 point_m = model.tool_m;
  for (int j = kJointCount - 1; j >= 0; --j) {
    const Link link = dh_link(model.joints[j], trig.sin_alpha[j], trig.cos_alpha[j], q_rad(j));
    point_m = link.rotation * point_m + link.translation_m;
  }
  return point_m;
}

Vec3 tool_point_jacobian(const RobotModel& model, const JointVector& q_rad, ToolPointJacobian* jacobian) {
  return tool_point_jacobian(model, twist_trig(model), q_rad, jacobian);
}

Vec3 tool_point_jacobian(const RobotModel& model, const TwistTrig& trig, const JointVector& q_rad,
                         ToolPointJacobian* jacobian) {
  // Frame i-1 (before joint i) gives z_{i-1}, o_{i-1}: theta_i rotates and d_i slides about/along
  // it. After Rz(theta) Tz(d) Tx(a) the x axis is x_i and the origin o_i: a_i slides along x_i and
  // alpha_i rotates about it. Each column is a screw applied to the final tool point.
  Mat3 axes_before[kJointCount];
  Vec3 origin_before_m[kJointCount];
  Vec3 x_axis_after[kJointCount];
  Vec3 origin_after_m[kJointCount];
  RigidTransform pose;
  for (int j = 0; j < kJointCount; ++j) {
    axes_before[j] = pose.rotation;
    origin_before_m[j] = pose.translation_m;
    const Link link = dh_link(model.joints[j], trig.sin_alpha[j], trig.cos_alpha[j], q_rad(j));
    pose.translation_m = pose.rotation * link.translation_m + pose.translation_m;
    pose.rotation = pose.rotation * link.rotation;
    x_axis_after[j] = pose.rotation.col(0);
    origin_after_m[j] = pose.translation_m;
  }
  const Vec3 tool_point_m = pose.rotation * model.tool_m + pose.translation_m;
  for (int j = 0; j < kJointCount; ++j) {
    const Vec3 z_before = axes_before[j].col(2);
    jacobian->col(model_param_index(j, DhField::theta_offset)) = z_before.cross(tool_point_m - origin_before_m[j]);
    jacobian->col(model_param_index(j, DhField::d)) = z_before;
    jacobian->col(model_param_index(j, DhField::a)) = x_axis_after[j];
    jacobian->col(model_param_index(j, DhField::alpha)) = x_axis_after[j].cross(tool_point_m - origin_after_m[j]);
  }
  jacobian->template block<3, 3>(0, kDhParamCount) = pose.rotation;
  return tool_point_m;
}

}  // namespace hivecal
