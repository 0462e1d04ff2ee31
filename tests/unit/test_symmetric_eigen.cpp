// symmetric_eigen (tridiagonal QL on the fixed 33x33 NormalMatrix): a decomposition
// (reconstruction, orthonormal vectors, increasing eigenvalues) that agrees with Eigen's
// SelfAdjointEigenSolver, used here as the host-only reference, and allocates nothing.
#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include "alloc_trap.hpp"
#include "hivecal/random.hpp"
#include "hivecal/symmetric_eigen.hpp"

namespace hivecal {
namespace {

constexpr double kEpsilon = std::numeric_limits<double>::epsilon();
// A backward-stable decomposition reconstructs to a few hundred eps * |A| at n = 33.
constexpr double kTolerance = 200.0 * kEpsilon;
// Sentinel outside the decomposed block: symmetric_eigen must leave it alone.
constexpr double kOutside = 7.25;

/// Matrix with `kOutside` everywhere and a random symmetric leading block.
NormalMatrix random_symmetric(int size, Random* random) {
  NormalMatrix a = NormalMatrix::Constant(kOutside);
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r <= c; ++r) {
      a(r, c) = random->uniform(-1.0, 1.0);
      a(c, r) = a(r, c);
    }
  }
  return a;
}

/// Random orthogonal size x size matrix (Q of a Gaussian matrix's QR).
Eigen::MatrixXd random_orthogonal(int size, Random* random) {
  Eigen::MatrixXd g(size, size);
  for (int c = 0; c < size; ++c) {
    for (int r = 0; r < size; ++r) g(r, c) = random->normal();
  }
  return Eigen::HouseholderQR<Eigen::MatrixXd>(g).householderQ();
}

/// Leading block Q diag(values) Q^T, `kOutside` elsewhere.
NormalMatrix with_spectrum(const Eigen::VectorXd& values, Random* random) {
  const int size = static_cast<int>(values.size());
  const Eigen::MatrixXd q = random_orthogonal(size, random);
  Eigen::MatrixXd block = q * values.asDiagonal() * q.transpose();
  block = 0.5 * (block + block.transpose()).eval();  // exactly symmetric
  NormalMatrix a = NormalMatrix::Constant(kOutside);
  a.topLeftCorner(size, size) = block;
  return a;
}

struct Decomposition {
  FullParams values = FullParams::Zero();
  NormalMatrix vectors = NormalMatrix::Zero();
  NormalMatrix work = NormalMatrix::Zero();
  int iterations = 0;
  Status status = Status::ok;
};

Decomposition decompose(const NormalMatrix& a, int size) {
  Decomposition d;
  d.work = a;
  EXPECT_NO_HEAP(d.status = symmetric_eigen(&d.work, size, &d.values, &d.vectors, &d.iterations));
  return d;
}

