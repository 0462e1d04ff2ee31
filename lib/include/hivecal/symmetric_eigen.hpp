// Eigen-decomposition of a symmetric matrix, written for the fixed 33x33 NormalMatrix so that
// it needs no heap on any target (Eigen's SelfAdjointEigenSolver keeps a malloc branch on
// bare metal, docs/firmware.md) and, with a fixed order of operations and only +, -, *, /
// and sqrt, gives the same bits everywhere. Method: rows and columns with no off-diagonal
// entry are exact eigenpairs and are set aside; the coupled rest is reduced to tridiagonal
// form by Householder reflections and diagonalised by the implicit QL algorithm with
// Wilkinson shifts (docs/solver-lm.md, identifiability).
#pragma once

#include "hivecal/full_model.hpp"
#include "hivecal/status.hpp"

namespace hivecal {

/// QL iterations per eigenvalue after which symmetric_eigen gives up (2-3 is typical).
inline constexpr int kSymmetricEigenMaxIterations = 30;
/// Largest entry magnitude accepted: the Householder norms square the entries once.
inline constexpr double kSymmetricEigenMaxMagnitude = 1e150;

/// Decomposes the symmetric leading size x size block of *matrix (upper and lower triangle
/// both read, assumed equal) as V diag(lambda) V^T. *matrix is the working copy and is
/// overwritten inside the block; entries outside the block are not touched. Writes
/// eigenvalues(0 .. size-1), increasing (ties keep their index order); if eigenvectors is not
/// null, its leading block gets the orthonormal eigenvectors, column k belonging to
/// eigenvalues(k) (sign arbitrary), and the rest of it becomes the identity. A row with no
/// off-diagonal entry gives its diagonal entry and unit vector exactly. The eigenvalues do
/// not depend on whether eigenvectors are computed (same bits). If iterations is not null it
/// receives the number of QL iterations made (0 for a diagonal block).
/// Errors: invalid_argument (size not in 1..33, or an entry above kSymmetricEigenMaxMagnitude),
/// non_finite_input (NaN/Inf in the block),
/// not_converged (an eigenvalue not isolated after kSymmetricEigenMaxIterations iterations).
Status symmetric_eigen(NormalMatrix* matrix, int size, FullParams* eigenvalues, NormalMatrix* eigenvectors,
                       int* iterations = nullptr);

}  // namespace hivecal
