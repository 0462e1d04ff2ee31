#include "hivecal/symmetric_eigen.hpp"

#include <cmath>
#include <limits>

#include "hivecal/math.hpp"

namespace hivecal {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

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

/// sqrt(a^2 + b^2) without overflow or destructive underflow.
double hypotenuse(double a, double b) {
  const double abs_a = std::fabs(a);
  const double abs_b = std::fabs(b);
  if (abs_a > abs_b) {
    const double ratio = abs_b / abs_a;
    return abs_a * std::sqrt(1.0 + ratio * ratio);
  }
  if (abs_b == 0.0) return 0.0;
  const double ratio = abs_a / abs_b;
  return abs_b * std::sqrt(1.0 + ratio * ratio);
}

/// Indices of the block, split into those coupled to another by a non-zero off-diagonal
/// entry and those that are not (already eigenpairs).
struct Coupling {
  int coupled[kFullParamCount];              ///< the coupled indices, increasing
  int coupled_count = 0;                     ///< how many
  bool is_coupled[kFullParamCount] = {};     ///< per index of the block
};

Coupling find_coupling(const NormalMatrix& a, int size) {
  Coupling coupling;
  for (int i = 0; i < size; ++i) {
    bool coupled = false;
    for (int j = 0; j < size && !coupled; ++j) coupled = j != i && a(i, j) != 0.0;
    coupling.is_coupled[i] = coupled;
    if (coupled) coupling.coupled[coupling.coupled_count++] = i;
  }
  return coupling;
}

/// Moves the coupled rows and columns to the leading block. In place: entry (i, j) comes
/// from (coupled[i], coupled[j]), never before (i, j) in column-major order, so walking
/// forward never overwrites an entry still to be read.
void pack(const Coupling& coupling, NormalMatrix* a) {
  const int m = coupling.coupled_count;
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) (*a)(i, j) = (*a)(coupling.coupled[i], coupling.coupled[j]);
  }
}

/// The tridiagonal form Q^T A Q = T of the leading m x m block: diagonal d, subdiagonal e
/// (e[k] couples k and k + 1; e[m-1] = 0). Reflection k acts on indices k+1..m-1; its vector
/// is kept in column k below the subdiagonal of *a (from row k+1), its scale in h[k] (0: none).
void tridiagonalize(NormalMatrix* matrix, int m, double* d, double* e, double* h) {
  NormalMatrix& a = *matrix;
  for (int k = 0; k + 2 < m; ++k) {
    double tail2 = 0.0;  // |x|^2 without its first entry, x = a(k+1.., k)
    for (int i = k + 2; i < m; ++i) tail2 += a(i, k) * a(i, k);
    const double head = a(k + 1, k);
    if (tail2 == 0.0) {  // already tridiagonal in this column
      e[k] = head;
      h[k] = 0.0;
      continue;
    }
    const double norm = std::sqrt(head * head + tail2);
    const double alpha = head >= 0.0 ? -norm : norm;  // H x = alpha e_1; v_1 = x_1 - alpha does not cancel
    a(k + 1, k) = head - alpha;                       // v, with v^T v = 2 h
    const double scale = norm * (norm + std::fabs(head));
    e[k] = alpha;
    h[k] = scale;
    // B <- H B H with H = I - v v^T / h: p = B v / h, q = p - (v^T p / 2h) v, B -= v q^T + q v^T.
    double p[kFullParamCount];
    double vp = 0.0;
    for (int i = k + 1; i < m; ++i) {
      double sum = 0.0;
      for (int j = k + 1; j < m; ++j) sum += a(i, j) * a(j, k);
      p[i] = sum / scale;
      vp += a(i, k) * p[i];
    }
    const double half = vp / (2.0 * scale);
    for (int i = k + 1; i < m; ++i) p[i] -= half * a(i, k);
    for (int j = k + 1; j < m; ++j) {
      for (int i = k + 1; i < m; ++i) a(i, j) -= a(i, k) * p[j] + p[i] * a(j, k);
    }
  }
  for (int k = 0; k < m; ++k) d[k] = a(k, k);
  if (m >= 2) {
    e[m - 2] = a(m - 1, m - 2);
    h[m - 2] = 0.0;
  }
  e[m - 1] = 0.0;
}

/// Q = H_0 H_1 ... H_{m-3} into the leading m x m block of *q, which holds the identity.
/// Backwards, H_k Q: the product so far is the identity on indices up to k + 1.
void accumulate_reflections(const NormalMatrix& a, int m, const double* h, NormalMatrix* q) {
  for (int k = m - 3; k >= 0; --k) {
    if (h[k] == 0.0) continue;
    for (int j = k + 1; j < m; ++j) {
      double dot = 0.0;
      for (int i = k + 1; i < m; ++i) dot += a(i, k) * (*q)(i, j);
      const double factor = dot / h[k];
      for (int i = k + 1; i < m; ++i) (*q)(i, j) -= factor * a(i, k);
    }
  }
}

