// Eigen-decomposition of a symmetric matrix, written for the fixed 37x37 SymmetricMatrix so that
// it needs no heap on any target (Eigen's SelfAdjointEigenSolver keeps a malloc branch on
// bare metal, docs/firmware.md) and, with a fixed order of operations and only +, -, *, /
// and sqrt, gives the same bits everywhere. Method: rows and columns with no off-diagonal
// entry are exact eigenpairs and are set aside; the coupled rest is reduced to tridiagonal
// form by Householder reflections and diagonalised by the implicit QL algorithm with
// Wilkinson shifts (docs/solver-lm.md, identifiability). When only the eigenvectors of the
// smallest eigenvalues are needed, symmetric_eigenvalues + symmetric_eigenvectors_lowest get
// them LAPACK-style (dstein + dormtr): inverse iteration on the tridiagonal form, then the
// stored Householder reflections.
#pragma once

#include <Eigen/Core>

#include "hivecal/core/capacity.hpp"
#include "hivecal/core/status.hpp"

namespace hivecal {

/// Largest matrix the solver decomposes: the full calibration model's parameters, 4 per joint,
/// 3 of the tool and 6 of the base for the build's joint capacity (33 for six joints), and its
/// joint terms (37 for six joints and 4 terms; normal_equations.hpp checks that the two agree).
inline constexpr int kSymmetricCapacity = 4 * kMaxJoints + 9 + kMaxJointTerms;
/// The working matrix: the leading size x size block is decomposed (10.9 kB at 37, 29.1 kB at 61, 41.6 kB at 73).
using SymmetricMatrix = Eigen::Matrix<double, kSymmetricCapacity, kSymmetricCapacity>;
/// Eigenvalues, or one column of eigenvectors, of that block.
using SymmetricVector = Eigen::Matrix<double, kSymmetricCapacity, 1>;

/// QL iterations per eigenvalue after which symmetric_eigen gives up (2-3 is typical).
inline constexpr int kSymmetricEigenMaxIterations = 30;
/// Largest entry magnitude accepted: the Householder norms square the entries once.
inline constexpr double kSymmetricEigenMaxMagnitude = 1e150;
/// Inverse-iteration steps per selected eigenvector after which symmetric_eigenvectors_lowest
/// gives up (LAPACK dstein's MAXITS; 3 is typical: residual reached, then 2 more).
inline constexpr int kInverseIterationMaxSteps = 5;

/// What symmetric_eigenvalues keeps for symmetric_eigenvectors_lowest (1.1 kB); the
/// Householder vectors themselves stay in the working matrix, below its subdiagonal.
struct SymmetricEigenReduction {
  int size = 0;                                 ///< decomposed block size [-] (0: none, or the decomposition failed)
  int coupled_count = 0;                        ///< block indices with an off-diagonal entry, reduced to T [-]
  int coupled[kSymmetricCapacity] = {};         ///< those indices, increasing: row i of T is coupled[i] [-]
  int source[kSymmetricCapacity] = {};          ///< block index whose eigenvalue sorted to position k [-]
  double diagonal[kSymmetricCapacity] = {};     ///< diagonal of the tridiagonal T [matrix unit]
  double subdiagonal[kSymmetricCapacity] = {};  ///< entry k couples rows k and k + 1 of T, the last 0 [matrix unit]
  double reflector_scale[kSymmetricCapacity] =
      {};                   ///< v^T v / 2 of reflection k (acts on k+1..), 0: none [matrix unit^2]
  double negligible = 0.0;  ///< couplings of T at or below this count as zero: eps * largest entry [matrix unit]
};

/// Decomposes the symmetric leading size x size block of *matrix (upper and lower triangle
/// both read, assumed equal) as V diag(lambda) V^T. *matrix is the working copy and is
/// overwritten inside the block; entries outside the block are not touched. Writes
/// eigenvalues(0 .. size-1), increasing (ties keep their index order); if eigenvectors is not
/// null, its leading block gets the orthonormal eigenvectors, column k belonging to
/// eigenvalues(k) (sign arbitrary), and the rest of it becomes the identity. A row with no
/// off-diagonal entry gives its diagonal entry and unit vector exactly. The eigenvalues do
/// not depend on whether eigenvectors are computed (same bits). If iterations is not null it
/// receives the number of QL iterations made (0 for a diagonal block).
/// Errors: invalid_argument (size not in 1..kSymmetricCapacity, or an entry above kSymmetricEigenMaxMagnitude),
/// non_finite_input (NaN/Inf in the block),
/// not_converged (an eigenvalue not isolated after kSymmetricEigenMaxIterations iterations).
Status symmetric_eigen(SymmetricMatrix* matrix, int size, SymmetricVector* eigenvalues, SymmetricMatrix* eigenvectors,
                       int* iterations = nullptr);

/// The eigenvalues of symmetric_eigen without vectors (same bits, same order, same errors and
/// iterations), keeping in *reduction and in *matrix (the working copy) what
/// symmetric_eigenvectors_lowest needs. On error reduction->size is 0.
Status symmetric_eigenvalues(SymmetricMatrix* matrix, int size, SymmetricVector* eigenvalues,
                             SymmetricEigenReduction* reduction, int* iterations = nullptr);

/// Orthonormal eigenvectors of the vector_count smallest eigenvalues: column k of
/// *eigenvectors belongs to eigenvalues(k) (sign arbitrary), every other entry becomes 0.
/// `matrix`, `reduction` and `eigenvalues` as a successful symmetric_eigenvalues left them.
/// Inverse iteration on each unreduced block of T (shift: the eigenvalue, raised by
/// 10 eps |lambda| above the previous one of its block when closer; modified Gram-Schmidt
/// against the earlier vectors of its cluster, eigenvalues less than 1e-3 |T| apart), then
/// the reflections. A row with no off-diagonal entry gives its unit vector exactly.
/// Errors: invalid_argument (vector_count not in 0..size, or reduction->size 0), not_converged
/// (a vector whose residual |(T - shift) x| stayed above n^1.5 sqrt(10) eps |T|_1 |x| after
/// kInverseIterationMaxSteps steps; it is still written).
Status symmetric_eigenvectors_lowest(const SymmetricMatrix& matrix, const SymmetricEigenReduction& reduction,
                                     const SymmetricVector& eigenvalues, int vector_count,
                                     SymmetricMatrix* eigenvectors);

/// symmetric_eigenvalues then symmetric_eigenvectors_lowest: every eigenvalue, and the
/// eigenvectors of the vector_count smallest (columns 0 .. vector_count-1). Errors of both.
Status symmetric_eigen_lowest(SymmetricMatrix* matrix, int size, int vector_count, SymmetricVector* eigenvalues,
                              SymmetricMatrix* eigenvectors, int* iterations = nullptr);

}  // namespace hivecal
