// Serial-chain finger kinematics: fingertip frame, contact point on a spherical
// fingertip, and the Jacobian of that point (docs/method.md section 4).
//
// The chain itself (joints, frames, limits, validation) is in chain_model.hpp.
//
// Jacobian: the m x n matrix (m = Dim, n = DOF) of the world velocity of a point
// RIGIDLY ATTACHED to the distal link, currently at world position p (the measured
// contact point, which moves over the fingertip as it rolls), column i = a_i x (p - o_i).
#pragma once

#include <cmath>
#include <type_traits>

#include "inhand/kinematics/chain_model.hpp"
#include "inhand/kinematics/chain_plan.hpp"
#include "inhand/math/sin_cos.hpp"

namespace inhand {

namespace detail {
/// R <- R * Rot(e_k, q) given c = cos q and s = sin q, for the columns a = k + 1 and
/// b = k + 2 (mod 3) of R: Rot_k maps e_a -> c e_a + s e_b, so only those two mix.
template <int A, int B, typename Scalar>
inline void mix_columns(Rotation<Scalar, 3>& R, Scalar c, Scalar s) noexcept {
  const Vector<Scalar, 3> ca = R.col(A), cb = R.col(B);
  R.col(A) = c * ca + s * cb;
  R.col(B) = c * cb - s * ca;
}

/// R <- R * Rot(sign e_k, q) given c = cos q and s = sign sin q: only the two columns
/// of R other than k mix (12 flops instead of building Rot and a 3 x 3 product).
template <typename Scalar>
inline void turn_about_coordinate_axis(Rotation<Scalar, 3>& R, int k, Scalar c, Scalar s) noexcept {
  if (k == 0) {
    mix_columns<1, 2>(R, c, s);
  } else if (k == 1) {
    mix_columns<2, 0>(R, c, s);
  } else {
    mix_columns<0, 1>(R, c, s);
  }
}

/// R t in space, each row summed as (R(r,0) t0 + R(r,1) t1) + R(r,2) t2: one order in every
/// build (Eigen's product sums the rows of a 3 x 3 by vector in an order that depends on
/// its vectorisation), which ChainLanes (finger_lanes.hpp) follows lane by lane.
template <typename Scalar>
inline Vector<Scalar, 3> rotate(const Rotation<Scalar, 3>& R, const Vector<Scalar, 3>& t) noexcept {
  Vector<Scalar, 3> out;
  for (int r = 0; r < 3; ++r) out(r) = R(r, 0) * t(0) + R(r, 1) * t(1) + R(r, 2) * t(2);
  return out;
}
/// R F in space, each entry summed in the order of rotate().
template <typename Scalar>
inline Rotation<Scalar, 3> rotate(const Rotation<Scalar, 3>& R,
                                  const Rotation<Scalar, 3>& F) noexcept {
  Rotation<Scalar, 3> out;
  for (int k = 0; k < 3; ++k) out.col(k) = rotate<Scalar>(R, Vector<Scalar, 3>(F.col(k)));
  return out;
}
/// The planar products (Eigen's; planar chains are not laned).
template <typename Scalar>
inline Vector<Scalar, 2> rotate(const Rotation<Scalar, 2>& R, const Vector<Scalar, 2>& t) noexcept {
  return R * t;
}
template <typename Scalar>
inline Rotation<Scalar, 2> rotate(const Rotation<Scalar, 2>& R,
                                  const Rotation<Scalar, 2>& F) noexcept {
  return R * F;
}

/// One joint in space given s = sin q and c = cos q: writes the joint's world axis
/// R * axis and turns R into R * Rot(axis, q). Real fingers mostly turn about a
/// coordinate axis of their joint frame (k >= 0: axis = sign e_k, as coordinate_axis()
/// says); R * Rot(+-e_k, q) then only mixes the other two columns of R. Any other axis
/// (k < 0) is turned by `turn_general(R)`.
template <typename Scalar, typename DerivedAxis, typename TurnGeneral>
inline void turn_joint(Rotation<Scalar, 3>& R, const Vector<Scalar, 3>& axis, int k, Scalar sign,
                       Scalar s, Scalar c, const Eigen::MatrixBase<DerivedAxis>& world_axis_out,
                       TurnGeneral&& turn_general) noexcept {
  auto& world_axis = const_cast<Eigen::MatrixBase<DerivedAxis>&>(world_axis_out);
  if (k < 0) {
    world_axis = R * axis;
    turn_general(R);
    return;
  }
  world_axis = sign * R.col(k);
  turn_about_coordinate_axis<Scalar>(R, k, c, sign * s);
}

/// The sine and cosine forward_kinematics turns a joint by: sin_cos() in double (one pair
/// costs about 50 instructions inline against 110 for glibc's sincos, counted under
/// callgrind in the controller's tick); std::sin and std::cos in other types (glibc's
/// sincosf, about 36 instructions a pair, beats sin_cos's float kernel at about 55).
template <typename Scalar>
inline void joint_sin_cos(Scalar q, Scalar& s, Scalar& c) noexcept {
  if constexpr (std::is_same<Scalar, double>::value) {
    sin_cos<Scalar>(q, s, c);
  } else {
    s = std::sin(q);
    c = std::cos(q);
  }
}

/// One spatial joint given s = sin q and c = cos q (k, sign as for turn_joint); a general
/// axis by Rodrigues' formula Rot(axis, q) = I + s K + (1 - c) K^2 with K = [axis]x.
template <typename Scalar, typename DerivedAxis>
inline void apply_joint_sincos(Rotation<Scalar, 3>& R, const Vector<Scalar, 3>& axis, int k,
                               Scalar sign, Scalar s, Scalar c,
                               const Eigen::MatrixBase<DerivedAxis>& world_axis_out) noexcept {
  turn_joint<Scalar>(R, axis, k, sign, s, c, world_axis_out, [&](Rotation<Scalar, 3>& Rg) {
    const Rotation<Scalar, 3> K = hat<Scalar>(axis);
    const Rotation<Scalar, 3> K2 = K * K;
    const Rotation<Scalar, 3> Rj = Rotation<Scalar, 3>::Identity() + s * K + (Scalar(1) - c) * K2;
    Rg = Rg * Rj;
  });
}
}  // namespace detail

/// Per-finger kinematic workspace: world-frame joint origins and axes and the
/// fingertip frame for the last joint angles given to forward_kinematics().
template <typename Chain>
struct FingerKinematics {
  using Scalar = typename Chain::Scalar;
  static constexpr int Dim = Chain::Dim;
  static constexpr int Cols = Chain::Cols;
  static constexpr int MaxCols = Chain::MaxCols;
  /// Column i: world position of joint i's origin.
  Eigen::Matrix<Scalar, Dim, Cols, Eigen::ColMajor, Dim, MaxCols> joint_origins;
  /// Column i: world unit axis of joint i (planar: only row 2 is used, +-1).
  Eigen::Matrix<Scalar, 3, Cols, Eigen::ColMajor, 3, MaxCols> joint_axes;
  /// Fingertip frame in the world; its origin is the fingertip sphere centre.
  Pose<Scalar, Dim> fingertip{};

