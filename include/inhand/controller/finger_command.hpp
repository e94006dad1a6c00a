// Layer 3, per finger: the hybrid servo (eqs. 4-7), the contact IK (eq. 3) and the
// command continuity bound (docs/method.md sections 4 and 6).
//
//   e        = g1(v_desired) + force part            (m/s, world frame)
//   force    = -u n   with u [m/s] from the force layer (into the object along -n;
//              u > 0 presses harder), or none when the finger does not touch
//   qdot     = J^+ e  (damped near singularities, scaled to the joint velocity limits)
//   |qdot - qdot_last|_inf <= max_joint_acceleration * dt  (the change is scaled,
//              its direction kept; then clamped back inside the velocity limits)
// The force part of HybridServo is not used: the force layer's loops replace it, and
// its motion PI carries the velocity part. noexcept, no allocation (fixed or bounded
// DOF).
#pragma once

#include <algorithm>
#include <limits>

#include "inhand/controller/controller_status.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"

namespace inhand {

/// The layer-3 state of one finger: servo, IK workspace, last command, velocity limits.
template <typename Scalar, int Dim, int Dof, int MaxDof = Dof>
struct FingerServo {
  using JointVector = typename ContactIk<Scalar, Dim, Dof, MaxDof>::JointVector;
  using Jacobian = typename ContactIk<Scalar, Dim, Dof, MaxDof>::Jacobian;
  using Vec = Vector<Scalar, Dim>;

  HybridServo<Scalar, Dim> servo{};
  ContactIk<Scalar, Dim, Dof, MaxDof> ik{};
  JointVector last_command{};  ///< rad/s, the last valid tick's joint velocities
  JointVector max_velocity{};  ///< rad/s, per joint (> 0)

  /// Sizes and configures (allocates only for run-time DOF without a bound).
  void configure(const JointVector& velocity_limits, const ServoGains<Scalar>& gains,
                 const IkParams<Scalar>& ik_params) {
    const int dof = static_cast<int>(velocity_limits.size());
    ik.set_dof(dof);
    ik.set_params(ik_params);
    servo.set_gains(gains);
    last_command.setZero(dof);
    max_velocity = velocity_limits;
  }

  /// One tick: contact velocity v [m/s] and force velocity `force` [m/s] (-u n, or zero
  /// when no force is servoed) at the point whose Jacobian is J; `normal` the measured
  /// normal (unused by the motion part). Writes the servo command and status, the IK
  /// report and the joint velocities; returns the warnings raised.
  template <typename FingerOutput>
  ControllerWarning command(const Jacobian& J, const Vec& v, const Vec& normal, const Vec* force,
                            Scalar max_joint_acceleration, Scalar dt, FingerOutput& fo) noexcept {
    ControllerWarning w = ControllerWarning::none;
    fo.servo_status = servo.update(v, Scalar(0), Scalar(0), normal, false, dt, fo.servo);
    if (force != nullptr) {
      fo.servo.force = *force;
      fo.servo.total = fo.servo.motion + fo.servo.force;
    }
    if (fo.servo_status != ServoStatus::ok) w |= ControllerWarning::servo_saturated;
    fo.ik = ik.solve(J, fo.servo.total, max_velocity, fo.joint_velocities);
    if (has(fo.ik.status, IkStatus::damped)) w |= ControllerWarning::ik_damped;
    if (has(fo.ik.status, IkStatus::limited)) w |= ControllerWarning::joint_velocity_limited;
    const Scalar max_step = max_joint_acceleration * dt;
    if (max_step < std::numeric_limits<Scalar>::infinity()) {
      const Scalar largest = (fo.joint_velocities - last_command).cwiseAbs().maxCoeff();
      if (largest > max_step) {
        fo.joint_velocities =
            last_command + (max_step / largest) * (fo.joint_velocities - last_command);
        // A convex combination of two commands within the joint limits: only rounding
        // can leave them; clamp it away (this only shrinks the step).
        fo.joint_velocities = fo.joint_velocities.cwiseMin(max_velocity).cwiseMax(-max_velocity);
        w |= ControllerWarning::rate_limited;
      }
    }
    last_command = fo.joint_velocities;
    return w;
  }
};

}  // namespace inhand
