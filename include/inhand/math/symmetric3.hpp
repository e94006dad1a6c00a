// The smallest eigenvalue of a symmetric positive semi-definite 3 x 3 matrix G (the Gram
// matrix J J^T of a contact Jacobian, math/damped_least_squares.hpp), and the LDL^T
// tests on G - x I it rests on. Fixed 3 x 3 storage: no allocation; noexcept.
#pragma once

#include <Eigen/Eigenvalues>
#include <cmath>

#include "inhand/math/jacobi_eigen.hpp"
#include "inhand/math/types.hpp"

namespace inhand {
namespace detail {

/// True if the three LDL^T pivots of G - x I are positive (x below G's smallest
/// eigenvalue, to rounding): the pivots d0, d1 and d1 d2 (one division).
template <typename Scalar>
bool shifted_positive_definite_3x3(const Eigen::Matrix<Scalar, 3, 3>& G, Scalar x) noexcept {
  const Scalar d0 = G(0, 0) - x;
  if (!(d0 > Scalar(0))) return false;
  const Scalar i0 = Scalar(1) / d0;
  const Scalar l10 = G(1, 0) * i0, l20 = G(2, 0) * i0;
  const Scalar d1 = G(1, 1) - x - l10 * G(1, 0);
  if (!(d1 > Scalar(0))) return false;
  const Scalar e21 = G(2, 1) - l20 * G(1, 0);
  return (G(2, 2) - x - l20 * G(2, 0)) * d1 - e21 * e21 > Scalar(0);
}

/// tr((G - x I)^-1) from the LDL^T factorisation of G - x I; false if a pivot is not
/// positive (x is not below the smallest eigenvalue, or G is not finite).
template <typename Scalar>
bool shifted_inverse_trace_3x3(const Eigen::Matrix<Scalar, 3, 3>& G, Scalar x,
                               Scalar& out) noexcept {
  const Scalar d0 = G(0, 0) - x;
  if (!(d0 > Scalar(0))) return false;
  const Scalar i0 = Scalar(1) / d0;
  const Scalar l10 = G(1, 0) * i0, l20 = G(2, 0) * i0;
  const Scalar d1 = G(1, 1) - x - l10 * G(1, 0);
  if (!(d1 > Scalar(0))) return false;
  const Scalar i1 = Scalar(1) / d1;
  const Scalar e21 = G(2, 1) - l20 * G(1, 0);
  const Scalar l21 = e21 * i1;
  const Scalar d2 = G(2, 2) - x - l20 * G(2, 0) - l21 * e21;
  if (!(d2 > Scalar(0))) return false;
  const Scalar i2 = Scalar(1) / d2;
  // (G - x I)^-1 = L^-T D^-1 L^-1 with L^-1 = [1 0 0; -l10 1 0; l10 l21 - l20, -l21, 1].
  const Scalar m20 = l10 * l21 - l20;
  out = i0 + (Scalar(1) + l10 * l10) * i1 + (Scalar(1) + l21 * l21 + m20 * m20) * i2;
  return true;
}

/// Smallest eigenvalue of a symmetric positive semi-definite 3 x 3 matrix G, to
/// |error| ~ eps |G| (the resolution of a backward-stable solver).
/// Newton's method on det(G - x I) from below, started just under the closed-form
/// (trigonometric) estimate: for x < mu_min, G - x I is positive definite, its LDL^T
/// factorisation is backward stable, and the Newton step 1 / tr((G - x I)^-1) never
/// overshoots mu_min, so every iterate is a lower bound. The closed form alone is
/// not accurate enough (up to ~1e7 eps |G| off for clustered eigenvalues), but its
/// error is small next to the gap to the second eigenvalue whenever that gap is not
/// tiny, and then one step reaches eps |G|. When the start is not below mu_min
/// (the closed form was further off than the margin allows) or the iteration does
/// not settle within four steps (clustered smallest eigenvalues), the Jacobi rotations of
/// math/jacobi_eigen.hpp decide. Fixed 3 x 3 storage: no allocation on any path.
template <typename Scalar>
Scalar smallest_eigenvalue_3x3(const Eigen::Matrix<Scalar, 3, 3>& G) noexcept {
  const Scalar tr = G.trace();
  if (!(tr > Scalar(0))) return Scalar(0);
  const Scalar tiny = Eigen::NumTraits<Scalar>::epsilon() * tr;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix<Scalar, 3, 3>> eig;
  eig.computeDirect(G, Eigen::EigenvaluesOnly);
  const Eigen::Matrix<Scalar, 3, 1> e = eig.eigenvalues();
  // Start below the estimate by more than its error, which was measured to stay
  // under ~30 eps tr sqrt(tr / gap) (gap: the estimated distance to the second
  // eigenvalue); a start that is still too high is detected and handed over.
  const Scalar gap = e(1) - e(0);
  const Scalar margin = Scalar(64) * tiny * std::sqrt(tr / (gap > tiny ? gap : tiny));
  const bool separated = gap > Scalar(8) * margin;  // e(1), e(2) then usable as bounds
  Scalar x = e(0) - margin;
  for (int it = 0; it < 4; ++it) {
    Scalar inverse_trace;
    if (!shifted_inverse_trace_3x3(G, x, inverse_trace)) {
      // At a later step x has reached mu_min to within rounding.
      if (it == 0) break;
      return x > Scalar(0) ? x : Scalar(0);
    }
    const Scalar step = Scalar(1) / inverse_trace;
    x += step;
    if (step <= tiny) return x > Scalar(0) ? x : Scalar(0);
    if (separated) {
      // After a step of length s from below, mu_min - x ~ s^2 sum_{i>1} 1/(mu_i - mu_min).
      const Scalar d2 = e(1) - margin - x, d3 = e(2) - margin - x;
      if (d2 > Scalar(0) && Scalar(2) * step * step * (Scalar(1) / d2 + Scalar(1) / d3) <= tiny)
        return x > Scalar(0) ? x : Scalar(0);
    }
  }
  SymmetricEigen<Scalar, 3> jacobi;
  jacobi.compute(G);
  return jacobi.values(0);
}

}  // namespace detail
}  // namespace inhand
