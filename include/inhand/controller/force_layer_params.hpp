// Parameters and status flags of the force layer (force_layer.hpp; docs/force_layer.md
// gives each parameter's role, range and the figures measured with the defaults).
// Units: SI; rates in 1/s, bandwidths in rad/s. Field names in Validation are relative to
// the controller Config ("force_layer.bandwidth").
#pragma once

#include <limits>

#include "inhand/math/flags.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar>
struct ForceLayerParams {
  Scalar bandwidth = Scalar(40);               ///< w_c [rad/s], crossover of each force loop
  Scalar integral_corner = Scalar(10);         ///< w_i [rad/s], PI zero; 0: proportional only
  Scalar min_stiffness = Scalar(200);          ///< [N/m], lower bound of the estimate
  Scalar max_stiffness = Scalar(1e5);          ///< [N/m], upper bound and initial estimate
  Scalar stiffness_window = Scalar(0.2);       ///< [s], estimator memory
  Scalar min_excitation = Scalar(1e-5);        ///< [m], std of the advance needed to update
  Scalar min_fit = Scalar(0.9);                ///< r^2 of the fit needed to update, in (0, 1]
  Scalar max_integral_velocity = Scalar(0.1);  ///< [m/s], bound on (w_c / k) w_i z
  Scalar slip_distance = Scalar(3e-4);         ///< [m], see the file comment
  Scalar grip_rise_rate = Scalar(50);          ///< [1/s], rise of s while slipping
  Scalar friction_margin = Scalar(1.5);        ///< >= 1, grip after a slip onset / grip at onset
  Scalar grip_decay_time = Scalar(20);         ///< [s], s_slip back to 1 (or s_g held) after a slip
  Scalar release_grip = Scalar(2);             ///< >= 1, s when the object is released
  /// true: the grip at release (the grasp's s_g, or release_grip) stays the grip's floor while
  /// the object is free (the load it is sized for, the weight, stays); false: it decays to 1
  /// with grip_decay_time, as a slip's raise does (force_layer.hpp, docs/force_layer.md).
  bool hold_release_grip = true;
  Scalar release_load = Scalar(4);       ///< [N], load the release grip is sized for
  Scalar rigid_tolerance = Scalar(0.1);  ///< eps, dimensionless (see the file comment)
  Scalar contact_damping = Scalar(10);   ///< c [N s/m], largest expected; 0: no gain cap
  Scalar capacity_time = Scalar(0.02);   ///< [s], slip at the grip's cap before beyond_capacity
  /// in [0, 1]: beyond_capacity also needs the slide at the cap running at least this
  /// fraction of its fastest since the cap began to bind (a settling pad's shear slows
  /// down; force_layer.hpp). 0: any slide.
  Scalar capacity_slide_ratio = Scalar(0.8);
  /// The hand's joint servo, every joint alike (joint_servo.hpp): position stiffness K
  /// [N m/rad] and velocity gain D [N m s/rad] with which it tracks the integral of the
  /// joint-velocity command. 0 (the default): not modelled, a rigid servo. With K > 0 the
  /// force loop is scheduled on the contact and the servo in series, and presses so that
  /// the two store a force along n (between J J^T n and n, weighted by their compliances).
  Scalar servo_stiffness = Scalar(0);
  Scalar servo_damping = Scalar(0);
  /// The direction gravity pulls in, world frame (x, y, z; a planar hand takes x and y),
  /// any length; all zero (the default): unknown. When known, the grasp's grip is also
  /// sized for the step of a weight of up to release_load along it (release_grip.hpp).
  Vector<Scalar, 3> gravity_direction = Vector<Scalar, 3>::Zero();

  Validation validate() const noexcept {
    const Scalar inf = std::numeric_limits<Scalar>::infinity();
    struct Field {
      const char* name;
      Scalar value, lo, hi;
      bool lo_open;
    };
    const Field fields[] = {
        {"force_layer.bandwidth", bandwidth, Scalar(0), inf, true},
        {"force_layer.integral_corner", integral_corner, Scalar(0), inf, false},
        {"force_layer.min_stiffness", min_stiffness, Scalar(0), inf, true},
        {"force_layer.max_stiffness", max_stiffness, min_stiffness, inf, false},
        {"force_layer.stiffness_window", stiffness_window, Scalar(0), inf, true},
        {"force_layer.min_excitation", min_excitation, Scalar(0), inf, true},
        {"force_layer.min_fit", min_fit, Scalar(0), Scalar(1) + Scalar(1e-12), true},
        {"force_layer.max_integral_velocity", max_integral_velocity, Scalar(0), inf, true},
        {"force_layer.slip_distance", slip_distance, Scalar(0), inf, true},
        {"force_layer.grip_rise_rate", grip_rise_rate, Scalar(0), inf, false},
        {"force_layer.friction_margin", friction_margin, Scalar(1), inf, false},
        {"force_layer.grip_decay_time", grip_decay_time, Scalar(0), inf, true},
        {"force_layer.release_grip", release_grip, Scalar(1), inf, false},
        {"force_layer.release_load", release_load, Scalar(0), inf, false},
        {"force_layer.rigid_tolerance", rigid_tolerance, Scalar(0), inf, true},
        {"force_layer.contact_damping", contact_damping, Scalar(0), inf, false},
        {"force_layer.capacity_time", capacity_time, Scalar(0), inf, false},
        {"force_layer.capacity_slide_ratio", capacity_slide_ratio, Scalar(0),
         Scalar(1) + Scalar(1e-12), false},
        {"force_layer.servo_stiffness", servo_stiffness, Scalar(0), inf, false},
        {"force_layer.servo_damping", servo_damping, Scalar(0), inf, false},
    };
    for (const Field& f : fields) {
      const bool ok =
          is_finite(f.value) && (f.lo_open ? f.value > f.lo : f.value >= f.lo) && f.value < f.hi;
      if (!ok)
        return Validation::invalid(
            f.name, f.lo_open ? "must be finite and > its lower bound (see the header)"
                              : "must be finite and >= its lower bound (see the header)");
    }
    if (!all_finite(gravity_direction))
      return Validation::invalid("force_layer.gravity_direction", "must be finite");
    return Validation::valid();
  }
};

/// What the force layer reports each tick (bit flags).
enum class ForceLayerStatus : unsigned {
  ok = 0,
  slipping = 1u << 0,          ///< some finger's contact slides along the object
  grip_raised = 1u << 1,       ///< s > 1: the grip is above the nominal pattern
  beyond_capacity = 1u << 2,   ///< the load needs more than max_force (or min_force is unreachable)
  integral_limited = 1u << 3,  ///< some force integrator reached max_integral_velocity
  /// object free: some touching finger measures more than max_force. No target asks for
  /// that much (every target is capped at max_force), so the object's motion presses it
  /// into the finger: the grasp is being deformed (controller_state.hpp, hold_risk)
  over_max_force = 1u << 4,
};
template <>
struct is_flags<ForceLayerStatus> : std::true_type {};

}  // namespace inhand
