#include "hivecal/solve/normal_equations.hpp"

#include <algorithm>
#include <cmath>

#include "hivecal/core/math.hpp"
#include "model/kinematics_detail.hpp"
#include "core/lanes.hpp"

namespace hivecal {
namespace {

Vec3 point_residual(const RobotModel& model, const ModelTrig& trig, const RigidTransform& base_to_tracker,
                    const Sample& sample) {
  return base_to_tracker.apply(fk_target_point(model, trig, sample.q_rad, sample.target)) - sample.point_m;
}

/// The basis of each compliance term at a sample's readings [m] or [kg m].
using TermBasis = double[kMaxComplianceTerms];

/// A deflection below this is turned by the series below instead of sincos [rad].
constexpr double kSmallDeflection_rad = 1.0 / 64.0;

/// sin and cos of a small angle |x| <= kSmallDeflection_rad by their Taylor series (the first
/// term left out is below 2e-22 there): the same operations on every target.
void small_sincos(double x, double* sin_x, double* cos_x) {
  const double x2 = x * x;
  *sin_x = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0)));
  *cos_x = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
}

/// For a model with compliance terms: the joint trig of a sample's deflected pose (where the
/// kernel differentiates) from the readings' joint trig `reading` and the deflection dq: the
/// angle sums with sin and cos of dq (a series for a small one; a reading without a term keeps
/// its bits; a prismatic joint's slide moved by dq), and the terms' basis (whose harmonics use
/// `reading` too). No sincos per sample when `reading` is stored; `reading` is joint_trig(q)
/// either way, so the bits are the same.
JointTrig deflected_trig(const RobotModel& model, const JointVector& q_rad, const JointTrig& reading,
                         TermBasis* basis) {
  const JointVector dq = compliance_deflection(model, q_rad, *basis, &reading);
  JointTrig trig = reading;
  for (int j = 0; j < model.joint_count; ++j) {
    if (dq(j) == 0.0) continue;
    if (joint_type(model, j) == JointType::prismatic) {
      trig.slide_m[j] = reading.slide_m[j] + dq(j);  // the bits of joint_trig(q + dq)
      continue;
    }
    double sin_dq = 0.0;
    double cos_dq = 1.0;
    if (std::fabs(dq(j)) <= kSmallDeflection_rad) {
      small_sincos(dq(j), &sin_dq, &cos_dq);
    } else {
      math::sincos(dq(j), &sin_dq, &cos_dq);
    }
    trig.sin_q[j] = reading.sin_q[j] * cos_dq + reading.cos_q[j] * sin_dq;
    trig.cos_q[j] = reading.cos_q[j] * cos_dq - reading.sin_q[j] * sin_dq;
  }
  return trig;
}

/// The columns a model of `model`'s joint count has: its rigid parameters and the build's joint
/// terms (every_column of its sample_rows_context; 73 for six joints and 40 terms).
int model_column_count(const RobotModel& model) {
  return rigid_param_count(model) + kMaxComplianceTerms;
}

/// IndexList's unlisted columns are scratch that the normal-equation update never reads.
using detail::IndexList;

IndexList indices_of(ParamMask mask, int joint_count) {
  IndexList list;
  list.base_rotation = base_rotation_param_index(joint_count, 0);
  list.base_translation = base_translation_param_index(joint_count, 0);
  list.base_end = rigid_param_count(joint_count);
  list.count = mask_indices(mask, list.index);
  int unlisted = list.count;
  for (int k = 0; k < list.count; ++k) list.slot[list.index[k]] = k;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(mask, i)) list.slot[i] = unlisted++;
  }
  return list;
}

/// Samples whose Jacobian rows are summed into the normal matrix together: each entry is
/// then loaded and stored once per batch instead of once per sample (memory traffic, not
/// arithmetic, bounds this update). 2 samples keep the scratch at 1.6 kB of stack.
constexpr int kBatchSamples = 2;
constexpr int kBatchRows = 3 * kBatchSamples;

/// Samples whose Jacobian rows one kernel call writes (one per double lane).
constexpr int kGroupSamples = detail::kJacobianLanes;
#ifdef HIVECAL_WIDE_LANES
using WidestLane = lanes::WiderLane;
constexpr int kWideGroupSamples = detail::kWideJacobianLanes;
/// Samples the row buffer holds: a wide group, flushed in passes of kPassBatches batches.
constexpr int kHeldSamples = kWideGroupSamples;
#else
using WidestLane = lanes::Lane;
constexpr int kHeldSamples = kBatchSamples;
#endif
/// Batches one pass over the normal matrix adds, one after the other: each entry is loaded
/// and stored once for them (more than two outgrow the registers and run slower).
constexpr int kPassBatches = kHeldSamples >= 2 * kBatchSamples ? 2 : 1;
constexpr int kPassSamples = kPassBatches * kBatchSamples;
constexpr int kPassRows = 3 * kPassSamples;
static_assert(kBatchSamples % kGroupSamples == 0 && kHeldSamples % kPassSamples == 0,
              "groups, batches and passes tile the row buffer");

/// Jacobian rows of a few samples over the listed columns, with their weights and residuals.
struct RowBatch {
  double rows[3 * kHeldSamples][kFullParamCount] = {};  ///< local Jacobian rows, compact column order
  double weight[3 * kHeldSamples] = {};                 ///< IRLS weight of each row's sample
  double residual_m[3 * kHeldSamples] = {};             ///< residual component of each row (base frame) [m]
  int samples = 0;                                      ///< samples held
};

