// Helpers shared by the plant tests: probe fingers and the test-size multiplier.
#pragma once

#include <cstdlib>

#include "inhand/sim/hand_plant.hpp"

namespace plant_test {

using inhand::plant::PlantFinger;

/// INHAND_TEST_SCALE (a multiplier for seeded sweeps), default 1.
inline int test_scale() {
  const char* s = std::getenv("INHAND_TEST_SCALE");
  const int v = s ? std::atoi(s) : 1;
  return v > 0 ? v : 1;
}

/// A one-joint "probe" finger: at q = 0 its fingertip centre is at `tip`; it swings about
/// `axis` through the pivot tip - arm, so the tip moves on a circle of radius |arm| in the
/// plane perpendicular to `axis`, with velocity q_dot * axis x arm at q = 0. With `axis`
/// along a contact normal the tip slides in the tangent plane at constant indentation.
inline PlantFinger probe(const Eigen::Vector3d& tip, const Eigen::Vector3d& axis,
                         const Eigen::Vector3d& arm, double radius = 0.01) {
  PlantFinger f;
  f.joints.resize(1);
  f.base.position = tip - arm;
  f.joints[0].axis = axis;
  f.joints[0].lower = -3.0;
  f.joints[0].upper = 3.0;
  f.joints[0].max_velocity = 10.0;
  f.joint_to_tip.position = arm;
  f.fingertip_radius = radius;
  return f;
}

/// A probe parked far from everything (no contact).
inline PlantFinger far_probe() {
  return probe(Eigen::Vector3d(10.0, 10.0, 10.0), Eigen::Vector3d::UnitZ(),
               Eigen::Vector3d::UnitX() * 0.1);
}

inline PlantFinger::JointVector one(double v) {
  PlantFinger::JointVector q(1);
  q(0) = v;
  return q;
}

}  // namespace plant_test
