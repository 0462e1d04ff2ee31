// The streaming normal equations of the full model's point residuals
// r_i = base_to_tracker * FK(q_i) * tool - m_i (docs/solver-lm.md): per-sample residual and
// Jacobian, column scaling, the Huber loss, and sums over samples that never store an N x p
// matrix. The parameters themselves (indices, masks, names, increments) are in
// model/full_params.hpp.
#pragma once

#include <cstddef>
#include <cstdint>

#include <Eigen/Core>

#include "hivecal/linalg/symmetric_eigen.hpp"
#include "hivecal/model/dataset.hpp"
#include "hivecal/model/full_params.hpp"
#include "hivecal/model/kinematics.hpp"
#include "hivecal/core/status.hpp"
#include "hivecal/core/types.hpp"

namespace hivecal {

/// A matrix over every parameter the build holds, such as J^T W J [m^2/unit^2] (37 x 37 for six
/// joints and four terms: 10.9 kB); keep it out of small stacks.
using NormalMatrix = Eigen::Matrix<double, kFullParamCount, kFullParamCount>;
static_assert(kFullParamCount == kSymmetricCapacity, "the eigen-solver is sized for the full model");

/// Residual r = base_to_tracker * FK(q) * tool - point [m] of one sample and, into
/// *jacobian, dr/d(full parameters): R [J_tool | -skew(p) | I], with R the base rotation,
/// J_tool the tool-point Jacobian (3 x model_param_count) and p the tool point in the base frame.
Vec3 full_residual_jacobian(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample,
                            FullJacobian* jacobian);

/// The same in the robot base frame: returns R^T r [m] and [J_tool | -skew(p) | I] into
/// *local_jacobian. R is orthonormal, so J^T J = J_local^T J_local and J^T r = J_local^T R^T r:
/// the normal equations need no rotation of the Jacobian.
Vec3 local_residual_jacobian(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample,
                             FullJacobian* local_jacobian);

/// Column (Jacobi) scaling of normal equations: (*scale)_i = 1 / sqrt(jtwj_ii) for i in
/// `mask` and 1 elsewhere; *scaled = S jtwj S on mask x mask (unit diagonal), with
/// `outside_diagonal` on the other diagonal entries and 0 off the diagonal there.
void scale_normal_matrix(const NormalMatrix& jtwj, ParamMask mask, double outside_diagonal, NormalMatrix* scaled,
                         FullParams* scale);
/// The same scale, and S jtwj S on mask x mask only: the other entries of *scaled are left as
/// they are. For a system that only a Cholesky factor over `mask` reads (cholesky_factor):
/// clearing the whole capacity (73 x 73 in hosted builds) cost the LM's steps on small sets
/// more than the scaling.
void scale_kept_block(const NormalMatrix& jtwj, ParamMask mask, NormalMatrix* scaled, FullParams* scale);

/// Loss of one sample as a function of its residual norm s = |r| [m].
struct PointLoss {
  double huber_threshold_m = 0.0;  ///< s beyond which the loss grows linearly [m]; <= 0: plain squares
  /// Joint-reading noise over point noise, sigma_q / sigma_p: > 0 whitens each sample's residual
  /// and rows by L^-1, L L^T = I + k^2 J_q J_q^T (J_q = d point / d q, the theta columns), before
  /// the loss sees them (errors in variables, docs/robust.md); 0: off [rad/m].
  double joint_noise_ratio_rad_per_m = 0.0;

