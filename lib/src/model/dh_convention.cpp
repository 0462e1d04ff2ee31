#include "hivecal/model/dh_convention.hpp"

#include "hivecal/core/math.hpp"

namespace hivecal {
RigidTransform ModifiedDhBase::transform() const {
  // Rx(alpha0) Tx(a0): the translation along x is unchanged by a rotation about x.
  return RigidTransform{rotation_x(alpha0_rad), Vec3(a0_m, 0.0, 0.0)};
}

Status model_from_modified_dh(const ModifiedDhRow (&rows)[kJointCount], const Vec3& tool_m, RobotModel* model,
                              ModifiedDhBase* base) {
  for (const ModifiedDhRow& row : rows) {
    if (!math::is_finite(row.alpha_prev_rad) || !math::is_finite(row.a_prev_m) ||
        !math::is_finite(row.theta_offset_rad) || !math::is_finite(row.d_m))
      return Status::non_finite_input;
  }
  if (!all_finite(tool_m)) return Status::non_finite_input;
  RobotModel out;
  for (int j = 0; j < kJointCount; ++j) {
    const bool last = j + 1 == kJointCount;
    out.joints[j] = DhJoint{rows[j].theta_offset_rad, rows[j].d_m, last ? 0.0 : rows[j + 1].a_prev_m,
                            last ? 0.0 : rows[j + 1].alpha_prev_rad};
  }
  out.tool_m = tool_m;
  *model = out;
  *base = ModifiedDhBase{rows[0].alpha_prev_rad, rows[0].a_prev_m};
  return Status::ok;
}

void modified_dh_from_model(const RobotModel& model, const ModifiedDhBase& base, ModifiedDhRow (&rows)[kJointCount],
                            Vec3* tool_m) {
  for (int j = 0; j < kJointCount; ++j) {
    const DhJoint& before = j == 0 ? DhJoint{0.0, 0.0, base.a0_m, base.alpha0_rad} : model.joints[j - 1];
    rows[j] = ModifiedDhRow{before.alpha_rad, before.a_m, model.joints[j].theta_offset_rad, model.joints[j].d_m};
  }
  const DhJoint& last = model.joints[kJointCount - 1];
  *tool_m = rotation_x(last.alpha_rad) * model.tool_m + Vec3(last.a_m, 0.0, 0.0);
}

}  // namespace hivecal
