// symmetric_eigen (tridiagonal QL on the fixed SymmetricMatrix): a decomposition
// (reconstruction, orthonormal vectors, increasing eigenvalues) whose eigenvalues agree with
// an independent reference (cyclic Jacobi rotations, written here), and allocates nothing.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "hivecal/core/random.hpp"
#include "hivecal/linalg/symmetric_eigen.hpp"
#include "testkit/alloc_trap.hpp"

namespace hivecal::symmetric_eigen_test {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// A backward-stable decomposition reconstructs to a few hundred eps * |A| at n = 33.
constexpr double kTolerance = 200.0 * kEpsilon;
// Sentinel outside the decomposed block: symmetric_eigen must leave it alone.
constexpr double kOutside = 7.25;

/// Matrix with `kOutside` everywhere and a random symmetric leading block.
SymmetricMatrix random_symmetric(int size, Random* random) {
  SymmetricMatrix a = SymmetricMatrix::Constant(kOutside);
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r <= c; ++r) {
      a(r, c) = random->uniform(-1.0, 1.0);
      a(c, r) = a(r, c);
    }
  }
  return a;
}

/// Random orthogonal size x size matrix: a Gaussian matrix's columns orthonormalised (the Q of
/// its QR). Gram-Schmidt by hand, twice for orthogonality to rounding: Eigen's QR costs this
/// file a tenth of its compile time in every preset that builds it.
Eigen::MatrixXd random_orthogonal(int size, Random* random) {
  Eigen::MatrixXd g(size, size);
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) g(r, c) = random->normal();
  }
  for (int pass = 0; pass < 2; ++pass) {
    for (int c = 0; c < size; ++c) {
      for (int k = 0; k < c; ++k) g.col(c) -= g.col(k).dot(g.col(c)) * g.col(k);
      g.col(c) /= g.col(c).norm();
    }
  }
  return g;
}

/// A size x rank matrix of standard normal entries, drawn column by column.
Eigen::MatrixXd random_factor(int size, int rank, Random* random) {
  Eigen::MatrixXd b(size, rank);
  for (int c = 0; c < rank; ++c) {
    for (int r = 0; r < size; ++r) b(r, c) = random->normal();
  }
  return b;
}

/// Leading block B B^T (positive semi-definite, rank of B), `kOutside` elsewhere.
SymmetricMatrix gram(const Eigen::MatrixXd& b) {
  SymmetricMatrix a = SymmetricMatrix::Constant(kOutside);
  const Eigen::MatrixXd product = b * b.transpose();
  a.topLeftCorner(b.rows(), b.rows()) = 0.5 * (product + product.transpose());
  return a;
}

/// Leading block Q diag(values) Q^T, `kOutside` elsewhere.
SymmetricMatrix with_spectrum(const Eigen::VectorXd& values, Random* random) {
  const int size = static_cast<int>(values.size());
  const Eigen::MatrixXd q = random_orthogonal(size, random);
  Eigen::MatrixXd block = q * values.asDiagonal() * q.transpose();
  block = 0.5 * (block + block.transpose()).eval();  // exactly symmetric
  SymmetricMatrix a = SymmetricMatrix::Constant(kOutside);
  a.topLeftCorner(size, size) = block;
  return a;
}

