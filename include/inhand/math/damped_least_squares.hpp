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

#include <Eigen/Cholesky>
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

/// Solver with preallocated workspace for an M x N matrix. N may be Eigen::Dynamic,
/// with MaxN a fixed capacity (no allocation) or Eigen::Dynamic (heap, sized once).
template <typename Scalar, int M, int N, int MaxN = N>
class DampedLeastSquares {
 public:
  static constexpr int K = (N == Eigen::Dynamic) ? Eigen::Dynamic : (M < N ? M : N);
  static constexpr int MaxK = (MaxN == Eigen::Dynamic) ? Eigen::Dynamic : (M < MaxN ? M : MaxN);
  using Matrix = Eigen::Matrix<Scalar, M, N, Eigen::ColMajor, M, MaxN>;
  using Rhs = Eigen::Matrix<Scalar, M, 1>;
  using Solution = Eigen::Matrix<Scalar, N, 1, Eigen::ColMajor, MaxN, 1>;
  using Gram = Eigen::Matrix<Scalar, K, K, Eigen::ColMajor, MaxK, MaxK>;
  using Inverse = Eigen::Matrix<Scalar, N, M, Eigen::ColMajor, MaxN, M>;

  struct Result {
    Scalar min_singular_value = Scalar(0);
    Scalar damping = Scalar(0);  ///< lambda (not squared)
    bool damped = false;
    bool valid = false;  ///< false: non-finite matrix, solution set to zero
  };

  explicit DampedLeastSquares(int n = (N == Eigen::Dynamic ? 0 : N))
      : n_(n),
        k_(std::min(M, n)),
        gram_(k_, k_),
        eig_(k_),
        llt_(k_),
        tmp_k_(k_),
        tmp_k2_(k_) {}

  int cols() const noexcept { return n_; }

  /// Factorises J (Gram matrix, singular values, damping). Must precede solve().
  Result factorize(const Matrix& J, const DampingSchedule<Scalar>& schedule) noexcept {
    Result r;
    if (!all_finite(J)) {
      factored_ = false;
      return r;
    }
    wide_ = n_ >= M;
    if (wide_) {
      gram_.noalias() = J * J.transpose();
    } else {
      gram_.noalias() = J.transpose() * J;
    }
    compute_eigenvalues();
    Scalar mu_min = eig_.eigenvalues()(0);  // ascending order
    if (mu_min < Scalar(0)) mu_min = Scalar(0);
    r.min_singular_value = std::sqrt(mu_min);
    const Scalar l2 = schedule.damping_squared(r.min_singular_value);
    r.damping = std::sqrt(l2);
    r.damped = l2 > Scalar(0);
    r.valid = true;
    gram_.diagonal().array() += l2;
    llt_.compute(gram_);
    factored_ = llt_.info() == Eigen::Success;
    r.valid = factored_;
    return r;
  }

  /// x = J^+_lambda b for the last factorised J. Writes zero if not factorised.
  void solve(const Matrix& J, const Rhs& b, Solution& x) noexcept {
    if (!factored_) {
      x.setZero();
      return;
    }
    if (wide_) {
      tmp_k_ = llt_.solve(b);
      x.noalias() = J.transpose() * tmp_k_;
    } else {
      tmp_k2_.noalias() = J.transpose() * b;
      tmp_k_ = llt_.solve(tmp_k2_);
      x = tmp_k_;
    }
  }

  /// The damped pseudo-inverse J^+_lambda (n x m) of the last factorised J.
  template <typename DerivedOut>
  void pseudo_inverse(const Matrix& J, Eigen::MatrixBase<DerivedOut>& out) noexcept {
    if (!factored_) {
      out.setZero();
      return;
    }
    if (wide_) {
      out.noalias() = J.transpose() * llt_.solve(Gram::Identity(k_, k_));
    } else {
      out.noalias() = llt_.solve(J.transpose());
    }
  }

 private:
  void compute_eigenvalues() noexcept {
    if constexpr (K == 2 || K == 3) {
      eig_.computeDirect(gram_, Eigen::EigenvaluesOnly);
    } else {
      eig_.compute(gram_, Eigen::EigenvaluesOnly);
    }
  }

  int n_;
  int k_;
  bool wide_ = true;
  bool factored_ = false;
  Gram gram_;
  Eigen::SelfAdjointEigenSolver<Gram> eig_;
  Eigen::LLT<Gram> llt_;
  Eigen::Matrix<Scalar, K, 1, Eigen::ColMajor, MaxK, 1> tmp_k_;
  Eigen::Matrix<Scalar, K, 1, Eigen::ColMajor, MaxK, 1> tmp_k2_;
};

}  // namespace inhand