/// Implicit QL with Wilkinson shifts on (d, e) (Numerical Recipes' tqli, 0-based), the plane
/// rotations also applied to the columns of *z when not null. A coupling e[i] counts as zero
/// below epsilon * (|d[i]| + |d[i+1]|) or below `floor`. False if it did not converge.
bool diagonalize_tridiagonal(double* d, double* e, int m, double floor, NormalMatrix* z, int* iterations) {
  for (int l = 0; l < m; ++l) {
    int tries = 0;
    for (;;) {
      int n = l;  // first negligible coupling at or after l
      for (; n + 1 < m; ++n) {
        const double magnitude = std::fabs(e[n]);
        if (magnitude <= floor || magnitude <= kEpsilon * (std::fabs(d[n]) + std::fabs(d[n + 1]))) break;
      }
      if (n == l) break;
      if (++tries > kSymmetricEigenMaxIterations) return false;
      ++*iterations;
      double g = (d[l + 1] - d[l]) / (2.0 * e[l]);
      double r = hypotenuse(g, 1.0);
      g = d[n] - d[l] + e[l] / (g + (g >= 0.0 ? r : -r));
      double s = 1.0;
      double c = 1.0;
      double p = 0.0;
      bool deflated = false;  // a rotation met an exact zero: restart on the split problem
      for (int i = n - 1; i >= l; --i) {
        const double f = s * e[i];
        const double b = c * e[i];
        r = hypotenuse(f, g);
        e[i + 1] = r;
        if (r == 0.0) {
          d[i + 1] -= p;
          e[n] = 0.0;
          deflated = true;
          break;
        }
        s = f / r;
        c = g / r;
        g = d[i + 1] - p;
        r = (d[i] - g) * s + 2.0 * c * b;
        p = s * r;
        d[i + 1] = g + p;
        g = c * r - b;
        if (z != nullptr) {
          for (int k = 0; k < m; ++k) {
            const double upper = (*z)(k, i + 1);
            (*z)(k, i + 1) = s * (*z)(k, i) + c * upper;
            (*z)(k, i) = c * (*z)(k, i) - s * upper;
          }
        }
      }
      if (deflated) continue;
      d[l] -= p;
      e[l] = g;
      e[n] = 0.0;
    }
  }
  return true;
}

/// Moves the packed m x m eigenvectors to the rows and columns of the coupled indices and
/// makes every other column of the size x size block its unit vector. In place: targets are
/// at or after their sources, so rows and columns are walked backwards.
void unpack_vectors(const Coupling& coupling, int size, NormalMatrix* matrix) {
  NormalMatrix& v = *matrix;
  const int m = coupling.coupled_count;
  const int* index = coupling.coupled;
  for (int j = 0; j < m; ++j) {
    for (int i = m - 1; i >= 0; --i) v(index[i], j) = v(i, j);
    for (int i = 0; i < size; ++i) {
      if (!coupling.is_coupled[i]) v(i, j) = 0.0;
    }
  }
  for (int j = m - 1; j >= 0; --j) {
    for (int i = 0; i < size; ++i) v(i, index[j]) = v(i, j);
  }
  for (int j = 0; j < size; ++j) {
    if (coupling.is_coupled[j]) continue;
    for (int i = 0; i < size; ++i) v(i, j) = i == j ? 1.0 : 0.0;
  }
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
                       int* iterations) {
  int iteration_count = 0;
  if (iterations != nullptr) *iterations = 0;
  if (size < 1 || size > kFullParamCount) return Status::invalid_argument;
  NormalMatrix& a = *matrix;
  if (!block_finite(a, size)) return Status::non_finite_input;
  const double largest = largest_magnitude(a, size);
  if (largest > kSymmetricEigenMaxMagnitude) return Status::invalid_argument;
  const double floor = kEpsilon * largest;
  const Coupling coupling = find_coupling(a, size);
  for (int i = 0; i < size; ++i) (*eigenvalues)(i) = a(i, i);  // the uncoupled ones are final
  const int m = coupling.coupled_count;
  double d[kFullParamCount];
  double e[kFullParamCount];
  double h[kFullParamCount];
  bool converged = true;
  if (eigenvectors != nullptr) eigenvectors->setIdentity();
  if (m > 0) {
    pack(coupling, &a);
    tridiagonalize(&a, m, d, e, h);
    if (eigenvectors != nullptr) accumulate_reflections(a, m, h, eigenvectors);
    converged = diagonalize_tridiagonal(d, e, m, floor, eigenvectors, &iteration_count);
    for (int j = 0; j < m; ++j) (*eigenvalues)(coupling.coupled[j]) = d[j];
    if (eigenvectors != nullptr) unpack_vectors(coupling, size, eigenvectors);
  }
  if (iterations != nullptr) *iterations = iteration_count;
  sort_increasing(eigenvalues, size, eigenvectors);
  return converged ? Status::ok : Status::not_converged;
}

}  // namespace hivecal
