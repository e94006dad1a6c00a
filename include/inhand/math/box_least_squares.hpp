// Box-constrained damped least squares for a small M x N matrix (M <= 3): the joint
// position limits of the contact IK (controller/ik.hpp, docs/method.md section 4).
//
//   minimise   f(z) = |J z - b|^2 + lambda^2 |z|^2     subject to  lo <= z <= hi
//
// with lo <= 0 <= hi (so z = 0 is feasible). lambda = 0 is allowed: f is then only
// convex, and among the minimisers over the free coordinates the minimum-norm one is
// taken. Method: a primal active-set method started at z = 0. Each iteration solves the
// problem over the free coordinates with the held ones fixed at their bound,
//   z_F = J_F^T (J_F J_F^T + lambda^2 I)^+ r,   r = b - J_H z_H
// (the M x M pseudo-inverse from its eigen-decomposition, so a free set that cannot span
// the task gives its least-squares solution), steps from the current feasible point
// towards it as far as the box allows, and holds the coordinate that blocks the step.
// When the step is not blocked, the held coordinates whose multiplier has the wrong sign
// (the gradient g = J^T (J z - b) + lambda^2 z points out of the box: g_i > 0 at an
// upper bound, g_i < 0 at a lower bound) are released, the most violating first. The
// Karush-Kuhn-Tucker conditions then hold: the result is the minimum of f over the box.
// Every iterate is feasible, f never increases, and the iteration count is capped at
// 3 N + 3 (each coordinate held, released and held again at most once in practice); at
// the cap the current (feasible) iterate is returned with `converged` false.
// Sizes: N = Eigen::Dynamic with MaxN fixed never allocates; the M x M work is fixed
// size. noexcept.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "inhand/math/jacobi_eigen.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar>
struct BoxLeastSquaresResult {
  std::uint32_t held = 0;  ///< bit i: coordinate i ended at a bound (i < 32)
  int iterations = 0;
  bool converged = true;  ///< false: the iteration cap was reached (z still feasible)
};

template <typename Scalar, int M, int N, int MaxN = N>
class BoxLeastSquares {
  static_assert(M >= 1 && M <= 3, "box least squares for 1 to 3 rows");

 public:
  using Matrix = Eigen::Matrix<Scalar, M, N, Eigen::ColMajor, M, MaxN>;
  using Rhs = Eigen::Matrix<Scalar, M, 1>;
  using Vector = Eigen::Matrix<Scalar, N, 1, Eigen::ColMajor, MaxN, 1>;

  explicit BoxLeastSquares(int n = (N == Eigen::Dynamic ? 0 : N)) { set_cols(n); }
  /// Sizes the work vectors (run-time N only; allocates only for MaxN == Dynamic).
  void set_cols(int n) {
    candidate_.setZero(n);
    gradient_.setZero(n);
    state_.setZero(n);
  }

