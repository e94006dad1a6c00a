// Properties of the Jacobi eigen-decomposition of small symmetric matrices
// (math/jacobi_eigen.hpp), in float and double, for 1 x 1 to 3 x 3: eigenvalues against a
// long-double reference (Eigen's QR solver), ascending order, orthogonal eigenvectors, the
// residual G v = mu v, only the lower triangle read, the sweep cap, and NaN (not a hang
// or a finite guess) from a non-finite matrix.
#include "inhand/math/jacobi_eigen.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <limits>
#include <random>
#include <string>

#include "common/test_support.hpp"

namespace {

template <typename S, int N>
struct JacobiCase {
  using Scalar = S;
  static constexpr int kN = N;
};

template <typename C>
class JacobiEigenTest : public ::testing::Test {};

using JacobiCases =
    ::testing::Types<JacobiCase<double, 1>, JacobiCase<double, 2>, JacobiCase<double, 3>,
                     JacobiCase<float, 2>, JacobiCase<float, 3>>;
struct JacobiCaseNames {
  template <typename C>
  static std::string GetName(int) {
    return std::string(sizeof(typename C::Scalar) == sizeof(float) ? "float" : "double") +
           std::to_string(C::kN);
  }
};
TYPED_TEST_SUITE(JacobiEigenTest, JacobiCases, JacobiCaseNames);

/// A random symmetric N x N matrix Q diag(d) Q^T whose spectrum mixes exact zeros, values
/// from 1 down to 1e-16, clusters around 1 (gaps of 1e-9) and negative values: the cases
/// a Gram matrix with null directions and the box solver's free sets produce.
template <int N>
Eigen::Matrix<long double, N, N> random_symmetric(std::mt19937_64& rng) {
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> kind(0, 4), exponent(0, 16);
  Eigen::Matrix<double, N, N> A;
  for (int i = 0; i < N; ++i)
    for (int j = 0; j < N; ++j) A(i, j) = normal(rng);
  Eigen::Matrix<double, N, N> Q = A;  // an orthogonal Q: Gram-Schmidt on A's columns, twice
  for (int pass = 0; pass < 2; ++pass) {
    for (int j = 0; j < N; ++j) {
      for (int i = 0; i < j; ++i) Q.col(j) -= Q.col(i).dot(Q.col(j)) * Q.col(i);
      Q.col(j).normalize();
    }
  }
  Eigen::Matrix<long double, N, 1> d;
  for (int i = 0; i < N; ++i) {
    switch (kind(rng)) {
      case 0:
        d(i) = 0;
        break;
      case 1:
        d(i) = std::pow(10.0L, -static_cast<long double>(exponent(rng)));
        break;
      case 2:
        d(i) = 1.0L + 1e-9L * normal(rng);
        break;
      case 3:
        d(i) = -std::abs(normal(rng));
        break;
      default:
        d(i) = std::abs(normal(rng));
        break;
    }
  }
  const Eigen::Matrix<long double, N, N> Ql = Q.template cast<long double>();
  return Ql * d.asDiagonal() * Ql.transpose();
}

// Eigenvalues within 4 N eps max|g_ij| of the exact ones of the rounded matrix (measured
// worst over 2e5 cases: 2.2 eps |G|_F for 3 x 3; Eigen's QR solver 9.1), vectors
// orthonormal and G v = mu v to 16 N eps max|g_ij|, ascending, within 8 sweeps (measured
// at most 6).
TYPED_TEST(JacobiEigenTest, AgreesWithTheLongDoubleReference) {
  using S = typename TypeParam::Scalar;
  constexpr int N = TypeParam::kN;
  const double eps = static_cast<double>(std::numeric_limits<S>::epsilon());
  std::mt19937_64 rng(20261203 + N);
  const int cases = inhand_test::scaled(4000);
  for (int c = 0; c < cases; ++c) {
    const Eigen::Matrix<S, N, N> G = random_symmetric<N>(rng).template cast<S>();
    const Eigen::Matrix<long double, N, N> Gl = G.template cast<long double>();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<long double, N, N>> ref(Gl);
    inhand::detail::SymmetricEigen<S, N> jacobi;
    jacobi.compute(G);
    const long double size = Gl.cwiseAbs().maxCoeff();
    ASSERT_LE(jacobi.sweeps, 8) << "case " << c;
    for (int k = 0; k < N; ++k) {
      ASSERT_LE(std::abs(jacobi.values(k) - ref.eigenvalues()(k)), 4.0L * N * eps * size)
          << "case " << c << " eigenvalue " << k;
      if (k > 0) {
        ASSERT_LE(jacobi.values(k - 1), jacobi.values(k)) << "case " << c;
      }
    }
    const Eigen::Matrix<long double, N, N> V = jacobi.vectors.template cast<long double>();
    const Eigen::Matrix<long double, N, 1> mu = jacobi.values.template cast<long double>();
    const long double orthogonality =
        (V.transpose() * V - Eigen::Matrix<long double, N, N>::Identity()).cwiseAbs().maxCoeff();
    ASSERT_LE(orthogonality, 16.0L * N * eps) << "case " << c;
    const long double residual = (Gl * V - V * mu.asDiagonal()).cwiseAbs().maxCoeff();
    ASSERT_LE(residual, 16.0L * N * eps * size) << "case " << c;
  }
}

TYPED_TEST(JacobiEigenTest, ReadsOnlyTheLowerTriangle) {
  using S = typename TypeParam::Scalar;
  constexpr int N = TypeParam::kN;
  std::mt19937_64 rng(77 + N);
  const Eigen::Matrix<S, N, N> G = random_symmetric<N>(rng).template cast<S>();
  Eigen::Matrix<S, N, N> lower = G;
  for (int j = 1; j < N; ++j)
    for (int i = 0; i < j; ++i) lower(i, j) = std::numeric_limits<S>::quiet_NaN();
  inhand::detail::SymmetricEigen<S, N> a, b;
  a.compute(G);
  b.compute(lower);
  EXPECT_EQ(a.values, b.values);
  EXPECT_EQ(a.vectors, b.vectors);
}

TYPED_TEST(JacobiEigenTest, DiagonalMatrixIsSortedWithoutRotation) {
  using S = typename TypeParam::Scalar;
  constexpr int N = TypeParam::kN;
  Eigen::Matrix<S, N, 1> d;
  for (int k = 0; k < N; ++k) d(k) = static_cast<S>(N - 2 * k);  // descending, one negative
  inhand::detail::SymmetricEigen<S, N> jacobi;
  jacobi.compute(d.asDiagonal().toDenseMatrix());
  EXPECT_EQ(jacobi.sweeps, 1);
  for (int k = 0; k < N; ++k) {
    EXPECT_EQ(jacobi.values(k), d(N - 1 - k));
    EXPECT_EQ(jacobi.vectors.col(k).cwiseAbs(),
              (Eigen::Matrix<S, N, 1>::Unit(N - 1 - k)).cwiseAbs());
  }
}

TYPED_TEST(JacobiEigenTest, NonFiniteMatrixGivesNaNAtOnce) {
  using S = typename TypeParam::Scalar;
  constexpr int N = TypeParam::kN;
  for (const S bad : {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                      -std::numeric_limits<S>::infinity()}) {
    Eigen::Matrix<S, N, N> G = Eigen::Matrix<S, N, N>::Identity();
    G(N - 1, 0) = bad;
    inhand::detail::SymmetricEigen<S, N> jacobi;
    jacobi.compute(G);
    EXPECT_EQ(jacobi.sweeps, 0);
    for (int k = 0; k < N; ++k) EXPECT_TRUE(std::isnan(jacobi.values(k))) << bad;
  }
}

// Entries near the overflow threshold, and a rotation whose tau = (g_qq - g_pp) / (2 g_pq)
// is large (1e10: the branch that does not square it): finite eigenvalues, the right ones.
TEST(JacobiEigen, HugeFiniteEntriesStayFinite) {
  Eigen::Matrix3d G;
  G << 1e300, 1e-10, 0, 1e-10, -1e300, 1e290, 0, 1e290, 1.0;
  inhand::detail::SymmetricEigen<double, 3> jacobi;
  jacobi.compute(G);
  EXPECT_TRUE(jacobi.values.allFinite()) << jacobi.values.transpose();
  EXPECT_NEAR(jacobi.values(0) / -1e300, 1.0, 1e-12);
  EXPECT_NEAR(jacobi.values(1) / 1e280, 1.0, 1e-12);  // 1 + (1e290)^2 / 1e300
  EXPECT_NEAR(jacobi.values(2) / 1e300, 1.0, 1e-12);
}

}  // namespace
