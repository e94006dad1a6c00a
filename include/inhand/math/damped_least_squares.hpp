// Damped least-squares inverse of a small m x n matrix (the contact Jacobian, eq. 3).
//
// With k = min(m, n) and the k x k Gram matrix G = J J^T (n >= m) or J^T J (n < m):
//   n >= m : x = J^T (G + lambda^2 I)^-1 b   exact inverse (m = n) or minimum-norm
//                                            pseudo-inverse (n > m) when lambda = 0
//   n <  m : x = (G + lambda^2 I)^-1 J^T b   least squares when lambda = 0
// The singular values of J are the square roots of G's eigenvalues; the smallest,
// sigma_min, drives the damping schedule (Nakamura-Hanafusa / Maciejewski style):
//   lambda^2 = 0                                        if sigma_min >= epsilon
//   lambda^2 = max_damping^2 * (1 - (sigma_min/epsilon)^2)  otherwise
// so damping rises continuously from 0 only inside the singular region. The gain
// from b to x along a singular direction is sigma / (sigma^2 + lambda^2); its
// supremum over sigma (gain_bound()) bounds |x| <= gain_bound() * |b|.
// Fixed sizes never allocate; Eigen::Dynamic allocates only at construction.
#pragma once

#include <algorithm>
#include <cmath>

#include "inhand/math/damping_schedule.hpp"
#include "inhand/math/symmetric3.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// Solver for an M x N matrix with M <= 3 (a contact Jacobian: M = Dim). N may be
/// Eigen::Dynamic, with MaxN a fixed capacity or Eigen::Dynamic. Because k = min(M, N)
/// <= 3, the k x k Gram matrix, its eigenvalues and its Cholesky factor
/// live in fixed 3 x 3 storage: no allocation in any size mode.
/// Accuracy: sigma_min comes from the Gram matrix, so it is resolved down to about
/// sqrt(machine epsilon) * sigma_max; smaller values read as roughly that floor, far
/// inside the damped region (the schedule treats both alike).
template <typename Scalar, int M, int N, int MaxN = N>
class DampedLeastSquares {
  static_assert(M >= 1 && M <= 3, "contact Jacobians have 1 to 3 rows");

 public:
  using Matrix = Eigen::Matrix<Scalar, M, N, Eigen::ColMajor, M, MaxN>;
  using Rhs = Eigen::Matrix<Scalar, M, 1>;
  using Solution = Eigen::Matrix<Scalar, N, 1, Eigen::ColMajor, MaxN, 1>;
  using Inverse = Eigen::Matrix<Scalar, N, M, Eigen::ColMajor, MaxN, M>;

  struct Result {
    /// sigma_min (to the resolution stated above) when min_singular_value_exact;
    /// otherwise the schedule's singular_threshold, a certified lower bound.
    Scalar min_singular_value = Scalar(0);
    Scalar damping = Scalar(0);  ///< lambda (not squared)
    bool damped = false;
    bool valid = false;  ///< false: non-finite matrix, solution set to zero
    bool min_singular_value_exact = true;
  };

  explicit DampedLeastSquares(int n = (N == Eigen::Dynamic ? 0 : N)) { set_cols(n); }

  int cols() const noexcept { return n_; }
  /// Sets the column count (run-time N only); never allocates.
  void set_cols(int n) noexcept {
    n_ = n;
    k_ = n < M ? n : M;
    gram_.setZero();
    chol_.setZero();
    factored_ = false;
  }