/// The Jacobian kernel for kWidth samples at once (detail::tool_point_jacobian_rows and its
/// AVX2 form).
template <std::size_t kWidth>
void kernel_rows(const RobotModel& model, const ModelTrig& trig, const JointTrig* const (&lane_trig)[kWidth],
                 const detail::JacobianRowsTarget (&target)[kWidth], Vec3 (&point_m)[kWidth]) {
#ifdef HIVECAL_WIDE_LANES
  if constexpr (kWidth == static_cast<std::size_t>(kWideGroupSamples)) {
    detail::tool_point_jacobian_rows_wide(model, trig, lane_trig, target, point_m);
    return;
  }
#endif
  if constexpr (kWidth == static_cast<std::size_t>(kGroupSamples))
    detail::tool_point_jacobian_rows(model, trig, lane_trig, target, point_m);
}

/// The compliance columns of one sample's rows for the terms the model has: term t's is
/// d(point)/d(its joint's reading: the theta_offset column of a revolute joint, the d column of a
/// prismatic one), taken at the deflected pose, times the term's basis
/// (the basis's own dependence on the geometry is second order and left out,
/// docs/solver-lm.md); 0 for every term when `basis` is null (a rigid model). The slots of the
/// terms a model does not have are never written: the row buffers start zeroed, which keeps
/// them 0 (a build holds room for 40 terms; writing 40 zeros per sample cost the update a
/// tenth of its time).
void write_compliance_columns(const RobotModel& model, const TermBasis* basis, const IndexList& columns,
                              double (*rows)[kFullParamCount]) {
  const ComplianceModel& compliance = model.compliance;
  for (int t = 0; t < compliance.term_count; ++t) {
    const int joint = compliance.terms[t].joint;
    const int slot = columns.slot[compliance_param_index(model, t)];
    const DhField variable = joint_type(model, joint) == JointType::revolute ? DhField::theta_offset : DhField::d;
    const int variable_slot = columns.slot[model_param_index(joint, variable)];
    for (int r = 0; r < 3; ++r) rows[r][slot] = basis != nullptr ? rows[r][variable_slot] * (*basis)[t] : 0.0;
  }
}

/// Writes the rows of the local Jacobian [J_tool | -skew(p) | I | J_compliance] of `count`
/// samples (1 .. kWidth) at the columns' slots, sample k at rows 3k .. 3k+2, and their
/// residuals rotated into the base frame, R^T r [m]. Lanes beyond `count` repeat the last
/// sample into their rows (which must exist) as scratch. `basis` (models with compliance
/// terms; else null): each sample's TermBasis, and sample_trig is then of the deflected pose.
template <std::size_t kWidth>
void add_rows(const RobotModel& model, const ModelTrig& trig, const RigidTransform& base_to_tracker,
              const Sample* const* sample, const JointTrig* const* sample_trig, const TermBasis* basis, int count,
              const IndexList& columns, double (*rows)[kFullParamCount], Vec3* residual_m) {
  const JointTrig* lane_trig[kWidth];
  detail::JacobianRowsTarget target[kWidth];
  for (int k = 0; k < static_cast<int>(kWidth); ++k) {
    lane_trig[k] = sample_trig[k < count ? k : count - 1];
    double(*lane_rows)[kFullParamCount] = rows + 3 * k;
    target[k] = {{lane_rows[0], lane_rows[1], lane_rows[2]}, columns.slot};
  }
  Vec3 point_m[kWidth];
  kernel_rows<kWidth>(model, trig, lane_trig, target, point_m);
  for (int k = 0; k < static_cast<int>(kWidth); ++k) {
    write_compliance_columns(model, basis != nullptr && k < count ? &basis[k] : nullptr, columns, rows + 3 * k);
  }
  // d(Exp(w) p)/dw_k at w = 0 is e_k x p; the translation increment is along the base axes.
  const int* rotation_slot = columns.slot + columns.base_rotation;
  const int* translation_slot = columns.slot + columns.base_translation;
  for (int k = 0; k < count; ++k) {
    const Vec3& p = point_m[k];
    const double moment[3][3] = {{0.0, -p.z(), p.y()}, {p.z(), 0.0, -p.x()}, {-p.y(), p.x(), 0.0}};  // e_a x p
    for (int r = 0; r < 3; ++r) {
      for (int a = 0; a < 3; ++a) {
        rows[3 * k + r][rotation_slot[a]] = moment[a][r];
        rows[3 * k + r][translation_slot[a]] = r == a ? 1.0 : 0.0;
      }
    }
    residual_m[k] = base_to_tracker.rotation.transpose() * (base_to_tracker.apply(p) - sample[k]->point_m);
  }
}

