// Analytic 3-D plant: kinematic fingers with spherical fingertips, one free rigid
// object, compliant point contacts with Coulomb friction and stiction, and noisy
// tactile / vision sensing. It stands in for the physics engine of the paper's
// experiments (method.md section 9) so that a controller can be tested end to end.
//
// Units: SI (m, s, kg, N, rad). Frames: everything public is in the WORLD frame
// (the paper's reference frame O_r) except ObjectShape queries (object frame).
// The object frame origin is the object's centre of mass.
//
// Fingers: velocity-driven and kinematic (infinitely stiff position servos): contact
// forces never move a joint. Commands are clamped to the joint velocity limits,
// optionally pass a first-order lag, and joints stop at their position limits; both
// events are counted per finger. Only the fingertip SPHERES touch the object; links,
// the palm and finger-finger contacts are not modelled.
//
// Contact (one per finger): penetration delta = r_tip - signed_distance(tip centre)
// (exact for a sphere against a convex solid). n is the OBJECT's outward unit normal
// at the contact, pointing towards the fingertip; the contact point is the middle of
// the overlap, p_c = object surface point - (delta / 2) n.
//   normal force   f_n = max(0, k_n delta + c_n delta_dot)            (>= 0, no adhesion)
//   friction       elasto-plastic bristle (a tangential spring to an anchor that
//                  slides), f_t acting on the fingertip: z += v_t h; if k_t |z| <= mu f_n
//                  the contact sticks and f_t = -(k_t z + c_t v_t), clipped to
//                  |f_t| <= mu f_n; otherwise the anchor slides so that k_t |z| = mu f_n
//                  and f_t = -k_t z (Coulomb, magnitude exactly mu f_n).
// v_t is the tangential velocity of the fingertip relative to the object at p_c and
// z the bristle deflection (fingertip relative to the anchor on the object), kept in
// the current tangent plane. The cone |f_t| <= mu f_n holds exactly (up to rounding);
// the only regularisation is the bristle compliance: a sticking contact deflects
// elastically by at most mu f_n / k_t (0.4 mm at 1 N with the defaults) and then holds
// without creep under any constant load below mu f_n; above it the anchor slides.
// Rolling needs no special treatment: v_t is the relative velocity of the two material
// points at the contact, zero for pure rolling.
// Reported contact forces are those acting ON THE OBJECT: -f_n n + friction, so the
// friction on the object drags it along with the fingertip.
//
// Object dynamics: Newton-Euler with the world-frame inertia I_w = R I R^T. The state
// is (p, R, v, L) with L = I_w omega the world angular momentum; L_dot = tau is the
// Euler equation I_w omega_dot + omega x I_w omega = tau, gyroscopic term included.
// One internal step of length h (semi-implicit / symplectic Euler, rotation by a
// second-order midpoint rule on SO(3)):
//   v += h (F_n/m + g); L += h tau_n; p += h v;
//   omega_half = omega - (h/2) I_w^-1 (omega x L); R = exp(h omega_half) R_n;
//   q_dot <- lag(command); q += h q_dot (stopped at the limits); forward kinematics;
//   F_n+1, tau_n+1 = contact forces of the new state (bristles advanced by h).
// So contact(i) and tactile(i) always describe the current joints and object pose.
// Frozen mode holds the object exactly at its pose (v = omega = 0); contacts still
// produce forces and tactile readings (the grasp phase, method.md section 8).
//
// Sensing (method.md section 1): tactile(i) and measured_object_pose() return the
// current truth corrupted by noise values that are drawn ONLY by sample_sensors()
// (call it once per control period); repeated reads between two samples agree.
// Noise is deterministic from the seed (own xoshiro256++ generator and Box-Muller, so
// the sequence does not depend on the standard library). See SensorNoise.
//
// step(), setters of commands and all getters are noexcept and allocation-free.
#pragma once

#include <algorithm>
#include <array>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/sim/shapes.hpp"

