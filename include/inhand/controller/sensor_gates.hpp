// Plausibility gates on what is sensed: the measured object pose and each finger's
// measured normal force (sensor faults: a vision outlier, a force spike). Part of the
// controller's input stage; see OutlierGates for the rule. Units: m, rad, N, s.
// noexcept, no allocation.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/math/status.hpp"

namespace inhand {

/// Plausibility gates on the sensed data (sensor faults: a vision outlier, a force
/// spike). A sample whose change since the last ACCEPTED one exceeds what the bound
/// allows over the elapsed time is rejected: the last accepted value is used instead
/// and the warning pose_outlier / force_outlier is raised. A reading is held for
/// `max_rejection_time` seconds of the caller's clock, and for at least one tick: a sample
/// is rejected only while the time since the last accepted one, this tick's dt included,
/// is below max(max_rejection_time, dt) + dt / 2 (the hold rounded to whole ticks, at
/// least one: for 5 ms, 5 ticks at 1 kHz, 10 at 2 kHz, 1 at 100 Hz and at 50 Hz, so a
/// gate that is on rejects a one-tick outlier at any rate); then it is accepted whatever it
/// is, so a real jump (the object was knocked) is followed after about that long.
/// Contacts that (re)start touching are always accepted. +infinity (the default)
/// disables a gate.
/// A force changes when the finger itself presses or withdraws: the force gate credits
/// the change the finger's own measured motion explains (contact_stiffness times the
/// fingertip's step into the object since the last accepted reading, ForceGate) and
/// bounds only the rest by max_force_rate, so the controller's own press is never
/// rejected as an outlier, at any loop rate.
template <typename Scalar>
struct OutlierGates {
  Scalar max_object_speed = std::numeric_limits<Scalar>::infinity();          ///< m/s
  Scalar max_object_angular_speed = std::numeric_limits<Scalar>::infinity();  ///< rad/s
  Scalar max_force_rate = std::numeric_limits<Scalar>::infinity();            ///< N/s
  /// N/m, >= 0 and finite: the stiffest contact the force gate expects. A change of the
  /// reading up to this times the fingertip's measured step into the object (along the
  /// contact normal, through the last tick's Jacobian) is the finger's own doing, not an
  /// outlier. 0: the rate bound alone. The default is force_layer.max_stiffness's.
  Scalar contact_stiffness = Scalar(1e5);
  /// s, >= 0 and finite: how long a rejected reading is held (above); 0: never held.
  Scalar max_rejection_time = Scalar(0.005);
  Validation validate() const noexcept {
    if (!(max_object_speed > Scalar(0)) || max_object_speed != max_object_speed)
      return Validation::invalid("outlier_gates.max_object_speed", "must be > 0 (+inf disables)");
    if (!(max_object_angular_speed > Scalar(0)) ||
        max_object_angular_speed != max_object_angular_speed)
      return Validation::invalid("outlier_gates.max_object_angular_speed",
                                 "must be > 0 (+inf disables)");
    if (!(max_force_rate > Scalar(0)) || max_force_rate != max_force_rate)
      return Validation::invalid("outlier_gates.max_force_rate", "must be > 0 (+inf disables)");
    if (!(contact_stiffness >= Scalar(0)) ||
        !(contact_stiffness < std::numeric_limits<Scalar>::infinity()))
      return Validation::invalid("outlier_gates.contact_stiffness", "must be >= 0 and finite");
    if (!(max_rejection_time >= Scalar(0)) ||
        !(max_rejection_time < std::numeric_limits<Scalar>::infinity()))
      return Validation::invalid("outlier_gates.max_rejection_time", "must be >= 0 and finite");
    return Validation::valid();
  }
};

/// Whether a reading rejected so far has been held as long as the gates allow: the time
/// since the last accepted one, elapsed [s] (this tick's dt [s] included), has reached
/// max(max_rejection_time, dt) + dt / 2; always, for a max_rejection_time of 0
/// (OutlierGates).
template <typename Scalar>
inline bool held_too_long(const OutlierGates<Scalar>& g, Scalar elapsed, Scalar dt) noexcept {
  if (!(g.max_rejection_time > Scalar(0))) return true;
  const Scalar hold = g.max_rejection_time > dt ? g.max_rejection_time : dt;
  return elapsed >= hold + Scalar(0.5) * dt;
}

/// The object-pose gate's state: the last accepted pose.
template <typename Scalar, int Dim>
class PoseGate {
 public:
  using PoseT = Pose<Scalar, Dim>;
  struct Step {
    PoseT pose{};          ///< the pose to use this tick (the measured or the held one)
    bool outlier = false;  ///< the measured pose was rejected
  };