/// column[k] += sum_j rows[b][j][k] * weight[b][j] for k in [0, count), batch after batch:
/// each batch's sum takes its rows in order, sizeof(Lane)/8 entries at a time, then single
/// ones (the same bits at any lane width), and is added to the column on its own, as if the
/// batches were flushed one after the other. A sum starts from the first product, not from
/// 0 + it: they differ only in the sign of a zero, and the column, which starts at +0, never
/// becomes -0 under addition.
/// The last full lane may run past `count` (up to kFullParamCount): the entries below the
/// diagonal it writes are scratch, overwritten by expand_compact's mirror, and the rows it
/// reads there are initialised (the row buffers start zeroed).
template <class Lane, std::size_t kRows>
__attribute__((always_inline)) inline void add_weighted_rows(const double* const (&rows)[kPassBatches][kRows],
                                                             const double (&weight)[kPassBatches][kRows], int count,
                                                             double* column) {
  constexpr int kWidth = static_cast<int>(sizeof(Lane) / sizeof(double));
  // One bound for the lane loop (the lanes that start below `count` and end inside the
  // column): a second test per lane cost the loop a fifth of its instructions.
  const int lane_end = std::min(count, kFullParamCount - kWidth + 1);
  int k = 0;
  for (; k < lane_end; k += kWidth) {
    Lane total;
    lanes::load_any(column + k, &total);
    for (int b = 0; b < kPassBatches; ++b) {
      Lane sum;
      lanes::load_any(rows[b][0] + k, &sum);
      sum *= weight[b][0];
      for (std::size_t j = 1; j < kRows; ++j) {
        Lane row;
        lanes::load_any(rows[b][j] + k, &row);
        sum += row * weight[b][j];
      }
      total += sum;
    }
    lanes::store_any(column + k, total);
  }
  for (; k < count; ++k) {
    for (int b = 0; b < kPassBatches; ++b) {
      double sum = rows[b][0][k] * weight[b][0];
      for (std::size_t j = 1; j < kRows; ++j) sum += rows[b][j][k] * weight[b][j];
      column[k] += sum;
    }
  }
}

/// A pass's rows weighted at one column, w[b][j] = w_j J_j of batch b's row j, and each
/// batch's gradient entry sum_j w_j J_j r_j (from 0, rows in order).
__attribute__((always_inline)) inline void weigh_column(const double (*rows)[kFullParamCount], const double* weight,
                                                        const double* residual_m, int column,
                                                        double (&w)[kPassBatches][kBatchRows],
                                                        double (&gradient)[kPassBatches]) {
  for (int b = 0; b < kPassBatches; ++b) {
    double sum = 0.0;
    for (int j = 0; j < kBatchRows; ++j) {
      const int row = b * kBatchRows + j;
      w[b][j] = rows[row][column] * weight[row];
      sum += w[b][j] * residual_m[row];
    }
    gradient[b] = sum;
  }
}

/// weigh_column for the lane of columns first .. first + kWidth - 1 at once, into
/// weighted[row][c] and gradient[b][c]: vector lanes where the rows have room for a whole
/// one, else column by column (the same bits).
template <class Lane, std::size_t kWidth>
__attribute__((always_inline)) inline void weigh_columns(const double (*rows)[kFullParamCount], const double* weight,
                                                         const double* residual_m, int first,
                                                         double (&weighted)[kPassRows][kWidth],
                                                         double (&gradient)[kPassBatches][kWidth]) {
  constexpr int kColumns = static_cast<int>(kWidth);
  if (first + kColumns <= kFullParamCount) {
    for (int b = 0; b < kPassBatches; ++b) {
      Lane sum = Lane{};
      for (int j = 0; j < kBatchRows; ++j) {
        const int row = b * kBatchRows + j;
        Lane value;
        lanes::load_any(rows[row] + first, &value);
        value *= weight[row];
        lanes::store_any(weighted[row], value);
        sum += value * residual_m[row];
      }
      lanes::store_any(gradient[b], sum);
    }
    return;
  }
  for (int c = 0; first + c < kFullParamCount; ++c) {
    double w[kPassBatches][kBatchRows];
    double column_gradient[kPassBatches];
    weigh_column(rows, weight, residual_m, first + c, w, column_gradient);
    for (int b = 0; b < kPassBatches; ++b) {
      gradient[b][c] = column_gradient[b];
      for (int j = 0; j < kBatchRows; ++j) weighted[b * kBatchRows + j][c] = w[b][j];
    }
  }
}

/// The update of column l of the compact normal matrix by a pass's rows: w[b][j] is batch b's
/// row j weighted at column l. The base-translation columns (the last ones of the list,
/// identity blocks of J) are 1 on their axis' row and 0 elsewhere: their entries only take
/// that row's products; the base-rotation columns e_k x p are exactly 0 on row k: their
/// entries skip that row. The same sums without exact zeros, so the same bits.
template <class Lane>
__attribute__((always_inline)) inline void add_column(const double* const (&rows)[kPassBatches][kBatchRows],
                                                      const double (&w)[kPassBatches][kBatchRows],
                                                      const IndexList& columns, int l, double* column) {
  const int parameter = columns.index[l];
  if (parameter >= columns.base_translation && parameter < columns.base_end) {  // e_axis: one row per sample
    const int axis = parameter - columns.base_translation;
    const double* axis_rows[kPassBatches][kBatchSamples];
    double axis_weights[kPassBatches][kBatchSamples];
    for (int b = 0; b < kPassBatches; ++b) {
      for (int s = 0; s < kBatchSamples; ++s) {
        axis_rows[b][s] = rows[b][3 * s + axis];
        axis_weights[b][s] = w[b][3 * s + axis];
      }
    }
    add_weighted_rows<Lane>(axis_rows, axis_weights, l + 1, column);
  } else if (parameter >= columns.base_rotation &&
             parameter < columns.base_translation) {  // e_axis x p: 0 on the axis' row
    const int axis = parameter - columns.base_rotation;
    const double* other_rows[kPassBatches][2 * kBatchSamples];
    double other_weights[kPassBatches][2 * kBatchSamples];
    for (int b = 0; b < kPassBatches; ++b) {
      int n = 0;
      for (int s = 0; s < kBatchSamples; ++s) {
        for (int r = 0; r < 3; ++r) {
          if (r == axis) continue;
          other_rows[b][n] = rows[b][3 * s + r];
          other_weights[b][n++] = w[b][3 * s + r];
        }
      }
    }
    add_weighted_rows<Lane>(other_rows, other_weights, l + 1, column);
  } else {
    add_weighted_rows<Lane>(rows, w, l + 1, column);
  }
}

