// Analytic 3-D plant: kinematic fingers with spherical fingertips, one free rigid
// object, compliant point contacts with Coulomb friction and stiction, and noisy
// tactile / vision sensing. It stands in for the physics engine of the paper's
// experiments (docs/method.md section 9) so that a controller can be tested end to end.
// The parts: plant_params.hpp (configuration), plant_readings.hpp (what it reports),
// finger_model.hpp (joints and commands), contact_model.hpp (contact forces),
// object_dynamics.hpp (the free object), sensing.hpp and noise_source.hpp (noise).
//
// Units: SI (m, s, kg, N, rad). Frames: everything public is in the WORLD frame
// (the paper's reference frame O_r) except ObjectShape queries (object frame).
// The object frame origin is the object's centre of mass. Contact forces reported are
// those acting ON THE OBJECT; normals are the object's outward normals.
//
// One internal step of length h: the object moves under the contact forces of the
// current state (object_dynamics.hpp); q_dot <- lag(command); q += h q_dot (stopped at
// the limits); forward kinematics; then the contact forces of the new state (bristles
// advanced by h), applied in the next step. So contact(i) and tactile(i) always
// describe the current joints and object pose. Frozen mode holds the object exactly at
// its pose (v = omega = 0); contacts still produce forces and tactile readings (the
// grasp phase, docs/method.md section 8).
//
// step(), setters of commands and all getters are noexcept and allocation-free.
#pragma once

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/sim/contact_model.hpp"
#include "inhand/sim/finger_model.hpp"
#include "inhand/sim/noise_source.hpp"
#include "inhand/sim/object_dynamics.hpp"
#include "inhand/sim/plant_params.hpp"
#include "inhand/sim/plant_readings.hpp"
#include "inhand/sim/sensing.hpp"
#include "inhand/sim/shapes.hpp"

namespace inhand::plant {

class HandPlant {
 public:
  using JointVector = PlantFinger::JointVector;

  /// Checks the fingers, the object, the parameters and the explicit-integration
  /// stability of the contact springs on this object (detail::validate_plant_setup()).
  static Validation validate(const std::vector<PlantFinger>& fingers, const ObjectDef& object,
                             const PlantParams& params) noexcept {
    return detail::validate_plant_setup(fingers, object, params);
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
    body_.inertia = object.shape.principal_inertia(object.mass);
    body_.inertia_inv = body_.inertia.cwiseInverse();
    body_.pose = object.pose;
    fingers_.reserve(fingers.size());
    for (auto& chain : fingers) fingers_.emplace_back(std::move(chain));
    for (auto& f : fingers_) {
      f.q = f.chain.lower_limits().cwiseMax(JointVector::Zero(f.chain.dof()));
      f.q = f.q.cwiseMin(f.chain.upper_limits());
      f.update_kinematics();
    }
    refresh_contacts();
  }

  int finger_count() const noexcept { return static_cast<int>(fingers_.size()); }
  const PlantFinger& finger(int i) const noexcept { return at(i).chain; }
  const PlantParams& params() const noexcept { return params_; }
  const ObjectDef& object() const noexcept { return object_; }
  /// Principal moments of inertia of the object (object axes) [kg m^2].
  const Eigen::Vector3d& principal_inertia() const noexcept { return body_.inertia; }

  // ---- joints (simulated hardware) -------------------------------------------------

  /// Sets finger i's joint angles [rad], clamped into the limits (not counted), and
  /// re-evaluates the contacts. Returns false (and changes nothing) on a wrong size,
  /// non-finite values or a bad index. Not real-time (may copy).
  bool set_joint_positions(int i, const Eigen::Ref<const Eigen::VectorXd>& q) {
    if (i < 0 || i >= finger_count()) return false;
    detail::FingerModel& f = fingers_[static_cast<std::size_t>(i)];
    if (q.size() != f.chain.dof() || !all_finite(q)) return false;
    for (int j = 0; j < f.chain.dof(); ++j)
      f.q(j) = std::clamp(q(j), f.chain.joints[j].lower, f.chain.joints[j].upper);
    f.update_kinematics();
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
    return fingers_[static_cast<std::size_t>(i)].command(qd, params_.command_delay);
  }
  const FingerCounters& counters(int i) const noexcept { return at(i).counters; }

  /// World pose of finger i's fingertip frame (origin = fingertip sphere centre).
  const Pose<double, 3>& fingertip_pose(int i) const noexcept { return at(i).ws.fingertip; }
  /// Forward-kinematics workspace of finger i at the current joint angles.
  const FingerKinematics<PlantFinger>& kinematics(int i) const noexcept { return at(i).ws; }

