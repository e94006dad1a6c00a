// Layer 2, the force layer: normal-force loops of all touching fingers together, the
// grip that follows the load, and slip detection (docs/method.md section 5).
//
// Frames, units, signs: world frame, SI. n_i is the object's OUTWARD unit normal at
// finger i's contact; forces are normal-force magnitudes >= 0 [N]; the force finger i
// exerts on the object is -f_i n_i. The output u_i [m/s] is the fingertip velocity INTO the
// object along -n_i (u_i > 0 presses harder), added as -u_i n_i to the motion (eq. 7).
//
// One equilibrium. A vector of normal forces f splits into
//   rigid    : range(A)          -- the part that has a resultant wrench on the object
//   internal : null(A^T)          -- squeezing that leaves the object in equilibrium
// where row i of A is [n_i^T, ((p_i - p_o) x n_i)^T / L] (A V is the normal velocity of
// the object's material points at the contacts for the twist V; L the RMS lever arm
// makes both halves dimensionless). The rigid part of the measured forces is what
// the normal forces carry of the external load (weight, a push, a sensor bias); the
// object's pose loop (layer 1) owns every rigid direction. The force loops own only
// the internal directions: their error is projected onto null(A^T),
//   e = P_int (s q - f_m),   P_int = I - A (A^T A + eps I)^-1 A^T,
// with q the planner's force pattern and s >= 1 the grip scale, and so is the state
// of their integrator. No direction has two integrators, so nothing can ramp along a
// family of equilibria (the drift of the paper's per-finger loops). At equilibrium
// the measured forces are f_m = P_r f_m + s P_int q: the load share plus the grip.
//
// A loop that does not scale with the contact stiffness. Each finger's loop is
//   u_i = (w_c / k_i) (e_i + w_i z_i),   z_i' = e_i   (z kept internal, bounded; force_loop.hpp)
// with k_i [N/m] the online estimate of the contact stiffness (StiffnessEstimator,
// contact_observers.hpp; max_stiffness until the fit is trusted). A joint servo in series
// (servo_stiffness, servo_damping) adds its stiffness in series and its damping as a
// feedthrough (joint_servo.hpp, force_loop_gain()). With k_i = k the loop crosses over at w_c
// whatever the stiffness; with one tick of command delay, z^2 - z + a = 0, a = rho w_c T, it
// is stable for a < 1: at w_c = 40 rad/s, T = 1 ms, for k_i up to rho = 25 times too low
// (docs/force_layer.md gives the phase margin with actuator lag).
// The contact's damping c [N s/m] answers a commanded velocity within the tick: the loop
// through it, f_{n+1} = ... - c kp f_n (kp = w_c / k_i), oscillates at period 2 once c kp >= 1,
// so kp <= 1 / (2 c) (c: the larger of contact_damping and the servo's feedthrough).
//
// Grip that follows the load. s is the largest of
//   1                 the nominal grip (the planner's pattern);
//   s_release   Step::release_grip (the grasp's s_g, release_grip.hpp; 0: release_grip) from
//               the first free tick, kept while the object is free (hold_release_grip; false:
//               decaying like s_slip): the load the held object hid arrives at release as a
//               step, faster than a slip is felt, and stays (its weight; friction's share unseen);
//   s_min_force the least s for which every target s (P_int q)_i + (P_r f_m)_i is at least
//               min_force: a normal load taken from a finger is given back by squeezing;
//   s_slip      raised at grip_rise_rate per second while any finger slips, and at a slip
//               onset at once to friction_margin times the grip at which it slipped (that
//               grip was at the friction cone's edge, eq. 8); back to 1 (or the held s_release)
//               with time constant grip_decay_time once the slip stops (falls when the load goes);
// capped at the largest s for which no target exceeds max_force. `beyond_capacity` (the load
// exceeds what the hand can hold with this friction) is raised when min_force has been out of
// reach for capacity_time (a release's step passes through it for a few ticks), or when a
// finger has slipped with the cap binding for capacity_time and the slide is not slowing
// down: its speed (SlipDetector's lead) at least capacity_slide_ratio times its peak since
// the cap began to bind. A pad's shear as the released object settles is flagged as slip too
// but slows down once the pad carries the load; a load beyond friction at the cap keeps the
// object accelerating (docs/force_layer.md, "Said in time"). Slip: SlipDetector.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/controller/contact_observers.hpp"
#include "inhand/controller/force_layer_params.hpp"
#include "inhand/controller/force_loop.hpp"
#include "inhand/controller/grasp_map.hpp"
#include "inhand/controller/joint_servo.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// Normal-force loops of NumFingers fingers (fixed, or Dynamic sized by resize()).
template <typename Scalar, int Dim, int NumFingers>
class ForceLayer {
 public:
  using Map = GraspMap<Scalar, Dim, NumFingers>;
  static constexpr int W = Map::W;  ///< wrench size
  using ForceVector = typename Map::ForceVector;
  using Points = typename Map::Points;  ///< one column per finger
  using Mask = typename Map::Mask;
  using Wrench = typename Map::Wrench;  ///< (force; torque about p_o)
  using Vec = Vector<Scalar, Dim>;