/// eq += sum over a pass's samples (from first_sample) of w J^T J and w J^T r, batch after
/// batch of kBatchSamples as if each were flushed on its own, in compact coordinates (entry
/// (k, l) for columns index[k], index[l]; upper triangle), one contiguous column at a time.
/// Rows beyond the samples held are zero, which adds exact zeros.
template <class Lane>
__attribute__((always_inline)) inline void flush_pass(RowBatch* batch, int first_sample, const IndexList& columns,
                                                      NormalEquations* eq) {
  constexpr std::size_t kWidth = sizeof(Lane) / sizeof(double);
  constexpr int kColumns = static_cast<int>(kWidth);
  const int count = columns.count;
  const int held = std::min(kPassSamples, batch->samples - first_sample);
  double(*rows)[kFullParamCount] = batch->rows + 3 * first_sample;
  double* weight = batch->weight + 3 * first_sample;
  double* residual_m = batch->residual_m + 3 * first_sample;
  for (int j = 3 * held; j < kPassRows; ++j) {
    for (int k = 0; k < count; ++k) rows[j][k] = 0.0;
    weight[j] = 0.0;
    residual_m[j] = 0.0;
  }
  const double* pass_rows[kPassBatches][kBatchRows];
  for (int b = 0; b < kPassBatches; ++b)
    for (int j = 0; j < kBatchRows; ++j) pass_rows[b][j] = rows[b * kBatchRows + j];
  double* compact = eq->jtwj.data();
  for (int first = 0; first < count; first += kColumns) {
    // With vector lanes a lane of columns is weighed at once; scalar lanes weigh each column
    // where it is used (a table of one column costs the firmware's loop its loads and stores).
    double weighted[kPassRows][kWidth];
    double gradients[kPassBatches][kWidth];
    if constexpr (kColumns > 1) weigh_columns<Lane, kWidth>(rows, weight, residual_m, first, weighted, gradients);
    const int end = std::min(count, first + kColumns);
    for (int l = first; l < end; ++l) {
      double w[kPassBatches][kBatchRows];
      double gradient[kPassBatches];
      if constexpr (kColumns > 1) {
        for (int b = 0; b < kPassBatches; ++b) {
          gradient[b] = gradients[b][l - first];
          for (int j = 0; j < kBatchRows; ++j) w[b][j] = weighted[b * kBatchRows + j][l - first];
        }
      } else {
        weigh_column(rows, weight, residual_m, l, w, gradient);
      }
      for (int b = 0; b < kPassBatches; ++b) eq->jtwr(l) += gradient[b];
      add_column<Lane>(pass_rows, w, columns, l, compact + l * kFullParamCount);
    }
  }
}

/// Flushes every sample held, kPassSamples at a time in order (the sums are those of
/// flushing each batch of kBatchSamples as it fills), and empties the buffer.
template <class Lane>
__attribute__((always_inline)) inline void flush_columns(RowBatch* batch, const IndexList& columns,
                                                         NormalEquations* eq) {
  for (int first = 0; first < batch->samples; first += kPassSamples) flush_pass<Lane>(batch, first, columns, eq);
  batch->samples = 0;
}

void flush(RowBatch* batch, const IndexList& columns, NormalEquations* eq) {
  flush_columns<lanes::Lane>(batch, columns, eq);
}

#ifdef HIVECAL_WIDE_LANES
/// flush on 4-double lanes, for CPUs with AVX2 (lanes::wide_lanes_available).
__attribute__((target("avx2"))) void flush_wide(RowBatch* batch, const IndexList& columns, NormalEquations* eq) {
  flush_columns<lanes::WideLane>(batch, columns, eq);
}
/// flush on 8-double lanes, for CPUs with AVX-512F (lanes::wider_lanes_available).
__attribute__((target("avx512f"))) void flush_wider(RowBatch* batch, const IndexList& columns, NormalEquations* eq) {
  flush_columns<lanes::WiderLane>(batch, columns, eq);
}
#endif

/// The flush this CPU runs fastest; all give the same bits.
using FlushFunction = void (*)(RowBatch*, const IndexList&, NormalEquations*);
FlushFunction fastest_flush() {
#ifdef HIVECAL_WIDE_LANES
  if (lanes::wider_lanes_available()) return flush_wider;
  if (lanes::wide_lanes_available()) return flush_wide;
#endif
  return flush;
}

/// Rows below the diagonal that add_weighted_rows's last lane of a column may write: a lane of
/// the widest kind, less the one entry on or above the diagonal.
constexpr int kLaneScratchRows = static_cast<int>(sizeof(WidestLane) / sizeof(double)) - 1;

