// What one ReactiveController::update() reports besides its command: the overall
// status, the input field a rejected tick names, and the warnings of a valid tick
// (bit flags; see reactive_controller.hpp for the contract each one belongs to).
#pragma once

#include "inhand/math/flags.hpp"

namespace inhand {

/// What a finger is doing this tick.
enum class FingerState : unsigned char {
  idle,         ///< no task: zero joint velocity
  approaching,  ///< grasp phase, moving towards its desired contact point
  pressing,     ///< grasp phase, touching, servoing to its grasp force
  in_contact,   ///< manipulation, touching: hybrid servo on eq. 2 + planned force
  reacquiring,  ///< manipulation, contact lost: re-approaching along the last normal
  /// grasp phase: approached past the plane through the measured object's centre normal to
  /// its target's normal without touching (grasp.hpp, "A finger that misses"): left out of
  /// the grasp and, until it touches the object, of the task; no command
  missed,
};
inline const char* to_string(FingerState s) noexcept {
  switch (s) {
    case FingerState::idle:
      return "idle";
    case FingerState::approaching:
      return "approaching";
    case FingerState::pressing:
      return "pressing";
    case FingerState::in_contact:
      return "in_contact";
    case FingerState::reacquiring:
      return "reacquiring";
    case FingerState::missed:
      return "missed";
  }
  return "unknown";
}

/// Overall result of one update().
enum class ControllerStatus : unsigned char {
  ok,               ///< manipulating, every finger in contact (but those left out: missed)
  grasping,         ///< grasp phase running
  grasped,          ///< grasp complete: every finger presses with the nominal force
  contact_lost,     ///< manipulating, at least one finger is reacquiring its contact
  idle,             ///< configured, no task started: zero output
  not_configured,   ///< configure() has not succeeded: zero output
  invalid_input,    ///< see ControllerOutput::fault; zero output, state frozen
  numerical_fault,  ///< a non-finite value arose (Output::numerical_fault names where);
                    ///< zero output, state as before the tick
};
inline const char* to_string(ControllerStatus s) noexcept {
  switch (s) {
    case ControllerStatus::ok:
      return "ok";
    case ControllerStatus::grasping:
      return "grasping";
    case ControllerStatus::grasped:
      return "grasped";
    case ControllerStatus::contact_lost:
      return "contact_lost";
    case ControllerStatus::idle:
      return "idle";
    case ControllerStatus::not_configured:
      return "not_configured";
    case ControllerStatus::invalid_input:
      return "invalid_input";
    case ControllerStatus::numerical_fault:
      return "numerical_fault";
  }
  return "unknown";
}

/// Which input field was rejected.
enum class InputField : unsigned char {
  none,
  time,
  object_pose,
  joint_positions,
  contact_point,
  contact_normal,
  normal_force,
  jacobian,
  virtual_contact_point,
  finger_count,             ///< Input::fingers or Output::fingers has the wrong size
  output_joint_velocities,  ///< an Output finger's joint_velocities is not its DOF long
};
inline const char* to_string(InputField f) noexcept {
  switch (f) {
    case InputField::none:
      return "none";
    case InputField::time:
      return "time";
    case InputField::object_pose:
      return "object_pose";
    case InputField::joint_positions:
      return "joint_positions";
    case InputField::contact_point:
      return "contact_point";
    case InputField::contact_normal:
      return "contact_normal";
    case InputField::normal_force:
      return "normal_force";
    case InputField::jacobian:
      return "jacobian";
    case InputField::virtual_contact_point:
      return "virtual_contact_point";
    case InputField::finger_count:
      return "finger_count";
    case InputField::output_joint_velocities:
      return "output_joint_velocities";
  }
  return "unknown";
}

struct InputFault {
  InputField field = InputField::none;
  int finger = -1;  ///< -1 for hand-level fields (time, object pose, finger_count)
};

/// Warnings raised during a valid tick (bit flags, never silent saturation).
enum class ControllerWarning : unsigned {
  none = 0,
  ik_damped = 1u << 0,               ///< some finger's IK was damped near a singularity
  joint_velocity_limited = 1u << 1,  ///< some finger's joint velocities were scaled down
  servo_saturated = 1u << 2,         ///< some servo PI hit its integral/output limit
  force_limited = 1u << 3,           ///< the planner limited a balancing force
  twist_limited = 1u << 4,           ///< the commanded object twist was scaled to its limit
  long_tick = 1u << 5,               ///< dt exceeded max_tick: integration used max_tick
  no_balancing_contact = 1u << 6,    ///< no balancing finger touching: forces unbalanced
  rate_limited = 1u << 7,   ///< some finger's command change was scaled to max_joint_acceleration
  pose_outlier = 1u << 8,   ///< the measured object pose jumped implausibly: previous one held
  force_outlier = 1u << 9,  ///< a measured normal force jumped implausibly: previous one held
  slipping = 1u << 10,      ///< some contact slides along the object (force layer)
  grip_raised = 1u << 11,   ///< the grip is above the nominal pattern (force layer)
  beyond_capacity = 1u << 12,  ///< the load needs more than max_force: the object may be lost
  force_integral_limited = 1u << 13,  ///< some force integrator reached its bound
  pose_integral_limited = 1u << 14,   ///< layer 1's pose-error integral reached its bound
  implausible_contact = 1u << 15,     ///< some contact is far from / behind its fingertip
  joint_position_limited = 1u << 16,  ///< some joint was held at its position limit (IK)
  /// the object twist asks a touching contact to move, along its normal, where a joint
  /// held at its limit cannot follow (workspace_limits.hpp); cut when keep_twist_in_reach,
  /// while the force layer reports beyond_capacity, slipping or over_max_force (and
  /// at_risk_hold after), and, once cut, while the twist goes on asking for it
  workspace_limited = 1u << 17,
  /// with workspace_limited: the commanded twist was cut there this tick, so the object
  /// does not follow the trajectory's twist, and the pose loop does not integrate the
  /// error along the cut (Config::keep_twist_in_reach, at_risk_hold)
  workspace_cut = 1u << 18,
  /// grasp phase: max_force holds the grasp's grip s_g below what release_grip and
  /// release_load ask (release_grip.hpp): released, a load of release_load along
  /// some direction may open a contact
  release_grip_capped = 1u << 19,
  /// manipulation: some touching finger measures more than force_planner.max_force, which
  /// no force target asks for: the object's motion presses it into the finger (a joint
  /// held at its limit, a twist faster than the force loop). Counts as the grasp at risk
  /// for workspace_limited's cut
  over_max_force = 1u << 20,
  /// grasp phase and after: some finger approached past the measured object's centre
  /// without touching it and is left out (FingerState::missed; grasp.hpp)
  grasp_finger_missed = 1u << 21,
  /// manipulation: the measured object has been at least pose_feedback.astray_distance
  /// (or astray_angle) from its desired pose for astray_time (pose_feedback.hpp): the
  /// hand is not carrying it where the task wants it, whatever the cause (its servos
  /// yielding under the load, friction, a push, a joint at its limit); it may be lost.
  /// Reported only: nothing in the controller acts on it
  object_astray = 1u << 22,
};
template <>
struct is_flags<ControllerWarning> : std::true_type {};

}  // namespace inhand
