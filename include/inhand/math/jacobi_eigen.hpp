// Eigen-decomposition of a small symmetric matrix (N x N, N <= 3, fixed size) by cyclic
// Jacobi rotations: G = V diag(mu) V^T with mu ascending and V orthogonal (its columns
// the eigenvectors, mu(k) belonging to column k). Only G's lower triangle is read, as
// Eigen's SelfAdjointEigenSolver reads it.
//
// Why not Eigen's iterative SelfAdjointEigenSolver: the same accuracy (below), a tenth of
// the code. That solver's tridiagonalisation and Householder machinery is a large
// template instantiation (about 6 s of gcc -O3 and 11 s of clang with the sanitizers per
// translation unit and scalar type, for the 2 x 2 and 3 x 3 sizes together), paid in
// every file that instantiates the contact IK; the rotations below are a few dozen
// lines.
//
// Accuracy: each rotation is backward stable, and a pair (p, q) is left alone once
// |g_pq| <= eps sqrt(|g_pp g_qq|) or |g_pq| <= eps^2 max |g_ij| (Demmel and Veselic's
// criterion, with an absolute floor for the null directions): every eigenvalue is then
// within a small multiple of eps |G| of the exact one, as with the QR solver, and for a
// positive definite G within a small multiple of eps of it relatively. Convergence is
// quadratic; a 3 x 3 matrix needs 3 to 6 sweeps of 3 rotations. The sweep count is capped
// at kMaxSweeps (bounded time). A matrix with a non-finite entry in its lower triangle
// gives NaN eigenvalues (and identity vectors) at once. No allocation; noexcept.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <utility>

namespace inhand {
namespace detail {

template <typename Scalar, int N>
struct SymmetricEigen {
  static_assert(N >= 1 && N <= 3, "SymmetricEigen: sizes 1 to 3 only");
  static constexpr int kMaxSweeps = 16;

  Eigen::Matrix<Scalar, N, 1> values;   ///< eigenvalues, ascending
  Eigen::Matrix<Scalar, N, N> vectors;  ///< column k: the unit eigenvector of values(k)
  int sweeps = 0;                       ///< sweeps taken (<= kMaxSweeps)

  /// Decomposes the symmetric matrix whose lower triangle G holds.
  void compute(const Eigen::Matrix<Scalar, N, N>& G) noexcept {
    Eigen::Matrix<Scalar, N, N> a;
    for (int j = 0; j < N; ++j)
      for (int i = j; i < N; ++i) a(i, j) = a(j, i) = G(i, j);
    vectors.setIdentity();
    sweeps = 0;
    if (!a.allFinite()) {
      values.setConstant(std::numeric_limits<Scalar>::quiet_NaN());
      return;
    }
    const Scalar scale = a.cwiseAbs().maxCoeff();  // max |g_ij|: no overflow of a norm
    const Scalar eps = Eigen::NumTraits<Scalar>::epsilon();
    const Scalar floor = eps * eps * scale;
    bool rotated = true;
    while (rotated && sweeps < kMaxSweeps) {
      rotated = false;
      ++sweeps;
      for (int p = 0; p < N - 1; ++p) {
        for (int q = p + 1; q < N; ++q) {
          const Scalar apq = a(p, q);
          const Scalar size = std::abs(apq);
          if (size <= floor || size <= eps * std::sqrt(std::abs(a(p, p) * a(q, q)))) continue;
          rotate(a, p, q);
          rotated = true;
        }
      }
    }
    for (int k = 0; k < N; ++k) values(k) = a(k, k);
    // Ascending order (at most three entries: insertion sort).
    for (int k = 1; k < N; ++k) {
      for (int m = k; m > 0 && values(m) < values(m - 1); --m) {
        std::swap(values(m), values(m - 1));
        vectors.col(m).swap(vectors.col(m - 1));
      }
    }
  }

 private:
  /// a <- R^T a R, vectors <- vectors R, with the rotation R in the (p, q) plane that
  /// zeroes a(p, q) (Golub and Van Loan, the symmetric Schur decomposition of order 2).
  void rotate(Eigen::Matrix<Scalar, N, N>& a, int p, int q) noexcept {
    const Scalar apq = a(p, q);
    const Scalar tau = (a(q, q) - a(p, p)) / (Scalar(2) * apq);
    const Scalar abs_tau = std::abs(tau);
    // t = sign(tau) / (|tau| + sqrt(1 + tau^2)), the smaller root; for |tau| past
    // 1/sqrt(eps) that is 1 / (2 |tau|) to rounding, without forming the square. (The
    // skip test above keeps |tau| below 1/eps^2, so the square would not overflow either.)
    const Scalar big = Scalar(1) / std::sqrt(Eigen::NumTraits<Scalar>::epsilon());
    Scalar t = abs_tau > big ? Scalar(1) / (Scalar(2) * abs_tau)
                             : Scalar(1) / (abs_tau + std::sqrt(Scalar(1) + tau * tau));
    if (tau < Scalar(0)) t = -t;
    const Scalar c = Scalar(1) / std::sqrt(Scalar(1) + t * t);
    const Scalar s = t * c;
    a(p, p) -= t * apq;
    a(q, q) += t * apq;
    a(p, q) = a(q, p) = Scalar(0);
    for (int r = 0; r < N; ++r) {
      if (r != p && r != q) {
        const Scalar arp = a(r, p), arq = a(r, q);
        a(r, p) = a(p, r) = c * arp - s * arq;
        a(r, q) = a(q, r) = s * arp + c * arq;
      }
      const Scalar vrp = vectors(r, p), vrq = vectors(r, q);
      vectors(r, p) = c * vrp - s * vrq;
      vectors(r, q) = s * vrp + c * vrq;
    }
  }
};

}  // namespace detail
}  // namespace inhand
