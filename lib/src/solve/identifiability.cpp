#include "hivecal/solve/identifiability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/linalg/symmetric_eigen.hpp"
#include "solve/kept_cholesky.hpp"

namespace hivecal {
namespace {

// Parameters outside the analysed set get this eigenvalue: below every eigenvalue of a
// positive semi-definite block, so they sort first and are skipped.
constexpr double kInactiveEigenvalue = -1.0;
// Smallest share of the null space (norm of the parameter's row in an orthonormal null
// basis) for a parameter to be dropped. Parameters are tried from the lowest index: a DH
// parameter before the tool, the tool before the base, d2 and d3 before d4 (the tool and
// base frame are what a user measures and reuses; d4 carries the parallel-axis sum). The
// leverages square-sum to the null dimension, so some parameter always has >= 1/sqrt(p).
constexpr double kMinDropLeverage = 0.1;
// Components smaller than this (relative to the dropped one) are not worth reporting.
constexpr double kReportedComponentFloor = 1e-3;
// A null basis whose inverse iteration missed its residual test is still used when each
// vector lies within this angle [rad] of the null space (Davis-Kahan: sin angle <= |S v - lambda v| /
// gap to the first kept eigenvalue) and the basis is orthonormal to kNullBasisOrthogonality.
// 1e-4 rad moves a leverage by at most ~1e-4, far below kMinDropLeverage; 1e-6 refused a
// cluster of eight exact nulls under a weak direction (gap 1.9e-7) whose eighth vector was
// within ~1e-5 rad (test_identifiability_cluster.cpp).
constexpr double kNullBasisAngle = 1e-4;
constexpr double kNullBasisOrthogonality = 1e-9;

// The confirming round's certificate: no eigenvalue of the scaled block after a drop lies below
// kCertificateMargin x the null threshold's eigenvalue (a shifted Cholesky factorisation
// succeeds), so its eigen-decomposition would find no null direction. The margin covers the
// rounding of both (relative ~1e-14 of the largest eigenvalue); thresholds whose squared
// value is not far above that rounding (below kCertificateMinThreshold) always decompose.
constexpr double kCertificateMargin = 2.0;
constexpr double kCertificateMinThreshold = 1e-5;

double singular_from_eigen(double eigenvalue) {
  return std::sqrt(eigenvalue > 0.0 ? eigenvalue : 0.0);
}

/// Rows and columns the analysis of `mask` decomposes: up to one past its last parameter, so
/// that one inactive entry (|kInactiveEigenvalue| = 1) stays in the block whenever the
/// parameter space goes further, as it did when the whole capacity was analysed: the
/// eigen-solver's rounding floor (relative to the block's largest entry) is then the same, and
/// the stable sort puts the eigenvalues of the analysed parameters in the same order. The
/// joint terms a build holds room for and a model does not use cost nothing.
int analysed_size(ParamMask mask) {
  int last = -1;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (mask_has(mask, i)) last = i;
  }
  return last + 2 < kFullParamCount ? last + 2 : kFullParamCount;
}

/// Writes the singular values of the analysed block (decreasing) and its condition number.
void fill_spectrum(const FullParams& eigenvalues, int size, int count, double* values, int* value_count,
                   double* condition) {
  for (int k = 0; k < count; ++k) values[k] = singular_from_eigen(eigenvalues(size - 1 - k));
  *value_count = count;
  const double smallest = values[count - 1];
  *condition = smallest > 0.0 ? values[0] / smallest : std::numeric_limits<double>::infinity();
}

/// Eigenvalues of ws->scaled (increasing), its reduction kept in ws->rotated and
/// ws->reduction for null_vectors. False if the QL iterations did not converge.
bool decompose(IdentifiabilityWorkspace* ws, int size) {
  ws->rotated.topLeftCorner(size, size) = ws->scaled.topLeftCorner(size, size);
  return symmetric_eigenvalues(&ws->rotated, size, &ws->eigenvalues, &ws->reduction) == Status::ok;
}

/// Whether the vectors in columns first_null..first_null+null_count-1 of ws->null_basis, which
/// inverse iteration wrote without meeting its residual test, are close enough to the null
/// space for the analysis (kNullBasisAngle). A cluster of eigenvalues at rounding level (two
/// or more exact null directions) can leave the second vector's residual ~10x above that
/// test: its shift cannot be separated from the first's, and the Gram-Schmidt step leaves
/// rounding noise of that size, which is far below any null threshold.
[[gnu::noinline]] bool close_to_null_space(const IdentifiabilityWorkspace& ws, int first_null, int null_count) {
  const int size = ws.reduction.size;
  const int next = first_null + null_count;
  if (next >= size) return false;
  const double gap = ws.eigenvalues(next) - ws.eigenvalues(next - 1);
  if (!(gap > 0.0)) return false;
  for (int j = first_null; j < next; ++j) {
    double residual2 = 0.0;
    for (int a = 0; a < kFullParamCount; ++a) {
      double y = -ws.eigenvalues(j) * ws.null_basis(a, j);
      for (int b = 0; b < kFullParamCount; ++b) y += ws.scaled(a, b) * ws.null_basis(b, j);
      residual2 += y * y;
    }
    if (!(std::sqrt(residual2) <= kNullBasisAngle * gap)) return false;
    for (int k = first_null; k <= j; ++k) {
      const double dot = ws.null_basis.col(j).dot(ws.null_basis.col(k));
      if (!(std::fabs(dot - (k == j ? 1.0 : 0.0)) <= kNullBasisOrthogonality)) return false;
    }
  }
  return true;
}

/// Orthonormal eigenvectors of the null_count smallest eigenvalues of the analysed block
/// (after the inactive parameters' `first_null`) into columns 0..null_count-1 of ws->null_basis.
bool null_vectors(IdentifiabilityWorkspace* ws, int first_null, int null_count) {
  NormalMatrix& basis = ws->null_basis;
  const Status status =
      symmetric_eigenvectors_lowest(ws->rotated, ws->reduction, ws->eigenvalues, first_null + null_count, &basis);
  if (status != Status::ok && !(status == Status::not_converged && close_to_null_space(*ws, first_null, null_count))) {
    return false;
  }
  // To the front; in increasing j each source lies at or after its target.
  for (int j = 0; j < null_count; ++j) basis.col(j) = basis.col(first_null + j);
  return true;
}

/// Directions whose sigmas direction_sigmas sums side by side.
constexpr int kSigmaGroup = 4;

/// sigma of the scaled Jacobian along each of the n directions in columns first.. of
/// `directions`: sqrt(v^T S v / v^T v) over the parameters in `mask`, into sigma[0..n). Each
/// direction's sums take their terms in the same order as one at a time (the same bits);
/// kSigmaGroup of them side by side, so that their chains of additions overlap.
// Not inlined: its sums stay out of analyze_identifiability's frame, which is live below the
// eigenvectors' (the firmware's deepest stack path).
[[gnu::noinline]] void direction_sigmas(const NormalMatrix& scaled, const NormalMatrix& directions, int first, int n,
                                        ParamMask mask, double* sigma) {
  int index[kFullParamCount];
  const int count = mask_indices(mask, index);
  for (int group = 0; group < n; group += kSigmaGroup) {
    int column[kSigmaGroup];  // beyond n: a valid column whose sums are dropped
    for (int t = 0; t < kSigmaGroup; ++t) column[t] = std::min(first + group + t, kFullParamCount - 1);
    double quadratic[kSigmaGroup] = {};
    double length2[kSigmaGroup] = {};
    for (int jb = 0; jb < count; ++jb) {
      const int b = index[jb];
      for (int t = 0; t < kSigmaGroup; ++t) length2[t] += directions(b, column[t]) * directions(b, column[t]);
      for (int ja = 0; ja < count; ++ja) {
        const int a = index[ja];
        for (int t = 0; t < kSigmaGroup; ++t) {
          quadratic[t] += directions(a, column[t]) * scaled(a, b) * directions(b, column[t]);
        }
      }
    }
    for (int t = 0; t < kSigmaGroup && group + t < n; ++t) {
      sigma[group + t] = length2[t] > 0.0 ? singular_from_eigen(quadratic[t] / length2[t]) : 0.0;
    }
  }
}

/// The largest components of a null combination, normalised so the dropped one is 1.
void describe_combination(const FullParams& v, int dropped, ParamMask mask, DroppedParam* entry) {
  entry->component_index[0] = dropped;
  entry->component[0] = 1.0;
  ParamMask listed = param_bit(dropped);
  for (int slot = 1; slot < kNullComponentCount; ++slot) {
    int best = -1;
    double best_abs = kReportedComponentFloor * std::fabs(v(dropped));
    for (int i = 0; i < kFullParamCount; ++i) {
      if (!mask_has(mask, i) || mask_has(listed, i)) continue;
      if (std::fabs(v(i)) > best_abs) {
        best = i;
        best_abs = std::fabs(v(i));
      }
    }
    if (best < 0) break;
    entry->component_index[slot] = best;
    entry->component[slot] = v(best) / v(dropped);
    listed |= param_bit(best);
  }
}

/// Rotates the first `count` columns of the orthonormal basis (a Householder reflection
/// acting on columns) so that row `row` is zero in all but the last of them; that last
/// column is then the null direction closest to parameter `row`.
void concentrate_row(NormalMatrix* basis, int count, int row) {
  NormalMatrix& v = *basis;
  double norm2 = 0.0;
  for (int j = 0; j < count; ++j) norm2 += v(row, j) * v(row, j);
  const double norm = std::sqrt(norm2);
  FullParams w = FullParams::Zero();  // reflector r - (-sign * |r|) e_last, length `count`
  for (int j = 0; j < count; ++j) w(j) = v(row, j);
  w(count - 1) += v(row, count - 1) >= 0.0 ? norm : -norm;
  double w2 = 0.0;
  for (int j = 0; j < count; ++j) w2 += w(j) * w(j);
  if (!(w2 > 0.0)) return;
  for (int i = 0; i < kFullParamCount; ++i) {
    double dot = 0.0;
    for (int j = 0; j < count; ++j) dot += v(i, j) * w(j);
    const double factor = 2.0 * dot / w2;
    for (int j = 0; j < count; ++j) v(i, j) -= factor * w(j);
  }
  for (int j = 0; j < count - 1; ++j) v(row, j) = 0.0;  // exact zeros: the row is deflated
}

/// Rewrites the drop directions (stored in columns first..first+n-1, one per dropped
/// parameter, each zero on the parameters dropped before it) so that each is 1 on its own
/// parameter and 0 on every other dropped one: a dropped parameter as a combination of
/// kept ones (back substitution, latest drop first).
void express_in_kept(NormalMatrix* basis, const int* dropped, int first, int n) {
  NormalMatrix& v = *basis;
  for (int j = n - 1; j >= 0; --j) {
    const int column = first + j;
    v.col(column) /= v(dropped[j], column);
    for (int m = j + 1; m < n; ++m) {
      const int later = first + m;
      v.col(column) -= v(dropped[m], column) * v.col(later);
      v(dropped[m], column) = 0.0;
    }
  }
}

/// Picks one parameter per null direction: scanning parameters from the lowest index, each
/// one with a substantial share of the null space (leverage |P_null e_i| >= kMinDropLeverage)
/// is dropped and its direction removed from the null space. The leverages of an
/// orthonormal basis square-sum to its dimension, so the scan always empties it.
void drop_null_directions(IdentifiabilityWorkspace* ws, int null_count, double sigma_max, ParamMask drop_first,
                          ParamMask* mask, IdentifiabilityReport* report) {
  NormalMatrix& basis = ws->null_basis;
  const ParamMask analysed = *mask;
  int dropped[kFullParamCount] = {};
  int count = null_count;
  // Two passes: the parameters of drop_first, then the others (each in index order).
  for (int pass = 0; pass < 2; ++pass) {
    const ParamMask candidates = analysed & (pass == 0 ? drop_first : ~drop_first);
    for (int i = 0; i < kFullParamCount && count > 0; ++i) {
      if (!mask_has(candidates, i)) continue;
      if (basis.row(i).head(count).norm() < kMinDropLeverage) continue;
      concentrate_row(&basis, count, i);
      dropped[null_count - count] = i;
      --count;
      *mask &= ~param_bit(i);
    }
  }
  // Direction of drop k sits in column null_count - 1 - k; reorder to drop order.
  const int n = null_count - count;
  for (int k = 0; k < n / 2; ++k) basis.col(count + k).swap(basis.col(null_count - 1 - k));
  express_in_kept(&basis, dropped, count, n);
  double sigma[kFullParamCount];
  direction_sigmas(ws->scaled, basis, count, n, analysed, sigma);
  for (int k = 0; k < n; ++k) {
    const FullParams direction = basis.col(count + k);
    DroppedParam& entry = report->dropped[report->dropped_count++];
    entry = DroppedParam{};
    entry.index = dropped[k];
    entry.reason = UnidentifiableReason::null_combination;
    entry.singular_ratio = sigma[k] / sigma_max;
    describe_combination(direction, dropped[k], analysed, &entry);
  }
}

/// Drops and reports the free parameters whose column norm is below threshold * the largest
/// column of all (the base translation columns, |e_k| per sample, are among them when
/// accumulated, so a single free parameter is still judged against a physical scale);
/// returns the free ones left.
ParamMask drop_no_effect(const NormalMatrix& jtwj, ParamMask free_mask, double threshold,
                         IdentifiabilityReport* report) {
  double largest = 0.0;
  for (int i = 0; i < kFullParamCount; ++i) largest = std::fmax(largest, std::sqrt(jtwj(i, i)));
  ParamMask no_effect = 0;
  for (int i = 0; i < kFullParamCount; ++i) {
    if (!mask_has(free_mask, i) || std::sqrt(jtwj(i, i)) > threshold * largest) continue;
    no_effect |= param_bit(i);
    DroppedParam& entry = report->dropped[report->dropped_count++];
    entry = DroppedParam{};
    entry.index = i;
    entry.reason = UnidentifiableReason::no_effect;
    entry.singular_ratio = largest > 0.0 ? std::sqrt(jtwj(i, i)) / largest : 0.0;
    entry.component_index[0] = i;
    entry.component[0] = 1.0;
  }
  return free_mask & ~no_effect;
}

/// Whether the scaled block over `mask` (in ws->scaled) provably has no eigenvalue below
/// (threshold * sigma_bound)^2, sigma_bound at or above its largest singular value (the
/// previous round's, whose block contains this one: Cauchy interlacing). Uses ws->rotated.
bool certified_without_null(IdentifiabilityWorkspace* ws, ParamMask mask, double threshold, double sigma_bound) {
  if (!(threshold >= kCertificateMinThreshold)) return false;
  const double floor = threshold * sigma_bound;
  int index[kFullParamCount];
  const int count = mask_indices(mask, index);
  return cholesky_factor_shifted(ws->scaled, index, count, kCertificateMargin * floor * floor, &ws->rotated);
}

Status check_arguments(const NormalMatrix& jtwj, ParamMask free_mask, double threshold) {
  if (!(threshold > 0.0 && threshold < 1.0)) return Status::invalid_argument;
  if (free_mask == 0 || (free_mask & ~valid_params_mask(kMaxJoints)) != 0) return Status::invalid_argument;
  if (!all_finite(jtwj)) return Status::non_finite_input;
  return Status::ok;
}

}  // namespace