namespace inhand::plant {

/// A finger of the plant: 1 to 6 revolute joints in fixed-capacity storage.
using PlantFinger = inhand::FingerChain<double, 3, inhand::Dynamic, 6>;

/// Compliant contact between a fingertip sphere and the object.
struct ContactParams {
  /// Normal spring k_n [N/m]: soft silicone fingertips are 1e3..5e3 N/m
  /// (2e3 N/m: 0.5 mm indentation at 1 N).
  double normal_stiffness = 2000.0;
  /// Normal damper c_n [N s/m]. 10 N s/m with k_n = 2e3 N/m is a damping ratio of 0.5 on
  /// a 50 g object for one contact, about 1 for four.
  double normal_damping = 10.0;
  /// Bristle (tangential) spring k_t [N/m]: sets the elastic pre-sliding displacement
  /// mu f_n / k_t (0.4 mm at 1 N, mu = 0.8).
  double tangential_stiffness = 2000.0;
  /// Bristle damper c_t [N s/m], acts only while sticking.
  double tangential_damping = 5.0;
  /// Coulomb friction coefficient mu (static = kinetic), >= 0.
  double friction = 0.8;
};

/// Sensor imperfections. All default to zero: the readings then equal the truth.
struct SensorNoise {
  /// Std [N] of Gaussian noise added to the measured normal force.
  double normal_force_std = 0.0;
  /// Constant bias [N] added to the measured normal force.
  double normal_force_bias = 0.0;
  /// Relative gain error of the force sensor: the reading is (1 + gain_error) f_n.
  double normal_force_gain_error = 0.0;
  /// Std of Gaussian noise relative to the force: adds N(0, (rel_std f_n)^2) [N].
  double normal_force_relative_std = 0.0;
  /// Std [m] per world axis of Gaussian noise added to the contact point.
  double contact_point_std = 0.0;
  /// Std [rad] of the rotation of the measured normal about each of the two tangent
  /// axes (the rotation vector is tangential, each component N(0, std^2)).
  double normal_angle_std = 0.0;
  /// Std [m] per world axis of the measured object position.
  double object_position_std = 0.0;
  /// Std [rad] per world axis of the rotation vector w of R_measured = exp(w) R.
  double object_rotation_std = 0.0;
  /// A finger reports `touching` only if in contact and its measured normal force
  /// exceeds this [N], >= 0.
  double touch_threshold = 0.0;
};

/// Plant configuration, filled with defaults by default_plant_params().
struct PlantParams {
  /// Internal integration step h [s]; (0, 1e-3], smaller than any control period.
  double time_step = 1e-4;
  ContactParams contact{};
  /// Gravity acceleration [m/s^2], world frame; may be zero.
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  /// First-order lag time constant [s] between commanded and actual joint velocity;
  /// 0 = none (the actual velocity equals the clamped command).
  double joint_velocity_lag = 0.0;
  /// Actuator transport delay, in commands: a joint-velocity command takes effect when
  /// `command_delay` further commands have been given (one per control period: 1 is
  /// one tick of delay, as a hand's bus and servo loop add). 0 = at once; at most 8.
  int command_delay = 0;
  static constexpr int kMaxCommandDelay = 8;
  SensorNoise sensing{};
  /// Seed of the sensing noise generator.
  std::uint64_t seed = 1;

  Validation validate() const noexcept {
    if (!is_finite(time_step) || !(time_step > 0.0) || time_step > 1e-3)
      return Validation::invalid("time_step", "must be finite, > 0 and <= 1e-3 s");
    const ContactParams& c = contact;
    if (!is_finite(c.normal_stiffness) || !(c.normal_stiffness > 0.0))
      return Validation::invalid("contact.normal_stiffness", "must be finite and > 0");
    if (!is_finite(c.normal_damping) || !(c.normal_damping >= 0.0))
      return Validation::invalid("contact.normal_damping", "must be finite and >= 0");
    if (!is_finite(c.tangential_stiffness) || !(c.tangential_stiffness > 0.0))
      return Validation::invalid("contact.tangential_stiffness", "must be finite and > 0");
    if (!is_finite(c.tangential_damping) || !(c.tangential_damping >= 0.0))
      return Validation::invalid("contact.tangential_damping", "must be finite and >= 0");
    if (!is_finite(c.friction) || !(c.friction >= 0.0))
      return Validation::invalid("contact.friction", "must be finite and >= 0");
    if (!all_finite(gravity)) return Validation::invalid("gravity", "must be finite");
    if (!is_finite(joint_velocity_lag) || !(joint_velocity_lag >= 0.0))
      return Validation::invalid("joint_velocity_lag", "must be finite and >= 0");
    const SensorNoise& s = sensing;
    const double stds[] = {s.normal_force_std,    s.contact_point_std,   s.normal_angle_std,
                           s.object_position_std, s.object_rotation_std, s.touch_threshold};
    const char* names[] = {"sensing.normal_force_std",    "sensing.contact_point_std",
                           "sensing.normal_angle_std",    "sensing.object_position_std",
                           "sensing.object_rotation_std", "sensing.touch_threshold"};
    for (int i = 0; i < 6; ++i)
      if (!is_finite(stds[i]) || !(stds[i] >= 0.0))
        return Validation::invalid(names[i], "must be finite and >= 0");
    if (!is_finite(s.normal_force_bias))
      return Validation::invalid("sensing.normal_force_bias", "must be finite");
    if (!is_finite(s.normal_force_gain_error) || !(s.normal_force_gain_error > -1.0))
      return Validation::invalid("sensing.normal_force_gain_error", "must be finite and > -1");
    if (!is_finite(s.normal_force_relative_std) || !(s.normal_force_relative_std >= 0.0))
      return Validation::invalid("sensing.normal_force_relative_std", "must be finite and >= 0");
    if (command_delay < 0 || command_delay > kMaxCommandDelay)
      return Validation::invalid("command_delay", "must be in [0, 8] commands");
    return Validation::valid();
  }
};

/// The defaults documented field by field in PlantParams.
inline PlantParams default_plant_params() noexcept { return PlantParams{}; }

/// The manipulated object: shape, mass [kg] and initial pose (centre of mass frame).
struct ObjectDef {
  ObjectShape shape{};
  double mass = 0.05;
  Pose<double, 3> pose{};

