// Configuration of the analytic plant (hand_plant.hpp): the finger type, contact and
// sensor-noise parameters, the integration step and the object definition.
//
// Units: SI (m, s, kg, N, rad). Frames: gravity and every pose are in the WORLD frame
// (the paper's reference frame O_r); the object frame's origin is its centre of mass.
#pragma once

#include <cstdint>

#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/math/status.hpp"
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

}  // namespace inhand::plant