  /// Restarts the hold's clock (the held pose stays until the next accepted one).
  void reset() noexcept { age_ = Scalar(0); }
  /// One tick, dt [s] since the last one; `first`: no pose accepted yet (always accepts).
  Step update(const OutlierGates<Scalar>& g, const PoseT& measured, Scalar dt,
              bool first) noexcept {
    const Scalar elapsed = age_ + dt;
    bool accept = first;
    if (!accept) {
      const Scalar dp = (measured.position - pose_.position).norm();
      const Scalar dr = rotation_log<Scalar>(
                            Rotation<Scalar, Dim>(measured.rotation * pose_.rotation.transpose()))
                            .norm();
      accept = dp <= g.max_object_speed * elapsed && dr <= g.max_object_angular_speed * elapsed;
      if (!accept && held_too_long(g, elapsed, dt)) accept = true;
    }
    if (accept) {
      pose_ = measured;
      age_ = Scalar(0);
    } else {
      age_ = elapsed;
    }
    return Step{pose_, !accept};
  }
  const PoseT& pose() const noexcept { return pose_; }  ///< the last accepted pose

 private:
  PoseT pose_{};
  Scalar age_ = Scalar(0);  ///< s since the last accepted pose
};

/// One finger's normal-force gate: the last accepted force.
template <typename Scalar>
class ForceGate {
 public:
  /// Back to "no force accepted yet".
  void reset() noexcept { valid_ = false; }
  /// One tick, dt [s] since the last one. `credit` [N], signed: the change of the reading
  /// the finger's own motion over this tick explains (contact_stiffness times the
  /// fingertip's step into the object; > 0 pressed in, < 0 withdrawn). The change since
  /// the last accepted reading is accepted when it lies within [min(0, C), max(0, C)]
  /// widened by max_force_rate times the time elapsed since then, C the credit summed
  /// over that time. A finger that does not touch clears the gate (the next touch is
  /// accepted as it comes). Returns true when the reading was rejected (an outlier).
  bool update(const OutlierGates<Scalar>& g, bool touching, Scalar reading, Scalar credit,
              Scalar dt) noexcept {
    if (!touching) {
      valid_ = false;
      return false;
    }
    const Scalar elapsed = age_ + dt;
    const Scalar credited = credit_ + credit;
    const Scalar change = reading - force_;
    const Scalar allowed = g.max_force_rate * elapsed;
    const bool ok = !valid_ ||
                    (change <= std::max(Scalar(0), credited) + allowed &&
                     change >= std::min(Scalar(0), credited) - allowed) ||
                    held_too_long(g, elapsed, dt);
    if (ok) {
      force_ = reading;
      valid_ = true;
      age_ = credit_ = Scalar(0);
    } else {
      age_ = elapsed;
      credit_ = credited;
    }
    return !ok;
  }
  Scalar force() const noexcept { return force_; }  ///< N, the force to use this tick

 private:
  Scalar force_ = Scalar(0);
  bool valid_ = false;
  Scalar age_ = Scalar(0);     ///< s since the last accepted force
  Scalar credit_ = Scalar(0);  ///< N, the credit summed since the last accepted force
};

}  // namespace inhand