void clear_report(IdentifiabilityReport* report) {
  // Field by field: `*report = IdentifiabilityReport{}` would build a 2.7 kB temporary on the stack.
  report->free_mask = 0;
  report->kept_mask = 0;
  report->dropped_count = 0;
  for (DroppedParam& entry : report->dropped) entry = DroppedParam{};
  report->singular_count_before = 0;
  report->singular_count_after = 0;
  for (int k = 0; k < kFullParamCount; ++k) {
    report->singular_values_before[k] = 0.0;
    report->singular_values_after[k] = 0.0;
  }
  report->condition_before = 0.0;
  report->condition_after = 0.0;
}

const char* unidentifiable_reason_name(UnidentifiableReason reason) {
  switch (reason) {
    case UnidentifiableReason::no_effect: return "no_effect";
    case UnidentifiableReason::null_combination: break;
  }
  return "null_combination";
}

Status analyze_identifiability(const NormalMatrix& jtwj, ParamMask free_mask, double threshold,
                               IdentifiabilityWorkspace* workspace, IdentifiabilityReport* report, ParamMask drop_first,
                               IdentifiabilityOutput output) {
  const Status status = check_arguments(jtwj, free_mask, threshold);
  if (status != Status::ok) return status;
  clear_report(report);
  report->free_mask = free_mask;
  ParamMask mask = drop_no_effect(jtwj, free_mask, threshold, report);
  // Each round removes every direction it finds; a second round only confirms (or catches a
  // direction that was hidden below a stronger null one). Eigenvalues first, then the
  // vectors of the null directions only.
  double previous_sigma_max = 0.0;
  for (bool first_round = true; mask != 0; first_round = false) {
    FullParams scale;
    scale_normal_matrix(jtwj, mask, kInactiveEigenvalue, &workspace->scaled, &scale);
    if (!first_round && output == IdentifiabilityOutput::kept_set &&
        certified_without_null(workspace, mask, threshold, previous_sigma_max)) {
      report->kept_mask = mask;
      return Status::ok;
    }
    const int size = analysed_size(mask);
    if (!decompose(workspace, size)) return Status::singular_system;
    const FullParams& eigenvalues = workspace->eigenvalues;
    const int count = mask_count(mask);
    const double sigma_max = singular_from_eigen(eigenvalues(size - 1));
    previous_sigma_max = sigma_max;
    if (first_round) {
      fill_spectrum(eigenvalues, size, count, report->singular_values_before, &report->singular_count_before,
                    &report->condition_before);
    }
    int null_count = 0;
    for (int k = size - count; k < size; ++k) {
      if (singular_from_eigen(eigenvalues(k)) >= threshold * sigma_max) break;
      ++null_count;
    }
    if (null_count == 0) {
      fill_spectrum(eigenvalues, size, count, report->singular_values_after, &report->singular_count_after,
                    &report->condition_after);
      report->kept_mask = mask;
      return Status::ok;
    }
    if (!null_vectors(workspace, size - count, null_count)) return Status::singular_system;
    const ParamMask before_drop = mask;
    drop_null_directions(workspace, null_count, sigma_max, drop_first, &mask, report);
    if (mask == before_drop) return Status::singular_system;
  }
  return Status::singular_system;
}

}  // namespace hivecal
