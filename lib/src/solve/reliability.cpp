#include "hivecal/solve/reliability.hpp"

#include <cmath>

#include "hivecal/core/distributions.hpp"
#include "hivecal/core/math.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal {
namespace {

using UnitMatrix = Eigen::Matrix<double, kMaxUnitRows, kMaxUnitRows>;

/// The settings are usable.
bool options_valid(const BlunderTestOptions& o) {
  return o.alpha > 0.0 && o.alpha < 1.0 && o.tracker_sigma_m > 0.0 && math::is_finite(o.tracker_sigma_m) &&
         o.min_redundancy >= 0.0 && o.min_redundancy < 1.0;
}

/// In-place Cholesky of the leading n x n block of *a (lower triangle); false unless positive definite.
bool small_cholesky(UnitMatrix* a, int n) {
  UnitMatrix& m = *a;
  for (int j = 0; j < n; ++j) {
    double pivot = m(j, j);
    for (int k = 0; k < j; ++k) pivot -= m(j, k) * m(j, k);
    if (!(pivot > 0.0) || !math::is_finite(pivot)) return false;
    m(j, j) = std::sqrt(pivot);
    for (int i = j + 1; i < n; ++i) {
      double sum = m(i, j);
      for (int k = 0; k < j; ++k) sum -= m(i, k) * m(j, k);
      m(i, j) = sum / m(j, j);
    }
  }
  return true;
}

/// e^T (L L^T)^-1 e = |L^-1 e|^2 for the factor L in the lower triangle of l.
double factored_quadratic(const UnitMatrix& l, const double* e, int n) {
  double y[kMaxUnitRows] = {};
  double sum = 0.0;
  for (int i = 0; i < n; ++i) {
    double v = e[i];
    for (int k = 0; k < i; ++k) v -= l(i, k) * y[k];
    y[i] = v / l(i, i);
    sum += y[i] * y[i];
  }
  return sum;
}

/// a . b over n entries summed in index order (a dot product of the full parameter vectors
/// visits the same non-zero products in the same order).
double ordered_dot(const double* a, const double* b, int n) {
  double sum = 0.0;
  for (int k = 0; k < n; ++k) sum += a[k] * b[k];
  return sum;
}

/// The fit the units are tested against.
struct Fit {
  const RobotModel& model;
  const RigidTransform& base;
  const PointLoss& loss;
  ParamMask kept;    ///< estimated parameters (without kOtherTargetTools)
  bool other_tools;  ///< the other targets' tool points were estimated (eliminated blocks)
  FullParams scale;  ///< column scale of the factored normal matrix
  bool grouped;      ///< several targets: units are runs at equal joints
};

/// One unit's rows and hat block (in the workspace).
struct UnitRows {
  int count = 0;           ///< rows [-]
  double largest_m = 0.0;  ///< largest raw 3-D residual of its samples [m]
};

/// The hat-matrix block H_uu of samples[begin, end) into ws->hat: with b_i row i of the
/// scaled Jacobian (other targets' tool points eliminated, b = a - t D^-1 S),
/// H_uu(i, j) = b_i . H^-1 b_j, plus t_i D^-1 t_j^T for two rows of one eliminated target.
/// The scratch lives in the workspace: this runs beside the job's deepest stack.
[[gnu::noinline]] void unit_rows(const Fit& fit, Span<const Sample> samples, std::size_t begin, std::size_t end,
                                 ReliabilityWorkspace* ws, UnitRows* u) {
  const KeptCholesky& f = ws->factor;
  ws->tool_rows.setZero();
  ws->tool_solved.setZero();
  int row_target[kMaxUnitRows] = {};
  u->count = 0;
  u->largest_m = 0.0;
  for (std::size_t s = begin; s < end; ++s) {
    const Sample& sample = samples[s];
    Mat3 tool_jacobian;
    double raw_squared_m2 = 0.0;
    const Vec3 residual_m = sample_rows(fit.model, ws->rows_context, fit.base, sample, fit.loss, fit.kept,
                                        &ws->jacobian, &tool_jacobian, &raw_squared_m2);
    u->largest_m = std::fmax(u->largest_m, std::sqrt(raw_squared_m2));
    const TargetBlock* block = nullptr;
    if (sample.target > 0 && fit.other_tools) {
      const TargetBlock& candidate = ws->normal.targets[static_cast<std::size_t>(sample.target - 1)];
      if (candidate.count > 0) block = &candidate;
    }
    for (int axis = 0; axis < 3; ++axis) {
      const int r = u->count++;
      FullParams& b = ws->row;
      b = ws->jacobian.row(axis).transpose();
      if (block != nullptr) {
        const Vec3 t = tool_jacobian.row(axis).transpose();
        const Vec3 d_inverse_t = block->tool_tool.inverse() * t;
        b -= block->tool_model.transpose() * d_inverse_t;
        ws->tool_rows.row(r) = t.transpose();
        ws->tool_solved.row(r) = d_inverse_t.transpose();
        row_target[r] = sample.target;
      }
      ws->residual_m[r] = residual_m(axis);
      // Over the estimated parameters only (the factor's, in its order): the others' entries
      // were zeros, whose products left every sum below as it is.
      double* const row = ws->rows.col(r).data();
      double* const solved = ws->solved.col(r).data();
      for (int k = 0; k < f.count; ++k) {
        const int i = f.index[k];
        row[k] = b(i) * fit.scale(i);
        solved[k] = row[k];
      }
    }
  }
  cholesky_solve_compact(f, ws->solved.data(), static_cast<int>(ws->solved.outerStride()), u->count);
  for (int i = 0; i < u->count; ++i) {
    for (int j = 0; j < u->count; ++j) {
      double value = ordered_dot(ws->rows.col(i).data(), ws->solved.col(j).data(), f.count);
      if (row_target[i] != 0 && row_target[i] == row_target[j]) {
        value += ws->tool_rows.row(i).dot(ws->tool_solved.row(j));
      }
      ws->hat(i, j) = value;
    }
  }
}

/// The test's scale: from the data (the fit's SSR over its dof) or the tracker's stated sigma.
struct Scale {
  SigmaSource source = SigmaSource::data;
  /// The statistic of a unit of n rows is taken as spread[n] times a chi-square (or F) of
  /// n / spread[n] degrees of freedom (Satterthwaite): spread[n] = |C_n|_F^2 / n, C_n the
  /// leading n x n block of the readings' pooled correlation; exactly 1 for independent rows,
  /// which leaves every operation below exact (the bits of the plain chi-square or F) [-].
  double spread[kMaxUnitRows + 1] = {};
  double ssr_m2 = 0.0;      ///< the fit's weighted sum of squares [m^2]
  double dof = 0.0;         ///< its redundancy [-]
  double sigma_m = 0.0;     ///< sigma per axis [m]
  double unit_alpha = 0.0;  ///< each unit's significance [-]
  /// Critical values by [fitted][rows], 0 until first needed: a quantile is a bisection of an
  /// incomplete beta, too dear to repeat for each of 10^4 poses.
  mutable double critical[2][kMaxUnitRows + 1] = {};
};

/// Critical value of e^T Q^-1 e / sigma^2 for a unit of `rows` rows (sigma from the data: the
/// fitted unit's own residual left out of it, F(rows, dof - rows); a predicted one's against
/// the whole fit, F(rows, dof); the tracker's sigma: chi-square). With correlated readings the
/// statistic is spread times one of rows / spread degrees of freedom: its eigenvalues are
/// those of the correlation block (Q^-1 L C L^T = L^-T C L^T), whose trace is `rows` and
/// squares sum to rows * spread.
double critical_statistic(const Scale& scale, int rows, bool fitted) {
  double& cached = scale.critical[fitted ? 1 : 0][rows];
  if (cached > 0.0) return cached;
  const double m = static_cast<double>(rows);
  const double spread = scale.spread[rows];
  const double h = m / spread;
  cached = spread * (scale.source == SigmaSource::tracker
                         ? math::chi_square_upper_quantile(scale.unit_alpha, h)
                         : h * math::f_upper_quantile(scale.unit_alpha, h, fitted ? scale.dof - m : scale.dof));
  return cached;
}

/// The correlation of the residual rows of a pose's readings (row k: reading k / 3 of the
/// pose, axis k % 3) pooled over the fitted poses of several readings into ws->correlation;
/// false when a pair of rows has fewer than kMinPooledPoses poses. Only one axis between
/// readings: the axes stay independent, as in the test of a pose of one reading (and the
/// correlation a proper one, positive semi-definite). Why: on a real arm the
/// model error moves every reflector of a pose, and the points a measured orientation adds,
/// alike; tested as independent rows, a pose whose error is merely large among its
/// neighbours' looks like a blunder of every reading at once.
[[gnu::noinline]] bool pool_correlation(const Fit& fit, Span<const Sample> samples, ReliabilityWorkspace* ws) {
  UnitMatrix& sum = ws->correlation;
  UnitMatrix& pairs = ws->hat;  // the poses each entry sums over (the units' hat blocks come after)
  sum.setZero();
  pairs.setZero();
  for (std::size_t begin = 0; begin < samples.size();) {
    const std::size_t end = unit_end(samples, begin, fit.grouped);
    const int rows = 3 * static_cast<int>(end - begin);
    if (rows == 3) {  // a pose of one reading: nothing between readings
      begin = end;
      continue;
    }
    for (std::size_t s = begin; s < end; ++s) {
      Mat3 tool_jacobian;
      double raw_squared_m2 = 0.0;
      const Vec3 residual_m = sample_rows(fit.model, ws->rows_context, fit.base, samples[s], fit.loss, fit.kept,
                                          &ws->jacobian, &tool_jacobian, &raw_squared_m2);
      for (int axis = 0; axis < 3; ++axis) ws->residual_m[3 * static_cast<int>(s - begin) + axis] = residual_m(axis);
    }
    for (int i = 0; i < rows; ++i) {
      for (int j = 0; j < rows; ++j) {
        sum(i, j) += ws->residual_m[i] * ws->residual_m[j];
        pairs(i, j) += 1.0;
      }
    }
    begin = end;
  }
  if (!(pairs(0, 3) >= static_cast<double>(kMinPooledPoses))) return false;  // not a set of several readings
  for (int i = 0; i < kMaxUnitRows; ++i) {
    for (int j = 0; j < kMaxUnitRows; ++j) {
      if (pairs(i, j) > 0.0 && pairs(i, j) < static_cast<double>(kMinPooledPoses)) return false;
    }
  }
  double variance[kMaxUnitRows] = {};
  for (int i = 0; i < kMaxUnitRows; ++i) variance[i] = pairs(i, i) > 0.0 ? sum(i, i) / pairs(i, i) : 0.0;
  for (int i = 0; i < kMaxUnitRows; ++i) {
    for (int j = 0; j < kMaxUnitRows; ++j) {
      const double scale = std::sqrt(variance[i] * variance[j]);
      const bool pooled = i != j && i % 3 == j % 3 && pairs(i, j) > 0.0 && scale > 0.0;  // an axis between readings
      sum(i, j) = pooled ? sum(i, j) / pairs(i, j) / scale : (i == j ? 1.0 : 0.0);
    }
  }
  return true;
}

/// Tests one unit whose hat block and residual rows are in the workspace (the block is
/// factored in place).
UnitTest test_unit(const Scale& scale, const BlunderTestOptions& o, bool fitted, const UnitRows& u,
                   ReliabilityWorkspace* ws) {
  UnitTest t;
  t.fitted = fitted;
  t.residual_m = u.largest_m;
  const int n = u.count;
  UnitMatrix& q = ws->hat;
  double trace = 0.0;
  for (int i = 0; i < n; ++i) trace += q(i, i);
  t.redundancy = fitted ? 1.0 - trace / static_cast<double>(n) : 1.0;
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) q(i, j) = (fitted ? -q(i, j) : q(i, j)) + (i == j ? 1.0 : 0.0);
  }
  const bool can_test = !(fitted && scale.source == SigmaSource::data && scale.dof - n < 1.0);
  t.controlled = can_test && (!fitted || t.redundancy >= o.min_redundancy) && small_cholesky(&q, n);
  if (!t.controlled) return t;
  const double quadratic_m2 = factored_quadratic(q, ws->residual_m, n);  // what leaving the unit out takes off the SSR
  double variance_m2 = scale.sigma_m * scale.sigma_m;
  if (scale.source == SigmaSource::data && fitted) {  // the others' sigma: the unit's own residual left out
    variance_m2 = std::fmax(scale.ssr_m2 - quadratic_m2, 0.0) / (scale.dof - static_cast<double>(n));
  }
  const double critical = critical_statistic(scale, n, fitted);
  t.w = variance_m2 > 0.0 ? std::sqrt(quadratic_m2 / variance_m2) : 0.0;
  t.critical_w = std::sqrt(critical);
  if (fitted) {  // a bias lambda moves the statistic by about lambda / spread in its own scale
    const double spread = scale.spread[n];
    const double lambda0 = spread * math::detectable_noncentrality(critical / spread, static_cast<double>(n) / spread);
    t.mdb_m = scale.sigma_m * std::sqrt(lambda0 / t.redundancy);
  }
  return t;
}

