// Rotations: SO(3) exp/log, the Euler convention and its rate matrix, and the
// planar (SO(2)) counterparts used when Dim == 2.
//
// Euler convention (docs/method.md section 3, the user-facing edge only): roll-pitch-yaw
// angles (phi, theta, psi) about the FIXED world axes x, then y, then z:
//     R = Rz(psi) * Ry(theta) * Rx(phi)
// (equivalently intrinsic z-y'-x''). With theta = psi = 0, phi is a rotation about
// world x, which is the paper's "Euler angle alpha" of Fig. 3b. The rate matrix E
// maps Euler rates to the angular velocity in the WORLD frame:
//     omega = E(phi, theta, psi) * (phi_dot, theta_dot, psi_dot)
// and is singular at theta = +-pi/2 (gimbal lock); euler_rates_from_omega reports it.
// Internally inhand keeps orientation as a rotation matrix; Euler angles are only
// for input/output.
#pragma once

#include <cmath>

#include "inhand/math/types.hpp"

namespace inhand {

/// Skew-symmetric matrix [w]x such that [w]x * r == w.cross(r).
template <typename Scalar>
inline Eigen::Matrix<Scalar, 3, 3> hat(const Vector<Scalar, 3>& w) noexcept {
  Eigen::Matrix<Scalar, 3, 3> m;
  m << Scalar(0), -w.z(), w.y(), w.z(), Scalar(0), -w.x(), -w.y(), w.x(), Scalar(0);
  return m;
}

/// Rotation angle threshold below which exp/log use Taylor series.
template <typename Scalar>
constexpr Scalar small_angle() noexcept {
  return std::is_same<Scalar, float>::value ? Scalar(1e-3) : Scalar(1e-6);
}

/// SO(3) exponential: rotation by |w| about w / |w| (Rodrigues).
template <typename Scalar>
inline Rotation<Scalar, 3> so3_exp(const Vector<Scalar, 3>& w) noexcept {
  const Scalar theta2 = w.squaredNorm();
  const Scalar theta = std::sqrt(theta2);
  Scalar a, b;  // R = I + a [w]x + b [w]x^2
  if (theta < small_angle<Scalar>()) {
    a = Scalar(1) - theta2 / Scalar(6);
    b = Scalar(0.5) - theta2 / Scalar(24);
  } else {
    a = std::sin(theta) / theta;
    b = (Scalar(1) - std::cos(theta)) / theta2;
  }
  const Eigen::Matrix<Scalar, 3, 3> W = hat(w);
  return Rotation<Scalar, 3>::Identity() + a * W + b * (W * W);
}

/// SO(3) logarithm: the rotation vector w with so3_exp(w) == R and |w| <= pi.
/// Accurate near 0 (Taylor series) and near pi (axis from the symmetric part).
template <typename Scalar>
inline Vector<Scalar, 3> so3_log(const Rotation<Scalar, 3>& R) noexcept {
  const Scalar tr = R.trace();
  Scalar c = (tr - Scalar(1)) / Scalar(2);
  c = c > Scalar(1) ? Scalar(1) : (c < Scalar(-1) ? Scalar(-1) : c);
  const Vector<Scalar, 3> v(R(2, 1) - R(1, 2), R(0, 2) - R(2, 0), R(1, 0) - R(0, 1));
  const Scalar s = Scalar(0.5) * v.norm();  // sin(theta)
  const Scalar theta = std::atan2(s, c);
  if (theta < small_angle<Scalar>()) {
    // theta / (2 sin theta) ~ 1/2 + theta^2 / 12
    return (Scalar(0.5) + theta * theta / Scalar(12)) * v;
  }
  if (c > Scalar(-0.7)) {
    return (theta / (Scalar(2) * s)) * v;
  }
  // Near pi: sin(theta) loses precision. R + R^T = 2 cos(t) I + 2 (1 - cos t) a a^T,
  // so the axis is read off the largest diagonal of B = (R + R^T)/2 - cos(t) I.
  const Eigen::Matrix<Scalar, 3, 3> B =
      (Scalar(0.5) * (R + R.transpose())) - c * Eigen::Matrix<Scalar, 3, 3>::Identity();
  int k = 0;
  B.diagonal().maxCoeff(&k);
  Vector<Scalar, 3> axis = B.col(k) / std::sqrt(B(k, k) > Scalar(0) ? B(k, k) : Scalar(1));
  axis.normalize();
  if (axis.dot(v) < Scalar(0)) axis = -axis;  // sign from the antisymmetric part
  return theta * axis;
}

/// Planar rotation by angle about +z.
template <typename Scalar>
inline Rotation<Scalar, 2> so2_exp(Scalar angle) noexcept {
  const Scalar c = std::cos(angle), s = std::sin(angle);
  Rotation<Scalar, 2> R;
  R << c, -s, s, c;
  return R;
}
/// Planar rotation angle in (-pi, pi].
template <typename Scalar>
inline Scalar so2_log(const Rotation<Scalar, 2>& R) noexcept {
  return std::atan2(R(1, 0), R(0, 0));
}

/// Dimension-generic exp/log: the rotation vector is an AngularVector<Scalar, Dim>.
template <typename Scalar>
inline Rotation<Scalar, 3> rotation_exp(const AngularVector<Scalar, 3>& w) noexcept {
  return so3_exp<Scalar>(w);
}
template <typename Scalar>
inline Rotation<Scalar, 2> rotation_exp(const AngularVector<Scalar, 2>& w) noexcept {
  return so2_exp<Scalar>(w(0));
}
template <typename Scalar>
inline AngularVector<Scalar, 3> rotation_log(const Rotation<Scalar, 3>& R) noexcept {
  return so3_log<Scalar>(R);
}
template <typename Scalar>
inline AngularVector<Scalar, 2> rotation_log(const Rotation<Scalar, 2>& R) noexcept {
  return AngularVector<Scalar, 2>(so2_log<Scalar>(R));
}

/// Roll-pitch-yaw angles (phi, theta, psi); see the file comment for the convention.
template <typename Scalar>
inline Rotation<Scalar, 3> rotation_from_euler(const Vector<Scalar, 3>& rpy) noexcept {
  using AA = Eigen::AngleAxis<Scalar>;
  return (AA(rpy.z(), Vector<Scalar, 3>::UnitZ()) * AA(rpy.y(), Vector<Scalar, 3>::UnitY()) *
          AA(rpy.x(), Vector<Scalar, 3>::UnitX()))
      .toRotationMatrix();
}

/// Inverse of rotation_from_euler, with theta in [-pi/2, pi/2]. At gimbal lock
/// (|theta| = pi/2) phi is set to 0 and psi carries the whole rotation about z.
template <typename Scalar>
inline Vector<Scalar, 3> euler_from_rotation(const Rotation<Scalar, 3>& R) noexcept {
  const Scalar sth = -R(2, 0);
  const Scalar cth = std::sqrt(R(0, 0) * R(0, 0) + R(1, 0) * R(1, 0));
  const Scalar theta = std::atan2(sth, cth);
  if (cth < Scalar(16) * Eigen::NumTraits<Scalar>::epsilon()) {
    return Vector<Scalar, 3>(Scalar(0), theta, std::atan2(-R(0, 1), R(1, 1)));
  }
  const Scalar psi = std::atan2(R(1, 0), R(0, 0));
  // phi is read from Rz(psi)^T R = Ry(theta) Rx(phi), whose entries (1,1) = cos(phi) and
  // (1,2) = -sin(phi) are O(1). Reading it from R(2,1), R(2,2) (both ~cos(theta))
  // instead loses eps / cos(theta) near gimbal lock, and the returned angles would
  // no longer reproduce R; this way the error in psi is compensated in phi.
  const Scalar cps = std::cos(psi), sps = std::sin(psi);
  const Scalar phi = std::atan2(sps * R(0, 2) - cps * R(1, 2), cps * R(1, 1) - sps * R(0, 1));
  return Vector<Scalar, 3>(phi, theta, psi);
}

/// Rate matrix E: omega_world = E(rpy) * rpy_dot. Columns are the world-frame axes
/// of the three elementary rotations: Rz Ry e_x, Rz e_y, e_z.
template <typename Scalar>
inline Eigen::Matrix<Scalar, 3, 3> euler_rate_matrix(const Vector<Scalar, 3>& rpy) noexcept {
  const Scalar cth = std::cos(rpy.y()), sth = std::sin(rpy.y());
  const Scalar cps = std::cos(rpy.z()), sps = std::sin(rpy.z());
  Eigen::Matrix<Scalar, 3, 3> E;
  E << cps * cth, -sps, Scalar(0),  //
      sps * cth, cps, Scalar(0),    //
      -sth, Scalar(0), Scalar(1);
  return E;
}

/// Inverse rate matrix E^-1 (rpy_dot = E^-1 * omega). Valid for |cos(theta)| > 0;
/// returns false (and leaves `out` untouched) within `min_cos` of gimbal lock.
template <typename Scalar>
inline bool euler_rate_matrix_inverse(const Vector<Scalar, 3>& rpy,
                                      Eigen::Matrix<Scalar, 3, 3>& out,
                                      Scalar min_cos = Scalar(1e-6)) noexcept {
  const Scalar cth = std::cos(rpy.y()), sth = std::sin(rpy.y());
  if (!(std::abs(cth) > min_cos)) return false;
  const Scalar cps = std::cos(rpy.z()), sps = std::sin(rpy.z());
  out << cps / cth, sps / cth, Scalar(0),  //
      -sps, cps, Scalar(0),                //
      cps * sth / cth, sps * sth / cth, Scalar(1);
  return true;
}

}  // namespace inhand