  /// Per-tick input: touching fingers' measured contact points, outward normals and normal
  /// forces (columns / entries of the others are ignored), the planner's pattern q, the
  /// object pose, the planner's min/max force bounds, and whether the object is free (false
  /// while the grasp holds it fixed: every direction is then internal, the grip stays 1).
  struct Step {
    const Mask* touching = nullptr;
    const Points* points = nullptr;
    const Points* normals = nullptr;
    const ForceVector* measured = nullptr;
    const ForceVector* pattern = nullptr;
    /// Fingertip steps at the contacts over the last tick [m], world: J (q - q_prev).
    const Points* tip_steps = nullptr;
    /// Per finger, servo_normal_gain() at its contact [1/m^2] (joint_servo.hpp); 0, null: none
    const ForceVector* servo_gain = nullptr;
    Vec object_position = Vec::Zero();
    Rotation<Scalar, Dim> object_rotation = Rotation<Scalar, Dim>::Identity();
    Scalar min_force = Scalar(0);
    Scalar max_force = std::numeric_limits<Scalar>::infinity();
    bool object_free = true;
    Scalar release_grip = Scalar(0);  ///< s on release: the grasp's s_g; 0: params'
    Scalar dt = Scalar(1e-3);
  };

  struct Result {
    ForceVector velocity;          ///< u_i [m/s] into the object along -n_i (0 when not touching)
    ForceVector target;            ///< the force each loop drives to [N]
    Mask slipping;                 ///< per finger
    Wrench load = Wrench::Zero();  ///< external wrench they balance, -sum(-f n; r x -f n)
    Scalar grip = Scalar(1);       ///< s
    ForceLayerStatus status = ForceLayerStatus::ok;
  };

  explicit ForceLayer(int fingers = (NumFingers == Dynamic ? 0 : NumFingers)) { resize(fingers); }

  /// Sizes the state (allocates only for a run-time finger count) and resets it.
  void resize(int fingers) {
    n_ = fingers;
    z_.setZero(fingers);
    was_touching_.setZero(fingers);
    e_.setZero(fingers);
    q_int_.setZero(fingers);
    r_load_.setZero(fingers);
    motion_.resize(fingers);
    stiffness_.resize(fingers);
    slip_.resize(fingers);
    map_.resize(fingers);
    reset();
  }
  int size() const noexcept { return n_; }
  void set_params(const ForceLayerParams<Scalar>& p) noexcept { params_ = p; }
  const ForceLayerParams<Scalar>& params() const noexcept { return params_; }

  /// Clears integrators, estimates (back to max_stiffness), slip filters and the grip.
  void reset() noexcept {
    z_.setZero();
    stiffness_.reset(params_.max_stiffness);
    was_touching_.setZero();
    motion_.reset();
    grip_slip_ = Scalar(1);
    was_slipping_ = was_free_ = false;
    short_time_ = capped_slip_time_ = capped_slide_peak_ = Scalar(0);
  }
  const ForceVector& stiffness_estimate() const noexcept { return stiffness_.estimate(); }
  /// The contact stiffness [N/m] for the press direction (StiffnessEstimator::press()).
  const ForceVector& press_stiffness() const noexcept { return stiffness_.press(); }
  const ForceVector& integral() const noexcept { return z_; }  ///< z_i [N s], internal