/// Moves the compact sums to their parameter positions and mirrors the upper triangle.
/// In place: a compact entry (k, l) goes to (index[k], index[l]) with index[k] >= k, so
/// walking down from the last one never overwrites an entry still to be moved. The mirror
/// covers the listed parameters' columns (b below `extent`, one past the last listed index)
/// down to the lanes' scratch (rows below count + kLaneScratchRows <= extent +
/// kLaneScratchRows): every other entry below the diagonal is the zero it was set to, and its
/// mirror image is 0 too, so the full mirror would write the same zeros over 73 x 73.
void expand_compact(const IndexList& columns, NormalEquations* eq) {
  NormalMatrix& h = eq->jtwj;
  for (int l = columns.count - 1; l >= 0; --l) {
    const int b = columns.index[l];
    eq->jtwr(b) = eq->jtwr(l);
    if (b != l) eq->jtwr(l) = 0.0;
    for (int k = l; k >= 0; --k) {
      const int a = columns.index[k];
      const double value = h(k, l);
      h(k, l) = 0.0;
      h(a, b) = value;
    }
  }
  const int extent = columns.count > 0 ? columns.index[columns.count - 1] + 1 : 0;
  const int rows = std::min(kFullParamCount, extent + kLaneScratchRows);
  for (int b = 0; b < extent; ++b)
    for (int a = b + 1; a < rows; ++a) h(a, b) = h(b, a);
}

// Log-spaced bins of the median histogram: 4 per decade from 1e-12 m to 100 m, plus an
// underflow bin (index 0, norms below 1e-12 m, zero included) and an overflow bin.
constexpr int kHistogramBins = 56;
constexpr int kRefineBins = 64;
constexpr double kHistogramFloor_m = 1e-12;
constexpr double kLn10 = 2.302585092994045684;
constexpr double kBinsPerLnUnit = 4.0 / kLn10;

int histogram_bin(double norm_m) {
  if (!(norm_m >= kHistogramFloor_m)) return 0;
  const double position = math::log(norm_m / kHistogramFloor_m) * kBinsPerLnUnit;
  if (position >= static_cast<double>(kHistogramBins)) return kHistogramBins + 1;
  return 1 + static_cast<int>(position);
}

double histogram_bin_lower_m(int bin) {
  return kHistogramFloor_m * math::exp(static_cast<double>(bin - 1) / kBinsPerLnUnit);
}

}  // namespace

SampleRowsContext sample_rows_context(const RobotModel& model) {
  SampleRowsContext context;
  context.trig = model_trig(model);
  context.every_column = indices_of(valid_params_mask(model), model.joint_count);
  return context;
}

namespace {

/// local_residual_jacobian with target `target`'s tool point (the deflection is the model's,
/// whatever the target: its tool load is target 1's tool point); the model's trig and the
/// pose's joint trig from `context`, the latter computed when the readings change.
Vec3 local_target_residual_jacobian(const RobotModel& model, SampleRowsContext& context, int target,
                                    const RigidTransform& base_to_tracker, const Sample& sample,
                                    FullJacobian* local_jacobian) {
  double rows[3 * kGroupSamples][kFullParamCount] = {};  // see write_compliance_columns
  const Sample* const samples[1] = {&sample};
  const bool compliant = model.compliance.term_count > 0;
  if (context.pose == nullptr || context.pose->q_rad != sample.q_rad) {
    context.pose_trig = joint_trig(model, sample.q_rad);
    if (compliant) context.pose_trig = deflected_trig(model, sample.q_rad, context.pose_trig, &context.pose_basis);
    context.pose = &sample;
  }
  const JointTrig* const trig_of[1] = {&context.pose_trig};
  RobotModel moved = model;  // the target's tool point: the tool does not enter the trig
  moved.tool_m = target_tool(model, target);
  Vec3 local_residual_m;
  add_rows<static_cast<std::size_t>(kGroupSamples)>(moved, context.trig, base_to_tracker, samples, trig_of,
                                                    compliant ? &context.pose_basis : nullptr, 1, context.every_column,
                                                    rows, &local_residual_m);
  // The model's columns (every_column lists them in place); those a build holds beyond them are 0.
  const int model_columns = model_column_count(model);
  for (int c = 0; c < model_columns; ++c)
    for (int r = 0; r < 3; ++r) (*local_jacobian)(r, c) = rows[r][c];
  local_jacobian->rightCols(kFullParamCount - model_columns).setZero();
  return local_residual_m;
}

}  // namespace

Vec3 local_residual_jacobian(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample,
                             FullJacobian* local_jacobian) {
  SampleRowsContext context = sample_rows_context(model);
  return local_target_residual_jacobian(model, context, 0, base_to_tracker, sample, local_jacobian);
}

Vec3 full_residual_jacobian(const RobotModel& model, const RigidTransform& base_to_tracker, const Sample& sample,
                            FullJacobian* jacobian) {
  FullJacobian local;
  const Vec3 local_residual_m = local_residual_jacobian(model, base_to_tracker, sample, &local);
  *jacobian = base_to_tracker.rotation * local;
  return base_to_tracker.rotation * local_residual_m;
}

void scale_normal_matrix(const NormalMatrix& jtwj, ParamMask mask, double outside_diagonal, NormalMatrix* scaled,
                         FullParams* scale) {
  scaled->setZero();
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(mask, i)) (*scaled)(i, i) = outside_diagonal;
  }
  scale_kept_block(jtwj, mask, scaled, scale);
}

void scale_kept_block(const NormalMatrix& jtwj, ParamMask mask, NormalMatrix* scaled, FullParams* scale) {
  for (int i = 0; i < kFullParamCount; ++i) (*scale)(i) = mask_has(mask, i) ? 1.0 / std::sqrt(jtwj(i, i)) : 1.0;
  int index[kFullParamCount];
  const int count = mask_indices(mask, index);
  for (int jb = 0; jb < count; ++jb) {
    const int b = index[jb];
    for (int ja = 0; ja < count; ++ja) {
      const int a = index[ja];
      (*scaled)(a, b) = jtwj(a, b) * (*scale)(a) * (*scale)(b);
    }
  }
}

