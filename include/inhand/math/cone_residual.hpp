// Distance from a point to a convex cone given by its generators, in 1 to 3 dimensions:
// the non-negative least-squares problem
//
//   t* = argmin_{t >= 0} |y - G t|^2,   r = y - G t*,
//
// G's columns the rays g_0 .. g_{m-1}. r is the residual: r = 0 when y lies in the cone;
// otherwise r^T g_i <= 0 for every ray and r^T y = |r|^2 > 0 (the optimality conditions),
// so r separates y from the cone: r^T x <= 0 for every x in it.
//
// Method: an optimal t* can be taken with linearly independent rays in its support
// (Caratheodory's theorem for cones), so at most Dim of them. Every subset of at most Dim
// rays is solved by its normal equations (a k x k Cholesky, k <= 3); a subset whose
// solution has a negative entry, or whose rays are (nearly) dependent, is passed over;
// the smallest residual of the rest, and of t = 0, is the optimum. Nearly dependent means
// a ray within about 1e-3 rad of the others' span (small_spd_solve): a point the cone
// reaches only through such a sliver, with coefficients of that inverse size, reads as
// outside it. m rays cost at most
// C(m, 1) + ... + C(m, Dim) solves: bounded time for the few rays this is used for (the
// held joints of one finger). No allocation; noexcept.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>

namespace inhand::detail {

/// Solves the k x k (k <= 3) symmetric system Q t = b (Q's lower triangle read) by
/// Cholesky; false when a pivot is not finite or not above max(1e-6, 1e3 eps) times its
/// diagonal entry: a ray at an angle below about 1e-3 rad (float: 0.011 rad) to the span
/// of the others counts as dependent on them, since the solution would amplify rounding by
/// the inverse of that angle.
template <typename Scalar>
inline bool small_spd_solve(const Eigen::Matrix<Scalar, 3, 3>& Q, int k,
                            Eigen::Matrix<Scalar, 3, 1>& t) noexcept {
  const Scalar tol = std::max(Scalar(1e-6), Scalar(1e3) * std::numeric_limits<Scalar>::epsilon());
  Eigen::Matrix<Scalar, 3, 3> L = Eigen::Matrix<Scalar, 3, 3>::Zero();
  for (int c = 0; c < k; ++c) {
    Scalar d = Q(c, c);
    for (int p = 0; p < c; ++p) d -= L(c, p) * L(c, p);
    if (!(d > tol * Q(c, c)) || !std::isfinite(d)) return false;
    L(c, c) = std::sqrt(d);
    for (int r = c + 1; r < k; ++r) {
      Scalar v = Q(r, c);
      for (int p = 0; p < c; ++p) v -= L(r, p) * L(c, p);
      L(r, c) = v / L(c, c);
    }
  }
  for (int r = 0; r < k; ++r) {  // L z = b, then L^T t = z
    for (int p = 0; p < r; ++p) t(r) -= L(r, p) * t(p);
    t(r) /= L(r, r);
  }
  for (int r = k - 1; r >= 0; --r) {
    for (int p = r + 1; p < k; ++p) t(r) -= L(p, r) * t(p);
    t(r) /= L(r, r);
  }
  return true;
}

/// The file comment: writes r and returns |r|^2. ray(i, g) writes ray i into g and returns
/// true, or returns false when index i is not a ray (it is skipped); i runs over [0, m).
template <typename Scalar, int Dim, typename Ray>
Scalar cone_residual(const Eigen::Matrix<Scalar, Dim, 1>& y, int m, Ray&& ray,
                     Eigen::Matrix<Scalar, Dim, 1>& r) noexcept {
  static_assert(Dim >= 1 && Dim <= 3, "cone_residual: 1 to 3 dimensions");
  using Vec = Eigen::Matrix<Scalar, Dim, 1>;
  r = y;
  Scalar best = y.squaredNorm();
  Vec g[3];
  const auto consider = [&](int k) {
    Eigen::Matrix<Scalar, 3, 3> Q = Eigen::Matrix<Scalar, 3, 3>::Zero();
    Eigen::Matrix<Scalar, 3, 1> t = Eigen::Matrix<Scalar, 3, 1>::Zero();
    for (int a = 0; a < k; ++a) {
      t(a) = g[a].dot(y);
      for (int c = 0; c <= a; ++c) Q(a, c) = g[a].dot(g[c]);
    }
    if (!small_spd_solve<Scalar>(Q, k, t)) return;
    Vec res = y;
    for (int a = 0; a < k; ++a) {
      if (!(t(a) >= Scalar(0))) return;
      res -= t(a) * g[a];
    }
    const Scalar s = res.squaredNorm();
    if (s < best) {
      best = s;
      r = res;
    }
  };
  for (int i = 0; i < m; ++i) {
    if (!ray(i, g[0])) continue;
    consider(1);
    if constexpr (Dim >= 2) {
      for (int j = i + 1; j < m; ++j) {
        if (!ray(j, g[1])) continue;
        consider(2);
        if constexpr (Dim >= 3) {
          for (int l = j + 1; l < m; ++l)
            if (ray(l, g[2])) consider(3);
        }
      }
    }
  }
  return best;
}

}  // namespace inhand::detail
