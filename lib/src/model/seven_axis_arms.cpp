// The built-in seven-axis arms: each maker's published DH table (in the maker's own convention)
// and joint position limits, the source named beside each table. Compiled in only where a model
// holds seven joints (HIVECAL_MAX_JOINTS >= 7: the hosted builds); the six-joint firmware knows
// Universal Robots' arms alone and spends no flash on these.
#include "model/seven_axis_arms.hpp"

#include "hivecal/core/math.hpp"
#include "hivecal/model/dh_convention.hpp"

namespace hivecal {
namespace detail {
namespace {

#if HIVECAL_MAX_JOINTS >= 7

constexpr int kSevenJoints = 7;
constexpr double kQuarterTurn = math::kHalfPi;  // [rad]
constexpr double kHalfTurn = math::kPi;         // [rad]
constexpr double kDeg = math::kRadPerDeg;       // [rad/deg]
constexpr double kTurn = 2.0 * math::kPi;       // an endless (continuous) joint's limit: a turn either way [rad]

/// One seven-axis arm as its maker publishes it.
struct SevenAxisArm {
  RobotType type;
  const char* name;         ///< robot_type_name
  DhConvention convention;  ///< how `rows` are written: the maker's
  const double (*rows)[4];  ///< standard: theta_offset, d, a, alpha; modified: alpha_{i-1}, a_{i-1}, theta_offset,
                            ///< d; a row per joint [rad, m]
  double base_alpha_rad;    ///< the maker's fixed Rx() from its base to frame 0, before joint 1 [rad]
  double flange_d_m;        ///< the maker's fixed flange row Tz() after joint 7 [m]
  double lower_rad[kSevenJoints];  ///< lowest joint positions [rad]
  double upper_rad[kSevenJoints];  ///< highest joint positions [rad]
};

// KUKA LBR iiwa 14 R820, standard DH (theta_offset, d, a, alpha): KUKA's "LBR iiwa 7 R800,
// LBR iiwa 14 R820 Specification" (base to A2 0.36 m, A2 to A4 0.42 m, A4 to A6 0.40 m, A6 to
// the flange without media flange 0.126 m; every axis through the one before), the axes' senses
// as in KUKA's own figures (A2 about +y, A4 about -y at zero: the twists of KST's
// constDhDataOf14R820, Modi1987/KST-Kuka-Sunrise-Toolbox, there in modified form). Straight up at zero: the flange at
// 1.306 m on the base axis.
constexpr double kIiwa14Rows[kSevenJoints][4] = {{0.0, 0.36, 0.0, -kQuarterTurn}, {0.0, 0.0, 0.0, kQuarterTurn},
                                                 {0.0, 0.42, 0.0, kQuarterTurn},  {0.0, 0.0, 0.0, -kQuarterTurn},
                                                 {0.0, 0.40, 0.0, -kQuarterTurn}, {0.0, 0.0, 0.0, kQuarterTurn},
                                                 {0.0, 0.126, 0.0, 0.0}};

// Franka Emika Robot (Panda) and Franka Research 3, modified DH (Craig: alpha_{i-1}, a_{i-1},
// theta_offset, d), as Franka publishes it: frankaemika.github.io/docs/control_parameters.html,
// "Denavit-Hartenberg parameters" (frankaemika/docs source/dh-parameters.csv): joint 1 d 0.333,
// joint 3 d 0.316, joint 4 a 0.0825, joint 5 a -0.0825 d 0.384, joint 7 a 0.088; then the
// "Flange" row d 0.107 (flange_d_m). Both arms share it.
constexpr double kFrankaRows[kSevenJoints][4] = {
    {0.0, 0.0, 0.0, 0.333},           {-kQuarterTurn, 0.0, 0.0, 0.0},       {kQuarterTurn, 0.0, 0.0, 0.316},
    {kQuarterTurn, 0.0825, 0.0, 0.0}, {-kQuarterTurn, -0.0825, 0.0, 0.384}, {kQuarterTurn, 0.0, 0.0, 0.0},
    {kQuarterTurn, 0.088, 0.0, 0.0}};

// Kinova Gen3, 7 DoF (spherical wrist), classic DH (theta_offset, d, a, alpha): the KINOVA Gen3
// User Guide, "Classic DH parameters" of the 7-DoF robot: base to frame 0 alpha pi
// (base_alpha_rad), then d = -(0.1564 + 0.1284), -(0.0054 + 0.0064), -(0.2104 + 0.2104),
// -(0.0064 + 0.0064), -(0.2084 + 0.1059), 0, -(0.1059 + 0.0615) to the interface module, theta
// offsets 0, pi, ..., pi, twists pi/2 and pi for joint 7. Kinova's URDF (Kinovarobotics/
// ros_kortex, kortex_description/arms/gen3/7dof/urdf/GEN3_URDF_V12.urdf) has the same frames
// within 0.4 mm (1.187255 m high at zero, against the guide's 1.1873 m).
constexpr double kGen3Rows[kSevenJoints][4] = {
    {0.0, -(0.1564 + 0.1284), 0.0, kQuarterTurn},       {kHalfTurn, -(0.0054 + 0.0064), 0.0, kQuarterTurn},
    {kHalfTurn, -(0.2104 + 0.2104), 0.0, kQuarterTurn}, {kHalfTurn, -(0.0064 + 0.0064), 0.0, kQuarterTurn},
    {kHalfTurn, -(0.2084 + 0.1059), 0.0, kQuarterTurn}, {kHalfTurn, 0.0, 0.0, kQuarterTurn},
    {kHalfTurn, -(0.1059 + 0.0615), 0.0, kHalfTurn}};

// Barrett WAM, 7 DoF, standard DH (theta_offset, d, a, alpha): Barrett's WAM Arm User's Manual
// (D1001, version AH.00, 2008), Table 5 "7-DOF WAM frame parameters": a3 0.045, a4 -0.045, d3
// 0.55, d5 0.3, d7 0.06, twists -+ pi/2; the table ../shared/data/wam-grid's targets were computed
// with (its README).
constexpr double kWamRows[kSevenJoints][4] = {{0.0, 0.0, 0.0, -kQuarterTurn},
                                              {0.0, 0.0, 0.0, kQuarterTurn},
                                              {0.0, 0.55, 0.045, -kQuarterTurn},
                                              {0.0, 0.0, -0.045, kQuarterTurn},
                                              {0.0, 0.3, 0.0, -kQuarterTurn},
                                              {0.0, 0.0, 0.0, kQuarterTurn},
                                              {0.0, 0.06, 0.0, 0.0}};

constexpr SevenAxisArm kSevenAxisArms[] = {
    // Limits: KUKA's specification, axis data (A1, A3, A5 +-170 deg, A2, A4, A6 +-120 deg, A7 +-175 deg).
    {RobotType::iiwa14,
     "iiwa14",
     DhConvention::standard,
     kIiwa14Rows,
     0.0,
     0.0,
     {-170 * kDeg, -120 * kDeg, -170 * kDeg, -120 * kDeg, -170 * kDeg, -120 * kDeg, -175 * kDeg},
     {170 * kDeg, 120 * kDeg, 170 * kDeg, 120 * kDeg, 170 * kDeg, 120 * kDeg, 175 * kDeg}},
    // Limits: Franka's control parameters, q_min and q_max of the Panda (control-parameters-joint-panda.csv).
    {RobotType::panda,
     "panda",
     DhConvention::modified,
     kFrankaRows,
     0.0,
     0.107,
     {-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973},
     {2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973}},
    // Limits: the same for the FR3 (control-parameters-joint-fr3.csv).
    {RobotType::fr3,
     "fr3",
     DhConvention::modified,
     kFrankaRows,
     0.0,
     0.107,
     {-2.7437, -1.7837, -2.9007, -3.0421, -2.8065, 0.5445, -3.0159},
     {2.7437, 1.7837, 2.9007, -0.1518, 2.8065, 4.5169, 3.0159}},
    // Limits: Kinova's URDF above: joints 1, 3, 5, 7 endless (continuous), 2 +-2.41, 4 +-2.66, 6 +-2.23 rad.
    {RobotType::gen3,
     "gen3",
     DhConvention::standard,
     kGen3Rows,
     kHalfTurn,
     0.0,
     {-kTurn, -2.41, -kTurn, -2.66, -kTurn, -2.23, -kTurn},
     {kTurn, 2.41, kTurn, 2.66, kTurn, 2.23, kTurn}},
    // Limits: Barrett's manual, Table 6 "Joint Limits" (the mechanical stops).
    {RobotType::wam,
     "wam",
     DhConvention::standard,
     kWamRows,
     0.0,
     0.0,
     {-2.6, -2.0, -2.8, -0.9, -4.76, -1.6, -3.0},
     {2.6, 2.0, 2.8, 3.1, 1.24, 1.6, 3.0}},
};

const SevenAxisArm* find_arm(RobotType type) {
  for (const SevenAxisArm& arm : kSevenAxisArms) {
    if (arm.type == type) return &arm;
  }
  return nullptr;
}

/// The standard-DH chain of `arm` (its base rotation, if any, left out: nominal_convention
/// carries it), the flange row folded into joint 7's d: Rz(q7 + theta7) Tz(d7) Tz(flange) is
/// Rz(q7 + theta7) Tz(d7 + flange) exactly, and a modified-DH joint 7 has a = alpha = 0 after it.
RobotModel arm_model(const SevenAxisArm& arm) {
  RobotModel model;
  if (arm.convention == DhConvention::modified) {
    ModifiedDhRow rows[kSevenJoints];
    for (int j = 0; j < kSevenJoints; ++j) {
      rows[j] = ModifiedDhRow{arm.rows[j][0], arm.rows[j][1], arm.rows[j][2], arm.rows[j][3]};
    }
    rows[kSevenJoints - 1].d_m += arm.flange_d_m;
    ModifiedDhBase base;  // Franka's alpha_0 = a_0 = 0: no offset
    model_from_modified_dh(Span<const ModifiedDhRow>(rows, kSevenJoints), Vec3::Zero(), &model, &base);
    return model;
  }
  model.joint_count = kSevenJoints;
  for (int j = 0; j < kSevenJoints; ++j) {
    model.joints[j] = DhJoint{arm.rows[j][0], arm.rows[j][1], arm.rows[j][2], arm.rows[j][3]};
  }
  model.joints[kSevenJoints - 1].d_m += arm.flange_d_m;
  return model;
}

#endif

}  // namespace

bool seven_axis_model(RobotType type, RobotModel* model) {
#if HIVECAL_MAX_JOINTS >= 7
  if (const SevenAxisArm* arm = find_arm(type); arm != nullptr) {
    *model = arm_model(*arm);
    return true;
  }
#endif
  (void)type;
  (void)model;
  return false;
}

const char* seven_axis_name(RobotType type) {
#if HIVECAL_MAX_JOINTS >= 7
  if (const SevenAxisArm* arm = find_arm(type); arm != nullptr) return arm->name;
#endif
  (void)type;
  return nullptr;
}

}  // namespace detail

Status maker_joint_limits(RobotType type, JointVector* lower_rad, JointVector* upper_rad) {
#if HIVECAL_MAX_JOINTS >= 7
  if (const detail::SevenAxisArm* arm = detail::find_arm(type); arm != nullptr) {
    *lower_rad = JointVector::Constant(-2.0 * math::kPi);
    *upper_rad = JointVector::Constant(2.0 * math::kPi);
    for (int j = 0; j < detail::kSevenJoints; ++j) {
      (*lower_rad)(j) = arm->lower_rad[j];
      (*upper_rad)(j) = arm->upper_rad[j];
    }
    return Status::ok;
  }
#endif
  (void)type;
  (void)lower_rad;
  (void)upper_rad;
  return Status::invalid_argument;
}

DhConvention nominal_convention(RobotType type, ModifiedDhBase* base) {
  *base = ModifiedDhBase{};
#if HIVECAL_MAX_JOINTS >= 7
  if (const detail::SevenAxisArm* arm = detail::find_arm(type); arm != nullptr) {
    // Kinova's classic table turns the base by pi about x before joint 1: only the modified
    // convention's alpha_0 holds a fixed rotation in front of the chain.
    if (arm->base_alpha_rad == 0.0) return arm->convention;
    base->alpha0_rad = arm->base_alpha_rad;
    return DhConvention::modified;
  }
#endif
  (void)type;
  return DhConvention::standard;
}

}  // namespace hivecal