/// The reference: eigenvalues of a symmetric matrix, increasing, by cyclic Jacobi rotations
/// (Rutishauser's form, as in Golub & Van Loan 8.5). A different method from the one under
/// test, accurate to eps |A|, and cheap to compile (Eigen's SelfAdjointEigenSolver cost this
/// file most of its compile time in every preset).
Eigen::VectorXd jacobi_eigenvalues(Eigen::MatrixXd a) {
  const Eigen::Index n = a.rows();
  for (int sweep = 0; sweep < 100; ++sweep) {
    double off = 0.0;
    for (Eigen::Index q = 1; q < n; ++q) {
      for (Eigen::Index p = 0; p < q; ++p) off += a(p, q) * a(p, q);
    }
    if (off <= 1e-34 * a.squaredNorm() || off == 0.0) break;
    for (Eigen::Index p = 0; p + 1 < n; ++p) {
      for (Eigen::Index q = p + 1; q < n; ++q) {
        if (a(p, q) == 0.0) continue;
        const double theta = (a(q, q) - a(p, p)) / (2.0 * a(p, q));
        const double t = (theta >= 0.0 ? 1.0 : -1.0) / (std::fabs(theta) + std::sqrt(theta * theta + 1.0));
        const double c = 1.0 / std::sqrt(t * t + 1.0);
        const double s = t * c;
        for (Eigen::Index k = 0; k < n; ++k) {  // columns p, q, then rows p, q: A <- J^T A J
          const double akp = a(k, p);
          const double akq = a(k, q);
          a(k, p) = c * akp - s * akq;
          a(k, q) = s * akp + c * akq;
        }
        for (Eigen::Index k = 0; k < n; ++k) {
          const double apk = a(p, k);
          const double aqk = a(q, k);
          a(p, k) = c * apk - s * aqk;
          a(q, k) = s * apk + c * aqk;
        }
      }
    }
  }
  Eigen::VectorXd values = a.diagonal();
  std::sort(values.data(), values.data() + n);
  return values;
}

struct Decomposition {
  SymmetricVector values = SymmetricVector::Zero();
  SymmetricMatrix vectors = SymmetricMatrix::Zero();
  SymmetricMatrix work = SymmetricMatrix::Zero();
  int iterations = 0;
  Status status = Status::ok;
};

Decomposition decompose(const SymmetricMatrix& a, int size) {
  Decomposition d;
  d.work = a;
  EXPECT_NO_HEAP(d.status = symmetric_eigen(&d.work, size, &d.values, &d.vectors, &d.iterations));
  return d;
}

/// Checks everything a decomposition of the leading size x size block of `a` must satisfy.
void expect_valid(const SymmetricMatrix& a, int size, const Decomposition& d) {
  ASSERT_EQ(d.status, Status::ok);
  const Eigen::MatrixXd block = a.topLeftCorner(size, size);
  const double norm = std::fmax(block.norm(), 1e-300);
  const Eigen::MatrixXd v = d.vectors.topLeftCorner(size, size);
  const Eigen::VectorXd lambda = d.values.head(size);
  EXPECT_LE((v * lambda.asDiagonal() * v.transpose() - block).norm(), kTolerance * norm) << "A = V L V^T";
  EXPECT_LE((v.transpose() * v - Eigen::MatrixXd::Identity(size, size)).norm(), kTolerance) << "V orthonormal";
  for (int k = 0; k + 1 < size; ++k) EXPECT_LE(lambda(k), lambda(k + 1)) << "increasing at " << k;
  // Eigenvalues agree with the Jacobi reference to eps * |A|.
  EXPECT_LE((jacobi_eigenvalues(block) - lambda).cwiseAbs().maxCoeff(), kTolerance * norm);
  // Outside the block: the input untouched, the vectors the identity.
  for (int c = 0; c < kSymmetricCapacity; ++c) {
    for (int r = 0; r < kSymmetricCapacity; ++r) {
      if (r < size && c < size) continue;
      EXPECT_EQ(d.work(r, c), kOutside);
      EXPECT_EQ(d.vectors(r, c), r == c ? 1.0 : 0.0);
    }
  }
}

TEST(SymmetricEigen, RandomMatricesOfSeveralSizes) {
  Random random(11);
  for (int size : {1, 2, 3, 5, 8, 13, 21, 32, 33}) {
    for (int trial = 0; trial < 4; ++trial) {
      SCOPED_TRACE(testing::Message() << "size " << size << " trial " << trial);
      const SymmetricMatrix a = random_symmetric(size, &random);
      const Decomposition d = decompose(a, size);
      expect_valid(a, size, d);
      EXPECT_LE(d.iterations, 3 * size);
    }
  }
}