  /// One tick. Inputs must be finite (the controller checks them); dt > 0.
  void update(const Step& in, Result& out) noexcept {
    const ForceLayerParams<Scalar>& p = params_;
    const Scalar dt = in.dt;
    const Mask& touching = *in.touching;
    out.velocity.setZero(n_);
    out.target.setZero(n_);
    out.slipping.setZero(n_);
    out.status = ForceLayerStatus::ok;
    // Touch onsets: fresh integrator, estimator window and slip filters.
    for (int i = 0; i < n_; ++i) {
      const bool t = touching(i) != 0;
      if (t && !was_touching_(i)) {
        z_(i) = Scalar(0);
        stiffness_.start(i, (*in.measured)(i));
        slip_.start(i);
      }
      was_touching_(i) = t ? 1 : 0;
    }
    motion_.update(touching, *in.points, *in.normals, *in.tip_steps, in.object_rotation,
                   in.object_position);
    stiffness_.update(
        {p.min_stiffness, p.max_stiffness, p.stiffness_window, p.min_excitation, p.min_fit},
        touching, motion_.advance(), *in.measured, dt);
    const typename SlipDetector<Scalar, Dim, NumFingers>::Report slip = slip_.update(
        touching, motion_.steps(), *in.normals, in.object_free, p.slip_distance, dt, out.slipping);

    // Rigid / internal split of the touching fingers' normal-force space.
    map_.build(touching, *in.points, *in.normals, in.object_position, p.rigid_tolerance);
    // q_int = P_int q, r_load = P_r f_m, and the load the normal forces balance.
    for (int i = 0; i < n_; ++i) {
      const bool t = touching(i) != 0;
      q_int_(i) = t ? (*in.pattern)(i) : Scalar(0);
      r_load_(i) = t ? (*in.measured)(i) : Scalar(0);
    }
    if (in.object_free) {
      map_.project_internal(q_int_);
      out.load = map_.balanced_wrench(r_load_);
      // r_load = f_m - P_int f_m = P_r f_m
      e_ = r_load_;
      map_.project_internal(e_);
      r_load_ -= e_;
    } else {
      out.load.setZero();
      r_load_.setZero();
    }
    const Scalar s = update_grip(in, slip.any, slip.lead, out.status);
    out.grip = s;

    // Internal force error (the rigid part belongs to the pose loop) and the loops.
    for (int i = 0; i < n_; ++i)
      e_(i) = touching(i) ? s * (*in.pattern)(i) - (*in.measured)(i) : Scalar(0);
    if (in.object_free) map_.project_internal(e_);
    for (int i = 0; i < n_; ++i) {
      const bool t = touching(i) != 0;
      out.target(i) = t ? (*in.measured)(i) + e_(i) : Scalar(0);
      z_(i) = t ? z_(i) + dt * e_(i) : Scalar(0);
    }
    if (in.object_free) map_.project_internal(z_);
    // Each loop's command and its limits (force_loop.hpp): max_force bounds the press
    // while the object is held.
    const Scalar bound = in.object_free ? std::numeric_limits<Scalar>::infinity() : in.max_force;
    for (int i = 0; i < n_; ++i) {
      if (!touching(i)) continue;
      const Scalar kp =
          force_loop_gain(stiffness_.estimate()(i), in.servo_gain ? (*in.servo_gain)(i) : Scalar(0),
                          p.bandwidth, p.contact_damping, p.servo_stiffness, p.servo_damping);
      const ForceLoopCommand<Scalar> c = force_loop_command(
          kp, e_(i), z_(i), p.integral_corner, p.max_integral_velocity, (*in.measured)(i), bound);
      out.velocity(i) = c.velocity;
      if (c.integral_limited) out.status |= ForceLayerStatus::integral_limited;
    }
  }

