// Modified (Craig) DH descriptions in the library's standard DH model, exactly.
//
// Modified DH: T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i + theta_i) Tz(d_i) (a prismatic joint:
// Rz(theta_i) Tz(q_i + d_i)), row i holding the alpha/a of the link before joint i. Since Rx
// and Tx about/along the same axis commute, the chain of n joints regroups as
//   Rx(alpha_0) Tx(a_0) * prod_i [Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)],  a_n = alpha_n = 0,
// i.e. a standard DH chain whose joint i takes row i's theta and d and row i+1's a and alpha,
// behind a fixed base offset Rx(alpha_0) Tx(a_0); the flange frames are the same. So every
// solver, the Jacobian and the identifiability analysis work on modified-DH arms unchanged;
// only reading and writing convert (docs/kinematics.md).
#pragma once

#include <cstdint>

#include "hivecal/core/span.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"
#include "hivecal/model/kinematics.hpp"

namespace hivecal {

/// How a robot description writes its DH rows.
enum class DhConvention : int {
  standard,  ///< T_i = Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)
  modified,  ///< T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i + theta_i) Tz(d_i) (Craig)
};

/// One modified-DH row: the link before joint i, then joint i.
struct ModifiedDhRow {
  double alpha_prev_rad = 0.0;    ///< alpha_{i-1}: twist of the previous link about x [rad]
  double a_prev_m = 0.0;          ///< a_{i-1}: length of the previous link along x [m]
  double theta_offset_rad = 0.0;  ///< theta_i: added to the joint reading [rad]
  double d_m = 0.0;               ///< d_i: offset along z_i [m]
};

/// The fixed part in front of joint 1 of a modified-DH arm: Rx(alpha_0) Tx(a_0).
struct ModifiedDhBase {
  double alpha0_rad = 0.0;  ///< alpha_0 of row 1 [rad]
  double a0_m = 0.0;        ///< a_0 of row 1 [m]

  /// The base offset as a transform: robot base frame <- frame of the standard chain.
  RigidTransform transform() const;
};

/// The standard-DH model (and base offset) of modified-DH rows, one per joint (1 ..
/// kMaxJoints), and a tool point in the flange frame: joint j is prismatic when bit j of
/// `prismatic_joints` is set (its d_i is the variable), else revolute (theta_i).
/// FK_modified(q) = base->transform() * FK_standard(q). Errors: invalid_argument (no rows, more
/// than kMaxJoints, or a type bit beyond them), non_finite_input.
Status model_from_modified_dh(Span<const ModifiedDhRow> rows, const Vec3& tool_m, RobotModel* model,
                              ModifiedDhBase* base, std::uint32_t prismatic_joints = 0);

/// The modified-DH rows (model.joint_count of them, into rows[0 ..], which has room: else
/// nothing is written and 0 returned) and tool of a model read by model_from_modified_dh (with
/// its base); returns the number of rows. A last-joint a or alpha that a calibration moved has
/// no modified-DH row: it is folded into the tool point (Tx(a_n) Rx(alpha_n) tool), which gives
/// the same points.
int modified_dh_from_model(const RobotModel& model, const ModifiedDhBase& base, Span<ModifiedDhRow> rows, Vec3* tool_m);

/// The convention a built-in type's table is written in, and into *base its base offset (zero
/// for standard): standard for Universal Robots', the KUKA LBR iiwa's and the Barrett WAM's
/// tables; modified for the Franka arms (as Franka publishes them) and for the Kinova Gen3, whose
/// classic table turns the base by pi about x before joint 1 (alpha_0 = pi here: a fixed rotation
/// in front of the chain has no standard-DH row). FK in the maker's base frame is
/// base->transform() * FK(nominal_model(type)).
DhConvention nominal_convention(RobotType type, ModifiedDhBase* base);

}  // namespace hivecal
