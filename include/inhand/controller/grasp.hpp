// The grasp phase (docs/method.md section 8) and the per-finger contact states.
//
// Grasp (object frozen by the simulator or held by a fixture): every finger moves a
// virtual contact point on its fingertip, p_v = fingertip centre - radius * n_t, towards
// its desired contact point p_t, where n_t is the EXPECTED outward object normal at p_t
// (the approach direction is -n_t). Because the geometry is unknown, the finger keeps
// creeping along -n_t at `creep_speed` after reaching p_t until tactile sensing reports
// contact. On contact the actual contact point is recorded and the finger presses with
// a light force (force servo along the measured normal; see below) while its contact point is
// drawn tangentially towards p_t with `tangential_gain`; in addition the fingertip
// slides along the tangential part of n_t at up to `alignment_speed`, which on a convex
// object turns the measured normal n towards the expected one (a target on the
// object's axis is otherwise ambiguous: p_t - p_c is then parallel to n). The grasp is
// complete once every finger has been placed -- its contact point came within
// `position_tolerance` of p_t in the tangent plane with the angle between n and n_t
// below `alignment_tolerance`, or the contact stalled short of that (over `settle_time`
// its normal turned by less than a quarter of alignment_tolerance and its point moved
// by less than a quarter of position_tolerance, as for an off-centre finger on a
// sphere) -- and touches with |f - f_g| <= force_tolerance * f_g, for `settle_time`
// seconds (the paper: "the predefined desired contact points and the desired force are
// approached").
// The grasp pattern q_g is the force planner's pattern over the EXPECTED normals n_t,
// every finger counted as touching (preset fingers nominal_force, the balancing ones
// what cancels the resultant): the object is then in equilibrium at release if the
// contacts are where they were asked for. (Equal forces on three fingers against a
// thumb would push the object into the thumb with twice the nominal force at release.)
// n_t is fixed, so q_g is planned once, by start_grasp, free of sensor noise.
// A placed finger presses with its grasp force f_g = s_g q_g (release_grip_scale below:
// at least release_grip, more where the grasp's geometry needs it to take release_load,
// less if some f_g would exceed max_force; one scale for all, so the pattern stays
// balanced): the grip the force layer holds the object with on its first free tick is
// then already there when the object is released. s_g is sized over the expected normals
// n_t by start_grasp, and again over the measured normals on the first tick every finger
// is placed (it is only raised then). A load the held
// object hid (its weight, say) arrives at release as a step, faster than any force
// loop can answer -- a 400 g object released towards the thumb of a 33 kN/m grasp
// opened the fingers' contacts (30 um of compression at 1 N) within 3 ms -- so only
// compression already in the contacts carries it.
// A finger slides to its target lightly: it servos to slide_force_fraction * q_g until
// its contact is first placed; from then on it presses with f_g and no longer slides
// (its contact velocity is the force servo's, along the normal). Sliding under a normal force f
// leaves a tangential force of up to mu f on the object (friction, which tactile normal
// sensing cannot see); the frozen object takes it, and at release it acts as a step
// load. Fingers that touched 9 mm below a cylinder's equator and slid to it at full
// force left 0.8 * 6 N = 4.8 N on a 50 g object, which then rolled out of a stiff
// (50 kN/m) grasp in 9 ms; sliding at 0.3 q_g leaves 30 % of that.
// A squeeze without a couple. q_g cancels the resultant force, not the moment: a thumb
// about 1 mm off the line of the fingers opposite (a slender box in MuJoCo's Shadow-like
// hand) squeezes with a couple q_thumb x offset that the fixture carries; released, it rolled
// the box 0.12 rad (release_grip 2). So on the first tick every finger is placed, the single
// balancing finger's target moves by balancing_shift() (grasp_map.hpp) to where the pattern's
// moment across its normal vanishes, and if that is more than position_tolerance / 4 away it
// slides there at slide_force_fraction, placed again within position_tolerance / 4 (one
// shot per grasp: contact noise moves the point by about its own size; none with several
// balancing fingers). Exact on a flat face, a first step on a curved one.
// A finger that loses its contact during the grasp after touching comes back at
// creep_speed (surface_point below), not at approach_speed: the object is held until
// release, so its surface is where the finger touched it. At approach_speed a finger
// behind an actuator lag of several milliseconds hit the surface again with several
// times its force target; its force integral wound up during that overshoot, so the
// finger backed off past its target until the contact opened again, a cycle that never let
// the grasp settle (0.3 N targets cycling between 0 and 2.3 N every 105 ms on a 47 kN/m
// contact with 6.7 ms of lag).
// During manipulation a finger that loses contact re-approaches along its last
// measured normal, aiming at its last contact point carried rigidly with the measured
// object pose, and is reported as `reacquiring` until it touches again.
// A finger that misses. An object smaller than expected, or narrower than the hand's
// spread, may lie beside a finger's line of approach (a 15 mm sphere between the Allegro-like
// hand's index and ring fingers): the finger creeps on and the grasp never completes. One
// that has not touched the object when its fingertip's centre p_c crosses the plane through
// the measured object centre c normal to n_t ((p_c - c) . n_t < 0, passed_object_centre())
// has passed the object's middle beside it and could only reach its far half, where the
// fingers opposite press (the virtual contact point is too early a test: the three-finger
// hand touches a 12 mm sphere with the fingertip's side after that point has crossed). It is
// left out (FingerState::missed, ControllerWarning::grasp_finger_missed, zero command); q_g
// is planned again over the other targets' normals and s_g sized over it
// (leave_out_missed(), tick_steps.hpp); the grasp completes once the others are placed, at
// least two, one balancing. In manipulation it stays out until the object touches it. A
// finger that touched once and lost its contact is not left out: its surface is known.
// Gravity's side. With ForceLayerParams::gravity_direction set (g, unit), a pressing finger
// aligns its normal not with n_t but with n_t turned towards g by up to `gravity_tilt`,
//   n_a = (n_t + tan(gravity_tilt) g_p) / |.|,   g_p = g - (g . n_t) n_t
// (the full tilt where g lies in the tangent plane, none where g is along n_t), so on a
// curved object its contact ends on the side of the centre gravity pulls towards and the
// squeeze, -f n, pushes against gravity: sin(tilt) f per finger. A finger stops aligning at
// the first normal within its tolerance of the aim, on the side it comes from; aiming at
// gravity's side that tolerance is alignment_tolerance / 2, so the default tilt, 1.5 times
// the default alignment_tolerance, leaves a contact 0.05-0.1 rad on gravity's side from
// either side. Without it a finger from the side away from gravity
// stops at the tolerance's edge there (1 mm from a 20 mm cylinder's axis), and the squeeze
// pushes the object the way gravity does (0.58 N of the paper cylinder's 12 N: with 0.4 kg
// at friction 0.4, a slide out at release instead of a hold; docs/force_layer.md).
// The tilt is scaled by 1 - |d_t| / position_tolerance (d_t: the point's tangential miss
// of p_t; 0 on a curved object for model-free targets on its axis): a finger still
// sliding to its target is not held back, and no contact is taken farther than
// position_tolerance from a surface target. A contact that moves over a settle window by
// more than a quarter of position_tolerance while its normal turns by less than
// flat_curvature times that distance (a flat face, a cylinder along its axis: the tilt is
// out of reach) aims at n_t for the rest of the grasp (SettleWindow::gravity_side). The
// pattern and s_g are planned over n_t as before; a balancing finger sent to its
// balancing point aims at the normal measured there.
// Release grip: release_grip.hpp (the grip the grasp presses with, sized for the load
// that arrives at release).
// Units: m, m/s, s, N; all points and normals in the world frame.
#pragma once

