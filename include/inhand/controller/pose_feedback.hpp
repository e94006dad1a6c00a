// Layer 1: the commanded object twist from the desired and the measured object pose
// (docs/method.md section 3).
//
//   e = pose_error(X_d, X_measured)            (position m; rotation vector rad, world)
//   I <- I + dt sat_b(e), each part's norm bounded (m s; rad s; anti-windup, direction kept)
//   V = V_ff + K_p e + K_i I                   (per part: position / orientation gains)
//   V <- V * min(1, v_max / |v|, w_max / |w|)  (the whole twist scaled: screw axis kept)
// Twists are (linear velocity of the object's reference point; angular velocity), world
// frame; in the plane the angular part is a scalar. Equilibrium: e = 0 with K_i I equal
// to whatever steady twist the lower layers fail to realise; the integrator I owns the
// rigid directions of the object's motion (the force layer's loops own only the
// internal ones: docs/force_layer.md). noexcept, no allocation.
//
// The integral band. sat_b scales each part of e down to its band b (position m,
// orientation rad; direction kept) before it is integrated, so a transient larger than the
// band (the object settling into its contacts at release, a knock) adds at most b per
// second to I instead of winding it up to unwind through the loop's slow pole. With the
// object following the twist (x' = V + d, d what the lower layers do not realise, constant)
// the error obeys e'' + K_p e' + K_i sat_b(e) = 0 per part: E = |e'|^2 / 2 + K_i Phi(e),
// Phi the convex potential whose gradient is sat_b (|e|^2 / 2 inside the band, b |e| - b^2 / 2
// beyond), gives E' = -K_p |e'|^2 <= 0, so every error returns to the one equilibrium e = 0,
// K_i I = -d, for any b > 0 (docs/method.md section 3). Inside the band the loop is the
// linear PI, s^2 + K_p s + K_i (poles -1.55 and -6.45 /s at the defaults).
//
// Astray. The loop reports `astray` once the position error's norm has stayed at or beyond
// astray_distance, or the orientation error's beyond astray_angle, for astray_time: an
// object that far from its desired pose for that long is not being carried where the task
// wants it, whatever the cause (the hand's servos yielding under the load, friction, a push,
// a joint at its limit), and may be lost (docs/force_layer.md, "Astray").
#pragma once

#include <algorithm>
#include <limits>

#include "inhand/math/pose.hpp"
#include "inhand/math/status.hpp"