TEST(SymmetricEigen, RankDeficientPositiveSemiDefinite) {
  Random random(12);
  for (int size : {4, 12, 33}) {
    for (int rank : {1, size / 2, size - 1}) {
      SCOPED_TRACE(testing::Message() << "size " << size << " rank " << rank);
      const Eigen::MatrixXd b = random_factor(size, rank, &random);
      const SymmetricMatrix a = gram(b);
      const Decomposition d = decompose(a, size);
      expect_valid(a, size, d);
      const double norm = a.topLeftCorner(size, size).norm();
      for (int k = 0; k < size - rank; ++k) EXPECT_LE(std::fabs(d.values(k)), kTolerance * norm) << "null " << k;
      EXPECT_GT(d.values(size - rank), kTolerance * norm);
    }
  }
}

TEST(SymmetricEigen, NearlyRepeatedEigenvalues) {
  Random random(13);
  for (int size : {6, 33}) {
    Eigen::VectorXd values(size);
    for (int k = 0; k < size; ++k) values(k) = 1.0 + static_cast<double>(k % 3) * 1e-12 + static_cast<double>(k / 3);
    values(size - 1) = values(size - 2);  // one exact double eigenvalue too
    const SymmetricMatrix a = with_spectrum(values, &random);
    const Decomposition d = decompose(a, size);
    expect_valid(a, size, d);
    // Sorted, they are the constructed ones (to eps * |A|), clusters included.
    std::sort(values.data(), values.data() + size);
    EXPECT_LE((d.values.head(size) - values).cwiseAbs().maxCoeff(), kTolerance * values.norm());
  }
}

// What the identifiability analysis decomposes: a unit-diagonal block with eigenvalues down
// to 1e-16 of the largest, inactive parameters at -1 with no coupling.
TEST(SymmetricEigen, GradedSpectrumWithInactiveParameters) {
  Random random(14);
  constexpr int kActive = 25;
  Eigen::VectorXd values(kActive);
  for (int k = 0; k < kActive; ++k) values(k) = std::pow(10.0, -16.0 * static_cast<double>(k) / (kActive - 1));
  const SymmetricMatrix block = with_spectrum(values, &random);
  // Scatter the active block over every 4th-but-one parameter pattern, -1 on the rest.
  SymmetricMatrix a = SymmetricMatrix::Zero();
  int active[kSymmetricCapacity] = {};
  int n = 0;
  for (int i = 0; i < kSymmetricCapacity; ++i) {
    if (i % 4 == 3) {
      a(i, i) = -1.0;
    } else if (n < kActive) {
      active[n++] = i;
    } else {
      a(i, i) = -1.0;
    }
  }
  ASSERT_EQ(n, kActive);
  for (int c = 0; c < kActive; ++c) {
    for (int r = 0; r < kActive; ++r) a(active[r], active[c]) = block(r, c);
  }
  Decomposition d;
  d.work = a;
  EXPECT_NO_HEAP(d.status = symmetric_eigen(&d.work, kSymmetricCapacity, &d.values, &d.vectors, &d.iterations));
  ASSERT_EQ(d.status, Status::ok);
  for (int k = 0; k < kSymmetricCapacity - kActive; ++k) EXPECT_EQ(d.values(k), -1.0);
  for (int k = 0; k < kSymmetricCapacity - kActive; ++k) {
    // An inactive parameter's eigenvector is its unit vector, exactly.
    int ones = 0;
    for (int r = 0; r < kSymmetricCapacity; ++r) ones += std::fabs(d.vectors(r, k)) == 1.0 ? 1 : 0;
    EXPECT_EQ(ones, 1);
  }
  EXPECT_LE((jacobi_eigenvalues(Eigen::MatrixXd(a)) - d.values).cwiseAbs().maxCoeff(), kTolerance * 6.0);
  EXPECT_LE(d.iterations, 2 * kActive);
}