#include <algorithm>
#include <cmath>

#include "inhand/controller/controller_status.hpp"
#include "inhand/controller/force_layer_params.hpp"
#include "inhand/controller/release_grip.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar>
struct GraspParams {
  Scalar approach_gain = Scalar(4);           ///< 1/s, proportional gain towards the target
  Scalar approach_speed = Scalar(0.03);       ///< m/s, cap on the approach velocity
  Scalar creep_speed = Scalar(0.005);         ///< m/s along -n until contact is sensed
  Scalar tangential_gain = Scalar(5);         ///< 1/s, pressing: tangential pull to the target
  Scalar force_tolerance = Scalar(0.1);       ///< relative, grasp-complete criterion
  Scalar position_tolerance = Scalar(1e-3);   ///< m, tangential, grasp-complete criterion
  Scalar alignment_speed = Scalar(0.1);       ///< m/s, pressing: normal alignment speed
  Scalar alignment_tolerance = Scalar(0.05);  ///< rad, grasp-complete criterion
  Scalar settle_time = Scalar(0.1);           ///< s the criterion must hold
  Scalar slide_force_fraction = Scalar(0.3);  ///< in (0, 1], force while sliding (see above)
  Scalar gravity_tilt = Scalar(0.075);        ///< rad, [0, pi/4], towards gravity (Gravity's side)
  Scalar flat_curvature = Scalar(10);         ///< 1/m, >= 0, a flatter contact aims at n_t (above)

