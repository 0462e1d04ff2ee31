#include "hivecal/model/dh_convention.hpp"

#include "hivecal/core/math.hpp"

namespace hivecal {
RigidTransform ModifiedDhBase::transform() const {
  // Rx(alpha0) Tx(a0): the translation along x is unchanged by a rotation about x.
  return RigidTransform{rotation_x(alpha0_rad), Vec3(a0_m, 0.0, 0.0)};
}

Status model_from_modified_dh(Span<const ModifiedDhRow> rows, const Vec3& tool_m, RobotModel* model,
                              ModifiedDhBase* base, std::uint32_t prismatic_joints) {
  const int count = static_cast<int>(rows.size());
  if (count < 1 || count > kMaxJoints) return Status::invalid_argument;
  if (count < 32 && (prismatic_joints >> static_cast<unsigned>(count)) != 0) return Status::invalid_argument;
  for (const ModifiedDhRow& row : rows) {
    if (!math::is_finite(row.alpha_prev_rad) || !math::is_finite(row.a_prev_m) ||
        !math::is_finite(row.theta_offset_rad) || !math::is_finite(row.d_m))
      return Status::non_finite_input;
  }
  if (!all_finite(tool_m)) return Status::non_finite_input;
  RobotModel out;
  out.joint_count = count;
  out.prismatic_joints = prismatic_joints;
  for (int j = 0; j < count; ++j) {
    const bool last = j + 1 == count;
    const auto at = static_cast<std::size_t>(j);
    out.joints[j] = DhJoint{rows[at].theta_offset_rad, rows[at].d_m, last ? 0.0 : rows[at + 1].a_prev_m,
                            last ? 0.0 : rows[at + 1].alpha_prev_rad};
  }
  out.tool_m = tool_m;
  *model = out;
  *base = ModifiedDhBase{rows[0].alpha_prev_rad, rows[0].a_prev_m};
  return Status::ok;
}

int modified_dh_from_model(const RobotModel& model, const ModifiedDhBase& base, Span<ModifiedDhRow> rows,
                           Vec3* tool_m) {
  const int count = model.joint_count;
  if (rows.size() < static_cast<std::size_t>(count)) return 0;
  for (int j = 0; j < count; ++j) {
    const DhJoint& before = j == 0 ? DhJoint{0.0, 0.0, base.a0_m, base.alpha0_rad} : model.joints[j - 1];
    rows[static_cast<std::size_t>(j)] =
        ModifiedDhRow{before.alpha_rad, before.a_m, model.joints[j].theta_offset_rad, model.joints[j].d_m};
  }
  const DhJoint& last = model.joints[count - 1];
  *tool_m = rotation_x(last.alpha_rad) * model.tool_m + Vec3(last.a_m, 0.0, 0.0);
  return count;
}

}  // namespace hivecal