// The identifiability analysis decomposes only the block its parameters reach (one inactive
// entry past the last): the eigenvalues, their order (ties included) and the vectors of the
// active entries must be those of the whole capacity, whatever the inactive entries after it.
TEST(SymmetricEigen, InactiveEntriesAfterTheBlockChangeNoBitsOfIt) {
  Random random(16);
  constexpr int kPrefix = 20;  // 17 coupled and 2 uncoupled active entries, 1 inactive
  SymmetricMatrix a = SymmetricMatrix::Zero();
  for (int i = 0; i < kSymmetricCapacity; ++i) a(i, i) = -1.0;
  const SymmetricMatrix coupled = random_symmetric(17, &random);
  const int coupled_at[17] = {1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12, 13, 14, 15, 16, 17, 18};
  for (int c = 0; c < 17; ++c) {
    for (int r = 0; r < 17; ++r) a(coupled_at[r], coupled_at[c]) = coupled(r, c) + (r == c ? 6.0 : 0.0);
  }
  a(0, 0) = 0.5;  // two uncoupled entries with the same value: a tie, kept in index order
  a(9, 9) = 0.5;
  ASSERT_EQ(a(kPrefix - 1, kPrefix - 1), -1.0);  // the block's eigenvalues lie above -1, as a scaled
                                                 // normal matrix's do
  SymmetricVector values_prefix = SymmetricVector::Zero();
  SymmetricVector values_all = SymmetricVector::Zero();
  SymmetricEigenReduction prefix;
  SymmetricEigenReduction all;
  SymmetricMatrix work_prefix = a;
  SymmetricMatrix work_all = a;
  ASSERT_EQ(symmetric_eigenvalues(&work_prefix, kPrefix, &values_prefix, &prefix), Status::ok);
  ASSERT_EQ(symmetric_eigenvalues(&work_all, kSymmetricCapacity, &values_all, &all), Status::ok);
  const int skipped = kSymmetricCapacity - kPrefix;  // the -1s the whole capacity sorts first
  for (int k = 1; k < kPrefix; ++k) {
    EXPECT_EQ(std::memcmp(&values_prefix(k), &values_all(k + skipped), sizeof(double)), 0) << k;
    EXPECT_EQ(prefix.source[k], all.source[k + skipped]) << k;
  }
  int tie = -1;
  for (int k = 0; k + 1 < kPrefix; ++k) {
    if (values_prefix(k) == 0.5 && values_prefix(k + 1) == 0.5) tie = k;
  }
  ASSERT_GE(tie, 0) << "0.5 is not an eigenvalue of the coupled block";
  EXPECT_EQ(prefix.source[tie], 0);
  EXPECT_EQ(prefix.source[tie + 1], 9);
  // The lowest vectors, from the stored reductions.
  constexpr int kWanted = 6;  // the -1 and the five smallest of the block
  SymmetricMatrix vectors_prefix;
  SymmetricMatrix vectors_all;
  ASSERT_EQ(symmetric_eigenvectors_lowest(work_prefix, prefix, values_prefix, kWanted, &vectors_prefix), Status::ok);
  ASSERT_EQ(symmetric_eigenvectors_lowest(work_all, all, values_all, kWanted + skipped, &vectors_all), Status::ok);
  for (int k = 1; k < kWanted; ++k) {
    for (int r = 0; r < kSymmetricCapacity; ++r) {
      EXPECT_EQ(std::memcmp(&vectors_prefix(r, k), &vectors_all(r, k + skipped), sizeof(double)), 0) << r << ", " << k;
    }
  }
}

TEST(SymmetricEigen, EigenvaluesOnlyGiveTheSameBits) {
  Random random(15);
  const SymmetricMatrix a = random_symmetric(kSymmetricCapacity, &random);
  const Decomposition full = decompose(a, kSymmetricCapacity);
  SymmetricMatrix work = a;
  SymmetricVector values = SymmetricVector::Zero();
  int iterations = 0;
  EXPECT_NO_HEAP(EXPECT_EQ(symmetric_eigen(&work, kSymmetricCapacity, &values, nullptr, &iterations), Status::ok));
  EXPECT_EQ(std::memcmp(values.data(), full.values.data(), sizeof(double) * kSymmetricCapacity), 0);
  EXPECT_EQ(iterations, full.iterations);
}