  /// Minimises f over the box; z (size N) receives the minimiser. Preconditions (the
  /// caller's): J, b, lo, hi finite, lambda2 >= 0, lo <= 0 <= hi, n <= 32 for the
  /// `held` bits (larger n solve correctly, their bits are not reported).
  BoxLeastSquaresResult<Scalar> solve(const Matrix& J, const Rhs& b, Scalar lambda2,
                                      const Vector& lo, const Vector& hi, Vector& z) noexcept {
    BoxLeastSquaresResult<Scalar> res;
    const int n = static_cast<int>(J.cols());
    z.setZero(n);
    for (int i = 0; i < n; ++i) state_(i) = kFree;
    const int cap = 3 * n + 3;
    const Scalar eps = Eigen::NumTraits<Scalar>::epsilon();
    const Scalar scale = J.norm() * (J.norm() * (hi - lo).cwiseAbs().maxCoeff() + b.norm());
    const Scalar tol = Scalar(64) * eps * (scale > Scalar(0) ? scale : Scalar(1));
    for (res.iterations = 0; res.iterations < cap; ++res.iterations) {
      free_optimum(J, b, lambda2, z);
      // The longest step along candidate - z that stays inside the box.
      Scalar alpha = Scalar(1);
      int blocking = -1;
      for (int i = 0; i < n; ++i) {
        if (state_(i) != kFree) continue;
        const Scalar d = candidate_(i) - z(i);
        Scalar a = Scalar(1);
        if (candidate_(i) > hi(i) && d > Scalar(0)) a = (hi(i) - z(i)) / d;
        if (candidate_(i) < lo(i) && d < Scalar(0)) a = (lo(i) - z(i)) / d;
        if (a < alpha) {
          alpha = std::max(a, Scalar(0));
          blocking = i;
        }
      }
      for (int i = 0; i < n; ++i)
        if (state_(i) == kFree) z(i) += alpha * (candidate_(i) - z(i));
      if (blocking >= 0) {
        const bool upper = candidate_(blocking) > hi(blocking);
        z(blocking) = upper ? hi(blocking) : lo(blocking);
        state_(blocking) = upper ? kUpper : kLower;
        continue;
      }
      // Unblocked: z is the optimum for this held set. Release a held coordinate whose
      // multiplier has the wrong sign, if any.
      gradient_.noalias() = J.transpose() * (J * z - b);
      gradient_ += lambda2 * z;
      int release = -1;
      Scalar worst = tol;
      for (int i = 0; i < n; ++i) {
        const Scalar v = state_(i) == kUpper   ? gradient_(i)
                         : state_(i) == kLower ? -gradient_(i)
                                               : Scalar(0);
        if (v > worst) {
          worst = v;
          release = i;
        }
      }
      if (release < 0) break;
      state_(release) = kFree;
    }
    res.converged = res.iterations < cap;
    for (int i = 0; i < n && i < 32; ++i)
      if (state_(i) != kFree) res.held |= (std::uint32_t{1} << i);
    // Rounding in the step can leave a free coordinate an ulp outside its bound.
    z = z.cwiseMax(lo).cwiseMin(hi);
    return res;
  }

 private:
  static constexpr Scalar kFree = Scalar(0), kLower = Scalar(1), kUpper = Scalar(2);

  /// candidate_ = z with the free coordinates replaced by the optimum over them.
  void free_optimum(const Matrix& J, const Rhs& b, Scalar lambda2, const Vector& z) noexcept {
    const int n = static_cast<int>(J.cols());
    Eigen::Matrix<Scalar, M, M> g = lambda2 * Eigen::Matrix<Scalar, M, M>::Identity();
    Rhs r = b;
    for (int i = 0; i < n; ++i) {
      if (state_(i) == kFree)
        g.noalias() += J.col(i) * J.col(i).transpose();
      else
        r -= J.col(i) * z(i);
    }
    Rhs y;
    if constexpr (M == 1) {
      y(0) = g(0, 0) > Scalar(0) ? r(0) / g(0, 0) : Scalar(0);
    } else {
      // Jacobi rotations (math/jacobi_eigen.hpp): their eigenvalues are accurate to
      // ~eps |G| absolutely, so the null directions of a free set that cannot span the
      // task fall below the cut; the closed form is not accurate enough for that.
      detail::SymmetricEigen<Scalar, M> eig;
      eig.compute(g);
      const Rhs mu = eig.values;
      const Scalar cut =
          Scalar(64) * Eigen::NumTraits<Scalar>::epsilon() * mu.cwiseAbs().maxCoeff();
      Rhs w = eig.vectors.transpose() * r;
      for (int k = 0; k < M; ++k) w(k) = mu(k) > cut ? w(k) / mu(k) : Scalar(0);
      y.noalias() = eig.vectors * w;
    }
    for (int i = 0; i < n; ++i) candidate_(i) = state_(i) == kFree ? J.col(i).dot(y) : z(i);
  }

  Vector candidate_;
  Vector gradient_;
  /// Per coordinate: kFree, kLower or kUpper, stored as Scalar (the same bounded storage
  /// as the solution; a byte vector of bounded size draws GCC 12 -Wstringop-overflow
  /// false positives when the solver is copied).
  Vector state_;
};

}  // namespace inhand