namespace inhand {

/// Gains and bounds of layer 1's pose loop (field names relative to the controller
/// Config, "pose_feedback.position_gain").
template <typename Scalar>
struct PoseFeedback {
  Scalar position_gain = Scalar(8);        ///< 1/s
  Scalar orientation_gain = Scalar(8);     ///< 1/s
  Scalar max_linear_speed = Scalar(0.05);  ///< m/s, bound on the commanded linear velocity
  Scalar max_angular_speed = Scalar(1.0);  ///< rad/s
  /// Integral action on the pose error (1/s^2): removes the steady offset left where
  /// the force servos' integrators balance the proportional pose feedback.
  Scalar position_integral_gain = Scalar(10);
  Scalar orientation_integral_gain = Scalar(10);
  /// Bounds on the integrated pose error (m s and rad s), anti-windup: the norm of
  /// each part is scaled down to its bound (direction kept) and the warning
  /// pose_integral_limited is raised. The defaults let the integral term add at most
  /// position_integral_gain * 2e-3 = 0.02 m/s and orientation_integral_gain * 2e-2 =
  /// 0.2 rad/s, i.e. 40 % and 20 % of the default speed bounds.
  Scalar position_integral_limit = Scalar(2e-3);
  Scalar orientation_integral_limit = Scalar(2e-2);
  /// The integral band (m and rad, > 0; +infinity: none): each part of the pose error is
  /// integrated scaled down to this norm (file comment). 10 mrad is the shipped scenarios'
  /// settle tolerance, below a release's roll; 2 mm lets a translation the workspace's edge
  /// stops wind the integral as before (docs/force_layer.md, "The pose loop's integral band").
  Scalar position_integral_band = Scalar(2e-3);
  Scalar orientation_integral_band = Scalar(1e-2);
  /// Astray (file comment): the position error's norm (m, > 0) and the orientation error's
  /// (rad, > 0) at or beyond which, held for astray_time (s, finite, >= 0), the loop reports
  /// the object astray (ControllerWarning::object_astray); +infinity: never. 3 mm is 1.5
  /// times the integral band; 0.3 rad is above the roll a release gives a held object on
  /// MuJoCo's hands (0.12 rad for a 20 g cylinder): docs/force_layer.md, "Astray".
  Scalar astray_distance = Scalar(3e-3);
  Scalar astray_angle = Scalar(0.3);
  Scalar astray_time = Scalar(0.01);
  Validation validate() const noexcept {
    if (!(astray_distance > Scalar(0)))
      return Validation::invalid("pose_feedback.astray_distance", "must be > 0");
    if (!(astray_angle > Scalar(0)))
      return Validation::invalid("pose_feedback.astray_angle", "must be > 0");
    if (!is_finite(astray_time) || astray_time < Scalar(0))
      return Validation::invalid("pose_feedback.astray_time", "must be finite and >= 0");
    if (!is_finite(position_integral_gain) || position_integral_gain < Scalar(0))
      return Validation::invalid("pose_feedback.position_integral_gain", "must be finite and >= 0");
    if (!is_finite(orientation_integral_gain) || orientation_integral_gain < Scalar(0))
      return Validation::invalid("pose_feedback.orientation_integral_gain",
                                 "must be finite and >= 0");
    if (!is_finite(position_integral_limit) || !(position_integral_limit > Scalar(0)))
      return Validation::invalid("pose_feedback.position_integral_limit", "must be finite and > 0");
    if (!is_finite(orientation_integral_limit) || !(orientation_integral_limit > Scalar(0)))
      return Validation::invalid("pose_feedback.orientation_integral_limit",
                                 "must be finite and > 0");
    if (!(position_integral_band > Scalar(0)))
      return Validation::invalid("pose_feedback.position_integral_band", "must be > 0");
    if (!(orientation_integral_band > Scalar(0)))
      return Validation::invalid("pose_feedback.orientation_integral_band", "must be > 0");
    if (!is_finite(position_gain) || position_gain < Scalar(0))
      return Validation::invalid("pose_feedback.position_gain", "must be finite and >= 0");
    if (!is_finite(orientation_gain) || orientation_gain < Scalar(0))
      return Validation::invalid("pose_feedback.orientation_gain", "must be finite and >= 0");
    if (!(max_linear_speed > Scalar(0)))
      return Validation::invalid("pose_feedback.max_linear_speed", "must be > 0");
    if (!(max_angular_speed > Scalar(0)))
      return Validation::invalid("pose_feedback.max_angular_speed", "must be > 0");
    return Validation::valid();
  }
};

/// What one pose-loop step gives: the pose error, the commanded twist and which bound
/// acted.
template <typename Scalar, int Dim>
struct PoseLoopStep {
  Twist<Scalar, Dim> pose_error = Twist<Scalar, Dim>::Zero();
  Twist<Scalar, Dim> commanded_twist = Twist<Scalar, Dim>::Zero();
  bool integral_limited = false;  ///< a part of the integral was scaled to its bound
  bool twist_limited = false;     ///< the twist was scaled to the speed bounds
  bool astray = false;  ///< the error beyond astray_distance or astray_angle for astray_time
};

/// The pose loop's state: the integral I of the pose error, and how long the error has
/// been astray (file comment).
template <typename Scalar, int Dim>
class PoseLoop {
 public:
  using TwistT = Twist<Scalar, Dim>;

  void reset() noexcept {
    integral_.setZero();
    astray_time_ = Scalar(0);
  }
  const TwistT& integral() const noexcept { return integral_; }  ///< (m s; rad s)