TEST(SymmetricEigen, DiagonalMatrixNeedsNoRotation) {
  SymmetricMatrix a = SymmetricMatrix::Zero();
  for (int i = 0; i < kSymmetricCapacity; ++i) a(i, i) = static_cast<double>((i * 7) % kSymmetricCapacity) - 3.0;
  const Decomposition d = decompose(a, kSymmetricCapacity);
  ASSERT_EQ(d.status, Status::ok);
  EXPECT_EQ(d.iterations, 0);
  int inverse7 = 1;  // 7 * inverse7 = 1 mod the capacity (a prime, or at least not a multiple of 7)
  while ((7 * inverse7) % kSymmetricCapacity != 1) ++inverse7;
  for (int k = 0; k < kSymmetricCapacity; ++k) {
    EXPECT_EQ(d.values(k), static_cast<double>(k) - 3.0);
    const int source = (k * inverse7) % kSymmetricCapacity;
    EXPECT_EQ(d.vectors(source, k), 1.0);
  }
  // The zero matrix too: every eigenvalue 0, the identity.
  const Decomposition zero = decompose(SymmetricMatrix::Zero(), 5);
  ASSERT_EQ(zero.status, Status::ok);
  EXPECT_TRUE(zero.values.head(5).isZero(0.0));
  EXPECT_TRUE(zero.vectors.isIdentity(0.0));
}

