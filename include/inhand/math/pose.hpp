// Poses in the plane or in space: pose error and interpolation (docs/method.md section 3).
//
// A Pose is the object (or a frame) in the world: `position` of its reference point
// and `rotation` R with x_world = R * x_body + position. Units: metres.
// Pose error (desired minus measured) stacks the position error p_d - p_m and the
// rotation error log(R_d * R_m^T), a world-frame rotation vector: the angular
// velocity that, held for one second, would carry R_m onto R_d. This is the layout
// of a Twist, so a pose error times a gain is a feedback twist.
#pragma once

#include "inhand/math/so3.hpp"

namespace inhand {

/// R is a proper rotation to `tolerance` (dimensionless, absolute on each entry of
/// R^T R - I, i.e. relative to the unit scale of a rotation): finite, orthonormal and
/// det R > 0. A NaN tolerance or entry gives false.
template <typename Scalar, int Dim>
inline bool is_rotation(const Rotation<Scalar, Dim>& R, Scalar tolerance) noexcept {
  if (!all_finite(R)) return false;
  const Rotation<Scalar, Dim> RtR = R.transpose() * R;
  return (RtR - Rotation<Scalar, Dim>::Identity()).cwiseAbs().maxCoeff() <= tolerance &&
         R.determinant() > Scalar(0);
}

template <typename Scalar, int Dim>
struct Pose {
  Vector<Scalar, Dim> position = Vector<Scalar, Dim>::Zero();
  Rotation<Scalar, Dim> rotation = Rotation<Scalar, Dim>::Identity();

  static Pose identity() noexcept { return Pose{}; }
  /// World coordinates of a point given in this frame.
  Vector<Scalar, Dim> transform_point(const Vector<Scalar, Dim>& p_body) const noexcept {
    return rotation * p_body + position;
  }
  /// Composition: (this * other) maps other's frame into this pose's parent frame.
  Pose operator*(const Pose& other) const noexcept {
    Pose out;
    out.rotation = rotation * other.rotation;
    out.position = rotation * other.position + position;
    return out;
  }
  Pose inverse() const noexcept {
    Pose out;
    out.rotation = rotation.transpose();
    out.position = -(out.rotation * position);
    return out;
  }
  bool is_finite() const noexcept { return all_finite(position) && all_finite(rotation); }
  /// The rotation is a proper rotation: max |R^T R - I| <= tolerance and det R > 0
  /// (rules out a scaled matrix, a zero matrix and a reflection).
  bool has_rotation(Scalar tolerance) const noexcept { return is_rotation(rotation, tolerance); }
  template <typename Other>
  Pose<Other, Dim> cast() const noexcept {
    Pose<Other, Dim> out;
    out.position = position.template cast<Other>();
    out.rotation = rotation.template cast<Other>();
    return out;
  }
};

/// Pose error of `measured` relative to `desired`: (p_d - p_m ; log(R_d R_m^T)).
template <typename Scalar, int Dim>
inline Twist<Scalar, Dim> pose_error(const Pose<Scalar, Dim>& desired,
                                     const Pose<Scalar, Dim>& measured) noexcept {
  Twist<Scalar, Dim> e;
  e.template head<Dim>() = desired.position - measured.position;
  e.template tail<SpatialDim<Dim>::kRot>() =
      rotation_log<Scalar>(Rotation<Scalar, Dim>(desired.rotation * measured.rotation.transpose()));
  return e;
}

/// Interpolation between two poses at s in [0, 1]: linear in position, geodesic
/// (SLERP) in rotation, R(s) = exp(s log(R1 R0^T)) R0. s outside [0,1] extrapolates.
template <typename Scalar, int Dim>
inline Pose<Scalar, Dim> interpolate(const Pose<Scalar, Dim>& from, const Pose<Scalar, Dim>& to,
                                     Scalar s) noexcept {
  Pose<Scalar, Dim> out;
  out.position = from.position + s * (to.position - from.position);
  const AngularVector<Scalar, Dim> w =
      rotation_log<Scalar>(Rotation<Scalar, Dim>(to.rotation * from.rotation.transpose()));
  out.rotation = rotation_exp<Scalar>(AngularVector<Scalar, Dim>(s * w)) * from.rotation;
  return out;
}

/// Integrate a constant world-frame twist over dt: p += v dt, R = exp(w dt) R.
template <typename Scalar, int Dim>
inline Pose<Scalar, Dim> integrate(const Pose<Scalar, Dim>& pose, const Twist<Scalar, Dim>& twist,
                                   Scalar dt) noexcept {
  Pose<Scalar, Dim> out;
  out.position = pose.position + dt * twist.template head<Dim>();
  out.rotation = rotation_exp<Scalar>(AngularVector<Scalar, Dim>(
                     dt * twist.template tail<SpatialDim<Dim>::kRot>())) *
                 pose.rotation;
  return out;
}

}  // namespace inhand
