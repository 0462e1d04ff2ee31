// Cholesky factorisation of a normal matrix restricted to a parameter mask (KeptCholesky,
// solve/lm.hpp): shared by the LM solver (steps, parameter sigmas) and the pose planner
// (D-optimal selection, predicted sigmas), so that there is one factorisation in the library.
#pragma once

#include "hivecal/solve/lm.hpp"

namespace hivecal {

/// Factors a(kept, kept) = U^T U (plain Cholesky, column-oriented dot products over
/// contiguous columns). False unless every pivot is positive and finite.
bool cholesky_factor(const NormalMatrix& a, ParamMask kept, KeptCholesky* f);

/// Factors a(index, index) - shift I = U^T U over the `count` parameters listed in `index`
/// into the leading count x count block of *upper (cholesky_factor's operations; shift 0
/// gives its bits). False unless every pivot is positive and finite: with a shift, a proof
/// that no eigenvalue of the block lies at or below it (up to rounding).
bool cholesky_factor_shifted(const NormalMatrix& a, const int* index, int count, double shift, NormalMatrix* upper);

/// x = A^-1 b over the factored parameters (U^T y = b, then U x = y); 0 elsewhere.
void cholesky_solve(const KeptCholesky& f, const FullParams& b, FullParams* x);

/// The same in compact coordinates, in place, for `count` right-hand sides: column r starts at
/// v + r * stride (stride >= 1), and its entry k holds b at parameter f.index[k] on entry and x there on
/// return (f.count values). Each column gets the bits of a solve of it alone.
void cholesky_solve_compact(const KeptCholesky& f, double* v, int stride, int count);

/// diag(A^-1) over the factored parameters, 0 elsewhere: A^-1 = W W^T with W = U^-1 (upper),
/// built in *scratch.
void cholesky_inverse_diagonal(const KeptCholesky& f, NormalMatrix* scratch, FullParams* diagonal);

/// A^-1 over the factored parameters (symmetric), 0 elsewhere; W = U^-1 built in *scratch.
void cholesky_inverse(const KeptCholesky& f, NormalMatrix* scratch, NormalMatrix* inverse);

}  // namespace hivecal
