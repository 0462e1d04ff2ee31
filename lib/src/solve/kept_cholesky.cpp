#include "solve/kept_cholesky.hpp"

#include <cmath>

#include "hivecal/core/math.hpp"

namespace hivecal {

namespace {

/// Entry (i, j) of U from the finished rows above it: (a(index[i], index[j]) - sum_k u(k, i)
/// u(k, j)) / u(i, i), the products subtracted in k order.
inline double upper_entry(const NormalMatrix& a, const int* index, const NormalMatrix& u, int i, int j) {
  double sum = a(index[i], index[j]);
  for (int k = 0; k < i; ++k) sum -= u(k, i) * u(k, j);
  return sum / u(i, i);
}

/// u(j, j) from column j's entries above it; false unless the pivot is positive and finite.
inline bool diagonal_entry(const NormalMatrix& a, const int* index, double shift, NormalMatrix* u, int j) {
  double pivot = a(index[j], index[j]) - shift;
  for (int k = 0; k < j; ++k) pivot -= (*u)(k, j) * (*u)(k, j);
  if (!(pivot > 0.0) || !math::is_finite(pivot)) return false;
  (*u)(j, j) = std::sqrt(pivot);
  return true;
}

}  // namespace

// Two columns at a time: their entries above the first one's diagonal depend only on the
// finished columns and on their own, so the two chains of subtractions overlap instead of
// each waiting on its last result (each entry keeps its operations: the same bits).
bool cholesky_factor_shifted(const NormalMatrix& a, const int* index, int count, double shift, NormalMatrix* upper) {
  NormalMatrix& u = *upper;
  int j = 0;
  for (; j + 1 < count; j += 2) {
    for (int i = 0; i < j; ++i) {
      double sum = a(index[i], index[j]);
      double next = a(index[i], index[j + 1]);
      for (int k = 0; k < i; ++k) {
        sum -= u(k, i) * u(k, j);
        next -= u(k, i) * u(k, j + 1);
      }
      u(i, j) = sum / u(i, i);
      u(i, j + 1) = next / u(i, i);
    }
    if (!diagonal_entry(a, index, shift, upper, j)) return false;
    u(j, j + 1) = upper_entry(a, index, u, j, j + 1);
    if (!diagonal_entry(a, index, shift, upper, j + 1)) return false;
  }
  if (j < count) {
    for (int i = 0; i < j; ++i) u(i, j) = upper_entry(a, index, u, i, j);
    if (!diagonal_entry(a, index, shift, upper, j)) return false;
  }
  return true;
}

/// The kept block of a scaled normal matrix is positive definite, damped or identifiable.
bool cholesky_factor(const NormalMatrix& a, ParamMask kept, KeptCholesky* f) {
  f->count = mask_indices(kept, f->index);
  return cholesky_factor_shifted(a, f->index, f->count, 0.0, &f->upper);
}

namespace {

/// cholesky_solve_compact on kWidth columns: each column gets the operations of a solve of it
/// alone, in their order (the same bits), its running sum in a register; the columns' chains of
/// subtractions are independent, so they overlap instead of each waiting on its own last result.
// Not inlined: one copy of each width in the firmware's flash.
template <std::size_t kWidth>
[[gnu::noinline]] void solve_columns(const KeptCholesky& f, double* v, int stride) {
  const NormalMatrix& u = f.upper;
  double* column[kWidth];
  for (std::size_t r = 0; r < kWidth; ++r) column[r] = v + static_cast<std::ptrdiff_t>(r) * stride;
  double sum[kWidth];
  for (int i = 0; i < f.count; ++i) {  // U^T y = b
    for (std::size_t r = 0; r < kWidth; ++r) sum[r] = column[r][i];
    for (int k = 0; k < i; ++k) {
      for (std::size_t r = 0; r < kWidth; ++r) sum[r] -= u(k, i) * column[r][k];
    }
    for (std::size_t r = 0; r < kWidth; ++r) column[r][i] = sum[r] / u(i, i);
  }
  for (int i = f.count - 1; i >= 0; --i) {  // U x = y
    for (std::size_t r = 0; r < kWidth; ++r) sum[r] = column[r][i];
    for (int k = i + 1; k < f.count; ++k) {
      for (std::size_t r = 0; r < kWidth; ++r) sum[r] -= u(i, k) * column[r][k];
    }
    for (std::size_t r = 0; r < kWidth; ++r) column[r][i] = sum[r] / u(i, i);
  }
}

}  // namespace

void cholesky_solve_compact(const KeptCholesky& f, double* v, int stride, int count) {
  // Three at a time: a pose's three rows (a w-test unit has 3, 6 or 9 of them).
  int first = 0;
  for (; first + 3 <= count; first += 3) solve_columns<3>(f, v + first * stride, stride);
  for (; first < count; ++first) solve_columns<1>(f, v + first * stride, stride);
}

void cholesky_solve(const KeptCholesky& f, const FullParams& b, FullParams* x) {
  double v[kFullParamCount];
  for (int i = 0; i < f.count; ++i) v[i] = b(f.index[i]);
  cholesky_solve_compact(f, v, 1, 1);
  x->setZero();
  for (int i = 0; i < f.count; ++i) (*x)(f.index[i]) = v[i];
}

namespace {

/// W = U^-1 (upper) in the leading count x count block of *w.
void invert_factor(const KeptCholesky& f, NormalMatrix* w_out) {
  const NormalMatrix& u = f.upper;
  NormalMatrix& w = *w_out;
  for (int j = 0; j < f.count; ++j) {
    w(j, j) = 1.0 / u(j, j);
    for (int i = 0; i < j; ++i) {
      double sum = 0.0;
      for (int k = i; k < j; ++k) sum += w(i, k) * u(k, j);
      w(i, j) = -sum / u(j, j);
    }
  }
}

/// (W W^T)(i, j) for compact positions i <= j: the rows of the upper W from j on.
double inverse_entry(const KeptCholesky& f, const NormalMatrix& w, int i, int j) {
  double sum = 0.0;
  for (int k = j; k < f.count; ++k) sum += w(i, k) * w(j, k);
  return sum;
}

}  // namespace

/// diag(A^-1) over the factored parameters, 0 elsewhere: A^-1 = W W^T with W = U^-1 (upper),
/// built in *scratch.
void cholesky_inverse_diagonal(const KeptCholesky& f, NormalMatrix* scratch, FullParams* diagonal) {
  invert_factor(f, scratch);
  diagonal->setZero();
  for (int i = 0; i < f.count; ++i) (*diagonal)(f.index[i]) = inverse_entry(f, *scratch, i, i);
}

void cholesky_inverse(const KeptCholesky& f, NormalMatrix* scratch, NormalMatrix* inverse) {
  invert_factor(f, scratch);
  inverse->setZero();
  for (int i = 0; i < f.count; ++i) {
    for (int j = i; j < f.count; ++j) {
      const double entry = inverse_entry(f, *scratch, i, j);
      (*inverse)(f.index[i], f.index[j]) = entry;
      (*inverse)(f.index[j], f.index[i]) = entry;
    }
  }
}

}  // namespace hivecal
