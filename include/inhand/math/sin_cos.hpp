// Sine and cosine of several angles at once, for forward kinematics (one pair per joint).
//
//   sin_cos(q, s, c, n): s[i] = sin q[i], c[i] = cos q[i] for i < n. Radians in, no units out.
//
// In float and double the angles are reduced to r in [-pi/4, pi/4] by the nearest multiple
// k of pi/2, r = q - k pi/2 with pi/2 split into three parts (Cody and Waite), and sin r and
// cos r are evaluated by minimax polynomials: the coefficients of fdlibm's kernel_sin and
// kernel_cos in double, of Cephes' sinf and cosf in float; the quadrant k mod 4 swaps and
// signs them. The loop has no branch, so a compiler evaluates several angles per vector
// instruction (two doubles per SSE2 or NEON register, four per AVX2 register); every
// operation is plain C++, there are no intrinsics. libm's sin and cos take one angle per
// call. forward_kinematics uses the one-angle form in double (kinematics/finger_chain.hpp).
//
// Accuracy against std::sin and std::cos, measured over seeded sweeps by
// tests/math/sin_cos_test.cpp (x86-64, GCC 12): within kReducedRange = 1e5 rad (double)
// or 8192 rad (float) the absolute error is at most 2^-52 (double) or 2^-23 (float), one
// unit in the last place of 1, and sin q of a small q keeps that relative accuracy
// (sin q = q for |q| < 1e-8). The tests assert twice that: a compiler that fuses
// multiply-adds rounds differently. Outside that range, and for a NaN or an infinity, s and c are
// std::sin and std::cos of the angle (a second, scalar pass), so a non-finite angle gives NaN as
// there. Joint angles are within a few pi of 0. Other Scalar types (long double, automatic
// differentiation types) use std::sin and std::cos throughout.
// k is rounded to the nearest integer by truncating q 2/pi +- 1/2 to int, so the
// floating-point rounding mode does not change it. Compiled with -ffast-math, the
// reduction's three parts may be reassociated and the accuracy above is not kept.
// noexcept, no allocation, n >= 0 angles; q, s and c must not overlap.
#pragma once

#include <cmath>
#include <type_traits>