/// Visits the units of one span.
void visit_units(const Fit& fit, const Scale& scale, const BlunderTestOptions& o, Span<const Sample> samples,
                 bool fitted, ReliabilityWorkspace* ws, UnitTestVisitor* visitor, BlunderTestSummary* summary) {
  UnitRows u;
  for (std::size_t begin = 0; begin < samples.size();) {
    const std::size_t end = unit_end(samples, begin, fit.grouped);
    unit_rows(fit, samples, begin, end, ws, &u);
    UnitTest t = test_unit(scale, o, fitted, u, ws);
    t.index = samples[begin].index;
    t.position = static_cast<std::uint32_t>(begin);
    t.samples = static_cast<std::uint32_t>(end - begin);
    ++summary->units;
    if (fitted) ++summary->fitted_units;
    if (fitted && !t.controlled) ++summary->uncontrolled;
    if (t.rejected()) ++summary->rejected;
    if (visitor != nullptr) visitor->on_unit(t);
    begin = end;
  }
}

}  // namespace

const char* sigma_source_name(SigmaSource source) {
  return source == SigmaSource::tracker ? "tracker" : "data";
}

std::size_t unit_end(Span<const Sample> samples, std::size_t begin, bool grouped) {
  std::size_t end = begin + 1;
  if (!grouped) return end;
  while (end < samples.size() && end - begin < static_cast<std::size_t>(kMaxUnitSamples) &&
         samples[end].q_rad == samples[begin].q_rad) {
    ++end;
  }
  return end;
}

