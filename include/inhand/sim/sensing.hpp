// Sensing of the analytic plant (docs/method.md section 1): tactile readings and the
// "vision" object pose are the current truth corrupted by noise that is drawn ONLY by
// sample() (once per control period, from the plant's NoiseSource); repeated reads
// between two samples agree. See SensorNoise for the parameters.
//
// Units: SI (m, N, rad). Frame: WORLD. The measured rotation is R_measured = exp(w) R
// (noise applied on the left, in the world frame); a tactile normal is turned by exp(w)
// with w tangential.
#pragma once

#include <algorithm>

#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/sim/noise_source.hpp"
#include "inhand/sim/plant_params.hpp"
#include "inhand/sim/plant_readings.hpp"

namespace inhand::plant::detail {

/// The last sampled noise of one fingertip's tactile sensor.
struct TactileNoise {
  double force = 0.0;
  double force_unit = 0.0;  ///< N(0, 1) draw of the relative force noise
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();

  /// Draws a fixed number of values for the given settings (the relative force noise
  /// only when used, so the other sequences do not move with the option).
  void sample(NoiseSource& noise, const SensorNoise& s) noexcept {
    force = s.normal_force_std * noise.normal();
    force_unit = s.normal_force_relative_std > 0.0 ? noise.normal() : 0.0;
    point = s.contact_point_std * noise.normal3();
    normal = s.normal_angle_std * noise.normal3();
  }

  /// Tactile reading of a contact (fingertip sphere centre `centre`): truth now,
  /// corrupted by this noise: force = max(0, (1 + gain_error) f_n + bias + noise +
  /// relative noise); point += noise; the normal is rotated by exp(w) with w the
  /// tangential part of the sampled 3-vector (std per axis).
  TactileReading read(const ContactState& contact, const Eigen::Vector3d& centre,
                      const SensorNoise& sn) const noexcept {
    TactileReading r;
    r.contact_point = centre;
    if (!contact.active) return r;
    const double f = std::max(
        0.0, (1.0 + sn.normal_force_gain_error) * contact.normal_force + sn.normal_force_bias +
                 force + sn.normal_force_relative_std * contact.normal_force * force_unit);
    if (!(f > sn.touch_threshold)) return r;
    r.touching = true;
    r.normal_force = f;
    r.contact_point = contact.point + point;
    const Eigen::Vector3d& n = contact.normal;
    const Eigen::Vector3d w = normal - normal.dot(n) * n;
    r.normal = so3_exp<double>(w) * n;
    return r;
  }
};

/// The last sampled noise of the object pose measurement.
struct PoseNoise {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();

  void sample(NoiseSource& noise, const SensorNoise& s) noexcept {
    position = s.object_position_std * noise.normal3();
    rotation = s.object_rotation_std * noise.normal3();
  }
  /// Position + noise, R_measured = exp(w) R.
  Pose<double, 3> measure(const Pose<double, 3>& truth) const noexcept {
    Pose<double, 3> p;
    p.position = truth.position + position;
    p.rotation = so3_exp<double>(rotation) * truth.rotation;
    return p;
  }
};

}  // namespace inhand::plant::detail