  Validation validate() const noexcept {
    const Validation v = shape.validate();
    if (!v.ok()) return v;
    if (!is_finite(mass) || !(mass > 0.0))
      return Validation::invalid("mass", "must be finite and > 0");
    if (!pose.is_finite()) return Validation::invalid("pose", "must be finite");
    const double err = (pose.rotation.transpose() * pose.rotation - Eigen::Matrix3d::Identity())
                           .cwiseAbs()
                           .maxCoeff();
    if (err > 1e-9 || pose.rotation.determinant() < 0.0)
      return Validation::invalid("pose.rotation", "must be a rotation matrix");
    return Validation::valid();
  }
};

/// What a fingertip tactile sensor reports (world frame, noisy per SensorNoise).
struct TactileReading {
  /// In contact with a measured normal force above the touch threshold.
  bool touching = false;
  /// Contact point [m] on the fingertip/object interface; when not touching, the
  /// fingertip sphere centre (carries no contact information).
  Eigen::Vector3d contact_point = Eigen::Vector3d::Zero();
  /// The OBJECT's outward unit normal at the contact (points towards the fingertip);
  /// zero when not touching.
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  /// Measured normal force [N], >= 0; zero when not touching.
  double normal_force = 0.0;
};

/// Ground truth of one fingertip contact after the last step (or setter).
struct ContactState {
  /// The fingertip sphere overlaps the object (penetration > 0).
  bool active = false;
  /// The bristle anchor slid during the last step (kinetic friction), else sticking.
  bool sliding = false;
  /// Overlap depth [m], > 0 when active.
  double penetration = 0.0;
  /// Normal force magnitude f_n [N], >= 0.
  double normal_force = 0.0;
  /// Contact point [m] and the object's outward unit normal, world frame (inactive:
  /// the fingertip centre and zero).
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  /// Tangential (friction) force ON THE OBJECT [N]; |friction_force| <= mu f_n.
  Eigen::Vector3d friction_force = Eigen::Vector3d::Zero();
  /// Total force ON THE OBJECT [N]: -f_n n + friction_force.
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  /// Bristle deflection z [m] (fingertip relative to its anchor, tangential).
  Eigen::Vector3d deflection = Eigen::Vector3d::Zero();
  /// Velocity [m/s] of the fingertip material point relative to the object's at `point`.
  Eigen::Vector3d relative_velocity = Eigen::Vector3d::Zero();
  /// Cumulative anchor slip [m] since construction (kept when contact is lost).
  double slip_distance = 0.0;
};

/// Simulated-hardware event counters of one finger.
struct FingerCounters {
  /// Joint velocity command components clamped to +-max_velocity.
  std::uint64_t velocity_clamped = 0;
  /// Joint-steps in which a joint was stopped at a position limit.
  std::uint64_t position_limited = 0;
  /// Commands rejected (wrong size or non-finite) and replaced by zero velocity.
  std::uint64_t invalid_commands = 0;
};

namespace detail {
/// xoshiro256++ with splitmix64 seeding and Box-Muller normals: a fixed, portable
/// sequence for a given seed.
class NoiseSource {
 public:
  explicit NoiseSource(std::uint64_t seed = 1) noexcept { reseed(seed); }
  void reseed(std::uint64_t seed) noexcept {
    std::uint64_t x = seed;
    for (auto& s : s_) {
      x += 0x9E3779B97F4A7C15ull;
      std::uint64_t z = x;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      s = z ^ (z >> 31);
    }
    has_spare_ = false;
  }
  std::uint64_t next() noexcept {
    const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  /// Uniform in (0, 1): 53 random bits, offset by half a unit so 0 never occurs.
  double uniform() noexcept { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }
  /// Standard normal.
  double normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    constexpr double kTwoPi = 6.283185307179586476925;
    const double r = std::sqrt(-2.0 * std::log(uniform()));
    const double a = kTwoPi * uniform();
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }
  Eigen::Vector3d normal3() noexcept {
    const double x = normal(), y = normal(), z = normal();
    return Eigen::Vector3d(x, y, z);
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4] = {0, 0, 0, 0};
  double spare_ = 0.0;
  bool has_spare_ = false;
};
}  // namespace detail

class HandPlant {
 public:
  using JointVector = PlantFinger::JointVector;

  /// Checks the fingers, the object, the parameters and the explicit-integration
  /// stability of the contact springs on this object: with N fingers, K = N max(k_n,
  /// k_t), C = N max(c_n, c_t) and m_eff the smallest of the mass and I_j / rho_j^2
  /// (rho_j the largest distance of the surface from principal axis j), it requires
  /// h sqrt(K / m_eff) <= 0.5 and h C / m_eff <= 1.
  static Validation validate(const std::vector<PlantFinger>& fingers, const ObjectDef& object,
                             const PlantParams& params) noexcept {
    if (fingers.empty()) return Validation::invalid("fingers", "need at least one finger");
    for (std::size_t i = 0; i < fingers.size(); ++i) {
      const Validation v = fingers[i].validate();
      if (!v.ok()) return v.for_finger(static_cast<int>(i));
      if (!(fingers[i].fingertip_radius > 0.0))
        return Validation::invalid("fingertip_radius", "must be > 0", -1, static_cast<int>(i));
    }
    Validation v = object.validate();
    if (!v.ok()) return v;
    v = params.validate();
    if (!v.ok()) return v;
    const double n = static_cast<double>(fingers.size());
    const ContactParams& c = params.contact;
    const double K = n * std::max(c.normal_stiffness, c.tangential_stiffness);
    const double C = n * std::max(c.normal_damping, c.tangential_damping);
    const double m_eff = effective_mass(object);
    const double h = params.time_step;
    if (h * std::sqrt(K / m_eff) > 0.5)
      return Validation::invalid("time_step", "too large for the contact stiffness on this object");
    if (h * C / m_eff > 1.0)
      return Validation::invalid("time_step", "too large for the contact damping on this object");
    return Validation::valid();
  }

