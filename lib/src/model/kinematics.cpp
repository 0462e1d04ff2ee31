#include "hivecal/model/kinematics.hpp"

#include "hivecal/core/math.hpp"
#include "model/kinematics_detail.hpp"
#include "model/seven_axis_arms.hpp"

namespace hivecal {
namespace {

/// One DH link: rotation Rz(theta) Rx(alpha) and translation [a cos, a sin, d].
struct Link {
  Mat3 rotation;
  Vec3 translation_m;
};

/// The link of a revolute joint at reading q [rad] with its twist's sin and cos given.
__attribute__((always_inline)) inline Link revolute_link(const DhJoint& joint, double sa, double ca, double q_rad) {
  double st = 0.0;
  double ct = 0.0;
  math::sincos(q_rad + joint.theta_offset_rad, &st, &ct);
  Link link;
  link.rotation << ct, -st * ca, st * sa, st, ct * ca, -ct * sa, 0.0, sa, ca;
  link.translation_m << joint.a_m * ct, joint.a_m * st, joint.d_m;
  return link;
}

/// The link of joint j of `model` at reading q with its twist's sin and cos given: q turns theta
/// (revolute, [rad]) or slides d (prismatic, [m]: the link of a joint at theta_offset, d + q).
/// A revolute joint takes the arithmetic of before joints had types, without a select.
__attribute__((always_inline)) inline Link dh_link(const RobotModel& model, int j, double sa, double ca, double q) {
  if (joint_type(model, j) == JointType::revolute) return revolute_link(model.joints[j], sa, ca, q);
  DhJoint slid = model.joints[j];
  slid.d_m += q;
  return revolute_link(slid, sa, ca, 0.0);
}

Link dh_link(const RobotModel& model, int j, double q) {
  double sa = 0.0;
  double ca = 0.0;
  math::sincos(model.joints[j].alpha_rad, &sa, &ca);
  return dh_link(model, j, sa, ca, q);
}

struct NominalTable {
  double d_m[kSixJoints];
  double a_m[kSixJoints];
};

// Universal Robots' published DH tables (standard DH, CB3 and e-Series), alpha = [pi/2, 0, 0, pi/2, -pi/2, 0].
constexpr NominalTable kUr3 = {{0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819}, {0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr5 = {{0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823}, {0.0, -0.425, -0.39225, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr10 = {{0.1273, 0.0, 0.0, 0.163941, 0.1157, 0.0922}, {0.0, -0.612, -0.5723, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr5e = {{0.1625, 0.0, 0.0, 0.1333, 0.0997, 0.0996}, {0.0, -0.425, -0.3922, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr3e = {{0.15185, 0.0, 0.0, 0.13105, 0.08535, 0.0921}, {0.0, -0.24355, -0.2132, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr10e = {{0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655},
                                 {0.0, -0.6127, -0.57155, 0.0, 0.0, 0.0}};
constexpr NominalTable kUr16e = {{0.1807, 0.0, 0.0, 0.17415, 0.11985, 0.11655}, {0.0, -0.4784, -0.36, 0.0, 0.0, 0.0}};
constexpr double kUrAlpha_rad[kSixJoints] = {math::kHalfPi, 0.0, 0.0, math::kHalfPi, -math::kHalfPi, 0.0};

const NominalTable& table_of(RobotType type) {
  switch (type) {
    case RobotType::ur3: return kUr3;
    case RobotType::ur10: return kUr10;
    case RobotType::ur5e: return kUr5e;
    case RobotType::ur3e: return kUr3e;
    case RobotType::ur10e: return kUr10e;
    case RobotType::ur16e: return kUr16e;
    case RobotType::ur5:
    default: break;  // the seven-axis arms are seven_axis_arms.cpp's
  }
  return kUr5;
}

constexpr RobotType kBuiltinTypes[] = {RobotType::ur3,    RobotType::ur5,   RobotType::ur10,  RobotType::ur3e,
                                       RobotType::ur5e,   RobotType::ur10e, RobotType::ur16e,
#if HIVECAL_MAX_JOINTS >= 7
                                       RobotType::iiwa14, RobotType::panda, RobotType::fr3,   RobotType::gen3,
                                       RobotType::wam
#endif
};

bool names_equal(const char* a, const char* b) {
  while (*a != '\0' && *a == *b) {
    ++a;
    ++b;
  }
  return *a == *b;
}

}  // namespace

ModelParams to_params(const RobotModel& model) {
  ModelParams p = ModelParams::Zero();
  for (int j = 0; j < model.joint_count; ++j) {
    const DhJoint& joint = model.joints[j];
    p(model_param_index(j, DhField::theta_offset)) = joint.theta_offset_rad;
    p(model_param_index(j, DhField::d)) = joint.d_m;
    p(model_param_index(j, DhField::a)) = joint.a_m;
    p(model_param_index(j, DhField::alpha)) = joint.alpha_rad;
  }
  for (int axis = 0; axis < 3; ++axis) p(tool_param_index(model, axis)) = model.tool_m(axis);
  return p;
}

double model_param(const RobotModel& model, int index) {
  const int dh_count = kParamsPerJoint * model.joint_count;
  if (index >= dh_count) return model.tool_m(index - dh_count);
  const DhJoint& joint = model.joints[index / kParamsPerJoint];
  switch (static_cast<DhField>(index % kParamsPerJoint)) {
    case DhField::theta_offset: return joint.theta_offset_rad;
    case DhField::d: return joint.d_m;
    case DhField::a: return joint.a_m;
    case DhField::alpha: break;
  }
  return joint.alpha_rad;
}

void set_model_params(const ModelParams& p, RobotModel* model) {
  for (int j = 0; j < model->joint_count; ++j) {
    DhJoint& joint = model->joints[j];
    joint.theta_offset_rad = p(model_param_index(j, DhField::theta_offset));
    joint.d_m = p(model_param_index(j, DhField::d));
    joint.a_m = p(model_param_index(j, DhField::a));
    joint.alpha_rad = p(model_param_index(j, DhField::alpha));
  }
  for (int axis = 0; axis < 3; ++axis) model->tool_m(axis) = p(tool_param_index(*model, axis));
}

Span<const RobotType> builtin_robot_types() {
  return Span<const RobotType>(kBuiltinTypes, sizeof kBuiltinTypes / sizeof kBuiltinTypes[0]);
}

RobotModel nominal_model(RobotType type) {
  RobotModel model;
  if (detail::seven_axis_model(type, &model)) return model;
  const NominalTable& table = table_of(type);
  model.joint_count = kSixJoints;
  for (int j = 0; j < kSixJoints; ++j) {
    model.joints[j] = DhJoint{0.0, table.d_m[j], table.a_m[j], kUrAlpha_rad[j]};
  }
  return model;
}

const char* robot_type_name(RobotType type) {
  if (const char* name = detail::seven_axis_name(type); name != nullptr) return name;
  switch (type) {
    case RobotType::ur3: return "ur3";
    case RobotType::ur10: return "ur10";
    case RobotType::ur5e: return "ur5e";
    case RobotType::ur3e: return "ur3e";
    case RobotType::ur10e: return "ur10e";
    case RobotType::ur16e: return "ur16e";
    case RobotType::ur5:
    default: break;
  }
  return "ur5";
}

const char* robot_type_names() {
#if HIVECAL_MAX_JOINTS >= 7
  return "ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e, iiwa14, panda, fr3, gen3, wam";
#else
  return "ur3, ur5, ur10, ur3e, ur5e, ur10e, ur16e";
#endif
}

Status robot_type_from_name(const char* name, RobotType* type) {
  if (name == nullptr) return Status::invalid_argument;
  for (RobotType candidate : kBuiltinTypes) {
    if (names_equal(name, robot_type_name(candidate))) {
      *type = candidate;
      return Status::ok;
    }
  }
  return Status::invalid_argument;
}

namespace detail {

void rigid_frames(const RobotModel& model, const JointVector& q_rad, RigidTransform (&frame)[kMaxJoints + 1]) {
  frame[0] = RigidTransform{};
  for (int j = 0; j < model.joint_count; ++j) {
    const Link link = dh_link(model, j, q_rad(j));
    frame[j + 1].translation_m = frame[j].rotation * link.translation_m + frame[j].translation_m;
    frame[j + 1].rotation = frame[j].rotation * link.rotation;
  }
}

}  // namespace detail

namespace {

/// The joint readings the rigid chain sees: q, plus the deflection when the model has terms.
JointVector deflected(const RobotModel& model, const JointVector& q_rad) {
  if (model.compliance.term_count == 0) return q_rad;
  return q_rad + compliance_deflection(model, q_rad);
}

RigidTransform rigid_flange(const RobotModel& model, const JointVector& q_rad) {
  RigidTransform pose;
  for (int j = 0; j < model.joint_count; ++j) {
    const Link link = dh_link(model, j, q_rad(j));
    pose.translation_m = pose.rotation * link.translation_m + pose.translation_m;
    pose.rotation = pose.rotation * link.rotation;
  }
  return pose;
}

/// The sin and cos of the joints' twists, all that the point's recursion reads (the model's first
/// joint_count; the rest not written).
struct TwistTrig {
  const double* sin_alpha;  ///< sine of alpha_j [-]
  const double* cos_alpha;  ///< cosine of alpha_j [-]
};

/// The rigid chain from the tool point `tool_m` inwards.
Vec3 rigid_point(const RobotModel& model, TwistTrig trig, const Vec3& tool_m, const JointVector& q_rad) {
  // Innermost first: p <- R_j p + t_j needs only matrix-vector products.
  Vec3 point_m = tool_m;
  for (int j = model.joint_count - 1; j >= 0; --j) {
    const Link link = dh_link(model, j, trig.sin_alpha[j], trig.cos_alpha[j], q_rad(j));
    point_m = link.rotation * point_m + link.translation_m;
  }
  return point_m;
}

Vec3 rigid_point(const RobotModel& model, const ModelTrig& trig, const Vec3& tool_m, const JointVector& q_rad) {
  return rigid_point(model, TwistTrig{trig.sin_alpha, trig.cos_alpha}, tool_m, q_rad);
}

/// The twists' sin and cos of a one-shot FK call, computed into storage of the caller's that
/// is not cleared (the joints beyond the model's are not read).
struct TwistStorage {
  double sin_alpha[kMaxJoints];
  double cos_alpha[kMaxJoints];
  explicit TwistStorage(const RobotModel& model) {
    for (int j = 0; j < model.joint_count; ++j) math::sincos(model.joints[j].alpha_rad, &sin_alpha[j], &cos_alpha[j]);
  }
  TwistTrig trig() const { return TwistTrig{sin_alpha, cos_alpha}; }
};

}  // namespace

RigidTransform fk_flange(const RobotModel& model, const JointVector& q_rad) {
  if (model.compliance.term_count == 0) return rigid_flange(model, q_rad);
  return rigid_flange(model, deflected(model, q_rad));
}

ModelTrig model_trig(const RobotModel& model) {
  ModelTrig trig;
  for (int j = 0; j < model.joint_count; ++j) {
    const DhJoint& joint = model.joints[j];
    math::sincos(joint.alpha_rad, &trig.sin_alpha[j], &trig.cos_alpha[j]);
    math::sincos(joint.theta_offset_rad, &trig.sin_offset[j], &trig.cos_offset[j]);
  }
  return trig;
}

JointTrig joint_trig(const RobotModel& model, const JointVector& q_rad) {
  JointTrig trig;
  for (int j = 0; j < model.joint_count; ++j) {
    if (joint_type(model, j) == JointType::revolute) {
      math::sincos(q_rad(j), &trig.sin_q[j], &trig.cos_q[j]);
    } else {
      // No trig call here (nor libm's): a prismatic joint turns nothing, so theta is the offset
      // alone and sin(0), cos(0) are exactly 0 and 1 (sin_q stays 0 from JointTrig's init).
      trig.cos_q[j] = 1.0;
      trig.slide_m[j] = q_rad(j);
    }
  }
  return trig;
}

Vec3 fk_tool_point(const RobotModel& model, const JointVector& q_rad) {
  const TwistStorage twist(model);  // the twist half of model_trig: fk_tool_point takes sin/cos of q + offset directly
  if (model.compliance.term_count == 0) return rigid_point(model, twist.trig(), model.tool_m, q_rad);
  return rigid_point(model, twist.trig(), model.tool_m, deflected(model, q_rad));
}

Vec3 fk_target_point(const RobotModel& model, const JointVector& q_rad, int target) {
  // The same recursion with the target's tool point (the same bits as fk_tool_point for
  // target 0); the deflection is the model's, whatever the target.
  const TwistStorage twist(model);
  if (model.compliance.term_count == 0) return rigid_point(model, twist.trig(), target_tool(model, target), q_rad);
  return rigid_point(model, twist.trig(), target_tool(model, target), deflected(model, q_rad));
}

Vec3 fk_target_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad, int target) {
  if (model.compliance.term_count == 0) return rigid_point(model, trig, target_tool(model, target), q_rad);
  return rigid_point(model, trig, target_tool(model, target), deflected(model, q_rad));
}

Vec3 fk_tool_point(const RobotModel& model, const ModelTrig& trig, const JointVector& q_rad) {
  if (model.compliance.term_count == 0) return rigid_point(model, trig, model.tool_m, q_rad);
  return rigid_point(model, trig, model.tool_m, deflected(model, q_rad));
}

namespace detail {
namespace {

/// Lane k of a value (a plain double has one).
inline double lane_at(double v, int) {
  return v;
}
#if defined(HIVECAL_LANES_ARE_VECTORS)
inline double lane_at(const lanes::Lane& v, int k) {
  return lanes::lane_value(v, k);
}
#endif
#ifdef HIVECAL_WIDE_LANES
inline double lane_at(const lanes::WideLane& v, int k) {
  return v[k];
}
#endif

/// Entry j of `field` of each lane's JointTrig, one per lane, built in registers (a store of
/// the halves and a vector load would stall on store forwarding). Out-parameter: a 32-byte
/// vector returned by value would change the ABI outside AVX code (-Wpsabi).
template <class Lane, int kWidth>
__attribute__((always_inline)) inline void gather(const JointTrig* const* trig,
                                                  const double (JointTrig::*field)[kMaxJoints], int j, Lane* out) {
  static_assert(kWidth == 1 || kWidth == 2 || kWidth == 4, "one, two or four lanes");
  if constexpr (kWidth == 1) {
    *out = (trig[0]->*field)[j];
  } else if constexpr (kWidth == 2) {
    *out = Lane{(trig[0]->*field)[j], (trig[1]->*field)[j]};
  } else {
    *out = Lane{(trig[0]->*field)[j], (trig[1]->*field)[j], (trig[2]->*field)[j], (trig[3]->*field)[j]};
  }
}

/// a * u + b * v, per component (the x and y axes after a rotation about z, or y and z after
/// one about x).
template <class Lane>
__attribute__((always_inline)) inline void combine(const Lane& a, const Lane* u, const Lane& b, const Lane* v,
                                                   Lane* out) {
  for (int r = 0; r < 3; ++r) out[r] = a * u[r] + b * v[r];
}

/// Where the lanes' columns go.
template <int kWidth>
struct LaneTargets {
  const JacobianRowsTarget* target;  ///< one per lane
  /// Writes component r of column c of every lane.
  template <class Lane>
  __attribute__((always_inline)) void put(int c, int r, const Lane& value) const {
    for (int k = 0; k < kWidth; ++k) target[k].row[r][target[k].slot[c]] = lane_at(value, k);
  }
};

/// u x (p - o) into column c (the screw of a rotation about u through o).
template <class Lane, int kWidth>
__attribute__((always_inline)) inline void write_moment(const Lane* u, const Lane* p, const Lane* o, int c,
                                                        const LaneTargets<kWidth>& out) {
  const Lane dx = p[0] - o[0];
  const Lane dy = p[1] - o[1];
  const Lane dz = p[2] - o[2];
  out.put(c, 0, u[1] * dz - u[2] * dy);
  out.put(c, 1, u[2] * dx - u[0] * dz);
  out.put(c, 2, u[0] * dy - u[1] * dx);
}

template <class Lane, int kWidth>
__attribute__((always_inline)) inline void write_vector(const Lane* u, int c, const LaneTargets<kWidth>& out) {
  for (int r = 0; r < 3; ++r) out.put(c, r, u[r]);
}

/// The kernel, lane k for sample k. The frame before joint j is kept as its axes x, y, z and
/// origin o (base frame). Joint j turns x, y about z by theta and slides o by d along z and a
/// along the new x: that is where theta_j rotates, d_j slides (z before), a_j slides (x
/// after); then alpha_j turns y, z about the new x through the new origin. Plain column
/// rotations: 48 flops per joint instead of two 3x3 products. A prismatic joint's trig is that
/// of q = 0 (its theta is the offset alone) and its reading adds to d, per lane.
template <class Lane, int kWidth>
__attribute__((always_inline)) inline void jacobian_lanes(const RobotModel& model, const ModelTrig& model_trig,
                                                          const JointTrig* const* joint_trig,
                                                          const LaneTargets<kWidth>& out, Vec3* point_out_m) {
  const Lane zero = Lane{};
  const Lane one = zero + 1.0;
  Lane x[3] = {one, zero, zero};
  Lane y[3] = {zero, one, zero};
  Lane z[3] = {zero, zero, one};
  const int joints = model.joint_count;
  Lane origin_m[kMaxJoints + 1][3];  // origin before joint j; [joints] = flange
  Lane z_before[kMaxJoints][3];
  Lane x_after[kMaxJoints][3];
  for (int r = 0; r < 3; ++r) origin_m[0][r] = zero;
  for (int j = 0; j < joints; ++j) {
    const DhJoint& joint = model.joints[j];
    Lane sq;
    Lane cq;
    gather<Lane, kWidth>(joint_trig, &JointTrig::sin_q, j, &sq);
    gather<Lane, kWidth>(joint_trig, &JointTrig::cos_q, j, &cq);
    // sin and cos of q + offset by the angle-sum formulas: a few ulp, as rounding q + offset
    // to a double already costs.
    const Lane st = sq * model_trig.cos_offset[j] + cq * model_trig.sin_offset[j];
    const Lane ct = cq * model_trig.cos_offset[j] - sq * model_trig.sin_offset[j];
    const Lane sa = zero + model_trig.sin_alpha[j];
    const Lane ca = zero + model_trig.cos_alpha[j];
    Lane turned_x[3];
    Lane turned_y[3];
    combine(ct, x, st, y, turned_x);
    combine(-st, x, ct, y, turned_y);
    if (joint_type(model, j) == JointType::revolute) {
      for (int r = 0; r < 3; ++r) origin_m[j + 1][r] = origin_m[j][r] + joint.d_m * z[r] + joint.a_m * turned_x[r];
    } else {
      Lane slide_m;
      gather<Lane, kWidth>(joint_trig, &JointTrig::slide_m, j, &slide_m);
      const Lane d_m = slide_m + joint.d_m;
      for (int r = 0; r < 3; ++r) origin_m[j + 1][r] = origin_m[j][r] + d_m * z[r] + joint.a_m * turned_x[r];
    }
    for (int r = 0; r < 3; ++r) {
      z_before[j][r] = z[r];
      x_after[j][r] = turned_x[r];
      x[r] = turned_x[r];
    }
    Lane new_z[3];
    combine(ca, turned_y, sa, z, y);
    combine(-sa, turned_y, ca, z, new_z);
    for (int r = 0; r < 3; ++r) z[r] = new_z[r];
  }
  const Lane* flange_m = origin_m[joints];
  const Vec3& tool = model.tool_m;
  Lane point_m[3];
  for (int r = 0; r < 3; ++r) point_m[r] = flange_m[r] + tool.x() * x[r] + tool.y() * y[r] + tool.z() * z[r];
  for (int j = 0; j < joints; ++j) {
    write_moment(z_before[j], point_m, origin_m[j], model_param_index(j, DhField::theta_offset), out);
    write_vector(z_before[j], model_param_index(j, DhField::d), out);
    write_vector(x_after[j], model_param_index(j, DhField::a), out);
    write_moment(x_after[j], point_m, origin_m[j + 1], model_param_index(j, DhField::alpha), out);
  }
  write_vector(x, tool_param_index(joints, 0), out);
  write_vector(y, tool_param_index(joints, 1), out);
  write_vector(z, tool_param_index(joints, 2), out);
  for (int k = 0; k < kWidth; ++k) {
    point_out_m[k] = Vec3(lane_at(point_m[0], k), lane_at(point_m[1], k), lane_at(point_m[2], k));
  }
}

}  // namespace

void tool_point_jacobian_rows(const RobotModel& model, const ModelTrig& model_trig,
                              const JointTrig* const (&joint_trig)[kJacobianLanes],
                              const JacobianRowsTarget (&target)[kJacobianLanes], Vec3 (&point_m)[kJacobianLanes]) {
  jacobian_lanes<lanes::Lane, kJacobianLanes>(model, model_trig, joint_trig, LaneTargets<kJacobianLanes>{target},
                                              point_m);
}

#ifdef HIVECAL_WIDE_LANES
__attribute__((target("avx2"))) void tool_point_jacobian_rows_wide(
    const RobotModel& model, const ModelTrig& model_trig, const JointTrig* const (&joint_trig)[kWideJacobianLanes],
    const JacobianRowsTarget (&target)[kWideJacobianLanes], Vec3 (&point_m)[kWideJacobianLanes]) {
  jacobian_lanes<lanes::WideLane, kWideJacobianLanes>(model, model_trig, joint_trig,
                                                      LaneTargets<kWideJacobianLanes>{target}, point_m);
}
#endif

}  // namespace detail

Vec3 tool_point_jacobian(const RobotModel& model, const JointVector& q_rad, ToolPointJacobian* jacobian) {
  double rows[3][kMaxModelParamCount] = {};
  int slot[kMaxModelParamCount];
  for (int c = 0; c < kMaxModelParamCount; ++c) slot[c] = c;
  const JointTrig q_trig = joint_trig(model, deflected(model, q_rad));
  const JointTrig* const trig_of[1] = {&q_trig};
  const detail::JacobianRowsTarget target[1] = {{{rows[0], rows[1], rows[2]}, slot}};
  Vec3 point_m;
#ifdef HIVECAL_LANES_ARE_VECTORS
  detail::jacobian_lanes<double, 1>(model, model_trig(model), trig_of, detail::LaneTargets<1>{target}, &point_m);
#else  // one lane of double (bare metal): the kernel's own copy, not a second one of it (flash)
  Vec3 points_m[1];
  detail::tool_point_jacobian_rows(model, model_trig(model), trig_of, target, points_m);
  point_m = points_m[0];
#endif
  for (int c = 0; c < kMaxModelParamCount; ++c)
    for (int r = 0; r < 3; ++r) (*jacobian)(r, c) = rows[r][c];
  return point_m;
}

}  // namespace hivecal