  Validation validate() const noexcept {
    if (!is_finite(approach_gain) || !(approach_gain > Scalar(0)))
      return Validation::invalid("grasp.approach_gain", "must be finite and > 0");
    if (!is_finite(approach_speed) || !(approach_speed > Scalar(0)))
      return Validation::invalid("grasp.approach_speed", "must be finite and > 0");
    if (!is_finite(creep_speed) || !(creep_speed > Scalar(0)) || creep_speed > approach_speed)
      return Validation::invalid("grasp.creep_speed", "must be finite, > 0 and <= approach_speed");
    if (!is_finite(tangential_gain) || !(tangential_gain >= Scalar(0)))
      return Validation::invalid("grasp.tangential_gain", "must be finite and >= 0");
    if (!is_finite(alignment_speed) || !(alignment_speed >= Scalar(0)))
      return Validation::invalid("grasp.alignment_speed", "must be finite and >= 0");
    if (!is_finite(alignment_tolerance) || !(alignment_tolerance > Scalar(0)))
      return Validation::invalid("grasp.alignment_tolerance", "must be finite and > 0");
    if (!is_finite(position_tolerance) || !(position_tolerance > Scalar(0)))
      return Validation::invalid("grasp.position_tolerance", "must be finite and > 0");
    if (!is_finite(force_tolerance) || !(force_tolerance > Scalar(0)))
      return Validation::invalid("grasp.force_tolerance", "must be finite and > 0");
    if (!is_finite(settle_time) || !(settle_time >= Scalar(0)))
      return Validation::invalid("grasp.settle_time", "must be finite and >= 0");
    if (!is_finite(slide_force_fraction) || !(slide_force_fraction > Scalar(0)) ||
        !(slide_force_fraction <= Scalar(1)))
      return Validation::invalid("grasp.slide_force_fraction", "must be in (0, 1]");
    if (!(gravity_tilt >= Scalar(0)) || !(gravity_tilt <= Scalar(0.7853981633974483)))
      return Validation::invalid("grasp.gravity_tilt", "must be in [0, pi/4]");
    if (!is_finite(flat_curvature) || !(flat_curvature >= Scalar(0)))
      return Validation::invalid("grasp.flat_curvature", "must be finite and >= 0");
    return Validation::valid();
  }
};

/// Desired contact point and expected outward normal for one finger (world frame).
template <typename Scalar, int Dim>
struct GraspTarget {
  Vector<Scalar, Dim> contact_point = Vector<Scalar, Dim>::Zero();
  Vector<Scalar, Dim> normal = Vector<Scalar, Dim>::UnitX();  ///< unit, out of the object

  Validation validate() const noexcept {
    if (!all_finite(contact_point))
      return Validation::invalid("grasp_target.contact_point", "must be finite");
    if (!all_finite(normal) || !(normal.norm() > Scalar(0.5)) || !(normal.norm() < Scalar(1.5)))
      return Validation::invalid("grasp_target.normal", "must be a finite unit vector");
    return Validation::valid();
  }
};

/// Approach velocity of a virtual contact point p_v towards target p_t with the
/// expected outward normal n: saturated P term plus creep along -n. Once p_v is past
/// p_t (on the -n side) the P term keeps only its tangential part, so the finger
/// goes on creeping inwards at creep_speed until contact is sensed.
template <typename Scalar, int Dim>
inline Vector<Scalar, Dim> approach_velocity(const GraspParams<Scalar>& g,
                                             const Vector<Scalar, Dim>& p_v,
                                             const Vector<Scalar, Dim>& p_t,
                                             const Vector<Scalar, Dim>& n) noexcept {
  Vector<Scalar, Dim> e = p_t - p_v;
  // Without this the outward pull of the P term would cancel the creep at
  // creep_speed / approach_gain behind p_t, and a finger whose object surface lies
  // deeper than expected would stall there, never touching.
  const Scalar en = e.dot(n), nn = n.squaredNorm();
  if (en > Scalar(0) && nn > Scalar(0)) e -= (en / nn) * n;
  Vector<Scalar, Dim> v = g.approach_gain * e;
  const Scalar speed = v.norm();
  if (speed > g.approach_speed) v *= g.approach_speed / speed;
  return v - g.creep_speed * n;
}

/// A finger that misses (file comment): whether the point p (the fingertip's centre) of a
/// finger approaching along -n_t (unit) has crossed the plane through the measured object
/// centre c normal to n_t.
template <typename Scalar, int Dim>
inline bool passed_object_centre(const Vector<Scalar, Dim>& p_v, const Vector<Scalar, Dim>& c,
                                 const Vector<Scalar, Dim>& n_t) noexcept {
  return (p_v - c).dot(n_t) < Scalar(0);
}

/// Where a finger that has touched its target's surface aims when it comes back (the
/// target moved along its normal to the fingertip's level): approach_velocity() then
/// keeps only the tangential correction and the creep; the surface is where it was
/// touched, and aiming deeper would hit it at approach_speed.
template <typename Scalar, int Dim>
inline Vector<Scalar, Dim> surface_point(const Vector<Scalar, Dim>& p_v,
                                         const GraspTarget<Scalar, Dim>& t) noexcept {
  return t.contact_point -
         ((t.contact_point - p_v).dot(t.normal) / t.normal.squaredNorm()) * t.normal;
}