  /// Throws std::invalid_argument naming the offending field if validate() fails.
  /// Joints start at 0 clamped into their limits; the object at rest, not frozen.
  HandPlant(std::vector<PlantFinger> fingers, const ObjectDef& object,
            const PlantParams& params = default_plant_params())
      : params_(params), object_(object), noise_(params.seed) {
    const Validation v = validate(fingers, object, params);
    if (!v.ok()) {
      std::string msg = "HandPlant: ";
      msg += v.field;
      if (v.finger >= 0) msg += " (finger " + std::to_string(v.finger) + ")";
      if (v.index >= 0) msg += " [" + std::to_string(v.index) + "]";
      msg += ": ";
      msg += v.reason;
      throw std::invalid_argument(msg);
    }
    h_ = params.time_step;
    lag_alpha_ =
        params.joint_velocity_lag > 0.0 ? 1.0 - std::exp(-h_ / params.joint_velocity_lag) : 1.0;
    inertia_ = object.shape.principal_inertia(object.mass);
    inertia_inv_ = inertia_.cwiseInverse();
    pose_ = object.pose;
    fingers_.reserve(fingers.size());
    for (auto& chain : fingers) fingers_.emplace_back(std::move(chain));
    for (auto& f : fingers_) {
      f.q = f.chain.lower_limits().cwiseMax(JointVector::Zero(f.chain.dof()));
      f.q = f.q.cwiseMin(f.chain.upper_limits());
      update_kinematics(f);
    }
    refresh_contacts();
  }

  int finger_count() const noexcept { return static_cast<int>(fingers_.size()); }
  const PlantFinger& finger(int i) const noexcept { return at(i).chain; }
  const PlantParams& params() const noexcept { return params_; }
  const ObjectDef& object() const noexcept { return object_; }
  /// Principal moments of inertia of the object (object axes) [kg m^2].
  const Eigen::Vector3d& principal_inertia() const noexcept { return inertia_; }

  // ---- joints (simulated hardware) -------------------------------------------------

  /// Sets finger i's joint angles [rad], clamped into the limits (not counted), and
  /// re-evaluates the contacts. Returns false (and changes nothing) on a wrong size,
  /// non-finite values or a bad index. Not real-time (may copy).
  bool set_joint_positions(int i, const Eigen::Ref<const Eigen::VectorXd>& q) {
    if (i < 0 || i >= finger_count()) return false;
    Finger& f = fingers_[static_cast<std::size_t>(i)];
    if (q.size() != f.chain.dof() || !all_finite(q)) return false;
    for (int j = 0; j < f.chain.dof(); ++j)
      f.q(j) = std::clamp(q(j), f.chain.joints[j].lower, f.chain.joints[j].upper);
    update_kinematics(f);
    refresh_contacts();
    return true;
  }
  const JointVector& joint_positions(int i) const noexcept { return at(i).q; }
  /// Actual joint velocities [rad/s] (after clamping, lag and limit stops).
  const JointVector& joint_velocities(int i) const noexcept { return at(i).qd; }
  /// The last accepted command after clamping [rad/s].
  const JointVector& joint_velocity_command(int i) const noexcept { return at(i).qd_cmd; }

  /// Commands finger i's joint velocities [rad/s], held until the next command. Each
  /// component is clamped to +-max_velocity (counted); a wrong size or non-finite
  /// command is replaced by zero (counted). Returns false for a rejected command.
  bool set_joint_velocity_command(int i, const JointVector& qd) noexcept {
    if (i < 0 || i >= finger_count()) return false;
    Finger& f = fingers_[static_cast<std::size_t>(i)];
    const int n = f.chain.dof();
    if (qd.size() != n || !all_finite(qd)) {
      f.pending[static_cast<std::size_t>(f.pending_head)].setZero();
      apply_delayed(f);
      ++f.counters.invalid_commands;
      return false;
    }
    for (int j = 0; j < n; ++j) {
      const double lim = f.chain.joints[j].max_velocity;
      double v = qd(j);
      if (v > lim || v < -lim) {
        v = v > lim ? lim : -lim;
        ++f.counters.velocity_clamped;
      }
      f.pending[static_cast<std::size_t>(f.pending_head)](j) = v;
    }
    apply_delayed(f);
    return true;
  }
  const FingerCounters& counters(int i) const noexcept { return at(i).counters; }

 private:
  /// The command written at pending_head goes in the ring; the one given
  /// command_delay commands ago takes effect.
  template <typename FingerState>  // Finger, declared below
  void apply_delayed(FingerState& f) const noexcept {
    constexpr int kRing = PlantParams::kMaxCommandDelay + 1;
    const int d = params_.command_delay;
    f.qd_cmd = f.pending[static_cast<std::size_t>((f.pending_head - d + kRing) % kRing)];
    f.pending_head = (f.pending_head + 1) % kRing;
  }

 public:
  /// World pose of finger i's fingertip frame (origin = fingertip sphere centre).
  const Pose<double, 3>& fingertip_pose(int i) const noexcept { return at(i).ws.fingertip; }
  /// Forward-kinematics workspace of finger i at the current joint angles.
  const FingerKinematics<PlantFinger>& kinematics(int i) const noexcept { return at(i).ws; }

  // ---- object ---------------------------------------------------------------------