  /// Factorises J (Gram matrix, singular values, damping). Must precede solve().
  /// With `exact_min_singular_value` false and k = 3, sigma_min is computed only inside
  /// the damped region: the LDL^T pivots of G - epsilon^2 I, all positive, certify
  /// sigma_min >= epsilon (to the resolution above) and hence lambda = 0, at the cost
  /// of one 3 x 3 factorisation instead of the eigenvalue computation; the result then
  /// reports epsilon as a lower bound (min_singular_value_exact false). The damping,
  /// and so the solution, are the same either way. k <= 2 is always exact (closed form).
  ///
  /// J is a Matrix or any M-row Eigen expression of the same column count cols(); one
  /// whose column count is fixed at compile time (a fixed-size view of a bounded J,
  /// controller/ik.hpp) runs the compile-time-sized code: the Gram product and the
  /// Cholesky factorisation unrolled, as for a fixed N. Its result is that of the
  /// fixed-N solver of that size, bitwise.
  template <typename DerivedJ>
  Result factorize(const Eigen::MatrixBase<DerivedJ>& J, const DampingSchedule<Scalar>& schedule,
                   bool exact_min_singular_value = true) noexcept {
    static_assert(DerivedJ::RowsAtCompileTime == M, "J has M rows");
    constexpr int C = DerivedJ::ColsAtCompileTime;
    constexpr int KC = factor_size(C);
    Result r;
    factored_ = false;
    if (!all_finite(J) || k_ < 1 || J.cols() != n_) return r;
    wide_ = n_ >= M;
    if constexpr (C != Eigen::Dynamic && C >= M) {
      gram_.template topLeftCorner<M, M>().noalias() = J * J.transpose();
    } else if (wide_) {  // run-time N: a sum of outer products of the fixed-size columns
      Eigen::Matrix<Scalar, M, M> g = Eigen::Matrix<Scalar, M, M>::Zero();
      for (int c = 0; c < n_; ++c) {
        const Eigen::Matrix<Scalar, M, 1> v = J.col(c);
        g.noalias() += v * v.transpose();
      }
      gram_.template topLeftCorner<M, M>() = g;
    } else {
      for (int a = 0; a < k_; ++a)
        for (int b = a; b < k_; ++b) gram_(a, b) = gram_(b, a) = J.col(a).dot(J.col(b));
    }
    if (!exact_min_singular_value && k_ == 3 &&
        detail::shifted_positive_definite_3x3(
            gram_, schedule.singular_threshold * schedule.singular_threshold)) {
      r.min_singular_value = schedule.singular_threshold;
      r.min_singular_value_exact = false;
      factored_ = cholesky<KC>(Scalar(0));
      r.valid = factored_;
      return r;
    }
    Scalar mu_min = smallest_eigenvalue();
    if (!(mu_min > Scalar(0))) mu_min = Scalar(0);
    r.min_singular_value = std::sqrt(mu_min);
    const Scalar l2 = schedule.damping_squared(r.min_singular_value);
    r.damping = std::sqrt(l2);
    r.damped = l2 > Scalar(0);
    factored_ = cholesky<KC>(l2);
    r.valid = factored_;
    return r;
  }

  /// x = J^+_lambda b for the last factorised J (a Matrix, or the same view factorize()
  /// was given; x a Solution or a vector of its fixed size). Writes zero if not factorised.
  template <typename DerivedJ, typename DerivedX>
  void solve(const Eigen::MatrixBase<DerivedJ>& J, const Rhs& b,
             Eigen::MatrixBase<DerivedX>& x) noexcept {
    constexpr int C = DerivedJ::ColsAtCompileTime;
    constexpr int KC = factor_size(C);
    constexpr bool kResizable = DerivedX::SizeAtCompileTime == Eigen::Dynamic;
    if (!factored_) {
      if constexpr (kResizable) {
        x.derived().setZero(n_);
      } else {
        x.setZero();
      }
      return;
    }
    // Zero-initialised: for M < 3 the unused tail would otherwise trip GCC 12's
    // -Wmaybe-uninitialized through the run-time-k Cholesky dispatch.
    Eigen::Matrix<Scalar, 3, 1> y = Eigen::Matrix<Scalar, 3, 1>::Zero();
    if (wide_) {
      y.template head<M>() = b;
      cholesky_solve<KC>(y);
      x.derived().noalias() = J.transpose() * y.template head<M>();
    } else if constexpr (C == Eigen::Dynamic ? kTallPossible : C < M) {
      for (int a = 0; a < k_; ++a) y(a) = J.col(a).dot(b);
      cholesky_solve<KC>(y);
      // Element-wise: a vectorised copy of y.head(k_) draws GCC 12 -Warray-bounds
      // false positives for float run-time column counts.
      if constexpr (kResizable) x.derived().resize(k_);
      for (int a = 0; a < k_; ++a) x(a) = y(a);
    }
  }

  /// The damped pseudo-inverse J^+_lambda (n x m) of the last factorised J.
  template <typename DerivedOut>
  void pseudo_inverse(const Matrix& J, Eigen::MatrixBase<DerivedOut>& out) noexcept {
    if (!factored_) {
      out.setZero();
      return;
    }
    Eigen::Matrix<Scalar, 3, 1> y;
    if (wide_) {  // J^T (G + l^2 I)^-1, column by column of the inverse
      Eigen::Matrix<Scalar, M, M> inv;
      for (int c = 0; c < M; ++c) {
        y.setZero();
        y(c) = Scalar(1);
        cholesky_solve<kFixedK>(y);
        inv.col(c) = y.template head<M>();
      }
      out.noalias() = J.transpose() * inv;
    } else if constexpr (kTallPossible) {  // (G + l^2 I)^-1 J^T
      for (int c = 0; c < M; ++c) {
        for (int a = 0; a < k_; ++a) y(a) = J(c, a);
        cholesky_solve<kFixedK>(y);
        for (int a = 0; a < k_; ++a) out(a, c) = y(a);
      }
    }
  }

