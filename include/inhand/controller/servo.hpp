// Hybrid position/force servo of one finger (docs/method.md section 6, eqs. 4-7).
//
//   e_m  = g1(v_d)                 PI on the desired contact-point velocity (eq. 4)
//   df   = f_d - f_m               normal-force error, newtons (eq. 5, scalar part)
//   e_f  = -g2(df) * n             PI on the force error along the normal (eq. 6)
//   e    = e_m + e_f               Cartesian contact-point velocity command (eq. 7)
// Sign convention: n is the object's OUTWARD unit surface normal at the contact, in
// the world frame, i.e. it points from the object towards the fingertip. A measured
// force below the desired one (df > 0) therefore drives the fingertip along -n, INTO
// the object; a force above it backs the fingertip off along +n. Forces are the
// magnitudes of the normal (pressing) force, >= 0.
// g2 acts on the scalar df and is applied along the CURRENT normal each tick, so a
// rolling contact does not carry a stale normal in the integrator.
// Units: velocities m/s; g2 gains are admittances, (m/s)/N and (m/s)/(N s).
// Integrator bounds. Both PIs get a finite integral bound by default, derived from
// the gains: the integral term ki * I may contribute at most `max_integral_velocity`
// (m/s) to the command, so the effective bound is
//   I_max = min(integral_limit, max_integral_velocity / ki)
// (g1: I in m, ki in 1/s; g2: I in N s, ki in (m/s)/(N s)); an explicit finite
// integral_limit below it wins. With ki = 0 the integral does not reach the output:
// it is cleared every step (so it cannot grow without bound either). Reaching the
// bound is reported: ServoStatus motion_saturated / force_saturated.
#pragma once

#include <algorithm>

#include "inhand/math/flags.hpp"
#include "inhand/math/pi_controller.hpp"

namespace inhand {

template <typename Scalar>
struct ServoGains {
  /// g1: the motion PI. kp = 1, ki = 0 passes the desired velocity through.
  PiGains<Scalar> motion{Scalar(1), Scalar(0)};
  /// g2: the force PI, (m/s)/N.
  PiGains<Scalar> force{Scalar(0.02), Scalar(0.2)};
  /// m/s, > 0: the most the integral term of either PI may add to the command (see
  /// the file comment: it bounds both integrators).
  Scalar max_integral_velocity = Scalar(0.1);

  /// Field names relative to the controller Config ("servo.force.ki").
  Validation validate() const noexcept {
    Validation v =
        motion.validate(PiGainNames{"servo.motion.kp", "servo.motion.ki",
                                    "servo.motion.integral_limit", "servo.motion.output_limit"});
    if (!v.ok()) return v;
    v = force.validate(PiGainNames{"servo.force.kp", "servo.force.ki", "servo.force.integral_limit",
                                   "servo.force.output_limit"});
    if (!v.ok()) return v;
    if (!is_finite(max_integral_velocity) || !(max_integral_velocity > Scalar(0)))
      return Validation::invalid("servo.max_integral_velocity", "must be finite and > 0");
    return Validation::valid();
  }

  /// The gains a PI runs with: integral_limit lowered to max_integral_velocity / ki
  /// (ki > 0), or to max_integral_velocity * 1 s (ki = 0, where it has no effect).
  PiGains<Scalar> bounded(const PiGains<Scalar>& g) const noexcept {
    PiGains<Scalar> b = g;
    const Scalar derived =
        g.ki > Scalar(0) ? max_integral_velocity / g.ki : max_integral_velocity * Scalar(1);
    b.integral_limit = std::min(g.integral_limit, derived);
    return b;
  }
};

/// The servo command split as in the paper's Fig. 5.
template <typename Scalar, int Dim>
struct ServoCommand {
  Vector<Scalar, Dim> motion = Vector<Scalar, Dim>::Zero();  ///< e_m, m/s
  Vector<Scalar, Dim> force = Vector<Scalar, Dim>::Zero();   ///< e_f, m/s
  Vector<Scalar, Dim> total = Vector<Scalar, Dim>::Zero();   ///< e = e_m + e_f, m/s
};

enum class ServoStatus : unsigned {
  ok = 0,
  motion_saturated = 1u << 0,  ///< g1 hit an integral or output limit
  force_saturated = 1u << 1,   ///< g2 hit an integral or output limit
  both_saturated = 3u,
  invalid_input = 1u << 2,  ///< non-finite input: command zero, integrators frozen
};
template <>
struct is_flags<ServoStatus> : std::true_type {};

template <typename Scalar, int Dim>
class HybridServo {
 public:
  HybridServo() = default;
  explicit HybridServo(const ServoGains<Scalar>& g) noexcept { set_gains(g); }

  void set_gains(const ServoGains<Scalar>& g) noexcept {
    gains_ = g;
    motion_.set_gains(g.bounded(g.motion));
    force_.set_gains(g.bounded(g.force));
  }
  const ServoGains<Scalar>& gains() const noexcept { return gains_; }
  void reset() noexcept {
    motion_.reset();
    force_.reset();
  }
  /// Resets only the force integrator (e.g. when the contact is lost).
  void reset_force() noexcept { force_.reset(); }

  /// One servo step. `force_active` false (no contact): the force part is zero and
  /// its integrator is left untouched.
  ServoStatus update(const Vector<Scalar, Dim>& desired_velocity, Scalar desired_force,
                     Scalar measured_force, const Vector<Scalar, Dim>& normal, bool force_active,
                     Scalar dt, ServoCommand<Scalar, Dim>& out) noexcept {
    if (!all_finite(desired_velocity) || !is_finite(dt) || !(dt > Scalar(0)) ||
        (force_active &&
         (!is_finite(desired_force) || !is_finite(measured_force) || !all_finite(normal)))) {
      out = ServoCommand<Scalar, Dim>{};
      return ServoStatus::invalid_input;
    }
    ServoStatus status = ServoStatus::ok;
    if (motion_.update(desired_velocity, dt, out.motion) != PiStatus::ok)
      status = status | ServoStatus::motion_saturated;
    if (!(gains_.motion.ki > Scalar(0))) motion_.reset();  // unused integral: kept at zero
    if (force_active) {
      Eigen::Matrix<Scalar, 1, 1> df(desired_force - measured_force), u;
      if (force_.update(df, dt, u) != PiStatus::ok) status = status | ServoStatus::force_saturated;
      if (!(gains_.force.ki > Scalar(0))) force_.reset();
      out.force = -u(0) * normal;  // df > 0: move along -n, into the object
    } else {
      out.force.setZero();
    }
    out.total = out.motion + out.force;
    return status;
  }

  const PiController<Scalar, Dim>& motion_pi() const noexcept { return motion_; }
  const PiController<Scalar, 1>& force_pi() const noexcept { return force_; }

 private:
  ServoGains<Scalar> gains_{};
  PiController<Scalar, Dim> motion_{gains_.motion};
  PiController<Scalar, 1> force_{gains_.force};
};

}  // namespace inhand