  /// Frozen: the object is held exactly at its pose with zero velocity.
  void set_frozen(bool frozen) noexcept {
    frozen_ = frozen;
    if (frozen_) {
      velocity_.setZero();
      momentum_.setZero();
      omega_.setZero();
      refresh_contacts();
    }
  }
  bool frozen() const noexcept { return frozen_; }
  /// Places the object (keeps its twist) and resets every bristle deflection (the old
  /// anchors lose their meaning after a jump). Ignored if the pose is not finite.
  void set_object_pose(const Pose<double, 3>& pose) noexcept {
    if (!pose.is_finite()) return;
    pose_ = pose;
    momentum_ = world_inertia_times(omega_);
    for (auto& f : fingers_) f.contact.deflection.setZero();
    refresh_contacts();
  }
  /// Sets the object twist (v; omega), world frame, about the centre of mass. Ignored
  /// while frozen or if not finite.
  void set_object_twist(const Twist<double, 3>& twist) noexcept {
    if (frozen_ || !all_finite(twist)) return;
    velocity_ = twist.head<3>();
    omega_ = twist.tail<3>();
    momentum_ = world_inertia_times(omega_);
    refresh_contacts();
  }
  /// Constant external force [N] and torque [N m] on the object (world frame, about the
  /// centre of mass), held until changed; a disturbance or test load. Not counted in the
  /// energy accessors (it is work done from outside). Ignored if not finite.
  void set_external_wrench(const Eigen::Vector3d& force, const Eigen::Vector3d& torque) noexcept {
    if (!all_finite(force) || !all_finite(torque)) return;
    external_force_ = force;
    external_torque_ = torque;
  }
  /// True object pose (centre of mass frame).
  const Pose<double, 3>& object_pose() const noexcept { return pose_; }
  /// True object twist (v; omega), world frame, v of the centre of mass.
  Twist<double, 3> object_twist() const noexcept {
    Twist<double, 3> t;
    t << velocity_, omega_;
    return t;
  }
  /// World angular momentum about the centre of mass [kg m^2/s].
  const Eigen::Vector3d& object_angular_momentum() const noexcept { return momentum_; }
  /// Sum of the contact forces on the object [N] and their torque about the centre of
  /// mass [N m] at the last evaluation (gravity excluded).
  const Eigen::Vector3d& contact_force_sum() const noexcept { return force_sum_; }
  const Eigen::Vector3d& contact_torque_sum() const noexcept { return torque_sum_; }

  // ---- time -----------------------------------------------------------------------

  /// Advances by the whole number of internal steps that brings time() closest to the
  /// sum of all durations requested so far (so 1e-3 s calls never drift). Returns the
  /// number of internal steps taken; a non-finite or negative duration does nothing.
  int step(double duration) noexcept {
    if (!is_finite(duration) || !(duration > 0.0)) return 0;
    requested_time_ += duration;
    const auto target = static_cast<std::int64_t>(std::llround(requested_time_ / h_));
    int n = 0;
    while (steps_ < target) {
      integrate();
      ++steps_;
      ++n;
    }
    return n;
  }
  /// Exactly one internal step (counted as a requested duration of one step).
  void step_once() noexcept {
    requested_time_ += h_;
    integrate();
    ++steps_;
  }
  double time() const noexcept { return static_cast<double>(steps_) * h_; }
  std::int64_t step_count() const noexcept { return steps_; }
  double time_step() const noexcept { return h_; }

  // ---- ground truth ---------------------------------------------------------------

  const ContactState& contact(int i) const noexcept { return at(i).contact; }
  /// Translational plus rotational kinetic energy of the object [J].
  double kinetic_energy() const noexcept {
    return 0.5 * object_.mass * velocity_.squaredNorm() + 0.5 * omega_.dot(momentum_);
  }
  /// Gravitational potential energy -m g . p [J] (zero at the world origin).
  double potential_energy() const noexcept {
    return -object_.mass * params_.gravity.dot(pose_.position);
  }
  /// Energy stored in the contact springs: sum of k_n delta^2 / 2 + k_t |z|^2 / 2 [J].
  double elastic_energy() const noexcept {
    double e = 0.0;
    const ContactParams& c = params_.contact;
    for (const auto& f : fingers_)
      if (f.contact.active)
        e += 0.5 * c.normal_stiffness * f.contact.penetration * f.contact.penetration +
             0.5 * c.tangential_stiffness * f.contact.deflection.squaredNorm();
    return e;
  }
  double total_energy() const noexcept {
    return kinetic_energy() + potential_energy() + elastic_energy();
  }

  // ---- sensing --------------------------------------------------------------------