  /// Conditional integration against a cut made after this loop (`pf` as in update()):
  /// `removed` is what a later stage took out of this tick's commanded twist (the
  /// workspace cut, workspace_limits.hpp), `pose_error` this tick's error, dt [s] this
  /// tick's. The integral adds K I to the twist, K = diag(position_integral_gain,
  /// orientation_integral_gain) per part; d is the unit direction of K `removed` (of
  /// `removed` itself when the two gains are equal, the defaults), so that d . I holds
  /// what K I adds along `removed`. The part along d gives back this tick's growth
  /// dt (d . sat_b(e)) when that points the way the cut removed, never below zero:
  /// I <- I - min(dt (d . sat_b(e)), d . I) d when both are > 0. The integral then does not wind
  /// up against a constraint the twist cannot pass, and its norm never grows (what it takes
  /// out is at most its own part along d). Taken after update()'s norm bounds: on a tick
  /// that scaled a part to its bound, the part along d may end a little lower than before
  /// the tick (never below zero). Otherwise, or with `removed` (or K `removed`) zero or not
  /// finite, I is left alone.
  void hold_integral_along(const PoseFeedback<Scalar>& pf, const TwistT& removed,
                           const TwistT& pose_error, Scalar dt) noexcept {
    constexpr int R = SpatialDim<Dim>::kRot;
    const Scalar kp = pf.position_integral_gain, ko = pf.orientation_integral_gain;
    TwistT d = removed;  // K removed, scaled by 1 / max(kp, ko): exact for equal gains
    if (kp > ko) d.template tail<R>() *= ko / kp;
    if (ko > kp) d.template head<Dim>() *= kp / ko;
    const Scalar r = d.norm();
    if (!(r > Scalar(0)) || !is_finite(r)) return;
    d /= r;
    const Scalar grown = dt * d.dot(banded(pf, pose_error)), held = d.dot(integral_);
    if (grown > Scalar(0) && held > Scalar(0)) integral_ -= std::min(grown, held) * d;
  }

  /// One tick: desired pose and feed-forward twist, measured pose, dt > 0 [s].
  PoseLoopStep<Scalar, Dim> update(const PoseFeedback<Scalar>& pf, const Pose<Scalar, Dim>& desired,
                                   const TwistT& feedforward, const Pose<Scalar, Dim>& measured,
                                   Scalar dt) noexcept {
    constexpr int R = SpatialDim<Dim>::kRot;
    PoseLoopStep<Scalar, Dim> out;
    out.pose_error = pose_error(desired, measured);
    const bool far = !(out.pose_error.template head<Dim>().norm() < pf.astray_distance) ||
                     !(out.pose_error.template tail<R>().norm() < pf.astray_angle);
    astray_time_ = far ? astray_time_ + dt : Scalar(0);
    out.astray = far && astray_time_ >= pf.astray_time;
    integral_ += dt * banded(pf, out.pose_error);
    const Scalar ip = integral_.template head<Dim>().norm();
    if (ip > pf.position_integral_limit) {
      integral_.template head<Dim>() *= pf.position_integral_limit / ip;
      out.integral_limited = true;
    }
    const Scalar ir = integral_.template tail<R>().norm();
    if (ir > pf.orientation_integral_limit) {
      integral_.template tail<R>() *= pf.orientation_integral_limit / ir;
      out.integral_limited = true;
    }
    TwistT V = feedforward;
    V.template head<Dim>() += pf.position_gain * out.pose_error.template head<Dim>() +
                              pf.position_integral_gain * integral_.template head<Dim>();
    V.template tail<R>() += pf.orientation_gain * out.pose_error.template tail<R>() +
                            pf.orientation_integral_gain * integral_.template tail<R>();
    const Scalar lin = V.template head<Dim>().norm(), ang = V.template tail<R>().norm();
    Scalar scale = Scalar(1);
    if (lin > pf.max_linear_speed) scale = pf.max_linear_speed / lin;
    if (ang > pf.max_angular_speed) scale = std::min(scale, pf.max_angular_speed / ang);
    if (scale < Scalar(1)) {
      V *= scale;
      out.twist_limited = true;
    }
    out.commanded_twist = V;
    return out;
  }

 private:
  /// sat_b(e): each part of e scaled down to its band, direction kept (file comment).
  static TwistT banded(const PoseFeedback<Scalar>& pf, const TwistT& e) noexcept {
    constexpr int R = SpatialDim<Dim>::kRot;
    TwistT b = e;
    const Scalar ep = e.template head<Dim>().norm(), er = e.template tail<R>().norm();
    if (ep > pf.position_integral_band) b.template head<Dim>() *= pf.position_integral_band / ep;
    if (er > pf.orientation_integral_band)
      b.template tail<R>() *= pf.orientation_integral_band / er;
    return b;
  }

  TwistT integral_ = TwistT::Zero();
  Scalar astray_time_ = Scalar(0);  ///< s the error has been at or beyond the astray bounds
};

}  // namespace inhand