/// A pressing finger's progress towards its target: the window over which a stall is
/// judged (see the file comment). Reset by start().
template <typename Scalar, int Dim>
struct SettleWindow {
  Vector<Scalar, Dim> normal = Vector<Scalar, Dim>::Zero();  ///< at the window's start
  Vector<Scalar, Dim> point = Vector<Scalar, Dim>::Zero();   ///< m, at the window's start
  Scalar time = Scalar(0);                                   ///< s into the window
  bool stalled = false;  ///< the last full window saw (almost) no progress
  bool placed = false;   ///< placed at least once since the touch (full grasp force)
  /// Aims at gravity's side (grasp.hpp); cleared for the grasp on a flat face or by the
  /// balancing shift. Kept by start() (a lost contact), set again by a new grasp.
  bool gravity_side = true;
  void start() noexcept {
    time = Scalar(0);
    stalled = false;
    placed = false;
  }
};

/// One pressing tick of the grasp phase for a touching finger.
template <typename Scalar, int Dim>
struct PressStep {
  Vector<Scalar, Dim> velocity = Vector<Scalar, Dim>::Zero();  ///< m/s, contact velocity
  bool placed = false;  ///< the contact reached its target, or stalled short of it
};

/// The normal a pressing finger aligns with (Gravity's side, above): the target's normal
/// n_t (unit) turned towards `gravity` (unit, or zero: unknown) by up to `tilt` [rad].
template <typename Scalar, int Dim>
inline Vector<Scalar, Dim> gravity_side_normal(const Vector<Scalar, Dim>& n_t,
                                               const Vector<Scalar, Dim>& gravity,
                                               Scalar tilt) noexcept {
  const Vector<Scalar, Dim> a = n_t + std::tan(tilt) * (gravity - gravity.dot(n_t) * n_t);
  return a / a.norm();  // |a| >= |n_t| = 1
}

/// The pressing finger's contact velocity: the tangential pull of the measured contact
/// point p (normal n) towards the target, plus the alignment of n with the aimed normal
/// (while window.gravity_side, gravity_side_normal() of the target's with the tilt scaled
/// by 1 - |d_t| / position_tolerance, d_t the point's tangential miss; `gravity` unit or
/// zero); and whether the contact is placed (reached, or stalled over the last settle
/// window). Updates the window.
template <typename Scalar, int Dim>
inline PressStep<Scalar, Dim> press_step(const GraspParams<Scalar>& g,
                                         const GraspTarget<Scalar, Dim>& target,
                                         const Vector<Scalar, Dim>& p, const Vector<Scalar, Dim>& n,
                                         const Vector<Scalar, Dim>& gravity, Scalar dt,
                                         SettleWindow<Scalar, Dim>& window) noexcept {
  using Vec = Vector<Scalar, Dim>;
  PressStep<Scalar, Dim> out;
  const Vec d = target.contact_point - p;
  const Vec d_tangential = d - d.dot(n) * n;
  const Scalar near = std::max(Scalar(0), Scalar(1) - d_tangential.norm() / g.position_tolerance);
  const Vec aim = window.gravity_side && near > Scalar(0)
                      ? gravity_side_normal(target.normal, gravity, near * g.gravity_tilt)
                      : target.normal;
  const Scalar cos_angle = n.dot(aim);
  const Vec misalignment = aim - cos_angle * n;  // |.| = sin(angle)
  out.velocity = g.tangential_gain * d_tangential + g.alignment_speed * misalignment;
  if (window.time <= Scalar(0)) {
    window.normal = n;
    window.point = p;
  }
  window.time += dt;
  if (window.time >= std::max(g.settle_time, dt)) {
    const Scalar turned = (n - window.normal).norm(), moved = (p - window.point).norm();
    window.stalled = turned < Scalar(0.25) * std::sin(g.alignment_tolerance) &&
                     moved < Scalar(0.25) * g.position_tolerance;
    if (moved >= Scalar(0.25) * g.position_tolerance && turned < g.flat_curvature * moved)
      window.gravity_side = false;  // a flat face: the tilt is out of reach
    window.time = Scalar(0);
  }
  const bool tilted = window.gravity_side && near > Scalar(0) && gravity.squaredNorm() > Scalar(0);
  const Scalar tolerance = tilted ? Scalar(0.5) * g.alignment_tolerance : g.alignment_tolerance;
  const bool reached = cos_angle > Scalar(0) && misalignment.norm() <= std::sin(tolerance) &&
                       d_tangential.norm() <= g.position_tolerance;
  out.placed = reached || window.stalled;
  return out;
}

}  // namespace inhand