  /// Draws new sensor noise (a fixed number of draws per call, so the sequence depends
  /// only on the seed and the number of calls). Call once per control period.
  void sample_sensors() noexcept {
    const SensorNoise& s = params_.sensing;
    for (auto& f : fingers_) {
      f.force_noise = s.normal_force_std * noise_.normal();
      // Drawn only when used, so the other sequences do not move with the option.
      f.force_noise_unit = s.normal_force_relative_std > 0.0 ? noise_.normal() : 0.0;
      f.point_noise = s.contact_point_std * noise_.normal3();
      f.normal_noise = s.normal_angle_std * noise_.normal3();
    }
    pose_position_noise_ = s.object_position_std * noise_.normal3();
    pose_rotation_noise_ = s.object_rotation_std * noise_.normal3();
  }
  /// Tactile reading of finger i: truth now, corrupted by the last sampled noise:
  /// force = max(0, (1 + gain_error) f_n + bias + noise + relative noise); point += noise; the
  /// normal is rotated by exp(w) with w the tangential part of the sampled 3-vector (std per axis).
  TactileReading tactile(int i) const noexcept {
    const Finger& f = at(i);
    TactileReading r;
    r.contact_point = f.ws.fingertip.position;
    if (!f.contact.active) return r;
    const SensorNoise& sn = params_.sensing;
    const double force = std::max(
        0.0, (1.0 + sn.normal_force_gain_error) * f.contact.normal_force + sn.normal_force_bias +
                 f.force_noise +
                 sn.normal_force_relative_std * f.contact.normal_force * f.force_noise_unit);
    if (!(force > params_.sensing.touch_threshold)) return r;
    r.touching = true;
    r.normal_force = force;
    r.contact_point = f.contact.point + f.point_noise;
    const Eigen::Vector3d& n = f.contact.normal;
    const Eigen::Vector3d w = f.normal_noise - f.normal_noise.dot(n) * n;
    r.normal = so3_exp<double>(w) * n;
    return r;
  }
  /// Object pose as seen by "vision": position + noise, R_measured = exp(w) R.
  Pose<double, 3> measured_object_pose() const noexcept {
    Pose<double, 3> p;
    p.position = pose_.position + pose_position_noise_;
    p.rotation = so3_exp<double>(pose_rotation_noise_) * pose_.rotation;
    return p;
  }

 private:
  /// Per-joint constants for the plant's own forward kinematics: Rodrigues' formula
  /// R(q) = I + sin(q) K + (1 - cos(q)) K^2 with K = [axis]x precomputed, and the fixed
  /// parent rotation skipped when it is the identity. Same result as
  /// inhand::forward_kinematics (to rounding) at a fraction of the cost.
  struct JointConstants {
    Eigen::Vector3d offset = Eigen::Vector3d::Zero();
    Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
    bool identity_rotation = true;
    Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
    Eigen::Matrix3d K = Eigen::Matrix3d::Zero();
    Eigen::Matrix3d K2 = Eigen::Matrix3d::Zero();
    /// Axis = sign * e_principal exactly (the common case): the rotation then only mixes
    /// two columns of R. -1 for a general axis.
    int principal = -1;
    double sign = 1.0;
  };

  struct Finger {
    explicit Finger(PlantFinger c)
        : chain(std::move(c)),
          ws(chain),
          q(JointVector::Zero(chain.dof())),
          qd(JointVector::Zero(chain.dof())),
          qd_cmd(JointVector::Zero(chain.dof())),
          sin_q(JointVector::Zero(chain.dof())),
          cos_q(JointVector::Ones(chain.dof())),
          sin_dq(JointVector::Zero(chain.dof())),
          cos_dq(JointVector::Ones(chain.dof())),
          trig_qd(JointVector::Zero(chain.dof())) {
      for (JointVector& p : pending) p = JointVector::Zero(chain.dof());
      for (int j = 0; j < chain.dof(); ++j) {
        const auto& jd = chain.joints[j];
        JointConstants& jc = constants[static_cast<std::size_t>(j)];
        jc.offset = jd.parent_to_joint.position;
        jc.rotation = jd.parent_to_joint.rotation;
        jc.identity_rotation = jc.rotation == Eigen::Matrix3d::Identity();
        jc.axis = jd.axis;
        jc.K = hat<double>(jd.axis);
        jc.K2 = jc.K * jc.K;
        for (int k = 0; k < 3; ++k) {
          const double a = jd.axis(k);
          if ((a == 1.0 || a == -1.0) && jd.axis((k + 1) % 3) == 0.0 &&
              jd.axis((k + 2) % 3) == 0.0) {
            jc.principal = k;
            jc.sign = a;
          }
        }
      }
      tip_identity_rotation = chain.joint_to_tip.rotation == Eigen::Matrix3d::Identity();
    }
    PlantFinger chain;
    std::array<JointConstants, 6> constants{};
    bool tip_identity_rotation = true;
    FingerKinematics<PlantFinger> ws;
    JointVector q, qd, qd_cmd;
    // sin/cos of q, advanced by the angle-addition formula with the sin/cos of h qd
    // (computed for the joint velocity trig_qd) while qd stays constant, recomputed
    // exactly whenever qd changes and every kResyncSteps steps.
    JointVector sin_q, cos_q, sin_dq, cos_dq, trig_qd;
    int steps_since_sync = 0;
    Eigen::Vector3d tip_velocity = Eigen::Vector3d::Zero();  // of the sphere centre
    Eigen::Vector3d tip_omega = Eigen::Vector3d::Zero();     // of the distal link
    ContactState contact{};
    FingerCounters counters{};
    double force_noise = 0.0;
    double force_noise_unit = 0.0;  ///< N(0, 1) draw of the relative force noise
    /// Commands not yet in effect (ring buffer; see PlantParams::command_delay).
    std::array<JointVector, PlantParams::kMaxCommandDelay + 1> pending{};
    int pending_head = 0;
    Eigen::Vector3d point_noise = Eigen::Vector3d::Zero();
    Eigen::Vector3d normal_noise = Eigen::Vector3d::Zero();
  };

  const Finger& at(int i) const noexcept {
    assert(i >= 0 && i < finger_count());
    return fingers_[static_cast<std::size_t>(i)];
  }

