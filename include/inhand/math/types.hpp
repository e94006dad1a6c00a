// Spatial types shared by every layer.
//
// Conventions (the whole library):
//  - Units: SI. Metres, radians, seconds, newtons; velocities in m/s and rad/s.
//  - Frames: every vector handed to or returned by inhand is expressed in the
//    world ("reference", O_r in the paper) frame unless its name says otherwise.
//  - Dim is the spatial dimension: 3 for a spatial hand, 2 for a planar hand
//    working in the world x-y plane (rotations about +z, counter-clockwise
//    positive).
//  - A twist stacks linear velocity of the object reference point, then
//    angular velocity: spatial (vx, vy, vz, wx, wy, wz), planar (vx, vy, wz).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <type_traits>

namespace inhand {

/// Compile-time facts about a spatial dimension (2 = planar, 3 = spatial).
template <int Dim>
struct SpatialDim {
  static_assert(Dim == 2 || Dim == 3, "inhand supports planar (2) and spatial (3) hands");
  /// Number of rotational degrees of freedom: 1 in the plane, 3 in space.
  static constexpr int kRot = (Dim == 2) ? 1 : 3;
  /// Size of a twist / pose-error vector.
  static constexpr int kTwist = Dim + kRot;
};

template <typename Scalar, int Dim>
using Vector = Eigen::Matrix<Scalar, Dim, 1>;
template <typename Scalar, int Dim>
using Rotation = Eigen::Matrix<Scalar, Dim, Dim>;
/// Angular quantity: a scalar (as 1-vector) in the plane, a 3-vector in space.
template <typename Scalar, int Dim>
using AngularVector = Eigen::Matrix<Scalar, SpatialDim<Dim>::kRot, 1>;
/// Twist (linear; angular), see the file comment for the layout.
template <typename Scalar, int Dim>
using Twist = Eigen::Matrix<Scalar, SpatialDim<Dim>::kTwist, 1>;

/// omega x r, the velocity of a point at offset r on a body rotating with omega.
/// Planar: omega is the scalar rate about +z, result is omega * (-r_y, r_x).
template <typename Scalar>
inline Vector<Scalar, 3> angular_cross(const AngularVector<Scalar, 3>& omega,
                                       const Vector<Scalar, 3>& r) noexcept {
  return omega.cross(r);
}
template <typename Scalar>
inline Vector<Scalar, 2> angular_cross(const AngularVector<Scalar, 2>& omega,
                                       const Vector<Scalar, 2>& r) noexcept {
  return Vector<Scalar, 2>(-omega(0) * r.y(), omega(0) * r.x());
}

/// x * 0 summed over m: exactly 0 when every coefficient is finite, NaN otherwise (inf * 0
/// and NaN * 0 are NaN; a sum of zeros cannot overflow). Sums of several stay 0 or NaN
/// alike, so one comparison checks many matrices (controller/tick_checks.hpp).
template <typename Derived>
inline typename Derived::Scalar zero_sum(const Eigen::MatrixBase<Derived>& m) noexcept {
  return (m.derived().array() * typename Derived::Scalar(0)).sum();
}

/// True when every coefficient is finite (no NaN, no +-inf).
template <typename Derived>
inline bool all_finite(const Eigen::MatrixBase<Derived>& m) noexcept {
  // One branch, and a reduction the compiler vectorises, instead of a test per
  // coefficient. Like (x - x) == 0, it does not raise FE_INVALID for quiet NaN on IEEE
  // hardware.
  return zero_sum(m) == typename Derived::Scalar(0);
}
/// J x for a J with a fixed row count (a contact Jacobian: Dim rows) and any column count,
/// as the sum of x_c times column c. For a run-time column count Eigen's general product
/// costs several times as much at these sizes; for a fixed one the loop unrolls.
template <typename DerivedJ, typename DerivedX>
inline Eigen::Matrix<typename DerivedJ::Scalar, DerivedJ::RowsAtCompileTime, 1> columns_times(
    const Eigen::MatrixBase<DerivedJ>& J, const Eigen::MatrixBase<DerivedX>& x) noexcept {
  static_assert(DerivedJ::RowsAtCompileTime != Eigen::Dynamic, "a fixed row count");
  using Out = Eigen::Matrix<typename DerivedJ::Scalar, DerivedJ::RowsAtCompileTime, 1>;
  Out r = Out::Zero();
  for (Eigen::Index c = 0; c < J.cols(); ++c) r += J.col(c) * x(c);
  return r;
}

template <typename Scalar, typename = std::enable_if_t<std::is_floating_point<Scalar>::value>>
inline bool is_finite(Scalar x) noexcept {
  return (x - x) == Scalar(0);
}

}  // namespace inhand
