#include "hivecal/linalg/symmetric_eigen.hpp"

#include <cmath>
#include <cstdint>
#include <limits>

#include "hivecal/core/math.hpp"
#include "hivecal/core/random.hpp"

namespace hivecal {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();

/// Largest |a_ij| of a finite block (a comparison, not std::fmax: that is a libm call).
double largest_magnitude(const SymmetricMatrix& a, int size) {
  double largest = 0.0;
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) {
      const double magnitude = std::fabs(a(r, c));
      if (magnitude > largest) largest = magnitude;
    }
  }
  return largest;
}

bool block_finite(const SymmetricMatrix& a, int size) {
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) {
      if (!math::is_finite(a(r, c))) return false;
    }
  }
  return true;
}

/// sqrt(a^2 + b^2) without overflow or destructive underflow. The plain formula when the sum
/// of squares is safely normal (a term that underflowed there is below its last bit): one
/// division less in the QL rotation's dependency chain, the solver's critical path.
double hypotenuse(double a, double b) {
  constexpr double kSafeLow = 0x1p-960;    // squares below 2^-1022 lose bits only under 2^-1012
  constexpr double kSafeHigh = 0x1p+1000;  // an overflowed square gives +Inf and fails the test
  const double squares = a * a + b * b;
  if (squares > kSafeLow && squares < kSafeHigh) return std::sqrt(squares);
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

/// Finds the block indices coupled to another by a non-zero off-diagonal entry (the others
/// are already eigenpairs) into r->coupled and r->coupled_count; *is_coupled per index.
void find_coupling(const SymmetricMatrix& a, int size, SymmetricEigenReduction* r, bool* is_coupled) {
  r->coupled_count = 0;
  for (int i = 0; i < size; ++i) {
    bool coupled = false;
    for (int j = 0; j < size && !coupled; ++j) coupled = j != i && a(i, j) != 0.0;
    is_coupled[i] = coupled;
    if (coupled) r->coupled[r->coupled_count++] = i;
  }
}

/// Moves the coupled rows and columns to the leading block. In place: entry (i, j) comes
/// from (coupled[i], coupled[j]), never before (i, j) in column-major order, so walking
/// forward never overwrites an entry still to be read.
void pack(const SymmetricEigenReduction& r, SymmetricMatrix* a) {
  const int m = r.coupled_count;
  for (int j = 0; j < m; ++j) {
    for (int i = 0; i < m; ++i) (*a)(i, j) = (*a)(r.coupled[i], r.coupled[j]);
  }
}

/// The tridiagonal form Q^T A Q = T of the leading m x m block: diagonal d, subdiagonal e
/// (e[k] couples k and k + 1; e[m-1] = 0). Reflection k acts on indices k+1..m-1; its vector
/// is kept in column k below the subdiagonal of *a (from row k+1), its scale in h[k] (0: none).
void tridiagonalize(SymmetricMatrix* matrix, int m, double* d, double* e, double* h) {
  SymmetricMatrix& a = *matrix;
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
    // p_i = sum_j b_ij v_j, summed over j in order for each i; the loops run j outer so that
    // the inner one walks a contiguous column and the compiler can do several i at once
    // (independent sums: the same bits).
    double p[kSymmetricCapacity] = {};
    for (int j = k + 1; j < m; ++j) {
      const double vj = a(j, k);
      for (int i = k + 1; i < m; ++i) p[i] += a(i, j) * vj;
    }
    double vp = 0.0;
    for (int i = k + 1; i < m; ++i) {
      p[i] /= scale;
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

/// Q z = H_0 H_1 ... H_{m-3} z for the first column_count columns z of *q (rows 0..m-1), the
/// reflections stored by tridiagonalize in *a and h (dormtr); columns j with `skip` non-null
/// and skip[j] set are left alone. `from_identity`: the columns hold the identity and Q
/// itself is accumulated; then H_k ... H_{m-3} is still the identity on columns up to k + 1,
/// which are skipped.
void apply_reflections(const SymmetricMatrix& a, int m, const double* h, SymmetricMatrix* q, int column_count,
                       bool from_identity, const bool* skip) {
  for (int k = m - 3; k >= 0; --k) {
    if (h[k] == 0.0) continue;
    for (int j = from_identity ? k + 1 : 0; j < column_count; ++j) {
      if (skip != nullptr && skip[j]) continue;
      double dot = 0.0;
      for (int i = k + 1; i < m; ++i) dot += a(i, k) * (*q)(i, j);
      const double factor = dot / h[k];
      for (int i = k + 1; i < m; ++i) (*q)(i, j) -= factor * a(i, k);
    }
  }
}

/// Whether coupling e[i] of (d, e) counts as zero: at or below `floor` or below
/// epsilon * (|d[i]| + |d[i+1]|).
bool negligible_coupling(const double* d, const double* e, int i, double floor) {
  const double magnitude = std::fabs(e[i]);
  return magnitude <= floor || magnitude <= kEpsilon * (std::fabs(d[i]) + std::fabs(d[i + 1]));
}

/// End (one past) of the unreduced block of the m x m tridiagonal (d, e) starting at `first`.
int unreduced_end(const double* d, const double* e, int m, int first, double floor) {
  int n = first;
  while (n + 1 < m && !negligible_coupling(d, e, n, floor)) ++n;
  return n + 1;
}

/// Implicit QL with Wilkinson shifts on rows first..end-1 of (d, e) (Numerical Recipes' tqli,
/// 0-based), the plane rotations also applied to rows 0..rows-1 of the columns of *z when not
/// null. False if it did not converge.
bool diagonalize_tridiagonal(double* d, double* e, int first, int end, double floor, SymmetricMatrix* z, int rows,
                             int* iterations) {
  for (int l = first; l < end; ++l) {
    int tries = 0;
    for (;;) {
      int n = l;  // first negligible coupling at or after l
      for (; n + 1 < end; ++n) {
        if (negligible_coupling(d, e, n, floor)) break;
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
          for (int k = 0; k < rows; ++k) {
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

/// QL on the m x m tridiagonal (d, e) block by block, split where T itself has a negligible
/// coupling (so each eigenvalue stays in its block's rows, as symmetric_eigenvectors_lowest
/// assumes), a coupling counting as zero as in negligible_coupling. False if it did not converge.
bool diagonalize_blocks(double* d, double* e, int m, double floor, SymmetricMatrix* z, int* iterations) {
  int ends[kSymmetricCapacity];
  for (int first = 0; first < m; first = ends[first]) ends[first] = unreduced_end(d, e, m, first, floor);
  for (int first = 0; first < m; first = ends[first]) {
    if (!diagonalize_tridiagonal(d, e, first, ends[first], floor, z, m, iterations)) return false;
  }
  return true;
}

/// Moves rows 0..m-1 of the first column_count columns to the rows of the coupled indices
/// and zeroes the other rows of the size x size block. In place: targets are at or after
/// their sources, so rows are walked backwards.
void unpack_rows(const SymmetricEigenReduction& r, const bool* is_coupled, int size, int column_count,
                 SymmetricMatrix* matrix) {
  SymmetricMatrix& v = *matrix;
  for (int j = 0; j < column_count; ++j) {
    for (int i = r.coupled_count - 1; i >= 0; --i) v(r.coupled[i], j) = v(i, j);
    for (int i = 0; i < size; ++i) {
      if (!is_coupled[i]) v(i, j) = 0.0;
    }
  }
}

/// Moves the packed m x m eigenvectors to the rows and columns of the coupled indices and
/// makes every other column of the size x size block its unit vector. In place: targets are
/// at or after their sources, so columns are walked backwards.
void unpack_vectors(const SymmetricEigenReduction& r, const bool* is_coupled, int size, SymmetricMatrix* matrix) {
  SymmetricMatrix& v = *matrix;
  const int m = r.coupled_count;
  unpack_rows(r, is_coupled, size, m, matrix);
  for (int j = m - 1; j >= 0; --j) {
    for (int i = 0; i < size; ++i) v(i, r.coupled[j]) = v(i, j);
  }
  for (int j = 0; j < size; ++j) {
    if (is_coupled[j]) continue;
    for (int i = 0; i < size; ++i) v(i, j) = i == j ? 1.0 : 0.0;
  }
}

/// Column k of the size x size block becomes the column source[k] was: each cycle of the
/// permutation is followed with one column held aside.
void permute_columns(const int* source, int size, SymmetricMatrix* matrix) {
  SymmetricMatrix& v = *matrix;
  bool placed[kSymmetricCapacity] = {};
  for (int start = 0; start < size; ++start) {
    if (placed[start] || source[start] == start) continue;
    const SymmetricVector held = v.col(start);
    int k = start;
    while (source[k] != start) {
      v.col(k).head(size) = v.col(source[k]).head(size);
      placed[k] = true;
      k = source[k];
    }
    v.col(k).head(size) = held.head(size);
    placed[k] = true;
  }
}

/// Stable sort, increasing (insertion): ties keep their index order, so the order of the
/// eigenvalues of a block does not depend on how many uncoupled entries come before or after
/// them (the identifiability analysis passes only the block its parameters reach).
/// source[k] is the index whose eigenvalue sorted to position k; the eigenvector columns, if
/// given, follow their eigenvalues.
void sort_increasing(SymmetricVector* eigenvalues, int size, SymmetricMatrix* eigenvectors, int* source) {
  SymmetricVector& values = *eigenvalues;
  for (int k = 0; k < size; ++k) {
    const double value = values(k);
    int j = k;
    for (; j > 0 && value < values(j - 1); --j) {
      values(j) = values(j - 1);
      source[j] = source[j - 1];
    }
    values(j) = value;
    source[j] = k;
  }
  if (eigenvectors != nullptr) permute_columns(source, size, eigenvectors);
}

/// Checks the block, writes the diagonal to eigenvalues (final for the uncoupled indices),
/// packs the coupled ones to the leading block and reduces it to T. *is_coupled per index.
Status reduce(SymmetricMatrix* matrix, int size, SymmetricVector* eigenvalues, SymmetricEigenReduction* r,
              bool* is_coupled) {
  r->size = 0;
  r->coupled_count = 0;
  if (size < 1 || size > kSymmetricCapacity) return Status::invalid_argument;
  SymmetricMatrix& a = *matrix;
  if (!block_finite(a, size)) return Status::non_finite_input;
  const double largest = largest_magnitude(a, size);
  if (largest > kSymmetricEigenMaxMagnitude) return Status::invalid_argument;
  r->size = size;
  r->negligible = kEpsilon * largest;
  find_coupling(a, size, r, is_coupled);
  for (int i = 0; i < size; ++i) (*eigenvalues)(i) = a(i, i);
  if (r->coupled_count > 0) {
    pack(*r, &a);
    tridiagonalize(&a, r->coupled_count, r->diagonal, r->subdiagonal, r->reflector_scale);
  }
  return Status::ok;
}

// ---- Selected eigenvectors: inverse iteration on T (LAPACK dstein) ----

/// Eigenvalues closer than this times |T| of their block are one cluster (dstein's ORTOL).
constexpr double kClusterGap = 1e-3;
/// Steps made after the residual is reached (dstein's EXTRA).
constexpr int kExtraSteps = 2;
/// Seed of the start vectors (any fixed value: the same stream everywhere).
constexpr std::uint64_t kStartSeed = 0x5eed;

/// LU factors with partial pivoting of the scaled (T_block - shift I) / |T| (dlagtf).
struct TridiagonalLu {
  double diagonal[kSymmetricCapacity];    ///< U's diagonal, tiny pivots raised to +-eps
  double upper[kSymmetricCapacity];       ///< U's first superdiagonal
  double fill[kSymmetricCapacity];        ///< U's second superdiagonal (from interchanges)
  double multiplier[kSymmetricCapacity];  ///< L's multiplier of step t
  bool swapped[kSymmetricCapacity];       ///< rows t and t + 1 interchanged at step t
};

void factor_shifted(const double* d, const double* e, int n, double shift, double scale, TridiagonalLu* lu) {
  for (int t = 0; t < n; ++t) {
    lu->diagonal[t] = (d[t] - shift) * scale;
    lu->upper[t] = t + 1 < n ? e[t] * scale : 0.0;
    lu->fill[t] = 0.0;
  }
  for (int t = 0; t + 1 < n; ++t) {
    const double lower = e[t] * scale;  // non-zero in an unreduced block
    double multiplier = 0.0;
    if (std::fabs(lu->diagonal[t]) >= std::fabs(lower)) {
      multiplier = lower / lu->diagonal[t];
      lu->diagonal[t + 1] -= multiplier * lu->upper[t];
      lu->swapped[t] = false;
    } else {
      multiplier = lu->diagonal[t] / lower;
      lu->diagonal[t] = lower;
      const double next = lu->diagonal[t + 1];
      lu->diagonal[t + 1] = lu->upper[t] - multiplier * next;
      if (t + 2 < n) {
        lu->fill[t] = lu->upper[t + 1];
        lu->upper[t + 1] = -multiplier * lu->fill[t];
      }
      lu->upper[t] = next;
      lu->swapped[t] = true;
    }
    lu->multiplier[t] = multiplier;
  }
  for (int t = 0; t < n; ++t) {
    if (std::fabs(lu->diagonal[t]) < kEpsilon) lu->diagonal[t] = lu->diagonal[t] < 0.0 ? -kEpsilon : kEpsilon;
  }
}

/// x <- (L U)^-1 P x.
void solve_shifted(const TridiagonalLu& lu, int n, double* x) {
  for (int t = 0; t + 1 < n; ++t) {
    if (lu.swapped[t]) {
      const double top = x[t];
      x[t] = x[t + 1];
      x[t + 1] = top - lu.multiplier[t] * x[t];
    } else {
      x[t + 1] -= lu.multiplier[t] * x[t];
    }
  }
  x[n - 1] /= lu.diagonal[n - 1];
  if (n >= 2) x[n - 2] = (x[n - 2] - lu.upper[n - 2] * x[n - 1]) / lu.diagonal[n - 2];
  for (int t = n - 3; t >= 0; --t) x[t] = (x[t] - lu.upper[t] * x[t + 1] - lu.fill[t] * x[t + 2]) / lu.diagonal[t];
}

double largest_entry(const double* x, int n) {
  double largest = 0.0;
  for (int t = 0; t < n; ++t) {
    const double magnitude = std::fabs(x[t]);
    if (magnitude > largest) largest = magnitude;
  }
  return largest;
}

/// Where the wanted vectors of the current unreduced block of T stand, for the next one.
struct BlockState {
  int computed = 0;                ///< vectors of this block computed so far
  int cluster_first = 0;           ///< first of them in the current cluster
  double previous_shift = 0.0;     ///< shift of the last one
  int column[kSymmetricCapacity];  ///< their columns of *v, in order
};

/// Inverse iteration for one eigenvector of the unreduced block rows first..first+n-1 of T,
/// |T|_1 = norm (of the whole T: its eigenvalues are accurate to eps |T|, however small the
/// block): writes it (unit length) into rows first.. of column `column` of *v, orthogonal to
/// the cluster's earlier vectors of the block (state). False if the residual was not reached.
bool inverse_iterate(const SymmetricEigenReduction& r, int first, int n, double norm, double eigenvalue, int column,
                     BlockState* state, Random* random, SymmetricMatrix* v) {
  const double* d = r.diagonal + first;
  const double* e = r.subdiagonal + first;
  const double scale = 1.0 / norm;
  double shift = eigenvalue;
  if (state->computed > 0) {
    const double spread = 10.0 * kEpsilon * std::fabs(shift);
    if (shift - state->previous_shift < spread) shift = state->previous_shift + spread;
    if (std::fabs(shift - state->previous_shift) > kClusterGap * norm) state->cluster_first = state->computed;
  }
  state->previous_shift = shift;
  TridiagonalLu lu;
  factor_shifted(d, e, n, shift, scale, &lu);
  // Accepted once |(T - shift I) x|_inf <= n^1.5 sqrt(10) eps |T| |x|_inf: the residual
  // dstein's growth test implies (its pivots are not raised, so it can read the residual off
  // the growth; here a block of rounding noise gets every pivot raised, and the growth says
  // nothing). Then kExtraSteps more steps.
  const double size = static_cast<double>(n);
  const double bound = size * std::sqrt(10.0 * size) * kEpsilon;
  double x[kSymmetricCapacity];
  for (int t = 0; t < n; ++t) x[t] = random->uniform(-1.0, 1.0);
  int accepted = 0;
  for (int step = 0; step < kInverseIterationMaxSteps && accepted <= kExtraSteps; ++step) {
    solve_shifted(lu, n, x);
    for (int earlier = state->cluster_first; earlier < state->computed; ++earlier) {  // modified Gram-Schmidt
      const int j = state->column[earlier];
      double dot = 0.0;
      for (int t = 0; t < n; ++t) dot += x[t] * (*v)(first + t, j);
      for (int t = 0; t < n; ++t) x[t] -= dot * (*v)(first + t, j);
    }
    const double largest = largest_entry(x, n);
    if (!(largest > 0.0 && largest <= std::numeric_limits<double>::max())) break;
    for (int t = 0; t < n; ++t) x[t] /= largest;
    double residual = 0.0;
    for (int t = 0; t < n; ++t) {
      double y = (d[t] - shift) * scale * x[t];
      if (t > 0) y += e[t - 1] * scale * x[t - 1];
      if (t + 1 < n) y += e[t] * scale * x[t + 1];
      if (std::fabs(y) > residual) residual = std::fabs(y);
    }
    if (residual <= bound) ++accepted;
  }
  const double largest = largest_entry(x, n);
  const bool finite = largest > 0.0 && largest <= std::numeric_limits<double>::max();
  if (!finite) {  // not expected; keep the output orthonormal-shaped and report it
    for (int t = 0; t < n; ++t) x[t] = t == 0 ? 1.0 : 0.0;
  } else {
    for (int t = 0; t < n; ++t) x[t] /= largest;
  }
  double length2 = 0.0;
  for (int t = 0; t < n; ++t) length2 += x[t] * x[t];
  const double length = std::sqrt(length2);
  for (int t = 0; t < n; ++t) (*v)(first + t, column) = x[t] / length;
  state->column[state->computed++] = column;
  return finite && accepted > kExtraSteps;
}

}  // namespace

Status symmetric_eigen(SymmetricMatrix* matrix, int size, SymmetricVector* eigenvalues, SymmetricMatrix* eigenvectors,
                       int* iterations) {
  int iteration_count = 0;
  if (iterations != nullptr) *iterations = 0;
  SymmetricEigenReduction r;
  bool is_coupled[kSymmetricCapacity] = {};
  const Status status = reduce(matrix, size, eigenvalues, &r, is_coupled);
  if (status != Status::ok) return status;
  const int m = r.coupled_count;
  bool converged = true;
  if (eigenvectors != nullptr) eigenvectors->setIdentity();
  if (m > 0) {
    if (eigenvectors != nullptr) apply_reflections(*matrix, m, r.reflector_scale, eigenvectors, m, true, nullptr);
    converged = diagonalize_blocks(r.diagonal, r.subdiagonal, m, r.negligible, eigenvectors, &iteration_count);
    for (int j = 0; j < m; ++j) (*eigenvalues)(r.coupled[j]) = r.diagonal[j];
    if (eigenvectors != nullptr) unpack_vectors(r, is_coupled, size, eigenvectors);
  }
  if (iterations != nullptr) *iterations = iteration_count;
  sort_increasing(eigenvalues, size, eigenvectors, r.source);
  return converged ? Status::ok : Status::not_converged;
}

Status symmetric_eigenvalues(SymmetricMatrix* matrix, int size, SymmetricVector* eigenvalues,
                             SymmetricEigenReduction* reduction, int* iterations) {
  int iteration_count = 0;
  if (iterations != nullptr) *iterations = 0;
  SymmetricEigenReduction& r = *reduction;
  bool is_coupled[kSymmetricCapacity] = {};
  const Status status = reduce(matrix, size, eigenvalues, &r, is_coupled);
  if (status != Status::ok) return status;
  const int m = r.coupled_count;
  bool converged = true;
  if (m > 0) {
    double d[kSymmetricCapacity];  // QL works on copies: T stays for the vectors
    double e[kSymmetricCapacity];
    for (int j = 0; j < m; ++j) {
      d[j] = r.diagonal[j];
      e[j] = r.subdiagonal[j];
    }
    converged = diagonalize_blocks(d, e, m, r.negligible, nullptr, &iteration_count);
    for (int j = 0; j < m; ++j) (*eigenvalues)(r.coupled[j]) = d[j];
  }
  if (iterations != nullptr) *iterations = iteration_count;
  sort_increasing(eigenvalues, size, nullptr, r.source);
  if (!converged) r.size = 0;  // symmetric_eigenvectors_lowest refuses it
  return converged ? Status::ok : Status::not_converged;
}

Status symmetric_eigenvectors_lowest(const SymmetricMatrix& matrix, const SymmetricEigenReduction& reduction,
                                     const SymmetricVector& eigenvalues, int vector_count,
                                     SymmetricMatrix* eigenvectors) {
  const SymmetricEigenReduction& r = reduction;
  const int size = r.size;
  if (size < 1 || size > kSymmetricCapacity || vector_count < 0 || vector_count > size) return Status::invalid_argument;
  SymmetricMatrix& v = *eigenvectors;
  v.setZero();
  const int m = r.coupled_count;
  bool is_coupled[kSymmetricCapacity] = {};
  int row_of[kSymmetricCapacity];  // row of T of a coupled block index
  for (int i = 0; i < m; ++i) {
    is_coupled[r.coupled[i]] = true;
    row_of[r.coupled[i]] = i;
  }
  double norm = 0.0;  // |T|_1
  for (int i = 0; i < m; ++i) {
    const double row = std::fabs(r.diagonal[i]) + (i > 0 ? std::fabs(r.subdiagonal[i - 1]) : 0.0) +
                       (i + 1 < m ? std::fabs(r.subdiagonal[i]) : 0.0);
    if (row > norm) norm = row;
  }
  // Block by block (dstein), each block's wanted vectors in increasing order of eigenvalue,
  // written in T's coordinates into their own columns; skip[k]: column k is not T's.
  bool skip[kSymmetricCapacity] = {};
  for (int k = 0; k < vector_count; ++k) skip[k] = !is_coupled[r.source[k]];
  Random random(kStartSeed);
  bool converged = true;
  for (int first = 0; first < m;) {
    const int end = unreduced_end(r.diagonal, r.subdiagonal, m, first, r.negligible);
    BlockState state;
    for (int k = 0; k < vector_count; ++k) {
      if (skip[k]) continue;
      const int row = row_of[r.source[k]];
      if (row < first || row >= end) continue;
      if (end - first == 1) {
        v(first, k) = 1.0;
      } else if (!inverse_iterate(r, first, end - first, norm, eigenvalues(k), k, &state, &random, &v)) {
        converged = false;
      }
    }
    first = end;
  }
  if (m > 0) {
    apply_reflections(matrix, m, r.reflector_scale, &v, vector_count, false, skip);
    unpack_rows(r, is_coupled, size, vector_count, &v);
  }
  for (int k = 0; k < vector_count; ++k) {
    if (skip[k]) v(r.source[k], k) = 1.0;
  }
  return converged ? Status::ok : Status::not_converged;
}

Status symmetric_eigen_lowest(SymmetricMatrix* matrix, int size, int vector_count, SymmetricVector* eigenvalues,
                              SymmetricMatrix* eigenvectors, int* iterations) {
  if (iterations != nullptr) *iterations = 0;
  if (vector_count < 0 || vector_count > size) return Status::invalid_argument;
  SymmetricEigenReduction reduction;
  const Status status = symmetric_eigenvalues(matrix, size, eigenvalues, &reduction, iterations);
  if (status != Status::ok) return status;
  return symmetric_eigenvectors_lowest(*matrix, reduction, *eigenvalues, vector_count, eigenvectors);
}

}  // namespace hivecal