double PointLoss::rho(double norm_m) const {
  const double k = huber_threshold_m;
  if (k <= 0.0 || norm_m <= k) return norm_m * norm_m;
  return 2.0 * k * norm_m - k * k;
}

double PointLoss::weight(double norm_m) const {
  const double k = huber_threshold_m;
  if (k <= 0.0 || norm_m <= k) return 1.0;
  return k / norm_m;
}

namespace {

/// Appends samples [first, first + kWidth) (fewer at the end) to the row buffer, which has
/// room for them, with their weights, and adds their losses to *eq in sample order.
template <std::size_t kWidth>
void add_group(const RobotModel& model, const ModelTrig& trig, const RigidTransform& base_to_tracker,
               Span<const Sample> samples, Span<const JointTrig> stored_trig, std::size_t first, const PointLoss& loss,
               const IndexList& list, RowBatch* batch, NormalEquations* eq) {
  const int count = static_cast<int>(std::min<std::size_t>(kWidth, samples.size() - first));
  const Sample* group[kWidth] = {};  // set up to count; initialised for arm-none-eabi-gcc's maybe-uninitialized
  JointTrig computed[kWidth];
  const JointTrig* group_trig[kWidth] = {};
  const bool compliant = model.compliance.term_count > 0;
  TermBasis basis[kWidth];
  for (int k = 0; k < count; ++k) {
    const std::size_t i = first + static_cast<std::size_t>(k);
    group[k] = &samples[i];
    if (compliant) {  // the stored trig is of the readings: turned by the deflection
      computed[k] =
          deflected_trig(model, samples[i].q_rad,
                         stored_trig.empty() ? joint_trig(model, samples[i].q_rad) : stored_trig[i], &basis[k]);
    } else if (stored_trig.empty()) {
      computed[k] = joint_trig(model, samples[i].q_rad);
    }
    group_trig[k] = compliant || stored_trig.empty() ? &computed[k] : &stored_trig[i];
  }
  Vec3 residual_m[kWidth];
  add_rows<kWidth>(model, trig, base_to_tracker, group, group_trig, compliant ? basis : nullptr, count, list,
                   batch->rows + 3 * batch->samples, residual_m);
  for (int k = 0; k < count; ++k) {
    const double squared = residual_m[k].squaredNorm();
    const double norm_m = std::sqrt(squared);
    const double weight = loss.weight(norm_m);
    const int first_row = 3 * batch->samples;
    for (int r = 0; r < 3; ++r) {
      batch->weight[first_row + r] = weight;
      batch->residual_m[first_row + r] = residual_m[k](r);
    }
    ++batch->samples;
    eq->loss_sum_m2 += loss.rho(norm_m);
    eq->weighted_squares_m2 += weight * squared;
    eq->squares_sum_m2 += squared;
  }
}

/// Whitens one sample's residual, Jacobian and tool Jacobian in place by L^-1, L L^T = I +
/// k^2 J_q J_q^T, with J_q the Jacobian's theta columns of the revolute joints (d point / d q)
/// and k = sigma_q / sigma_p: the covariance of a point from joints read with sigma_q, in units
/// of the point noise (a prismatic joint's reading, a length, is taken as exact). 3x3 Cholesky
/// by hand (the same operations on every target). Nothing to do when k is 0.
void whiten_sample(const RobotModel& model, double k, Vec3* residual_m, FullJacobian* jacobian, Mat3* tool_jacobian) {
  if (!(k > 0.0)) return;
  Mat3 c = Mat3::Identity();
  for (int j = 0; j < model.joint_count; ++j) {
    if (joint_type(model, j) != JointType::revolute) continue;
    const Vec3 column = k * jacobian->col(model_param_index(j, DhField::theta_offset));
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) c(a, b) += column(a) * column(b);
  }
  // c = L L^T, L lower triangular (c is I + a Gram matrix: positive definite, l_ii >= 1).
  const double l00 = std::sqrt(c(0, 0));
  const double l10 = c(1, 0) / l00;
  const double l20 = c(2, 0) / l00;
  const double l11 = std::sqrt(c(1, 1) - l10 * l10);
  const double l21 = (c(2, 1) - l20 * l10) / l11;
  const double l22 = std::sqrt(c(2, 2) - l20 * l20 - l21 * l21);
  const auto solve = [&](auto& m) {  // rows of m := L^-1 m (forward substitution)
    m.row(0) /= l00;
    m.row(1) = (m.row(1) - l10 * m.row(0)) / l11;
    m.row(2) = (m.row(2) - l20 * m.row(0) - l21 * m.row(1)) / l22;
  };
  solve(*residual_m);
  solve(*jacobian);
  solve(*tool_jacobian);
}

}  // namespace

namespace {

/// sample_rows with the model's per-sample context given.
Vec3 sample_rows_in(const RobotModel& model, SampleRowsContext& context, const RigidTransform& base_to_tracker,
                    const Sample& sample, const PointLoss& loss, ParamMask columns, FullJacobian* jacobian,
                    Mat3* tool_jacobian, double* raw_squared_m2) {
  Vec3 residual_m = local_target_residual_jacobian(model, context, sample.target, base_to_tracker, sample, jacobian);
  *tool_jacobian = jacobian->block<3, 3>(0, tool_param_index(model, 0));
  *raw_squared_m2 = residual_m.squaredNorm();
  whiten_sample(model, loss.joint_noise_ratio_rad_per_m, &residual_m, jacobian, tool_jacobian);
  if (sample.target != 0) jacobian->block<3, 3>(0, tool_param_index(model, 0)).setZero();  // not target 1's tool
  for (int c = 0; c < kFullParamCount; ++c) {
    if (!mask_has(columns, c)) jacobian->col(c).setZero();
  }
  return residual_m;
}

}  // namespace

