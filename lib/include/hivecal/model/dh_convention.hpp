// Modified (Craig) DH descriptions in the library's standard DH model, exactly.
//
// Modified DH: T_i = Rx(alpha_{i-1}) Tx(a_{i-1}) Rz(q_i + theta_i) Tz(d_i), row i holding the
// alpha/a of the link before joint i. Since Rx and Tx about/along the same axis commute, the
// chain regroups as
//   Rx(alpha_0) Tx(a_0) * prod_i [Rz(q_i + theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)],  a_6 = alpha_6 = 0,
// i.e. a standard DH chain whose joint i takes row i's theta and d and row i+1's a and alpha,
// behind a fixed base offset Rx(alpha_0) Tx(a_0); the flange frames are the same. So every
// solver, the Jacobian and the identifiability analysis work on modified-DH arms unchanged;
// only reading and writing convert (docs/kinematics.md).
#pragma once

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

/// The standard-DH model (and base offset) of six modified-DH rows and a tool point in the
/// flange frame. FK_modified(q) = base->transform() * FK_standard(q). Errors:
/// non_finite_input.
Status model_from_modified_dh(const ModifiedDhRow (&rows)[kJointCount], const Vec3& tool_m, RobotModel* model,
                              ModifiedDhBase* base);

/// The modified-DH rows and tool of a model read by model_from_modified_dh (with its base).
/// A joint-6 a or alpha that a calibration moved has no modified-DH row: it is folded into
/// the tool point (Tx(a_6) Rx(alpha_6) tool), which gives the same points.
void modified_dh_from_model(const RobotModel& model, const ModifiedDhBase& base, ModifiedDhRow (&rows)[kJointCount],
                            Vec3* tool_m);

}  // namespace hivecal
