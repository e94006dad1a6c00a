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

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar>
struct DampingSchedule {
  /// Singular-value threshold epsilon (units of J, m/rad for a contact Jacobian), > 0.
  Scalar singular_threshold = Scalar(5e-3);
  /// Damping lambda reached at sigma_min = 0 (same units), >= 0.
  Scalar max_damping = Scalar(5e-3);

  Validation validate() const noexcept {
    if (!is_finite(singular_threshold) || !(singular_threshold > Scalar(0)))
      return Validation::invalid("singular_threshold", "must be finite and > 0");
    if (!is_finite(max_damping) || !(max_damping >= Scalar(0)))
      return Validation::invalid("max_damping", "must be finite and >= 0");
    return Validation::valid();
  }
  /// lambda^2 for a given smallest singular value.
  Scalar damping_squared(Scalar sigma_min) const noexcept {
    if (sigma_min >= singular_threshold) return Scalar(0);
    const Scalar r = sigma_min / singular_threshold;
    return max_damping * max_damping * (Scalar(1) - r * r);
  }
  /// sup over sigma >= 0 of sigma / (sigma^2 + lambda^2(sigma)): |x| <= this * |b|.
  /// Infinite when max_damping == 0 (no damping: no bound near singularity).
  Scalar gain_bound() const noexcept {
    const Scalar e = singular_threshold, l = max_damping;
    if (!(l > Scalar(0))) return std::numeric_limits<Scalar>::infinity();
    // For sigma < e: f = sigma / (l^2 + c sigma^2), c = 1 - l^2/e^2.
    const Scalar c = Scalar(1) - (l * l) / (e * e);
    Scalar best = Scalar(1) / e;  // undamped region and the boundary
    if (c > Scalar(0)) {
      const Scalar s_star = l / std::sqrt(c);
      if (s_star < e) best = std::max(best, Scalar(1) / (Scalar(2) * l * std::sqrt(c)));
    }
    return best;
  }
};

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
    Scalar min_singular_value = Scalar(0);
    Scalar damping = Scalar(0);  ///< lambda (not squared)
    bool damped = false;
    bool valid = false;  ///< false: non-finite matrix, solution set to zero
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
  Result factorize(const Matrix& J, const DampingSchedule<Scalar>& schedule) noexcept {
    Result r;
    factored_ = false;
    if (!all_finite(J) || k_ < 1) return r;
    wide_ = n_ >= M;
    if (wide_) {
      gram_.template topLeftCorner<M, M>().noalias() = J * J.transpose();
    } else {
      for (int a = 0; a < k_; ++a)
        for (int b = a; b < k_; ++b) gram_(a, b) = gram_(b, a) = J.col(a).dot(J.col(b));
    }
    Scalar mu_min = smallest_eigenvalue();
    if (!(mu_min > Scalar(0))) mu_min = Scalar(0);
    r.min_singular_value = std::sqrt(mu_min);
    const Scalar l2 = schedule.damping_squared(r.min_singular_value);
    r.damping = std::sqrt(l2);
    r.damped = l2 > Scalar(0);
    factored_ = cholesky(l2);
    r.valid = factored_;
    return r;
  }

  /// x = J^+_lambda b for the last factorised J. Writes zero if not factorised.
  void solve(const Matrix& J, const Rhs& b, Solution& x) noexcept {
    if (!factored_) {
      x.setZero(n_);
      return;
    }
    Eigen::Matrix<Scalar, 3, 1> y;
    if (wide_) {
      y.template head<M>() = b;
      cholesky_solve(y);
      x.noalias() = J.transpose() * y.template head<M>();
    } else if constexpr (kTallPossible) {
      for (int a = 0; a < k_; ++a) y(a) = J.col(a).dot(b);
      cholesky_solve(y);
      // Element-wise: a vectorised copy of y.head(k_) draws GCC 12 -Warray-bounds
      // false positives for float run-time column counts.
      x.resize(k_);
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
        cholesky_solve(y);
        inv.col(c) = y.template head<M>();
      }
      out.noalias() = J.transpose() * inv;
    } else if constexpr (kTallPossible) {  // (G + l^2 I)^-1 J^T
      for (int c = 0; c < M; ++c) {
        for (int a = 0; a < k_; ++a) y(a) = J(c, a);
        cholesky_solve(y);
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
    Eigen::Matrix<Scalar, 3, 1> ev;
    // The iterative (QR) solver is backward stable: |error| ~ eps * |G|, i.e. the
    // resolution stated above. The closed-form computeDirect() was measured 1e7 times
    // worse on the smallest eigenvalue of near-singular 3 x 3 Gram matrices (double).
    // Fixed 3 x 3: no allocation either way.
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Scalar, 3, 3>> eig;
    eig.compute(gram_, Eigen::EigenvaluesOnly);
    ev = eig.eigenvalues();
    return ev(0);
  }

  /// Cholesky of the leading k x k block of G + l2 I into chol_ (lower). false if
  /// not positive definite (only possible for a rank-deficient J with l2 == 0).
  bool cholesky(Scalar l2) noexcept {
    for (int c = 0; c < k_; ++c) {
      Scalar d = gram_(c, c) + l2;
      for (int p = 0; p < c; ++p) d -= chol_(c, p) * chol_(c, p);
      if (!(d > Scalar(0))) return false;
      d = std::sqrt(d);
      chol_(c, c) = d;
      for (int r = c + 1; r < k_; ++r) {
        Scalar v = gram_(r, c);
        for (int p = 0; p < c; ++p) v -= chol_(r, p) * chol_(c, p);
        chol_(r, c) = v / d;
      }
    }
    return true;
  }
  void cholesky_solve(Eigen::Matrix<Scalar, 3, 1>& y) const noexcept {
    for (int r = 0; r < k_; ++r) {
      Scalar v = y(r);
      for (int p = 0; p < r; ++p) v -= chol_(r, p) * y(p);
      y(r) = v / chol_(r, r);
    }
    for (int r = k_ - 1; r >= 0; --r) {
      Scalar v = y(r);
      for (int p = r + 1; p < k_; ++p) v -= chol_(p, r) * y(p);
      y(r) = v / chol_(r, r);
    }
  }

  int n_ = 0;
  int k_ = 0;
  bool wide_ = true;
  bool factored_ = false;
  Eigen::Matrix<Scalar, 3, 3> gram_;
  Eigen::Matrix<Scalar, 3, 3> chol_;
};

}  // namespace inhand