Vec3 sample_rows(const RobotModel& model, SampleRowsContext& context, const RigidTransform& base_to_tracker,
                 const Sample& sample, const PointLoss& loss, ParamMask columns, FullJacobian* jacobian,
                 Mat3* tool_jacobian, double* raw_squared_m2) {
  return sample_rows_in(model, context, base_to_tracker, sample, loss, columns, jacobian, tool_jacobian,
                        raw_squared_m2);
}

namespace {

/// accumulate_normal_equations for samples of several targets (or whitened ones): sample by
/// sample with each sample's tool point, the other targets' tool blocks summed and then
/// eliminated.
[[gnu::noinline]] Status accumulate_several_targets(const RobotModel& model, const RigidTransform& base_to_tracker,
                                                    Span<const Sample> samples, const PointLoss& loss,
                                                    NormalEquations* eq, ParamMask columns) {
  const bool eliminate = (columns & kOtherTargetTools) != 0;
  if (eliminate && static_cast<std::size_t>(target_count(samples) - 1) > eq->targets.size()) {
    return Status::dimension_out_of_range;  // no storage for these targets' blocks
  }
  for (TargetBlock& block : eq->targets) block = TargetBlock{};
  // Only the estimated columns (the others are zero) and only the upper triangle (the lower one
  // is mirrored below): a quarter of the full 37 x 37 products, the same bits.
  const IndexList list = indices_of(columns, model.joint_count);
  SampleRowsContext context = sample_rows_context(model);
  double rows[3][kFullParamCount];  // the sample's Jacobian rows over the listed columns
  for (const Sample& sample : samples) {
    FullJacobian jacobian;
    Mat3 tool_jacobian;
    double raw_squared_m2 = 0.0;
    const Vec3 residual_m = sample_rows_in(model, context, base_to_tracker, sample, loss, columns, &jacobian,
                                           &tool_jacobian, &raw_squared_m2);
    const double squared = residual_m.squaredNorm();
    const double norm_m = std::sqrt(squared);
    const double weight = loss.weight(norm_m);
    // Over the listed columns only, into the compact leading block of jtwj and jtwr
    // (expand_compact places them): each entry adds w (j0a j0b + (j1a j1b + j2a j2b)), the sum
    // of a 3-term dot product in Eigen's order, so a column of entries is independent work on
    // contiguous memory (the compiler does two at once) with the bits of one at a time.
    for (int i = 0; i < list.count; ++i) {
      for (int r = 0; r < 3; ++r) rows[r][i] = jacobian(r, list.index[i]);
    }
    for (int j = 0; j < list.count; ++j) {
      double* const column = &eq->jtwj(0, j);
      const double b0 = rows[0][j];
      const double b1 = rows[1][j];
      const double b2 = rows[2][j];
      for (int i = 0; i <= j; ++i) column[i] += weight * (rows[0][i] * b0 + (rows[1][i] * b1 + rows[2][i] * b2));
      eq->jtwr(j) += weight * (b0 * residual_m(0) + (b1 * residual_m(1) + b2 * residual_m(2)));
    }
    eq->loss_sum_m2 += loss.rho(norm_m);
    eq->weighted_squares_m2 += weight * squared;
    eq->squares_sum_m2 += raw_squared_m2;
    if (sample.target == 0 || !eliminate) continue;
    TargetBlock& block = eq->targets[static_cast<std::size_t>(sample.target - 1)];
    block.tool_tool += weight * (tool_jacobian.transpose() * tool_jacobian);
    for (int i = 0; i < list.count; ++i) {  // the other columns of J are 0, and so stay theirs
      const int a = list.index[i];
      block.tool_model.col(a) += weight * (tool_jacobian.transpose() * jacobian.col(a));
    }
    block.tool_residual_m += weight * (tool_jacobian.transpose() * residual_m);
    ++block.count;
  }
  expand_compact(list, eq);
  for (const TargetBlock& block : eq->targets) {
    if (block.count == 0) continue;
    const Mat3 inverse = block.tool_tool.inverse();
    const Eigen::Matrix<double, 3, kFullParamCount> solved = inverse * block.tool_model;
    for (int a = 0; a < kFullParamCount; ++a) {  // no p x p temporary (see above)
      for (int b = 0; b < kFullParamCount; ++b) eq->jtwj(a, b) -= block.tool_model.col(a).dot(solved.col(b));
      eq->jtwr(a) -= solved.col(a).dot(block.tool_residual_m);
    }
  }
  for (int b = 0; b < kFullParamCount; ++b)  // exactly symmetric, as the fast path leaves it
    for (int a = b + 1; a < kFullParamCount; ++a) eq->jtwj(a, b) = eq->jtwj(b, a);
  if (!math::is_finite(eq->loss_sum_m2) || !all_finite(eq->jtwr) || !all_finite(eq->jtwj.diagonal())) {
    return Status::non_finite_input;
  }
  return Status::ok;
}

}  // namespace

void apply_target_step(const NormalEquations& eq, const FullParams& step, RobotModel* model) {
  for (std::size_t k = 1; k <= eq.targets.size(); ++k) {
    const TargetBlock& block = eq.targets[k - 1];
    if (block.count == 0) continue;
    target_tool(model, static_cast<int>(k)) -=
        block.tool_tool.inverse() * (block.tool_residual_m + block.tool_model * step);
  }
}