  // ---- object ---------------------------------------------------------------------

  /// Frozen: the object is held exactly at its pose with zero velocity.
  void set_frozen(bool frozen) noexcept {
    frozen_ = frozen;
    if (frozen_) {
      body_.velocity.setZero();
      body_.momentum.setZero();
      body_.omega.setZero();
      refresh_contacts();
    }
  }
  bool frozen() const noexcept { return frozen_; }
  /// Places the object (keeps its twist) and resets every bristle deflection (the old
  /// anchors lose their meaning after a jump). Ignored if the pose is not finite.
  void set_object_pose(const Pose<double, 3>& pose) noexcept {
    if (!pose.is_finite()) return;
    body_.pose = pose;
    body_.momentum = body_.world_inertia_times(body_.omega);
    for (auto& f : fingers_) f.contact.deflection.setZero();
    refresh_contacts();
  }
  /// Sets the object twist (v; omega), world frame, about the centre of mass. Ignored
  /// while frozen or if not finite.
  void set_object_twist(const Twist<double, 3>& twist) noexcept {
    if (frozen_ || !all_finite(twist)) return;
    body_.velocity = twist.head<3>();
    body_.omega = twist.tail<3>();
    body_.momentum = body_.world_inertia_times(body_.omega);
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
  const Pose<double, 3>& object_pose() const noexcept { return body_.pose; }
  /// True object twist (v; omega), world frame, v of the centre of mass.
  Twist<double, 3> object_twist() const noexcept {
    Twist<double, 3> t;
    t << body_.velocity, body_.omega;
    return t;
  }
  /// World angular momentum about the centre of mass [kg m^2/s].
  const Eigen::Vector3d& object_angular_momentum() const noexcept { return body_.momentum; }
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
    return 0.5 * object_.mass * body_.velocity.squaredNorm() +
           0.5 * body_.omega.dot(body_.momentum);
  }
  /// Gravitational potential energy -m g . p [J] (zero at the world origin).
  double potential_energy() const noexcept {
    return -object_.mass * params_.gravity.dot(body_.pose.position);
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
    for (auto& f : fingers_) f.noise.sample(noise_, params_.sensing);
    pose_noise_.sample(noise_, params_.sensing);
  }
  /// Tactile reading of finger i: truth now, corrupted by the last sampled noise:
  /// force = max(0, (1 + gain_error) f_n + bias + noise + relative noise); point += noise; the
  /// normal is rotated by exp(w) with w the tangential part of the sampled 3-vector (std per axis).
  TactileReading tactile(int i) const noexcept {
    const detail::FingerModel& f = at(i);
    return f.noise.read(f.contact, f.ws.fingertip.position, params_.sensing);
  }
  /// Object pose as seen by "vision": position + noise, R_measured = exp(w) R.
  Pose<double, 3> measured_object_pose() const noexcept { return pose_noise_.measure(body_.pose); }

 private:
  const detail::FingerModel& at(int i) const noexcept {
    assert(i >= 0 && i < finger_count());
    return fingers_[static_cast<std::size_t>(i)];
  }

  /// Contacts of the current state; dt: bristle interval (see evaluate_contact).
  void evaluate_contacts(double dt) noexcept {
    force_sum_.setZero();
    torque_sum_.setZero();
    for (auto& f : fingers_)
      detail::evaluate_contact(f, params_.contact, object_.shape, body_, dt, force_sum_,
                               torque_sum_);
  }
  void refresh_contacts() noexcept { evaluate_contacts(0.0); }

  void integrate() noexcept {
    // force_sum_ / torque_sum_ hold the contact forces of the current state (evaluated at
    // the end of the previous step or by a setter).
    if (!frozen_)
      body_.step(h_, object_.mass, force_sum_ + external_force_, torque_sum_ + external_torque_,
                 params_.gravity);
    for (auto& f : fingers_) f.advance(h_, lag_alpha_);
    // Contacts of the new state: reported now, applied in the next step.
    evaluate_contacts(h_);
  }

  PlantParams params_;
  ObjectDef object_;
  std::vector<detail::FingerModel> fingers_;
  detail::NoiseSource noise_;
  double h_ = 1e-4;
  double lag_alpha_ = 1.0;
  detail::RigidBody body_{};
  Eigen::Vector3d force_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d torque_sum_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d external_force_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d external_torque_ = Eigen::Vector3d::Zero();
  detail::PoseNoise pose_noise_{};
  bool frozen_ = false;
  double requested_time_ = 0.0;
  std::int64_t steps_ = 0;
};

}  // namespace inhand::plant
