// Joint compliance: the joints that carry the arm's weight deflect under it (docs/compliance.md).
//
// Joint j deflects by dq_j = sum over the terms t of joint j of coefficient_t * basis_t(q),
// where basis_t is a gravity torque about joint j's axis per unit g, computed from the model's
// RIGID forward kinematics at the joint readings q:
//   basis = sum over the term's point masses m at P of  z_j . ((P - o_j) x g_hat) * m
// (z_j, o_j: axis and origin of DH frame j, the frame joint j turns about, 0-based joints;
// g_hat: unit gravity direction in the robot base frame). The tool point is then the rigid FK at
// q + dq: the deflection adds to the joint reading as theta_offset does. A prismatic joint is
// loaded by the weight along its axis instead, basis = z_j . g_hat * m (per unit g), and
// deflects along it. With no term the model is rigid and every FK gives the bits of the rigid
// chain.
//
// A term may instead be a harmonic of its joint's reading, basis sin(k q_j) or cos(k q_j)
// (k = 1 .. kMaxHarmonicOrder): the classic model of encoder eccentricity (k = 1) and gear
// transmission error. It deflects the joint the same way, so the solver treats both alike.
#pragma once

#include "hivecal/core/capacity.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

struct JointTrig;  // model/kinematics.hpp: sin and cos of a pose's joint readings

struct RobotModel;
enum class RobotType : int;

/// Most compliance terms one model holds (each is one more LM parameter): the build's
/// capacity for joint terms (core/capacity.hpp).
inline constexpr int kMaxComplianceTerms = kMaxJointTerms;
/// The frame number of a point load at the tool point (target 1's): beyond the DH frames 1 ..
/// joint_count of any model the build holds (7 for six joints).
inline constexpr int kToolLoadFrame = kMaxJoints + 1;

/// What the basis of a model's terms weighs.
enum class ComplianceLoad : int {
  /// A unit mass (1 kg) at one DH frame's origin or at the tool point: basis [m], coefficient
  /// [rad/m]. The generic gravity-shaped basis for arms without dynamic data.
  point = 0,
  /// The links' masses at their centres of mass plus the payload (ArmMasses), all the mass the
  /// joint carries: basis [kg m], coefficient [rad/(kg m)].
  arm_masses = 1,
};

/// What a term's basis is. The sine and cosine below are evaluated with
/// the library's own math::sincos (compliance.cpp), never libm's, so the bits are the same on
/// every target.
enum class JointTermKind : int {
  gravity = 0,       ///< a gravity torque of the model's load (ComplianceLoad)
  harmonic_sin = 1,  ///< the sine of order * q_j, the joint's own reading: coefficient [rad]
  harmonic_cos = 2,  ///< the cosine of order * q_j: coefficient [rad]
};

/// Highest order of a joint-angle harmonic (one or two per turn of the joint: encoder
/// eccentricity; higher: gear transmission error) [-].
inline constexpr int kMaxHarmonicOrder = 3;

/// Largest magnitude of a plausible joint-term coefficient (a gravity term's rad/m or
/// rad/(kg m), a harmonic's rad): real arms have 1e-6 .. 1e-4. Beyond it a value is not a
/// robot's: a unit error in a model file (which the readers refuse), or a fit's terms taking
/// up something else (which the job fixes) [-].
inline constexpr double kMaxJointTermCoefficient = 1e-2;

/// One compliance term: the joint that deflects and, for a point load, where the mass sits;
/// or a harmonic of the joint's reading (encoder eccentricity, transmission error).
struct ComplianceTerm {
  int joint = 0;  ///< deflecting joint, 0-based (1 = a UR's shoulder) [-]
  /// Point load: DH frame 1 .. joint_count whose origin holds the unit mass, or kToolLoadFrame
  /// for the tool point; must lie beyond the joint (> joint). Unused (0) for arm masses and
  /// harmonics [-].
  int frame = 0;
  JointTermKind kind = JointTermKind::gravity;  ///< gravity torque or harmonic
  int order = 0;  ///< harmonic: 1 .. kMaxHarmonicOrder (periods per joint turn); gravity: 0 [-]
};

/// True when `term` is a joint-angle harmonic, not a gravity term.
constexpr bool is_harmonic(const ComplianceTerm& term) {
  return term.kind != JointTermKind::gravity;
}

/// Masses and centres of mass of the links and the payload (ComplianceLoad::arm_masses).
struct ArmMasses {
  ArmMasses();                           ///< no masses: every mass and centre 0
  double link_mass_kg[kMaxJoints] = {};  ///< mass of link 1 .. joint_count (moved by joint 1 ..) [kg]
  /// Centre of mass of link j + 1 in DH frame j + 1 (the frame at the link's end) [m].
  Vec3 link_com_m[kMaxJoints];
  double payload_kg = 0.0;            ///< payload (tool, reflector mount) mass [kg]
  Vec3 payload_com_m = Vec3::Zero();  ///< payload centre of mass in the flange frame [m]
};

