#include "hivecal/symmetric_eigen.hpp"

#include <cmath>
#include <limits>

#include "hivecal/math.hpp"

namespace hivecal {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// An off-diagonal entry is negligible below epsilon * sqrt(|a_pp| |a_qq|) (the relative
// criterion of Demmel and Veselic: a pair of small diagonal entries is still rotated while
// its coupling matters to them) ...
constexpr double kRelativeTolerance = kEpsilon;
// ... or below epsilon * the largest entry of the input: the accuracy of a tridiagonal QR
// (Eigen's solver), so the eigenvalues are as good as before. Without this floor the sweeps
// go on resolving exact null blocks, whose entries are rounding noise: on the UR's normal
// matrix with 8 null directions 13-15 sweeps instead of 9-11, for the same decisions.
constexpr double kAbsoluteTolerance = kEpsilon;
// Beyond this |theta| = |a_qq - a_pp| / |2 a_pq|, theta^2 + 1 would overflow; tan(phi) is then
// 1 / (2 theta) to double precision.
constexpr double kLargeTheta = 1e150;

double largest_magnitude(const NormalMatrix& a, int size) {
  double largest = 0.0;
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) largest = std::fmax(largest, std::fabs(a(r, c)));
  }
  return largest;
}

bool block_finite(const NormalMatrix& a, int size) {
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) {
      if (!math::is_finite(a(r, c))) return false;
    }
  }
  return true;
}

bool negligible(double off_diagonal, double diagonal_p, double diagonal_q, double floor) {
  const double magnitude = std::fabs(off_diagonal);
  return magnitude <= floor ||
         magnitude <= kRelativeTolerance * std::sqrt(std::fabs(diagonal_p)) * std::sqrt(std::fabs(diagonal_q));
}

/// Applies the rotation (c, s) with tau = s / (1 + c) to columns p and q of the first `size`
/// rows of *m: the update of Numerical Recipes' jacobi, written as a correction of each entry
/// so that a small angle changes it by a small rounding.
void rotate_columns(NormalMatrix* m, int size, int p, int q, double s, double tau) {
  NormalMatrix& v = *m;
  for (int k = 0; k < size; ++k) {
    const double g = v(k, p);
    const double h = v(k, q);
    v(k, p) = g - s * (h + g * tau);
    v(k, q) = h + s * (g - h * tau);
  }
}

/// One Jacobi rotation zeroing a(p, q) (not negligible). Rows p and q are kept equal to
/// columns p and q, so the matrix stays exactly symmetric.
void rotate(NormalMatrix* matrix, int size, int p, int q, NormalMatrix* eigenvectors) {
  NormalMatrix& a = *matrix;
  const double apq = a(p, q);
  const double theta = (a(q, q) - a(p, p)) / (2.0 * apq);
  const double magnitude = std::fabs(theta);
  // tan of the rotation angle: the smaller root of t^2 + 2 theta t - 1 = 0 (|angle| <= pi/4).
  double t = magnitude > kLargeTheta ? 0.5 / magnitude : 1.0 / (magnitude + std::sqrt(magnitude * magnitude + 1.0));
  if (theta < 0.0) t = -t;
  const double c = 1.0 / std::sqrt(t * t + 1.0);
  const double s = t * c;
  const double tau = s / (1.0 + c);
  const double shift = t * apq;
  const double app = a(p, p) - shift;
  const double aqq = a(q, q) + shift;
  rotate_columns(matrix, size, p, q, s, tau);
  for (int k = 0; k < size; ++k) {
    a(p, k) = a(k, p);
    a(q, k) = a(k, q);
  }
  // The 2x2 block is set from its closed form: the rotated diagonal and an exact zero.
  a(p, p) = app;
  a(q, q) = aqq;
  a(p, q) = 0.0;
  a(q, p) = 0.0;
  if (eigenvectors != nullptr) rotate_columns(eigenvectors, size, p, q, s, tau);
}

/// Selection sort, increasing; ties keep their order, so the result is the same everywhere.
void sort_increasing(FullParams* eigenvalues, int size, NormalMatrix* eigenvectors) {
  FullParams& values = *eigenvalues;
  for (int k = 0; k + 1 < size; ++k) {
    int smallest = k;
    for (int j = k + 1; j < size; ++j) {
      if (values(j) < values(smallest)) smallest = j;
    }
    if (smallest == k) continue;
    const double value = values(k);
    values(k) = values(smallest);
    values(smallest) = value;
    if (eigenvectors != nullptr) eigenvectors->col(k).swap(eigenvectors->col(smallest));
  }
}

}  // namespace

Status symmetric_eigen(NormalMatrix* matrix, int size, FullParams* eigenvalues, NormalMatrix* eigenvectors,
                       int* sweeps) {
  if (sweeps != nullptr) *sweeps = 0;
  if (size < 1 || size > kFullParamCount) return Status::invalid_argument;
  NormalMatrix& a = *matrix;
  if (!block_finite(a, size)) return Status::non_finite_input;
  if (eigenvectors != nullptr) eigenvectors->setIdentity();
  const double floor = kAbsoluteTolerance * largest_magnitude(a, size);
  // Cyclic by rows: a fixed order of pairs, and a sweep without a rotation ends it.
  bool converged = false;
  int sweep = 0;
  while (!converged && sweep < kSymmetricEigenMaxSweeps) {
    ++sweep;
    converged = true;
    for (int p = 0; p + 1 < size; ++p) {
      for (int q = p + 1; q < size; ++q) {
        if (negligible(a(p, q), a(p, p), a(q, q), floor)) continue;
        rotate(matrix, size, p, q, eigenvectors);
        converged = false;
      }
    }
  }
  if (sweeps != nullptr) *sweeps = sweep;
  for (int k = 0; k < size; ++k) (*eigenvalues)(k) = a(k, k);
  sort_increasing(eigenvalues, size, eigenvectors);
  return converged ? Status::ok : Status::not_converged;
}

}  // namespace hivecal