TEST(SymmetricEigen, RejectsBadSizeAndNonFiniteEntries) {
  SymmetricMatrix a = SymmetricMatrix::Identity();
  SymmetricVector values = SymmetricVector::Zero();
  EXPECT_EQ(symmetric_eigen(&a, 0, &values, nullptr), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen(&a, kSymmetricCapacity + 1, &values, nullptr), Status::invalid_argument);
  a(2, 2) = 2.0 * kSymmetricEigenMaxMagnitude;  // would overflow when squared
  EXPECT_EQ(symmetric_eigen(&a, kSymmetricCapacity, &values, nullptr), Status::invalid_argument);
  a(2, 2) = kSymmetricEigenMaxMagnitude;  // the largest accepted
  EXPECT_EQ(symmetric_eigen(&a, kSymmetricCapacity, &values, nullptr), Status::ok);
  EXPECT_EQ(values(kSymmetricCapacity - 1), kSymmetricEigenMaxMagnitude);
  a = SymmetricMatrix::Identity();
  a(3, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(symmetric_eigen(&a, kSymmetricCapacity, &values, nullptr), Status::non_finite_input);
  EXPECT_EQ(symmetric_eigen(&a, 4, &values, nullptr), Status::ok);  // outside the block
}

// ---- Selected eigenvectors (symmetric_eigen_lowest: values-only QL, inverse iteration on
// the tridiagonal form, back through the reflections) ----

struct Lowest {
  SymmetricVector values = SymmetricVector::Zero();
  SymmetricMatrix vectors = SymmetricMatrix::Constant(kOutside);  // must be fully overwritten
  SymmetricMatrix work = SymmetricMatrix::Zero();
  int iterations = 0;
  Status status = Status::ok;
};

Lowest decompose_lowest(const SymmetricMatrix& a, int size, int count) {
  Lowest d;
  d.work = a;
  EXPECT_NO_HEAP(d.status = symmetric_eigen_lowest(&d.work, size, count, &d.values, &d.vectors, &d.iterations));
  return d;
}

/// The `count` selected vectors of `lowest` against the full decomposition of the same block:
/// same eigenvalue bits and iterations; orthonormal; eigenvectors (residual); zero elsewhere;
/// and for each j <= count, the first j vectors lie in the span of the full decomposition's
/// first c >= j vectors, c the first index with a gap lambda_c - lambda_{c-1} above
/// 1e-9 |A| (c = j: the same subspace), to eps |A| / gap.
void expect_valid_lowest(const SymmetricMatrix& a, int size, int count, const Lowest& lowest) {
  ASSERT_EQ(lowest.status, Status::ok);
  const Decomposition full = decompose(a, size);
  ASSERT_EQ(full.status, Status::ok);
  EXPECT_EQ(std::memcmp(lowest.values.data(), full.values.data(), sizeof(double) * kSymmetricCapacity), 0);
  EXPECT_EQ(lowest.iterations, full.iterations);
  const Eigen::MatrixXd block = a.topLeftCorner(size, size);
  const double norm = std::fmax(block.norm(), 1e-300);
  for (int c = 0; c < kSymmetricCapacity; ++c) {
    for (int r = 0; r < kSymmetricCapacity; ++r) {
      if (r < size && c < count) continue;
      ASSERT_EQ(lowest.vectors(r, c), 0.0) << "(" << r << ", " << c << ") outside the selected vectors";
    }
  }
  if (count == 0) return;
  const Eigen::MatrixXd v = lowest.vectors.topLeftCorner(size, count);
  EXPECT_LE((v.transpose() * v - Eigen::MatrixXd::Identity(count, count)).cwiseAbs().maxCoeff(), 1e-12)
      << "orthonormal";
  for (int k = 0; k < count; ++k) {
    const double residual = (block * v.col(k) - lowest.values(k) * v.col(k)).norm();
    EXPECT_LE(residual, 1e-13 * norm) << "A v = lambda v for vector " << k << ", lambda " << lowest.values(k);
  }
  const Eigen::MatrixXd w = full.vectors.topLeftCorner(size, size);
  for (int j = 1; j <= count; ++j) {
    int c = j;
    while (c < size && full.values(c) - full.values(c - 1) <= 1e-9 * norm) ++c;
    const double gap = c < size ? full.values(c) - full.values(c - 1) : norm;
    const Eigen::MatrixXd wc = w.leftCols(c);
    const Eigen::MatrixXd vj = v.leftCols(j);
    const double outside = (vj - wc * (wc.transpose() * vj)).norm();
    EXPECT_LE(outside, 1000.0 * kEpsilon * norm / gap) << "first " << j << " vectors inside the first " << c;
  }
}

TEST(SymmetricEigenLowest, RandomMatricesOfSeveralSizes) {
  Random random(21);
  for (int size : {1, 2, 3, 5, 8, 13, 21, 32, 33}) {
    for (int count : {0, 1, size / 2, size}) {
      SCOPED_TRACE(testing::Message() << "size " << size << " count " << count);
      const SymmetricMatrix a = random_symmetric(size, &random);
      expect_valid_lowest(a, size, count, decompose_lowest(a, size, count));
    }
  }
}

// The identifiability case: ~8 eigenvalues at rounding level (a tight cluster near 0, some
// negative), a gap of four decades, then the identifiable ones.
TEST(SymmetricEigenLowest, TightClusterOfEightNearZero) {
  Random random(22);
  for (int trial = 0; trial < 6; ++trial) {
    SCOPED_TRACE(testing::Message() << "trial " << trial);
    Eigen::VectorXd values(kSymmetricCapacity);
    for (int k = 0; k < kSymmetricCapacity; ++k) {
      values(k) = k < 8 ? random.uniform(-1.0, 1.0) * 1e-16 * static_cast<double>(trial % 3)
                        : std::pow(10.0, -3.0 + 3.5 * static_cast<double>(k - 8) / (kSymmetricCapacity - 9));
    }
    const SymmetricMatrix a = with_spectrum(values, &random);
    for (int count : {3, 8, 10}) {
      SCOPED_TRACE(testing::Message() << "count " << count);
      expect_valid_lowest(a, kSymmetricCapacity, count, decompose_lowest(a, kSymmetricCapacity, count));
    }
  }
}

TEST(SymmetricEigenLowest, GradedSpectra) {
  Random random(23);
  for (double decades : {8.0, 16.0, 20.0}) {
    Eigen::VectorXd values(kSymmetricCapacity);
    for (int k = 0; k < kSymmetricCapacity; ++k) {
      values(k) = std::pow(10.0, -decades * static_cast<double>(k) / (kSymmetricCapacity - 1));
    }
    const SymmetricMatrix a = with_spectrum(values, &random);
    for (int count : {4, 8, 16}) {
      SCOPED_TRACE(testing::Message() << decades << " decades, count " << count);
      expect_valid_lowest(a, kSymmetricCapacity, count, decompose_lowest(a, kSymmetricCapacity, count));
    }
  }
}

TEST(SymmetricEigenLowest, RankDeficientNullSpace) {
  Random random(24);
  for (int size : {4, 12, 33}) {
    for (int rank : {1, size / 2, size - 1}) {
      SCOPED_TRACE(testing::Message() << "size " << size << " rank " << rank);
      const Eigen::MatrixXd b = random_factor(size, rank, &random);
      const SymmetricMatrix a = gram(b);
      for (int count : {size - rank, std::min(size, size - rank + 2)}) {
        const Lowest lowest = decompose_lowest(a, size, count);
        expect_valid_lowest(a, size, count, lowest);
        // The null vectors are orthogonal to the range of b.
        const Eigen::MatrixXd v = lowest.vectors.topLeftCorner(size, size - rank);
        EXPECT_LE((b.transpose() * v).norm(), 1e-13 * b.squaredNorm());
      }
    }
  }
}

TEST(SymmetricEigenLowest, RepeatedEigenvaluesAndSplitTridiagonal) {
  Random random(25);
  // An exact 5-fold lowest eigenvalue.
  Eigen::VectorXd values(kSymmetricCapacity);
  for (int k = 0; k < kSymmetricCapacity; ++k) values(k) = k < 5 ? 0.5 : 1.0 + static_cast<double>(k);
  const SymmetricMatrix a = with_spectrum(values, &random);
  expect_valid_lowest(a, kSymmetricCapacity, 5, decompose_lowest(a, kSymmetricCapacity, 5));
  // Already tridiagonal and split in two identical halves: every eigenvalue twice, one in
  // each block of T; the vectors must still come out orthonormal.
  SymmetricMatrix t = SymmetricMatrix::Zero();
  for (int half = 0; half < 2; ++half) {
    for (int i = 0; i < 6; ++i) {
      const int r = 6 * half + i;
      t(r, r) = 2.0 + 0.1 * static_cast<double>(i);
      if (i + 1 < 6) t(r, r + 1) = t(r + 1, r) = 0.7;
    }
  }
  for (int count : {1, 2, 7, 12}) expect_valid_lowest(t, 12, count, decompose_lowest(t, 12, count));
}

// Rows without off-diagonal entries are exact eigenpairs wherever their eigenvalue sorts:
// here among the coupled ones, and the inactive -1 of the identifiability analysis first.
TEST(SymmetricEigenLowest, DecoupledRowsGiveUnitVectors) {
  Random random(26);
  SymmetricMatrix a = random_symmetric(kSymmetricCapacity, &random);
  const int decoupled[] = {0, 4, 17, 32};
  const double diagonal[] = {-1.0, -1.0, 0.01, -0.2};
  for (int n = 0; n < 4; ++n) {
    const int i = decoupled[n];
    a.row(i).setZero();
    a.col(i).setZero();
    a(i, i) = diagonal[n];
  }
  for (int count : {2, 9, kSymmetricCapacity}) {
    SCOPED_TRACE(testing::Message() << "count " << count);
    const Lowest lowest = decompose_lowest(a, kSymmetricCapacity, count);
    expect_valid_lowest(a, kSymmetricCapacity, count, lowest);
    for (int k = 0; k < count; ++k) {
      for (int n = 0; n < 4; ++n) {
        const int i = decoupled[n];
        const double entry = lowest.vectors(i, k);
        if (lowest.values(k) == diagonal[n] && entry != 0.0) {
          EXPECT_EQ(entry, 1.0);
          for (int r = 0; r < kSymmetricCapacity; ++r) {
            if (r != i) {
              EXPECT_EQ(lowest.vectors(r, k), 0.0);
            }
          }
        } else {
          EXPECT_EQ(entry, 0.0) << "a coupled vector touches decoupled row " << i;
        }
      }
    }
  }
  // The inactive parameters first at -1, the rest coupled: as analyze_identifiability does it.
  const SymmetricMatrix graded = [&] {
    Eigen::VectorXd values(25);
    for (int k = 0; k < 25; ++k) values(k) = k < 8 ? 1e-17 * static_cast<double>(k) : static_cast<double>(k) * 0.1;
    const SymmetricMatrix block = with_spectrum(values, &random);
    SymmetricMatrix m = SymmetricMatrix::Zero();
    for (int c = 0; c < 25; ++c) {
      for (int r = 0; r < 25; ++r) m(r + (r >= 10 ? 8 : 0), c + (c >= 10 ? 8 : 0)) = block(r, c);
    }
    for (int i = 10; i < 18; ++i) m(i, i) = -1.0;
    return m;
  }();
  const Lowest lowest = decompose_lowest(graded, kSymmetricCapacity, 16);
  expect_valid_lowest(graded, kSymmetricCapacity, 16, lowest);
  for (int k = 0; k < 8; ++k) EXPECT_EQ(lowest.vectors(10 + k, k), 1.0);
}

TEST(SymmetricEigenLowest, StagesAgreeWithTheOneCall) {
  Random random(27);
  const SymmetricMatrix a = random_symmetric(kSymmetricCapacity, &random);
  const Lowest one_call = decompose_lowest(a, kSymmetricCapacity, 7);
  SymmetricMatrix work = a;
  SymmetricVector values = SymmetricVector::Zero();
  SymmetricMatrix vectors = SymmetricMatrix::Zero();
  SymmetricEigenReduction reduction;
  int iterations = 0;
  EXPECT_NO_HEAP({
    EXPECT_EQ(symmetric_eigenvalues(&work, kSymmetricCapacity, &values, &reduction, &iterations), Status::ok);
    EXPECT_EQ(symmetric_eigenvectors_lowest(work, reduction, values, 7, &vectors), Status::ok);
  });
  EXPECT_EQ(std::memcmp(values.data(), one_call.values.data(), sizeof(double) * kSymmetricCapacity), 0);
  EXPECT_EQ(
      std::memcmp(vectors.data(), one_call.vectors.data(), sizeof(double) * kSymmetricCapacity * kSymmetricCapacity),
      0);
  EXPECT_EQ(iterations, one_call.iterations);
  // The vectors can be asked for again, more or fewer, from the same reduction.
  SymmetricMatrix more = SymmetricMatrix::Zero();
  EXPECT_EQ(symmetric_eigenvectors_lowest(work, reduction, values, 9, &more), Status::ok);
  EXPECT_EQ(std::memcmp(more.data(), vectors.data(), sizeof(double) * kSymmetricCapacity * 7), 0);
}

TEST(SymmetricEigenLowest, RejectsBadArguments) {
  SymmetricMatrix a = SymmetricMatrix::Identity();
  SymmetricVector values = SymmetricVector::Zero();
  SymmetricMatrix vectors = SymmetricMatrix::Zero();
  EXPECT_EQ(symmetric_eigen_lowest(&a, 0, 0, &values, &vectors), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen_lowest(&a, kSymmetricCapacity + 1, 1, &values, &vectors), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen_lowest(&a, 5, -1, &values, &vectors), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen_lowest(&a, 5, 6, &values, &vectors), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen_lowest(&a, 5, 5, &values, &vectors), Status::ok);
  a(2, 2) = 2.0 * kSymmetricEigenMaxMagnitude;
  EXPECT_EQ(symmetric_eigen_lowest(&a, 5, 1, &values, &vectors), Status::invalid_argument);
  a = SymmetricMatrix::Identity();
  a(3, 4) = std::numeric_limits<double>::infinity();
  EXPECT_EQ(symmetric_eigen_lowest(&a, 5, 1, &values, &vectors), Status::non_finite_input);
  // No reduction (never made, or its decomposition refused): nothing to take vectors from.
  const SymmetricEigenReduction none;
  EXPECT_EQ(symmetric_eigenvectors_lowest(a, none, values, 1, &vectors), Status::invalid_argument);
  SymmetricEigenReduction refused;
  EXPECT_EQ(symmetric_eigenvalues(&a, 5, &values, &refused), Status::non_finite_input);
  EXPECT_EQ(symmetric_eigenvectors_lowest(a, refused, values, 1, &vectors), Status::invalid_argument);
}

}  // namespace
}  // namespace hivecal::symmetric_eigen_test
