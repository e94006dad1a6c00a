// What the analytic plant reports per finger: the tactile reading (sensed, noisy), the
// contact's ground truth and the simulated-hardware event counters.
//
// Units: SI (m, s, N). Frame: WORLD. Sign convention: `normal` is the OBJECT's outward
// unit normal (pointing towards the fingertip); forces are those acting ON THE OBJECT.
#pragma once

#include <Eigen/Core>
#include <cstdint>

namespace inhand::plant {

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

}  // namespace inhand::plant
