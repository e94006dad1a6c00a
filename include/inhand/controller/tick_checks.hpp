// The checks around one controller tick: what makes an Input invalid (before the tick
// changes any state) and which stage produced a non-finite output (after it). Both
// name what they found; see reactive_controller.hpp for the contract they serve. Each
// first decides the common case (the input valid, the output finite) in one pass without
// early exits, and searches for what to name only when that fails. noexcept, no allocation.
#pragma once

#include <cmath>
#include <cstddef>

#include "inhand/controller/controller_io.hpp"

namespace inhand {
namespace detail {
/// Whether check_input() finds `in` valid: the same conditions, combined without early
/// exits (finiteness as one zero_sum, math/types.hpp), so that a valid input -- every tick but a
/// faulty one -- takes one pass and no search for the field to name.
template <typename Types>
bool input_valid(const typename Types::Config& c, const typename Types::Input& in, bool has_time,
                 double last_time) noexcept {
  using Scalar = typename Types::Chain::Scalar;
  bool ok =
      is_finite(in.time) & (!has_time | (static_cast<Scalar>(in.time - last_time) > Scalar(0)));
  ok &= in.object_pose.has_rotation(Scalar(1e-3));  // its rotation finite too
  Scalar acc = zero_sum(in.object_pose.position);
  for (int i = 0; i < static_cast<int>(c.fingers.size()); ++i) {
    const typename Types::FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
    const typename Types::FingerConfig& fc = c.fingers[static_cast<std::size_t>(i)];
    ok &= f.joint_positions.size() == fc.chain.dof();
    acc += zero_sum(f.joint_positions);
    if (f.contact.touching) {
      const Scalar force = f.contact.normal_force;
      acc += zero_sum(f.contact.contact_point) + zero_sum(f.contact.normal) + force * Scalar(0);
      ok &= (std::abs(f.contact.normal.norm() - Scalar(1)) <= Scalar(1e-3)) &
            (force >= c.min_measured_force) & (force <= c.max_measured_force);
    }
    if (fc.kinematics == KinematicsSource::external) {
      ok &= f.jacobian.cols() == fc.chain.dof();
      acc += zero_sum(f.jacobian);
      if (!f.contact.touching) acc += zero_sum(f.virtual_contact_point);
    }
  }
  return ok && acc == Scalar(0);
}
}  // namespace detail

/// The first invalid field of `in` for the configuration `c`, or field none.
/// `last_time`: the last accepted time stamp, when `has_time`.
template <typename Types>
InputFault check_input(const typename Types::Config& c, const typename Types::Input& in,
                       bool has_time, double last_time) noexcept {
  using Scalar = typename Types::Chain::Scalar;
  if (detail::input_valid<Types>(c, in, has_time, last_time)) return {};
  // Invalid: the first field, in the order below.
  // Strictly increasing, also once the step is converted to Scalar.
  if (!is_finite(in.time) || (has_time && !(static_cast<Scalar>(in.time - last_time) > Scalar(0))))
    return {InputField::time, -1};
  // A measured rotation: orthonormal to 1e-3 (a pose estimate is not re-orthonormalised
  // to machine precision) and det +1 (not a reflection).
  if (!in.object_pose.has_rotation(Scalar(1e-3))) return {InputField::object_pose, -1};
  if (!in.object_pose.is_finite()) return {InputField::object_pose, -1};
  for (int i = 0; i < static_cast<int>(c.fingers.size()); ++i) {
    const typename Types::FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
    const typename Types::FingerConfig& fc = c.fingers[static_cast<std::size_t>(i)];
    if (f.joint_positions.size() != fc.chain.dof() || !all_finite(f.joint_positions))
      return {InputField::joint_positions, i};
    if (f.contact.touching) {
      if (!all_finite(f.contact.contact_point)) return {InputField::contact_point, i};
      if (!all_finite(f.contact.normal) ||
          !(std::abs(f.contact.normal.norm() - Scalar(1)) <= Scalar(1e-3)))
        return {InputField::contact_normal, i};
      if (!is_finite(f.contact.normal_force) || f.contact.normal_force < c.min_measured_force ||
          f.contact.normal_force > c.max_measured_force)
        return {InputField::normal_force, i};
    }
    if (fc.kinematics == KinematicsSource::external) {
      if (f.jacobian.cols() != fc.chain.dof() || !all_finite(f.jacobian))
        return {InputField::jacobian, i};
      if (!f.contact.touching && !all_finite(f.virtual_contact_point))
        return {InputField::virtual_contact_point, i};
    }
  }
  return {};
}

namespace detail {
/// zero_sum over every value non_finite_stage() checks: one pass and one branch for the
/// common case, every value finite.
template <typename Types>
typename Types::Chain::Scalar output_zero_sum(const typename Types::Output& out) noexcept {
  using Scalar = typename Types::Chain::Scalar;
  Scalar acc = zero_sum(out.desired_object_pose.position) +
               zero_sum(out.desired_object_pose.rotation) + zero_sum(out.feedforward_twist) +
               out.manipulation_time * Scalar(0) + zero_sum(out.pose_error) +
               zero_sum(out.commanded_twist) + zero_sum(out.pose_error_integral) +
               zero_sum(out.force_residual) + zero_sum(out.load_estimate) + out.grip * Scalar(0);
  for (const typename Types::FingerOutput& fo : out.fingers) {
    acc += (fo.desired_normal_force + fo.force_target + fo.stiffness_estimate + fo.force_integral +
            fo.ik.min_singular_value + fo.ik.damping + fo.ik.limit_scale + fo.ik.task_error) *
               Scalar(0) +
           zero_sum(fo.desired_contact_velocity) + zero_sum(fo.servo.motion) +
           zero_sum(fo.servo.force) + zero_sum(fo.servo.total) + zero_sum(fo.joint_velocities);
  }
  return acc;
}
}  // namespace detail

/// The first stage whose output is not finite ("trajectory", "pose_feedback",
/// "force_layer", "servo", "ik"), or nullptr.
template <typename Types>
const char* non_finite_stage(const typename Types::Output& out) noexcept {
  using Scalar = typename Types::Chain::Scalar;
  if (detail::output_zero_sum<Types>(out) == Scalar(0)) return nullptr;  // all finite
  // Some value is not finite: find the first stage, in the order of the tick.
  if (!out.desired_object_pose.is_finite() || !all_finite(out.feedforward_twist) ||
      !is_finite(out.manipulation_time))
    return "trajectory";
  if (!all_finite(out.pose_error) || !all_finite(out.commanded_twist) ||
      !all_finite(out.pose_error_integral))
    return "pose_feedback";
  if (!all_finite(out.force_residual) || !all_finite(out.load_estimate) || !is_finite(out.grip))
    return "force_layer";
  for (const typename Types::FingerOutput& fo : out.fingers) {
    if (!is_finite(fo.desired_normal_force) || !is_finite(fo.force_target) ||
        !is_finite(fo.stiffness_estimate) || !is_finite(fo.force_integral))
      return "force_layer";
    if (!all_finite(fo.desired_contact_velocity) || !all_finite(fo.servo.motion) ||
        !all_finite(fo.servo.force) || !all_finite(fo.servo.total))
      return "servo";
    if (!all_finite(fo.joint_velocities) || !is_finite(fo.ik.min_singular_value) ||
        !is_finite(fo.ik.damping) || !is_finite(fo.ik.limit_scale) || !is_finite(fo.ik.task_error))
      return "ik";
  }
  return nullptr;
}

/// The fallback command: every finger slot the Output has zeroed at its current size
/// (never resized: no allocation), and the commanded twists zero.
template <typename Types>
void zero_command(typename Types::Output& out) noexcept {
  using Scalar = typename Types::Chain::Scalar;
  for (typename Types::FingerOutput& fo : out.fingers) {
    fo.joint_velocities.setZero();
    fo.desired_contact_velocity.setZero();
    fo.desired_normal_force = Scalar(0);
    fo.servo = ServoCommand<Scalar, Types::Chain::Dim>{};
    fo.ik = IkReport<Scalar>{};
    fo.servo_status = ServoStatus::ok;
    fo.force_target = Scalar(0);
    fo.implausible_contact = false;
  }
  out.commanded_twist.setZero();
  out.feedforward_twist.setZero();
}

}  // namespace inhand
