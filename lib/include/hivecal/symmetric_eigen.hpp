// Eigen-decomposition of a symmetric matrix by cyclic Jacobi rotations, written for the
// fixed 33x33 NormalMatrix so that it needs no heap on any target (Eigen's
// SelfAdjointEigenSolver keeps a malloc branch on bare metal, docs/firmware.md) and, with a
// fixed rotation order and only +, -, *, / and sqrt, gives the same bits everywhere.
#pragma once

#include "hivecal/full_model.hpp"
#include "hivecal/status.hpp"

namespace hivecal {

/// Sweeps over all pairs after which symmetric_eigen gives up (a 33x33 needs about 8-11).
inline constexpr int kSymmetricEigenMaxSweeps = 40;

/// Decomposes the symmetric leading size x size block of *matrix (upper and lower triangle
/// both read, assumed equal) as V diag(lambda) V^T. *matrix is the working copy and is
/// overwritten (its diagonal ends up holding the unsorted eigenvalues); entries outside the
/// block are not touched. Writes eigenvalues(0 .. size-1), increasing; if eigenvectors is
/// not null, its leading block gets the orthonormal eigenvectors, column k belonging to
/// eigenvalues(k) (sign arbitrary), and the rest of it becomes the identity. The eigenvalues
/// do not depend on whether eigenvectors are computed (same bits). If sweeps is not null it
/// receives the number of sweeps made, the last one finding nothing to rotate.
/// Errors: invalid_argument (size not in 1..33), non_finite_input (NaN/Inf in the block),
/// not_converged (off-diagonal not negligible after kSymmetricEigenMaxSweeps sweeps).
Status symmetric_eigen(NormalMatrix* matrix, int size, FullParams* eigenvalues, NormalMatrix* eigenvectors,
                       int* sweeps = nullptr);

}  // namespace hivecal