  /// rho(s) [m^2]: s^2, or 2 k s - k^2 beyond the Huber threshold k.
  double rho(double norm_m) const;
  /// IRLS weight rho'(s) / (2 s) [-]: 1, or k / s beyond k.
  double weight(double norm_m) const;
};

/// The tool point t of one target 2.. as a parameter block beside the model's (docs/solver-lm.md,
/// "Several targets"): with T = d r / d t (3x3), D = sum w T^T T, S = sum w T^T J (J the
/// model's columns) and c = sum w T^T r, the block is eliminated from the normal equations
/// (Schur complement: H - S^T D^-1 S, g - S^T D^-1 c) and its step follows from the others'.
struct TargetBlock {
  Mat3 tool_tool = Mat3::Zero();  ///< D [-]
  Eigen::Matrix<double, 3, kFullParamCount> tool_model =
      Eigen::Matrix<double, 3, kFullParamCount>::Zero();  ///< S [m/unit]
  Vec3 tool_residual_m = Vec3::Zero();                    ///< c [m]
  std::size_t count = 0;  ///< samples of this target summed; 0: the block is not eliminated
};

/// Weighted normal equations of the point residuals, summed sample by sample (no N x p
/// matrix is ever stored).
struct NormalEquations {
  NormalMatrix jtwj;                 ///< sum w_i J_i^T J_i [m^2/unit^2]
  FullParams jtwr;                   ///< sum w_i J_i^T r_i [m^2/unit]
  double loss_sum_m2 = 0.0;          ///< sum rho(|r_i|) [m^2]
  double weighted_squares_m2 = 0.0;  ///< sum w_i |r_i|^2 [m^2]
  double squares_sum_m2 = 0.0;       ///< sum |r_i|^2, unweighted [m^2]
  std::size_t count = 0;             ///< samples summed
  /// Eliminated tool points of targets 2 .. (entry k - 2 for target k): caller storage, no
  /// ownership (LmWorkspaceWithTargets, or a TargetBlock array). Empty: one target only; a
  /// set with more targets than blocks is refused (dimension_out_of_range) when their tool
  /// points are to be estimated.
  Span<TargetBlock> targets;
};

/// The step of the eliminated target tool points that goes with `step` of the model's parameters:
/// t_k += -D_k^-1 (c_k + S_k step), for every target block of `eq` with samples.
void apply_target_step(const NormalEquations& eq, const FullParams& step, RobotModel* model);

/// Sums the normal equations over `samples`, for the parameters in `columns` only (the
/// other rows and columns of jtwj and jtwr are 0; fewer columns, less work). Samples of
/// targets 2.. use their own tool point; when `columns` holds kOtherTargetTools, those tool
/// points are estimated too and eliminated into jtwj and jtwr (TargetBlock), else they stay fixed. One target takes the
/// fast streaming path (the bits of one target), unless the loss whitens (joint_noise_ratio_rad_per_m > 0): then every
/// sample goes the per-sample path, whitened; squares_sum_m2 stays of the raw residuals. `sample_trig`, if it holds an
/// entry per sample (joint_trig of sample i at i), saves the joint trig of every sample; otherwise it is computed here.
/// The same bits either way. Errors: dataset_empty, non_finite_input (a NaN or Inf residual or Jacobian).
Status accumulate_normal_equations(const RobotModel& model, const RigidTransform& base_to_tracker,
                                   Span<const Sample> samples, const PointLoss& loss, NormalEquations* out,
                                   ParamMask columns, Span<const JointTrig> sample_trig = {});
/// The same over the model's rigid parameters (rigid_params_mask) and the other targets' tool points.
Status accumulate_normal_equations(const RobotModel& model, const RigidTransform& base_to_tracker,
                                   Span<const Sample> samples, const PointLoss& loss, NormalEquations* out);

namespace detail {
/// The parameters of a mask as a list of indices, increasing, and where each of the columns
/// sits in a compact row: the listed ones at 0..count-1 in order, the others after them; and
/// where the base's columns are for the model's joint count.
struct IndexList {
  int index[kFullParamCount];
  int slot[kFullParamCount];
  int count = 0;
  int base_rotation = 0;     ///< index of the base's first rotation parameter
  int base_translation = 0;  ///< index of the base's first translation parameter
  int base_end = 0;          ///< one past the base's last parameter
};
}  // namespace detail

/// What the per-sample rows reuse from one call to the next on one model: the model's trig
/// and the joint trig (and compliance basis) of the pose last seen, which that pose's next
/// samples (its other targets, in a row) share. Make one per pass with sample_rows_context().
struct SampleRowsContext {
  ModelTrig trig;                               ///< the model's trig
  detail::IndexList every_column;               ///< every parameter, in order
  const Sample* pose = nullptr;                 ///< the sample pose_trig is of (null: none yet)
  JointTrig pose_trig;                          ///< its joint trig (of the deflected pose when compliant)
  double pose_basis[kMaxComplianceTerms] = {};  ///< its compliance basis [m] or [kg m]
};
/// A context for sample_rows on `model`.
SampleRowsContext sample_rows_context(const RobotModel& model);

/// One sample's rows as the normal equations sum them (the per-sample path): the residual in
/// the base frame and dr/d(full parameters) into *jacobian, both whitened by `loss`'s joint
/// noise; for a sample of a target k > 1 target 1's tool columns are zero and its own tool
/// point's 3x3 Jacobian is in *tool_jacobian; columns outside `columns` zero. *raw_squared_m2
/// is the unwhitened |r|^2 [m^2]. `context`: sample_rows_context(model), the same for the
/// calls of one pass (the same bits as a fresh one). Returns the (whitened) residual [m].
Vec3 sample_rows(const RobotModel& model, SampleRowsContext& context, const RigidTransform& base_to_tracker,
                 const Sample& sample, const PointLoss& loss, ParamMask columns, FullJacobian* jacobian,
                 Mat3* tool_jacobian, double* raw_squared_m2);

/// Loss sums only (no Jacobian, fk_tool_point), e.g. to compare candidate geometries: sum
/// rho(|r_i|) and sum |r_i|^2 [m^2]. Agrees with accumulate_normal_equations to rounding.
/// Errors: dataset_empty, non_finite_input.
Status evaluate_point_loss(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                           const PointLoss& loss, double* loss_sum_m2, double* squares_sum_m2);

/// Median of the residual norms |r_i| [m] without storing them: a log-spaced histogram
/// locates the median's bin, a second pass splits that bin linearly (relative resolution
/// better than 1 %). Errors: dataset_empty, non_finite_input.
Status median_residual_norm(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                            double* median_m);

}  // namespace hivecal