/// The joints' errors beyond the rigid chain in a RobotModel: gravity compliance terms and
/// joint-angle harmonics, each deflecting its joint by coefficient * basis. term_count 0 = rigid. Laid out without
/// padding (plain doubles, then ints in pairs) so that whole models compare byte for byte.
struct ComplianceModel {
  /// Coefficient of each term: [rad/m] for point loads, [rad/(kg m)] for arm masses, [rad]
  /// for harmonics.
  double coefficient[kMaxComplianceTerms] = {};
  Vec3 gravity_direction = Vec3(0.0, 0.0, -1.0);  ///< unit gravity direction, robot base frame [-]
  ArmMasses masses;                               ///< read by ComplianceLoad::arm_masses only
  ComplianceTerm terms[kMaxComplianceTerms];      ///< the first term_count are used
  int term_count = 0;                             ///< 0 .. kMaxComplianceTerms; 0 = rigid [-]
  ComplianceLoad load = ComplianceLoad::point;    ///< what every gravity term's basis weighs
};

/// Status::ok when `compliance` is usable for the joints of `model` (whose own compliance is not
/// read): rigid (term_count 0, the rest unread), or term_count in [1, kMaxComplianceTerms],
/// joints in [0, joint_count), point frames in (joint, joint_count] or kToolLoadFrame,
/// harmonics of revolute joints only with orders in [1, kMaxHarmonicOrder], finite
/// coefficients, masses >= 0 and finite, and a finite gravity direction of unit length (within
/// 1e-9); invalid_argument or non_finite_input otherwise.
Status check_compliance(const ComplianceModel& compliance, const RobotModel& model);

/// The basis of each of the model's terms at joint readings q (rigid FK of `model`), into
/// basis[0 .. term_count - 1]; the rest 0. [m] (point), [kg m] (arm masses) or [-] (harmonics).
/// A harmonic of order k is sin or cos of k q_j from sin q_j and cos q_j by the angle-sum
/// formulas; `trig`, when given, holds them (joint_trig(q): the same bits), else they are computed.
void compliance_basis(const RobotModel& model, const JointVector& q_rad, double (&basis)[kMaxComplianceTerms],
                      const JointTrig* trig = nullptr);

/// The joints' deflection at readings q: dq_j = sum of coefficient_t * basis_t over the terms
/// of joint j [rad]; zero when term_count is 0.
JointVector compliance_deflection(const RobotModel& model, const JointVector& q_rad);
/// The same, with the basis of each term (compliance_basis, `trig` the readings' joint trig or
/// null) into basis[].
JointVector compliance_deflection(const RobotModel& model, const JointVector& q_rad,
                                  double (&basis)[kMaxComplianceTerms], const JointTrig* trig = nullptr);

/// The default terms of `load` for `model` (its nominal geometry) with gravity along
/// `gravity_direction` (normalised here), into *compliance: terms, term_count, load, the unit
/// gravity direction, zero coefficients; the masses are left as they are. The shoulder is the
/// first joint whose axis is horizontal at q = 0 (|z . g_hat| < cos 45 deg), the elbow the
/// next one (revolute joints: a horizontal axis carries the arm's weight as a torque). Point:
/// (shoulder, its link's end = frame shoulder + 1), (shoulder, frame 4 = wrist), (elbow, frame
/// 4), (elbow, tool). Arm masses: one term per horizontal joint among the first four.
/// invalid_argument when gravity is zero or not finite, or no joint (point: no two joints) is
/// horizontal. docs/compliance.md says why these.
Status default_compliance_terms(const RobotModel& model, const Vec3& gravity_direction, ComplianceLoad load,
                                ComplianceModel* compliance);

/// Appends the harmonics of orders 1 .. `orders` of every revolute joint of `model` (whose own
/// compliance is not read) to *compliance: per joint and order a sine and a cosine term with
/// zero coefficients (a prismatic joint's reading is a length: it has none). invalid_argument
/// when `orders` is outside [1, kMaxHarmonicOrder] or the terms would not fit in
/// kMaxComplianceTerms (the build's capacity: for six joints 28 holds the 4 gravity terms and
/// orders 1 .. 2, 40 orders 1 .. 3).
Status append_harmonic_terms(int orders, const RobotModel& model, ComplianceModel* compliance);
/// The terms append_harmonic_terms(orders) adds to `model`: two per revolute joint and order [-].
int harmonic_term_count(const RobotModel& model, int orders);

/// Universal Robots' published link masses and centres of mass of `type` into *masses (payload
/// left as it is): every RobotType (the CB-series UR3, UR5, UR10 and the e-Series UR3e, UR5e,
/// UR10e, UR16e); invalid_argument for any other value.
Status nominal_arm_masses(RobotType type, ArmMasses* masses);

/// Short name of term t of `compliance` for tables: "c_j2_o2", "c_j2_o4", "c_j3_tool" (point:
/// 1-based joint and frame), "c_j2_mass" (arm masses), "h_j2_sin1", "h_j2_cos2" (harmonics:
/// 1-based joint, function and order); "?" outside [0, term_count). Static storage.
const char* compliance_term_name(const ComplianceModel& compliance, int t);

}  // namespace hivecal
