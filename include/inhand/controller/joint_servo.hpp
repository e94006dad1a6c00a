// The hand's joint servo as the force layer meets it at a contact (docs/force_layer.md,
// "The hand's joint servo").
//
// A real hand realises the joint-velocity command through a servo: a set-point that
// integrates the command, tracked with a position stiffness K [N m/rad] and a velocity
// gain (damping) D [N m s/rad] per joint, every joint alike (ForceLayerParams::
// servo_stiffness, servo_damping; 0: not modelled, a rigid servo). A fingertip pressed on
// an object then sits on two springs in series, the contact's and the servo's, and a
// change of the commanded velocity reaches the contact force at once through D (the
// servo's feedthrough). Both are seen along the contact normal n through the contact
// Jacobian J (Dim x dof, world frame, m/rad).
//
// Press direction. The servo's stiffness at the fingertip is K (J J^T)^-1 (for J of full
// row rank), not isotropic, and the contact's is finite: the two in series have the
// compliance J J^T / K + C_c. A set-point step d then stores the force
// f = (J J^T / K + C_c)^-1 d, which is along n alone for d = (J J^T / K + C_c) n f_n.
// Since n is a principal direction of the contact's compliance (C_c n = n / k_c, whatever
// its tangential compliance, rigid included), that step is J J^T n / K + n / k_c: the
// servo's direction J J^T n and n itself, weighted by the two compliances along n. With
// the servo modelled, the force part of the command (layer 3's e_F = -u n, eqs. 4-7) is
// therefore sent along
//   e_F = -u (w J J^T n / (n^T J J^T n) + (1 - w) n),  w = k_c / (k_c + k_s),
// whose normal part is still u; k_c is the force layer's contact stiffness estimate. Along
// n alone (w = 0) a stiff contact stores a tangential force from the servo's anisotropy;
// along J J^T n alone (w = 1) a contact as soft as the servo stores one from its own
// compliance, which friction without creep keeps until the object is released.
// The servo then meets the contact with stiffness k_s = K / |J^T n|^2 [N/m] and feedthrough
// d_s = D / |J^T n|^2 [N s/m] along n (joint velocities J^T n u / |J^T n|^2, the torques
// they build, J^T f = tau solved for f); servo_normal_gain() returns 1 / |J^T n|^2.
// Units: m, rad, N, s. noexcept, no allocation (loops over J's columns).
#pragma once

#include "inhand/math/types.hpp"

namespace inhand {

/// 1 / |J^T n|^2 [1/m^2]: the factor from joint-servo stiffness (or damping) to its value
/// along the contact normal n (unit) for a set-point step along J J^T n; 0 when J^T n vanishes
/// (no joint moves the fingertip along n: nothing is known).
template <typename Scalar, typename Jacobian, typename Normal>
Scalar servo_normal_gain(const Jacobian& J, const Normal& n) noexcept {
  Scalar s = Scalar(0);
  for (Eigen::Index j = 0; j < J.cols(); ++j) {
    const Scalar c = J.col(j).dot(n);
    s += c * c;
  }
  return s > Scalar(1e-12) ? Scalar(1) / s : Scalar(0);
}

/// The press direction for the servo in series with the contact (see the file comment):
/// w J J^T n / (n^T J J^T n) + (1 - w) n, w = k_contact / (k_contact + k_s),
/// k_s = servo_stiffness / (n^T J J^T n); its normal part is 1. k_contact [N/m]: the
/// contact's normal stiffness estimate (finite; <= 0 is taken as a rigid contact, w = 1);
/// servo_stiffness K [N m/rad]. n itself when J^T n vanishes or the servo is not modelled
/// (K = 0).
template <typename Scalar, int Dim, typename Jacobian>
Vector<Scalar, Dim> servo_press_direction(const Jacobian& J, const Vector<Scalar, Dim>& n,
                                          Scalar k_contact, Scalar servo_stiffness) noexcept {
  if (!(servo_stiffness > Scalar(0))) return n;
  Vector<Scalar, Dim> d = Vector<Scalar, Dim>::Zero();
  for (Eigen::Index j = 0; j < J.cols(); ++j) d += J.col(j) * J.col(j).dot(n);
  const Scalar nd = n.dot(d);
  if (!(nd > Scalar(1e-12))) return n;
  const Scalar ks = servo_stiffness / nd;
  const Scalar w = k_contact > Scalar(0) ? k_contact / (k_contact + ks) : Scalar(1);
  return w * (d / nd) + (Scalar(1) - w) * n;
}

/// The force loop's proportional gain kp [m/s per N] at one contact. k_contact [N/m]: the
/// contact's stiffness estimate; servo_gain: servo_normal_gain() (0: servo not modelled);
/// bandwidth w_c [rad/s]; contact_damping c [N s/m] (0: no cap); servo K [N m/rad] and
/// D [N m s/rad]. The loop drives the series stiffness k = (1/k_contact + 1/k_s)^-1 to the
/// crossover w_c, kp = w_c / k, and the feedthrough of the larger of c and d_s is kept
/// at half a unit per tick: kp <= 1 / (2 max(c, d_s)) (docs/force_layer.md).
template <typename Scalar>
Scalar force_loop_gain(Scalar k_contact, Scalar servo_gain, Scalar bandwidth,
                       Scalar contact_damping, Scalar servo_stiffness,
                       Scalar servo_damping) noexcept {
  Scalar k = k_contact;
  const Scalar ks = servo_stiffness * servo_gain, ds = servo_damping * servo_gain;
  if (ks > Scalar(0)) k = Scalar(1) / (Scalar(1) / k + Scalar(1) / ks);
  Scalar kp = bandwidth / k;
  const Scalar c = contact_damping > ds ? contact_damping : ds;
  if (c > Scalar(0) && kp > Scalar(0.5) / c) kp = Scalar(0.5) / c;
  return kp;
}

}  // namespace inhand