  static double effective_mass(const ObjectDef& object) noexcept {
    const Eigen::Vector3d I = object.shape.principal_inertia(object.mass);
    const ObjectShape& s = object.shape;
    Eigen::Vector3d rho2 =
        Eigen::Vector3d::Ones();  // squared largest surface distance from each axis
    switch (s.kind) {
      case ObjectShape::Kind::sphere:
        rho2.setConstant(s.radius * s.radius);
        break;
      case ObjectShape::Kind::box: {
        const Eigen::Vector3d e = s.half_extents.cwiseAbs2();
        rho2 = Eigen::Vector3d(e.y() + e.z(), e.x() + e.z(), e.x() + e.y());
        break;
      }
      case ObjectShape::Kind::cylinder: {
        const double r2 = s.radius * s.radius, h2 = s.half_length * s.half_length;
        rho2 = Eigen::Vector3d(r2 + h2, r2 + h2, r2);
        break;
      }
    }
    return std::min(object.mass, I.cwiseQuotient(rho2).minCoeff());
  }

  Eigen::Vector3d world_inertia_times(const Eigen::Vector3d& w) const noexcept {
    return pose_.rotation * inertia_.cwiseProduct(pose_.rotation.transpose() * w);
  }
  Eigen::Vector3d omega_from(const Eigen::Matrix3d& R, const Eigen::Vector3d& L) const noexcept {
    return R * inertia_inv_.cwiseProduct(R.transpose() * L);
  }

  /// Exact sin/cos of q, forward kinematics and the fingertip's rigid-body velocity.
  static void update_kinematics(Finger& f) noexcept {
    for (int j = 0; j < f.chain.dof(); ++j) {
      f.sin_q(j) = std::sin(f.q(j));
      f.cos_q(j) = std::cos(f.q(j));
    }
    fast_forward_kinematics(f);
    update_tip_velocity(f);
  }
  /// Fills f.ws exactly as inhand::forward_kinematics does (see JointConstants).
  static void fast_forward_kinematics(Finger& f) noexcept {
    Eigen::Matrix3d R = f.chain.base.rotation;
    Eigen::Vector3d p = f.chain.base.position;
    for (int j = 0; j < f.chain.dof(); ++j) {
      const JointConstants& jc = f.constants[static_cast<std::size_t>(j)];
      p.noalias() += R * jc.offset;
      if (!jc.identity_rotation) R = (R * jc.rotation).eval();
      f.ws.joint_origins.col(j) = p;
      const double s = f.sin_q(j), c = f.cos_q(j);
      if (jc.principal >= 0) {
        // R * Rot(sign q, e_k): with (i, l) the cyclic successors of k,
        // col_i <- c col_i + s' col_l, col_l <- -s' col_i + c col_l, s' = sign sin q.
        const int k = jc.principal, i = (k + 1) % 3, l = (k + 2) % 3;
        f.ws.joint_axes.col(j) = jc.sign * R.col(k);
        const double ss = jc.sign * s;
        const Eigen::Vector3d ci = R.col(i), cl = R.col(l);
        R.col(i) = c * ci + ss * cl;
        R.col(l) = c * cl - ss * ci;
      } else {
        f.ws.joint_axes.col(j).noalias() = R * jc.axis;
        const Eigen::Matrix3d Rj = Eigen::Matrix3d::Identity() + s * jc.K + (1.0 - c) * jc.K2;
        R = (R * Rj).eval();
      }
    }
    f.ws.fingertip.position.noalias() = p + R * f.chain.joint_to_tip.position;
    if (f.tip_identity_rotation) {
      f.ws.fingertip.rotation = R;
    } else {
      f.ws.fingertip.rotation.noalias() = R * f.chain.joint_to_tip.rotation;
    }
  }
  static void update_tip_velocity(Finger& f) noexcept {
    f.tip_velocity.setZero();
    f.tip_omega.setZero();
    const Eigen::Vector3d& c = f.ws.fingertip.position;
    for (int j = 0; j < f.chain.dof(); ++j) {
      const Eigen::Vector3d a = f.ws.joint_axes.col(j) * f.qd(j);
      f.tip_omega += a;
      f.tip_velocity += a.cross(c - f.ws.joint_origins.col(j));
    }
  }