std::size_t count_units(Span<const Sample> samples, bool grouped) {
  std::size_t count = 0;
  for (std::size_t i = 0; i < samples.size(); i = unit_end(samples, i, grouped)) ++count;
  return count;
}

Status test_for_blunders(const RobotModel& model, const RigidTransform& base, Span<const Sample> fitted,
                         Span<const Sample> predicted, ParamMask estimated, const PointLoss& loss,
                         const BlunderTestOptions& options, ReliabilityWorkspace* workspace, UnitTestVisitor* visitor,
                         BlunderTestSummary* summary) {
  *summary = BlunderTestSummary{};
  if (!options_valid(options) || workspace == nullptr) return Status::invalid_argument;
  if (fitted.empty()) return Status::dataset_empty;
  ReliabilityWorkspace& ws = *workspace;
  ws.normal.targets = Span<TargetBlock>(ws.blocks, kMaxTargets - 1);
  ws.rows_context = sample_rows_context(model);
  const ParamMask kept = estimated & ~kOtherTargetTools;
  Status status = accumulate_normal_equations(model, base, fitted, PointLoss{0.0, loss.joint_noise_ratio_rad_per_m},
                                              &ws.normal, estimated);
  if (status != Status::ok) return status;
  Fit fit{model,
          base,
          loss,
          kept,
          (estimated & kOtherTargetTools) != 0,
          FullParams::Ones(),
          target_count(fitted) > 1 || target_count(predicted) > 1};
  scale_kept_block(ws.normal.jtwj, kept, &ws.scaled, &fit.scale);
  if (!cholesky_factor(ws.scaled, kept, &ws.factor)) return Status::singular_system;
  int eliminated = 0;
  for (const TargetBlock& block : ws.normal.targets) eliminated += fit.other_tools && block.count > 0 ? 3 : 0;
  Scale scale;
  scale.ssr_m2 = ws.normal.weighted_squares_m2;
  scale.dof = 3.0 * static_cast<double>(fitted.size()) - mask_count(kept) - eliminated;
  const std::size_t units = count_units(fitted, fit.grouped) + count_units(predicted, fit.grouped);
  scale.unit_alpha = options.alpha / static_cast<double>(units);
  // The data's sigma needs a unit's rows left out and one degree of freedom beyond them, and
  // is never below the tracker's stated noise: residuals finer than the instrument (a fit
  // through noise-free or rounded readings) say nothing of a blunder.
  const double unit_rows = fit.grouped ? static_cast<double>(kMaxUnitRows) : 3.0;
  summary->dof = scale.dof;
  summary->fit_sigma_m = scale.dof > 0.0 ? std::sqrt(scale.ssr_m2 / scale.dof) : 0.0;
  const bool from_data = scale.dof >= unit_rows + 1.0 && summary->fit_sigma_m >= options.tracker_sigma_m;
  scale.source = from_data ? SigmaSource::data : SigmaSource::tracker;
  scale.sigma_m = from_data ? summary->fit_sigma_m : options.tracker_sigma_m;
  summary->sigma_source = scale.source;
  summary->sigma_m = scale.sigma_m;
  summary->pooled_correlation = from_data && fit.grouped && pool_correlation(fit, fitted, &ws);
  for (int n = 1; n <= kMaxUnitRows; ++n) {
    scale.spread[n] =
        summary->pooled_correlation ? ws.correlation.topLeftCorner(n, n).squaredNorm() / static_cast<double>(n) : 1.0;
  }
  visit_units(fit, scale, options, fitted, true, &ws, visitor, summary);
  visit_units(fit, scale, options, predicted, false, &ws, visitor, summary);
  return Status::ok;
}

}  // namespace hivecal