/// Checks everything a decomposition of the leading size x size block of `a` must satisfy.
void expect_valid(const NormalMatrix& a, int size, const Decomposition& d) {
  ASSERT_EQ(d.status, Status::ok);
  const Eigen::MatrixXd block = a.topLeftCorner(size, size);
  const double norm = std::fmax(block.norm(), 1e-300);
  const Eigen::MatrixXd v = d.vectors.topLeftCorner(size, size);
  const Eigen::VectorXd lambda = d.values.head(size);
  EXPECT_LE((v * lambda.asDiagonal() * v.transpose() - block).norm(), kTolerance * norm) << "A = V L V^T";
  EXPECT_LE((v.transpose() * v - Eigen::MatrixXd::Identity(size, size)).norm(), kTolerance) << "V orthonormal";
  for (int k = 0; k + 1 < size; ++k) EXPECT_LE(lambda(k), lambda(k + 1)) << "increasing at " << k;
  // Eigenvalues agree with Eigen's tridiagonal QR to its own accuracy, eps * |A|.
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> reference(block, Eigen::EigenvaluesOnly);
  EXPECT_LE((reference.eigenvalues() - lambda).cwiseAbs().maxCoeff(), kTolerance * norm);
  // Outside the block: the input untouched, the vectors the identity.
  for (int c = 0; c < kFullParamCount; ++c) {
    for (int r = 0; r < kFullParamCount; ++r) {
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
      const NormalMatrix a = random_symmetric(size, &random);
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
      Eigen::MatrixXd b(size, rank);
      for (int c = 0; c < rank; ++c) {
        for (int r = 0; r < size; ++r) b(r, c) = random.normal();
      }
      NormalMatrix a = NormalMatrix::Constant(kOutside);
      const Eigen::MatrixXd product = b * b.transpose();
      a.topLeftCorner(size, size) = 0.5 * (product + product.transpose());
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
    const NormalMatrix a = with_spectrum(values, &random);
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
  const NormalMatrix block = with_spectrum(values, &random);
  // Scatter the active block over every 4th-but-one parameter pattern, -1 on the rest.
  NormalMatrix a = NormalMatrix::Zero();
  int active[kFullParamCount] = {};
  int n = 0;
  for (int i = 0; i < kFullParamCount; ++i) {
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
  EXPECT_NO_HEAP(d.status = symmetric_eigen(&d.work, kFullParamCount, &d.values, &d.vectors, &d.iterations));
  ASSERT_EQ(d.status, Status::ok);
  for (int k = 0; k < kFullParamCount - kActive; ++k) EXPECT_EQ(d.values(k), -1.0);
  for (int k = 0; k < kFullParamCount - kActive; ++k) {
    // An inactive parameter's eigenvector is its unit vector, exactly.
    int ones = 0;
    for (int r = 0; r < kFullParamCount; ++r) ones += std::fabs(d.vectors(r, k)) == 1.0 ? 1 : 0;
    EXPECT_EQ(ones, 1);
  }
  const Eigen::SelfAdjointEigenSolver<NormalMatrix> reference(a);
  EXPECT_LE((reference.eigenvalues() - d.values).cwiseAbs().maxCoeff(), kTolerance * 6.0);
  EXPECT_LE(d.iterations, 2 * kActive);
}

TEST(SymmetricEigen, EigenvaluesOnlyGiveTheSameBits) {
  Random random(15);
  const NormalMatrix a = random_symmetric(kFullParamCount, &random);
  const Decomposition full = decompose(a, kFullParamCount);
  NormalMatrix work = a;
  FullParams values = FullParams::Zero();
  int iterations = 0;
  EXPECT_NO_HEAP(EXPECT_EQ(symmetric_eigen(&work, kFullParamCount, &values, nullptr, &iterations), Status::ok));
  EXPECT_EQ(std::memcmp(values.data(), full.values.data(), sizeof(double) * kFullParamCount), 0);
  EXPECT_EQ(iterations, full.iterations);
}

TEST(SymmetricEigen, DiagonalMatrixNeedsNoRotation) {
  NormalMatrix a = NormalMatrix::Zero();
  for (int i = 0; i < kFullParamCount; ++i) a(i, i) = static_cast<double>((i * 7) % kFullParamCount) - 3.0;
  const Decomposition d = decompose(a, kFullParamCount);
  ASSERT_EQ(d.status, Status::ok);
  EXPECT_EQ(d.iterations, 0);
  for (int k = 0; k < kFullParamCount; ++k) {
    EXPECT_EQ(d.values(k), static_cast<double>(k) - 3.0);
    const int source = (k * 19) % kFullParamCount;  // 7 * 19 = 133 = 1 mod 33
    EXPECT_EQ(d.vectors(source, k), 1.0);
  }
  // The zero matrix too: every eigenvalue 0, the identity.
  const Decomposition zero = decompose(NormalMatrix::Zero(), 5);
  ASSERT_EQ(zero.status, Status::ok);
  EXPECT_TRUE(zero.values.head(5).isZero(0.0));
  EXPECT_TRUE(zero.vectors.isIdentity(0.0));
}

TEST(SymmetricEigen, RejectsBadSizeAndNonFiniteEntries) {
  NormalMatrix a = NormalMatrix::Identity();
  FullParams values = FullParams::Zero();
  EXPECT_EQ(symmetric_eigen(&a, 0, &values, nullptr), Status::invalid_argument);
  EXPECT_EQ(symmetric_eigen(&a, kFullParamCount + 1, &values, nullptr), Status::invalid_argument);
  a(2, 2) = 2.0 * kSymmetricEigenMaxMagnitude;  // would overflow when squared
  EXPECT_EQ(symmetric_eigen(&a, kFullParamCount, &values, nullptr), Status::invalid_argument);
  a(2, 2) = kSymmetricEigenMaxMagnitude;  // the largest accepted
  EXPECT_EQ(symmetric_eigen(&a, kFullParamCount, &values, nullptr), Status::ok);
  EXPECT_EQ(values(kFullParamCount - 1), kSymmetricEigenMaxMagnitude);
  a = NormalMatrix::Identity();
  a(3, 4) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(symmetric_eigen(&a, kFullParamCount, &values, nullptr), Status::non_finite_input);
  EXPECT_EQ(symmetric_eigen(&a, 4, &values, nullptr), Status::ok);  // outside the block
}

}  // namespace
}  // namespace hivecal