Status accumulate_normal_equations(const RobotModel& model, const RigidTransform& base_to_tracker,
                                   Span<const Sample> samples, const PointLoss& loss, NormalEquations* out,
                                   ParamMask columns, Span<const JointTrig> sample_trig) {
  if (samples.empty()) return Status::dataset_empty;
  NormalEquations& eq = *out;
  eq.jtwj.setZero();
  eq.jtwr.setZero();
  eq.loss_sum_m2 = 0.0;
  eq.weighted_squares_m2 = 0.0;
  eq.squares_sum_m2 = 0.0;
  eq.count = samples.size();
  for (TargetBlock& block : eq.targets) block.count = 0;  // the sums are reset where they are used
  if (target_count(samples) > 1 || loss.joint_noise_ratio_rad_per_m > 0.0) {
    return accumulate_several_targets(model, base_to_tracker, samples, loss, &eq, columns);
  }
  const IndexList list = indices_of(columns, model.joint_count);
  const ModelTrig trig = model_trig(model);
  const FlushFunction flush_batch = fastest_flush();
  RowBatch batch;
  const Span<const JointTrig> stored = sample_trig.size() >= samples.size() ? sample_trig : Span<const JointTrig>{};
  std::size_t first = 0;
#ifdef HIVECAL_WIDE_LANES
  if (lanes::wide_lanes_available()) {
    for (; first < samples.size(); first += kWideGroupSamples) {
      add_group<static_cast<std::size_t>(kWideGroupSamples)>(model, trig, base_to_tracker, samples, stored, first, loss,
                                                             list, &batch, &eq);
      if (batch.samples == kHeldSamples) flush_batch(&batch, list, &eq);
    }
  }
#endif
  for (; first < samples.size(); first += kGroupSamples) {
    add_group<static_cast<std::size_t>(kGroupSamples)>(model, trig, base_to_tracker, samples, stored, first, loss, list,
                                                       &batch, &eq);
    if (batch.samples == kHeldSamples) flush_batch(&batch, list, &eq);
  }
  if (batch.samples > 0) flush_batch(&batch, list, &eq);
  expand_compact(list, &eq);
  // A NaN or Inf anywhere in J or r reaches the diagonal, the gradient or the loss.
  if (!math::is_finite(eq.loss_sum_m2) || !all_finite(eq.jtwr) || !all_finite(eq.jtwj.diagonal())) {
    return Status::non_finite_input;
  }
  return Status::ok;
}

Status accumulate_normal_equations(const RobotModel& model, const RigidTransform& base_to_tracker,
                                   Span<const Sample> samples, const PointLoss& loss, NormalEquations* out) {
  return accumulate_normal_equations(model, base_to_tracker, samples, loss, out,
                                     rigid_params_mask(model) | kOtherTargetTools);
}

Status evaluate_point_loss(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                           const PointLoss& loss, double* loss_sum_m2, double* squares_sum_m2) {
  if (samples.empty()) return Status::dataset_empty;
  const ModelTrig trig = model_trig(model);
  double loss_sum = 0.0;
  double squares = 0.0;
  for (const Sample& sample : samples) {
    const double squared = point_residual(model, trig, base_to_tracker, sample).squaredNorm();
    loss_sum += loss.rho(std::sqrt(squared));
    squares += squared;
  }
  if (!math::is_finite(loss_sum) || !math::is_finite(squares)) return Status::non_finite_input;
  *loss_sum_m2 = loss_sum;
  *squares_sum_m2 = squares;
  return Status::ok;
}

Status median_residual_norm(const RobotModel& model, const RigidTransform& base_to_tracker, Span<const Sample> samples,
                            double* median_m) {
  if (samples.empty()) return Status::dataset_empty;
  const ModelTrig trig = model_trig(model);
  std::size_t counts[kHistogramBins + 2] = {};
  for (const Sample& sample : samples) {
    const double norm_m = point_residual(model, trig, base_to_tracker, sample).norm();
    if (!math::is_finite(norm_m)) return Status::non_finite_input;
    ++counts[histogram_bin(norm_m)];
  }
  const std::size_t rank = (samples.size() - 1) / 2;  // lower median, 0-based
  std::size_t below = 0;
  int bin = 0;
  while (below + counts[bin] <= rank) below += counts[bin++];
  if (bin == 0) {  // at or below the floor: report the floor
    *median_m = kHistogramFloor_m;
    return Status::ok;
  }
  const double lower_m = histogram_bin_lower_m(bin);
  // The overflow bin has no upper edge: split [100 m, 10 * 100 m) and clamp into it.
  const double upper_m = bin <= kHistogramBins ? histogram_bin_lower_m(bin + 1) : 10.0 * lower_m;
  std::size_t refined[kRefineBins] = {};
  for (const Sample& sample : samples) {
    const double norm_m = point_residual(model, trig, base_to_tracker, sample).norm();
    if (histogram_bin(norm_m) != bin) continue;
    const double position = (norm_m - lower_m) / (upper_m - lower_m) * kRefineBins;
    int sub = position <= 0.0 ? 0 : static_cast<int>(position);
    if (sub >= kRefineBins) sub = kRefineBins - 1;
    ++refined[sub];
  }
  int sub = 0;
  while (sub < kRefineBins - 1 && below + refined[sub] <= rank) below += refined[sub++];
  *median_m = lower_m + (static_cast<double>(sub) + 0.5) / kRefineBins * (upper_m - lower_m);
  return Status::ok;
}

}  // namespace hivecal