  FingerKinematics() = default;
  explicit FingerKinematics(const Chain& chain)
      : joint_origins(Dim, chain.dof()), joint_axes(3, chain.dof()) {
    joint_origins.setZero();
    joint_axes.setZero();
  }
};

namespace detail {
/// The chain walk of forward kinematics: from the base through each joint's fixed
/// transform (its world origin written to ws), `turn(R, i, ws.joint_axes.col(i))` writes
/// joint i's world axis and turns R by it, then the fingertip frame. `facts`: a ChainPlan
/// of the chain or detail::ChainTests (which frames turn).
template <typename Chain, typename Facts, typename TurnJoint>
inline void walk_chain(const Chain& chain, const Facts& facts, FingerKinematics<Chain>& ws,
                       TurnJoint&& turn) noexcept {
  using Scalar = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  Rotation<Scalar, Dim> R = chain.base.rotation;
  Vector<Scalar, Dim> p = chain.base.position;
  for (int i = 0; i < chain.dof(); ++i) {
    const auto& j = chain.joints[i];
    p += rotate<Scalar>(R, j.parent_to_joint.position);
    if (facts.frame_turns(i)) R = rotate<Scalar>(R, j.parent_to_joint.rotation);
    ws.joint_origins.col(i) = p;
    turn(R, i, ws.joint_axes.col(i));
  }
  ws.fingertip.position = p + rotate<Scalar>(R, chain.joint_to_tip.position);
  if (facts.tip_turns()) {
    ws.fingertip.rotation = rotate<Scalar>(R, chain.joint_to_tip.rotation);
  } else {
    ws.fingertip.rotation = R;
  }
}

/// forward_kinematics() given the chain's facts (a ChainPlan or ChainTests).
template <typename Chain, typename Facts, typename DerivedQ>
inline void forward_kinematics_with(const Chain& chain, const Facts& facts,
                                    const Eigen::MatrixBase<DerivedQ>& q,
                                    FingerKinematics<Chain>& ws) noexcept {
  using Scalar = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  walk_chain(chain, facts, ws, [&](Rotation<Scalar, Dim>& R, int i, auto&& world_axis) {
    Scalar sin_q, cos_q;
    joint_sin_cos<Scalar>(static_cast<Scalar>(q(i)), sin_q, cos_q);
    const auto& j = chain.joints[i];
    if constexpr (Dim == 3) {
      Scalar sign = Scalar(1);
      const int k = facts.coordinate_axis(i, sign);
      apply_joint_sincos<Scalar>(R, j.axis, k, sign, sin_q, cos_q, world_axis);
    } else {
      // Planar: the axis is +z or -z (validated); Rot(-z, q) = Rot(z, -q).
      const Scalar s = j.axis.z() * sin_q, c = cos_q;
      world_axis = Vector<Scalar, 3>(Scalar(0), Scalar(0), j.axis.z());
      Rotation<Scalar, 2> Rj;
      Rj << c, -s, s, c;
      R = R * Rj;
    }
  });
}

/// forward_kinematics_sincos() given the chain's facts (a ChainPlan or ChainTests).
template <typename Chain, typename Facts, typename DerivedS, typename DerivedC>
inline void forward_kinematics_sincos_with(const Chain& chain, const Facts& facts,
                                           const Eigen::MatrixBase<DerivedS>& sin_q,
                                           const Eigen::MatrixBase<DerivedC>& cos_q,
                                           FingerKinematics<Chain>& ws) noexcept {
  static_assert(Chain::Dim == 3, "forward_kinematics_sincos is for spatial chains");
  using Scalar = typename Chain::Scalar;
  walk_chain(chain, facts, ws, [&](Rotation<Scalar, 3>& R, int i, auto&& world_axis) {
    Scalar sign = Scalar(1);
    const int k = facts.coordinate_axis(i, sign);
    apply_joint_sincos<Scalar>(R, chain.joints[i].axis, k, sign, static_cast<Scalar>(sin_q(i)),
                               static_cast<Scalar>(cos_q(i)), world_axis);
  });
}
}  // namespace detail

/// Forward kinematics: fills `ws` for joint angles q (size dof). In double each joint's
/// sine and cosine come from sin_cos() (math/sin_cos.hpp: inline polynomials, within one
/// unit in the last place of 1 of std::sin / std::cos), so the result equals
/// forward_kinematics_sincos given sin_cos()'s values; in float from std::sin and std::cos
/// (detail::joint_sin_cos says why). noexcept, no allocation.
template <typename Chain, typename DerivedQ>
inline void forward_kinematics(const Chain& chain, const Eigen::MatrixBase<DerivedQ>& q,
                               FingerKinematics<Chain>& ws) noexcept {
  detail::forward_kinematics_with(chain, detail::ChainTests<Chain>(chain), q, ws);
}

/// Forward kinematics with the chain's plan (chain_plan.hpp): the same result as above,
/// bitwise, for the plan of this chain, without testing its frames and axes on every call.
/// noexcept, no allocation.
template <typename Chain, typename DerivedQ>
inline void forward_kinematics(const Chain& chain, const ChainPlan<Chain>& plan,
                               const Eigen::MatrixBase<DerivedQ>& q,
                               FingerKinematics<Chain>& ws) noexcept {
  detail::forward_kinematics_with(chain, plan, q, ws);
}

/// Forward kinematics in space from the sines and cosines of the joint angles (each of
/// size dof) instead of the angles, for a caller that keeps them up to date itself (the
/// simulator advances them by the angle-addition formula). Given sin_cos()'s values it
/// equals forward_kinematics exactly. noexcept, no allocation.
template <typename Chain, typename DerivedS, typename DerivedC>
inline void forward_kinematics_sincos(const Chain& chain, const Eigen::MatrixBase<DerivedS>& sin_q,
                                      const Eigen::MatrixBase<DerivedC>& cos_q,
                                      FingerKinematics<Chain>& ws) noexcept {
  detail::forward_kinematics_sincos_with(chain, detail::ChainTests<Chain>(chain), sin_q, cos_q, ws);
}

/// forward_kinematics_sincos with the chain's plan (chain_plan.hpp): bitwise the same
/// result for the plan of this chain. noexcept, no allocation.
template <typename Chain, typename DerivedS, typename DerivedC>
inline void forward_kinematics_sincos(const Chain& chain, const ChainPlan<Chain>& plan,
                                      const Eigen::MatrixBase<DerivedS>& sin_q,
                                      const Eigen::MatrixBase<DerivedC>& cos_q,
                                      FingerKinematics<Chain>& ws) noexcept {
  detail::forward_kinematics_sincos_with(chain, plan, sin_q, cos_q, ws);
}

/// Jacobian of the world velocity of a point attached to the distal link and now at
/// world position `point` (m x n, m = Dim). Call forward_kinematics first.
template <typename Chain, typename DerivedJ>
inline void point_jacobian(const FingerKinematics<Chain>& ws,
                           const Vector<typename Chain::Scalar, Chain::Dim>& point,
                           const Eigen::MatrixBase<DerivedJ>& J_out) noexcept {
  using Scalar = typename Chain::Scalar;
  auto& J = const_cast<Eigen::MatrixBase<DerivedJ>&>(J_out);  // Eigen's documented out-param idiom
  const int n = static_cast<int>(ws.joint_origins.cols());
  for (int i = 0; i < n; ++i) {
    const Vector<Scalar, Chain::Dim> r = point - ws.joint_origins.col(i);
    if constexpr (Chain::Dim == 3) {
      J.col(i) = ws.joint_axes.col(i).cross(r);
    } else {
      const Scalar w = ws.joint_axes(2, i);
      J.col(i) = Vector<Scalar, 2>(-w * r.y(), w * r.x());
    }
  }
}

/// Point on the fingertip sphere that touches an object whose OUTWARD normal at the
/// contact is `object_normal` (unit, world): centre - radius * normal.
template <typename Chain>
inline Vector<typename Chain::Scalar, Chain::Dim> fingertip_surface_point(
    const Chain& chain, const FingerKinematics<Chain>& ws,
    const Vector<typename Chain::Scalar, Chain::Dim>& object_normal) noexcept {
  return ws.fingertip.position - chain.fingertip_radius * object_normal;
}

}  // namespace inhand