namespace inhand {

namespace detail {
/// The reduction and polynomial coefficients of sin_cos() per Scalar (none: std::sin/cos).
template <typename Scalar>
struct SinCosKernel {
  static constexpr bool kPolynomial = false;
};

template <>
struct SinCosKernel<double> {
  static constexpr bool kPolynomial = true;
  static constexpr double kReducedRange = 1e5;
  static constexpr double kTwoOverPi = 6.36619772367581382433e-01;
  // pi/2 = kPio2a + kPio2b + kPio2c; kPio2a has 33 significant bits, so k kPio2a is exact
  // for |k| < 2^20 (|q| < 1.6e6).
  static constexpr double kPio2a = 1.57079632673412561417e+00;
  static constexpr double kPio2b = 6.07710050650619224932e-11;
  static constexpr double kPio2c = 2.02226624879595063154e-21;
  static double sin_r(double r, double z) noexcept {
    return r + r * z *
                   (-1.66666666666666324348e-01 +
                    z * (8.33333333332248946124e-03 +
                         z * (-1.98412698298579493134e-04 +
                              z * (2.75573137070700676789e-06 +
                                   z * (-2.50507602534068634195e-08 +
                                        z * 1.58969099521155010221e-10)))));
  }
  static double cos_r(double z) noexcept {
    return 1.0 - 0.5 * z +
           z * z *
               (4.16666666666666019037e-02 +
                z * (-1.38888888888741095749e-03 +
                     z * (2.48015872894767294178e-05 +
                          z * (-2.75573143513906633035e-07 +
                               z * (2.08757232129817482790e-09 +
                                    z * -1.13596475577881948265e-11)))));
  }
};

template <>
struct SinCosKernel<float> {
  static constexpr bool kPolynomial = true;
  static constexpr float kReducedRange = 8192.0f;
  static constexpr float kTwoOverPi = 0.636619772f;
  // pi/2 = kPio2a + kPio2b + kPio2c; kPio2a has 8 significant bits.
  static constexpr float kPio2a = 1.5703125f;
  static constexpr float kPio2b = 4.837512969970703125e-4f;
  static constexpr float kPio2c = 7.54978995489188216e-8f;
  static float sin_r(float r, float z) noexcept {
    return r + r * z * (-1.6666654611e-1f + z * (8.3321608736e-3f + z * -1.9515295891e-4f));
  }
  static float cos_r(float z) noexcept {
    return 1.0f - 0.5f * z +
           z * z *
               (4.166664568298827e-2f + z * (-1.388731625493765e-3f + z * 2.443315711809948e-5f));
  }
};
}  // namespace detail

namespace detail {
/// The polynomial part for one angle of at most the kernel's reduced range (the file
/// comment); for a larger, infinite or NaN angle its s and c mean nothing, and the callers
/// replace them. Kept free of loops and calls so that it inlines wherever it is used.
template <typename Scalar>
inline void sin_cos_reduced(Scalar q, Scalar& s, Scalar& c) noexcept {
  using K = SinCosKernel<Scalar>;
  // k = nearest integer to q 2/pi, 0 for an angle outside the reduced range (its s and c
  // are replaced by the caller; the int conversion of a larger one would overflow). Only
  // the conversion's argument is selected: GCC 12 vectorises the array loop so.
  const Scalar t = q * K::kTwoOverPi;
  const Scalar t_in = std::abs(q) <= K::kReducedRange ? t : Scalar(0);
  const int k = static_cast<int>(t_in + std::copysign(Scalar(0.5), t));
  const Scalar kf = static_cast<Scalar>(k);
  const Scalar r = ((q - kf * K::kPio2a) - kf * K::kPio2b) - kf * K::kPio2c;
  const Scalar z = r * r;
  const Scalar sr = K::sin_r(r, z), cr = K::cos_r(z);
  // q = r + k pi/2: sin q = (sin r, cos r, -sin r, -cos r) and cos q = (cos r, -sin r,
  // -cos r, sin r) for k mod 4 = 0, 1, 2, 3.
  const Scalar sq = (k & 1) ? cr : sr, cq = (k & 1) ? sr : cr;
  s = (k & 2) ? -sq : sq;
  c = ((k + 1) & 2) ? -cq : cq;
}
}  // namespace detail

/// s[i] = sin q[i] and c[i] = cos q[i] for i in [0, n) (file comment: method, accuracy).
template <typename Scalar>
inline void sin_cos(const Scalar* q, Scalar* s, Scalar* c, int n) noexcept {
  using K = detail::SinCosKernel<Scalar>;
  if constexpr (K::kPolynomial) {
    for (int i = 0; i < n; ++i) detail::sin_cos_reduced<Scalar>(q[i], s[i], c[i]);
    for (int i = 0; i < n; ++i) {
      if (!(std::abs(q[i]) <= K::kReducedRange)) {
        s[i] = std::sin(q[i]);
        c[i] = std::cos(q[i]);
      }
    }
  } else {
    for (int i = 0; i < n; ++i) {
      s[i] = std::sin(q[i]);
      c[i] = std::cos(q[i]);
    }
  }
}

/// One angle: s = sin q, c = cos q, the same values as sin_cos(&q, &s, &c, 1).
template <typename Scalar>
inline void sin_cos(Scalar q, Scalar& s, Scalar& c) noexcept {
  using K = detail::SinCosKernel<Scalar>;
  if constexpr (K::kPolynomial) {
    if (std::abs(q) <= K::kReducedRange) {
      detail::sin_cos_reduced<Scalar>(q, s, c);
      return;
    }
  }
  s = std::sin(q);
  c = std::cos(q);
}

}  // namespace inhand
