// The contact-point IK's parameters (IkParams) and the joint-velocity box that keeps joint
// positions inside their limits over one tick (joint_position_box); the solver that reads
// them is controller/ik.hpp. Units: rad, rad/s, s; damping in m (docs/method.md section 4).
#pragma once

#include <algorithm>

#include "inhand/math/damping_schedule.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// The joint-velocity box [rad/s] that keeps joint positions q inside
/// [lower + margin, upper - margin] over a tick of dt seconds: a joint inside may move
/// up to its bound, a joint already beyond it may not move further out (its bound is 0),
/// so lo <= 0 <= hi always. All vectors of one size; dt > 0, margin >= 0 (rad).
template <typename JointVector, typename Scalar>
void joint_position_box(const JointVector& q, const JointVector& lower, const JointVector& upper,
                        Scalar margin, Scalar dt, JointVector& lo, JointVector& hi) noexcept {
  for (int i = 0; i < static_cast<int>(q.size()); ++i) {
    lo(i) = std::min(Scalar(0), (lower(i) + margin - q(i)) / dt);
    hi(i) = std::max(Scalar(0), (upper(i) - margin - q(i)) / dt);
  }
}

template <typename Scalar>
struct IkParams {
  DampingSchedule<Scalar> damping{};
  /// Joint position limits (FingerChain joints' lower/upper) enforced in the controller's
  /// IK with this margin [rad] inside each limit; false: only the velocity limits act.
  bool joint_limits = true;
  Scalar joint_limit_margin = Scalar(0.01);
  /// false: sigma_min of a 3-row Jacobian is computed only inside the damped region
  /// (outside it a factorisation certifies sigma_min >= epsilon and the report gives
  /// epsilon, min_singular_value_exact false); the command is the same (to rounding at
  /// sigma_min = epsilon, where the damping is continuous and 0). true: always.
  bool exact_min_singular_value = false;
  /// Weight w >= 1 of the contact normal when joints are held (normal priority, top of this
  /// file); 1: every direction alike.
  Scalar limited_normal_weight = Scalar(10);
  /// Field names relative to the controller Config ("ik.damping.max_damping").
  Validation validate() const noexcept {
    if (!is_finite(joint_limit_margin) || !(joint_limit_margin >= Scalar(0)))
      return Validation::invalid("ik.joint_limit_margin", "must be finite and >= 0");
    if (!is_finite(limited_normal_weight) || !(limited_normal_weight >= Scalar(1)))
      return Validation::invalid("ik.limited_normal_weight", "must be finite and >= 1");
    return damping.validate(
        DampingScheduleNames{"ik.damping.singular_threshold", "ik.damping.max_damping"});
  }
};

namespace detail {
/// Velocity limits > 0 (NaN fails), and a box [lo, hi] (if given) of n joints, finite,
/// with lo <= 0 <= hi: the IK's check of its limits (controller/ik.hpp). One pass.
template <typename V>
bool ik_limits_valid(const V& max_velocity, const V* lo, const V* hi, int n) noexcept {
  using Scalar = typename V::Scalar;
  bool ok = max_velocity.size() == n;
  const bool boxed = lo != nullptr && hi != nullptr;
  if (boxed) ok = ok && lo->size() == n && hi->size() == n;
  if (!ok) return false;
  for (int i = 0; i < n; ++i) ok = ok && max_velocity(i) > Scalar(0);
  if (boxed) {
    for (int i = 0; i < n; ++i)
      ok = ok && (*lo)(i) <= Scalar(0) && (*hi)(i) >= Scalar(0) && is_finite((*lo)(i)) &&
           is_finite((*hi)(i));
  }
  return ok;
}
}  // namespace detail

}  // namespace inhand
