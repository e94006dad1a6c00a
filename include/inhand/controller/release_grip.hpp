// The grip the grasp presses with, sized for the load that arrives at release (grasp.hpp:
// a placed finger presses with f_g = s_g q_g; docs/force_layer.md, after its parameter table).
//
// Released, the object's load w [N] (its weight, say) arrives as a step and is first
// carried by the contacts' compression: a translation d of the object presses it by
// n_i^T d into finger i (n_i outward), which with equal contact stiffness k changes the
// finger's normal force by k n_i^T d; balancing w (sum_i k n_i n_i^T d = w) gives
// d = (k G)^-1 w, G = sum_i n_i n_i^T + eps I, so finger i's force changes by
// n_i^T G^-1 w. eps = rigid_tolerance: a direction the normals barely span (eigenvalue of
// sum n n^T below eps) is carried by friction, as in the force layer's split
// (force_layer.hpp). k cancels: the sizing is the same from soft to stiff contacts.
//
// Any direction. Finger i loses up to |w| |G^-1 n_i| [N] (w along -G^-1 n_i), so it keeps
// min_force under any load up to release_load when
//   s q_i >= min_force + release_load |G^-1 n_i|.                                     (1)
// Each finger is sized for its own worst direction, which no single load is for all of
// them at once.
//
// Along gravity, when its direction is known (ForceLayerParams::gravity_direction, g after
// normalising; a planar hand takes g's part in its plane, none if g is normal to it). A
// weight W g unloads only the fingers with n_i^T G^-1 g < 0, by W |n_i^T G^-1 g|, and it
// arrives as a step: on the contacts' spring the compression overshoots the static share,
// by up to twice on an undamped contact (a mass stepped onto a spring). With g known the
// grip is also sized for that peak, for a weight up to release_load:
//   s q_i >= min_force + 2 release_load max(0, -n_i^T G^-1 g).                        (2)
// s_g is the largest of release_grip, (1) and (2), then lowered until no s_g q_i exceeds
// max_force. (1) is kept with g known: a push or a sensor bias at release has no
// direction. Twice (1) would size every finger for the step along its worst direction,
// squeezing grasps whose weight is carried elsewhere (measured on a soft joint servo,
// docs/force_layer.md); (2) presses only the fingers the weight unloads.
// A grip capped by max_force is warned during the grasp (release_grip_capped); the load
// beyond it meets the force layer's slip and capacity flags. Not covered: the load's
// moment about the contacts (the object turning on them), and friction's share, which the
// normals' geometry does not give.
// Units: N; normals and g in the world frame.
#pragma once

#include <algorithm>
#include <cmath>

#include "inhand/controller/force_layer_params.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// The grasp's grip scale s_g and whether max_force lowered it (release_grip_scale).
template <typename Scalar>
struct ReleaseGrip {
  Scalar scale = Scalar(1);  ///< s_g, dimensionless
  bool capped = false;       ///< s_g is below what release_grip / release_load ask
};

/// The unit direction of gravity in a Dim-dimensional world from `gravity_direction` (any
/// length; a planar world takes its x and y), or zero where it is unknown: all zero, or
/// (planar) normal to the plane, or not finite.
template <typename Scalar, int Dim>
inline Vector<Scalar, Dim> gravity_unit(const Vector<Scalar, 3>& gravity_direction) noexcept {
  const Vector<Scalar, Dim> g = gravity_direction.template head<Dim>();
  const Scalar norm = g.norm();
  if (!(norm > Scalar(1e-9) * (Scalar(1) + gravity_direction.norm())) || !is_finite(norm))
    return Vector<Scalar, Dim>::Zero();
  return g / norm;
}

/// The grip scale s_g of the grasp (file comment): for normals (Dim x n, the object's
/// outward unit normals, world) and the pattern q (n, N), the largest of `release_grip`,
/// (1) (min_force + release_load |G^-1 n_i|) / q_i and, with fl.gravity_direction set,
/// (2) (min_force + 2 release_load max(0, -n_i^T G^-1 g)) / q_i over the fingers with
/// q_i > 0, then lowered until no s_g q_i exceeds max_force (`capped`: a load of
/// release_load may then take some finger below min_force, or release_grip is not met).
/// noexcept, no allocation (a Dim x Dim inverse).
template <typename Scalar, typename DerivedN, typename DerivedQ>
inline ReleaseGrip<Scalar> release_grip_scale(const Eigen::MatrixBase<DerivedN>& normals,
                                              const Eigen::MatrixBase<DerivedQ>& pattern,
                                              const ForceLayerParams<Scalar>& fl, Scalar min_force,
                                              Scalar max_force) noexcept {
  constexpr int Dim = DerivedN::RowsAtCompileTime;
  using Mat = Eigen::Matrix<Scalar, Dim, Dim>;
  const int n = static_cast<int>(pattern.size());
  Mat G = fl.rigid_tolerance * Mat::Identity();
  for (int i = 0; i < n; ++i) G.noalias() += normals.col(i) * normals.col(i).transpose();
  const Mat G_inv = G.inverse();
  const Vector<Scalar, Dim> G_inv_g = G_inv * gravity_unit<Scalar, Dim>(fl.gravity_direction);
  ReleaseGrip<Scalar> r;
  r.scale = fl.release_grip;
  for (int i = 0; i < n; ++i) {
    if (!(pattern(i) > Scalar(0))) continue;
    const Scalar any = (G_inv * normals.col(i)).norm();                                  // (1)
    const Scalar along = Scalar(2) * std::max(Scalar(0), -normals.col(i).dot(G_inv_g));  // (2)
    r.scale = std::max(r.scale, (min_force + fl.release_load * std::max(any, along)) / pattern(i));
  }
  for (int i = 0; i < n; ++i) {
    if (r.scale * pattern(i) > max_force) {
      r.scale = max_force / pattern(i);
      r.capped = true;
    }
  }
  return r;
}

}  // namespace inhand