 private:
  /// The grip scale s (file comment) from q_int_, r_load_ and the slide's speed `lead`
  /// (SlipDetector::Report::lead, for capacity_slide_ratio); raises the status flags.
  Scalar update_grip(const Step& in, bool slipping, Scalar lead,
                     ForceLayerStatus& status) noexcept {
    const ForceLayerParams<Scalar>& p = params_;
    Scalar s_lo = Scalar(1), s_hi = std::numeric_limits<Scalar>::infinity();
    bool short_of_min = false, over_max = false;  // short: min_force out of reach
    if (in.object_free) {
      const Scalar s_release = in.release_grip > Scalar(0) ? in.release_grip : p.release_grip;
      const Scalar grip_floor =
          p.hold_release_grip ? s_release : Scalar(1);  // what s_slip decays to
      if (!was_free_) grip_slip_ = std::max(grip_slip_, s_release);
      for (int i = 0; i < n_; ++i) {
        if (!(*in.touching)(i)) continue;
        const Scalar q = q_int_(i), r = r_load_(i);
        over_max = over_max || (*in.measured)(i) > in.max_force;
        if (q > Scalar(1e-9)) {
          s_lo = std::max(s_lo, (in.min_force - r) / q);
          s_hi = std::min(s_hi, (in.max_force - r) / q);
        } else if (r < in.min_force) {
          short_of_min = true;
        }
      }
      if (slipping) {
        if (!was_slipping_) grip_slip_ = std::max(grip_slip_, p.friction_margin * grip_);
        grip_slip_ += p.grip_rise_rate * in.dt;
      } else {
        grip_slip_ = grip_floor + (grip_slip_ - grip_floor) * std::exp(-in.dt / p.grip_decay_time);
      }
      was_slipping_ = slipping;
    } else {
      grip_slip_ = Scalar(1);
      was_slipping_ = false;
    }
    was_free_ = in.object_free;
    Scalar s = std::max(s_lo, grip_slip_);
    bool capped_slip = false;
    if (s > s_hi) {
      s = std::max(Scalar(1), s_hi);
      capped_slip = slipping;
      short_of_min = short_of_min || s_lo > s_hi;
      grip_slip_ = std::min(grip_slip_, s);  // no windup above the cap
    }
    short_time_ = short_of_min ? short_time_ + in.dt : Scalar(0);
    capped_slip_time_ = capped_slip ? capped_slip_time_ + in.dt : Scalar(0);
    capped_slide_peak_ = capped_slip ? std::max(capped_slide_peak_, lead) : Scalar(0);
    const bool infeasible = (short_of_min && short_time_ >= p.capacity_time) ||
                            (capped_slip && capped_slip_time_ >= p.capacity_time &&
                             lead >= p.capacity_slide_ratio * capped_slide_peak_);
    grip_ = s;
    if (s > Scalar(1) + Scalar(1e-6)) status |= ForceLayerStatus::grip_raised;
    if (infeasible) status |= ForceLayerStatus::beyond_capacity;
    if (slipping) status |= ForceLayerStatus::slipping;
    if (over_max) status |= ForceLayerStatus::over_max_force;
    return s;
  }

  ForceLayerParams<Scalar> params_{};
  int n_ = 0;
  ForceVector z_;
  Mask was_touching_;
  StiffnessEstimator<Scalar, NumFingers> stiffness_{};
  SlipDetector<Scalar, Dim, NumFingers> slip_{};
  Map map_{};
  ContactMotion<Scalar, Dim, NumFingers> motion_{};
  ForceVector e_, q_int_, r_load_;  ///< per-tick scratch (preallocated)
  Scalar grip_ = Scalar(1), grip_slip_ = Scalar(1);
  Scalar short_time_ = Scalar(0);         ///< s min_force has been out of reach
  Scalar capped_slip_time_ = Scalar(0);   ///< s a finger has slipped with the cap binding
  Scalar capped_slide_peak_ = Scalar(0);  ///< [m] the largest slide lead since then
  bool was_slipping_ = false, was_free_ = false;
};

}  // namespace inhand