 private:
  // Fewer columns than rows (least squares) can only occur for a run-time column
  // count or a fixed N < M. Compiling that branch out otherwise keeps GCC's
  // -Warray-bounds from flagging the (unreachable) copy of the 3-vector y into a
  // longer fixed-size solution.
  static constexpr bool kTallPossible = (N == Eigen::Dynamic) || (N < M);
  /// Smallest eigenvalue of the leading k x k block of the (symmetric) Gram matrix.
  Scalar smallest_eigenvalue() const noexcept {
    if (k_ == 1) return gram_(0, 0);
    if (k_ == 2) {
      const Scalar a = gram_(0, 0), b = gram_(0, 1), d = gram_(1, 1);
      const Scalar mean = Scalar(0.5) * (a + d);
      const Scalar half = std::hypot(Scalar(0.5) * (a - d), b);
      // mean - half cancels for near-singular blocks; det / larger root does not.
      const Scalar big = mean + half;
      return big > Scalar(0) ? (a * d - b * b) / big : Scalar(0);
    }
    return detail::smallest_eigenvalue_3x3(gram_);
  }

  /// Cholesky of the leading k x k block of G + l2 I into chol_ (lower). false if
  /// not positive definite (only possible for a rank-deficient J with l2 == 0).
  /// The size is a template argument so that the tiny loops unroll: KC = k when it is
  /// known at compile time (a fixed N or a fixed-size view), 0 to dispatch once on k.
  template <int KC>
  bool cholesky(Scalar l2) noexcept {
    if constexpr (KC > 0) {
      return cholesky_k<KC>(l2);
    } else {
      if (k_ == 1) return cholesky_k<1>(l2);
      if (k_ == 2) return cholesky_k<(M < 2 ? M : 2)>(l2);
      return cholesky_k<M>(l2);
    }
  }
  template <int KC>
  void cholesky_solve(Eigen::Matrix<Scalar, 3, 1>& y) const noexcept {
    if constexpr (KC > 0) {
      cholesky_solve_k<KC>(y);
    } else if (k_ == 1) {
      cholesky_solve_k<1>(y);
    } else if (k_ == 2) {
      cholesky_solve_k<(M < 2 ? M : 2)>(y);
    } else {
      cholesky_solve_k<M>(y);  // k = M: never instantiates a larger size than y holds
    }
  }
  /// k = min(M, N) when N is fixed, otherwise 0 (run-time).
  static constexpr int kFixedK = N == Eigen::Dynamic ? 0 : (N < M ? N : M);
  /// The Cholesky size for a J whose column count is C at compile time: min(M, C), or
  /// kFixedK when C is run-time (factorize() and solve() must agree on it).
  static constexpr int factor_size(int C) noexcept {
    return C == Eigen::Dynamic ? kFixedK : (C < M ? C : M);
  }

  template <int K>
  bool cholesky_k(Scalar l2) noexcept {
    for (int c = 0; c < K; ++c) {
      Scalar d = gram_(c, c) + l2;
      for (int p = 0; p < c; ++p) d -= chol_(c, p) * chol_(c, p);
      if (!(d > Scalar(0))) return false;
      d = std::sqrt(d);
      chol_(c, c) = d;
      // The substitutions multiply by the reciprocal: one division per pivot here
      // instead of two per solve on the latency chain.
      const Scalar inv = Scalar(1) / d;
      inv_diag_(c) = inv;
      for (int r = c + 1; r < K; ++r) {
        Scalar v = gram_(r, c);
        for (int p = 0; p < c; ++p) v -= chol_(r, p) * chol_(c, p);
        chol_(r, c) = v * inv;
      }
    }
    return true;
  }
  template <int K>
  void cholesky_solve_k(Eigen::Matrix<Scalar, 3, 1>& y) const noexcept {
    for (int r = 0; r < K; ++r) {
      Scalar v = y(r);
      for (int p = 0; p < r; ++p) v -= chol_(r, p) * y(p);
      y(r) = v * inv_diag_(r);
    }
    for (int r = K - 1; r >= 0; --r) {
      Scalar v = y(r);
      for (int p = r + 1; p < K; ++p) v -= chol_(p, r) * y(p);
      y(r) = v * inv_diag_(r);
    }
  }

  int n_ = 0;
  int k_ = 0;
  bool wide_ = true;
  bool factored_ = false;
  Eigen::Matrix<Scalar, 3, 3> gram_;
  Eigen::Matrix<Scalar, 3, 3> chol_;
  Eigen::Matrix<Scalar, 3, 1> inv_diag_ = Eigen::Matrix<Scalar, 3, 1>::Zero();
};

}  // namespace inhand