  /// Evaluates finger f's contact and accumulates its force and torque on the object.
  /// dt is the bristle integration interval: h in a step, 0 for a re-evaluation.
  void evaluate_contact(Finger& f, double dt) noexcept {
    ContactState& cs = f.contact;
    const ContactParams& cp = params_.contact;
    const Eigen::Vector3d& centre = f.ws.fingertip.position;
    const Eigen::Matrix3d& R = pose_.rotation;
    const SurfaceQuery sq = object_.shape.query(R.transpose() * (centre - pose_.position));
    const double pen = f.chain.fingertip_radius - sq.distance;
    if (!(pen > 0.0)) {
      cs.active = false;
      cs.sliding = false;
      cs.penetration = 0.0;
      cs.normal_force = 0.0;
      cs.point = centre;
      cs.normal.setZero();
      cs.friction_force.setZero();
      cs.force.setZero();
      cs.deflection.setZero();
      cs.relative_velocity.setZero();
      return;
    }
    const Eigen::Vector3d n = R * sq.normal;
    const Eigen::Vector3d point = pose_.position + R * sq.closest - (0.5 * pen) * n;
    const Eigen::Vector3d r_obj = point - pose_.position;
    const Eigen::Vector3d v_rel =
        (f.tip_velocity + f.tip_omega.cross(point - centre)) - (velocity_ + omega_.cross(r_obj));
    const double vn = n.dot(v_rel);
    const double fn = std::max(0.0, cp.normal_stiffness * pen - cp.normal_damping * vn);
    const Eigen::Vector3d vt = v_rel - vn * n;

    // Bristle: keep the deflection tangential, advance it, then stick or slide.
    Eigen::Vector3d z = cs.deflection - cs.deflection.dot(n) * n;
    z += dt * vt;
    const double fmax = cp.friction * fn;
    const double kz = cp.tangential_stiffness * z.norm();
    Eigen::Vector3d ft;  // friction on the fingertip
    bool sliding = false;
    if (kz <= fmax) {
      ft = -(cp.tangential_stiffness * z + cp.tangential_damping * vt);
      const double m = ft.norm();
      if (m > fmax) ft *= fmax / m;
    } else {
      const Eigen::Vector3d z_new = (fmax / kz) * z;
      cs.slip_distance += (z - z_new).norm();
      z = z_new;
      ft = -cp.tangential_stiffness * z;
      sliding = true;
    }
    cs.active = true;
    cs.sliding = sliding;
    cs.penetration = pen;
    cs.normal_force = fn;
    cs.point = point;
    cs.normal = n;
    cs.friction_force = -ft;
    cs.force = -fn * n - ft;
    cs.deflection = z;
    cs.relative_velocity = v_rel;
    force_sum_ += cs.force;
    torque_sum_ += r_obj.cross(cs.force);
  }

  void refresh_contacts() noexcept {
    force_sum_.setZero();
    torque_sum_.setZero();
    for (auto& f : fingers_) evaluate_contact(f, 0.0);
  }

  void integrate() noexcept {
    const double h = h_;
    // force_sum_ / torque_sum_ hold the contact forces of the current state (evaluated at
    // the end of the previous step or by a setter).
    if (!frozen_) {
      velocity_ += h * ((force_sum_ + external_force_) / object_.mass + params_.gravity);
      momentum_ += h * (torque_sum_ + external_torque_);
      pose_.position += h * velocity_;
      const Eigen::Matrix3d R0 = pose_.rotation;
      const Eigen::Vector3d w0 = omega_from(R0, momentum_);
      // omega at the half step to O(h^2): omega_dot = -I_w^-1 (omega x L) with L already
      // holding this step's torque impulse (the Euler equation's gyroscopic term).
      const Eigen::Vector3d w_half = w0 - (0.5 * h) * omega_from(R0, w0.cross(momentum_));
      Eigen::Matrix3d R1 = so3_exp<double>(Eigen::Vector3d(h * w_half)) * R0;
      // One Newton step towards orthonormality keeps rounding from accumulating.
      R1 = R1 * (1.5 * Eigen::Matrix3d::Identity() - 0.5 * (R1.transpose() * R1));
      pose_.rotation = R1;
      omega_ = omega_from(R1, momentum_);
    }

    for (auto& f : fingers_) {
      const int n = f.chain.dof();
      bool moved = false;
      const bool resync = ++f.steps_since_sync >= kResyncSteps;
      if (resync) f.steps_since_sync = 0;
      for (int j = 0; j < n; ++j) {
        double qd = f.qd(j) + lag_alpha_ * (f.qd_cmd(j) - f.qd(j));
        if (qd != 0.0) {
          double q = f.q(j) + h * qd;
          const auto& jd = f.chain.joints[j];
          bool exact = resync || qd != f.qd(j);
          if (q > jd.upper || q < jd.lower) {
            q = q > jd.upper ? jd.upper : jd.lower;
            qd = 0.0;
            exact = true;
            ++f.counters.position_limited;
          }
          if (q != f.q(j)) moved = true;
          f.q(j) = q;
          if (exact) {
            f.sin_q(j) = std::sin(q);
            f.cos_q(j) = std::cos(q);
          } else {
            if (qd != f.trig_qd(j)) {
              f.sin_dq(j) = std::sin(h * qd);
              f.cos_dq(j) = std::cos(h * qd);
              f.trig_qd(j) = qd;
            }
            const double s0 = f.sin_q(j), c0 = f.cos_q(j);
            f.sin_q(j) = s0 * f.cos_dq(j) + c0 * f.sin_dq(j);
            f.cos_q(j) = c0 * f.cos_dq(j) - s0 * f.sin_dq(j);
          }
        }
        f.qd(j) = qd;
      }
      if (moved) fast_forward_kinematics(f);
      update_tip_velocity(f);
    }

    // Contacts of the new state: reported now, applied in the next step.
    force_sum_.setZero();
    torque_sum_.setZero();
    for (auto& f : fingers_) evaluate_contact(f, h);
  }

  static constexpr int kResyncSteps = 1000;

  PlantParams params_;
  ObjectDef object_;
  std::vector<Finger> fingers_;
  detail::NoiseSource noise_;
  double h_ = 1e-4;
  double lag_alpha_ = 1.0;
  Eigen::Vector3d inertia_ = Eigen::Vector3d::Ones();
  Eigen::Vector3d inertia_inv_ = Eigen::Vector3d::Ones();
  Pose<double, 3> pose_{};
  Eigen::Vector3d velocity_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d momentum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d force_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d external_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d external_torque_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d pose_position_noise_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d pose_rotation_noise_ = Eigen::Vector3d::Zero();
  bool frozen_ = false;
  double requested_time_ = 0.0;
  std::int64_t steps_ = 0;
};

}  // namespace inhand::plant
