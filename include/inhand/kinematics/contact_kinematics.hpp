// Contact kinematics under the micro-manipulation assumption (docs/method.md section 2).
//
// Eq. 2: the object point at the contact moves with v_c = v_o + omega_o x (p_c - p_o).
// Within one control tick the fingertip contact point is assumed to move with the
// object's contact point (rolling and sliding are disturbances corrected by the next
// tick's feedback), so this is also the desired fingertip contact-point velocity.
// All quantities are in the world frame: p_c is the MEASURED contact point (from
// tactile sensing), p_o the object reference point (the measured object position),
// twist = (v_o ; omega_o) as laid out in math/types.hpp. One template serves the
// planar (Dim = 2) and the spatial (Dim = 3) case.
#pragma once

#include "inhand/math/types.hpp"

namespace inhand {

/// Desired contact-point velocity v_o + omega_o x (p_c - p_o), eq. 2.
template <typename Scalar, int Dim>
inline Vector<Scalar, Dim> contact_point_velocity(
    const Twist<Scalar, Dim>& object_twist, const Vector<Scalar, Dim>& contact_point,
    const Vector<Scalar, Dim>& object_origin) noexcept {
  const AngularVector<Scalar, Dim> omega = object_twist.template tail<SpatialDim<Dim>::kRot>();
  return object_twist.template head<Dim>() +
         angular_cross<Scalar>(omega, Vector<Scalar, Dim>(contact_point - object_origin));
}

}  // namespace inhand
