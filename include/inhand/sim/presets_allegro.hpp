// Allegro-like hand preset for the plant: the kinematics of models/urdf/allegro_like_hand.urdf
// (Wonik Robotics Allegro Hand, right hand: four fingers of four revolute joints, 12 mm
// fingertip spheres) written out in C++, with the file's placement in the paper's set-up.
// tests/urdf/urdf_models_test.cpp checks that both agree (frames, axes, limits, forward
// kinematics); tests/sim/presets_test.cpp checks the reach as for the other presets.
//
// Units: metres, radians, rad/s. Frame: the world (hand) frame of presets.hpp: the
// nominal object centre at the origin, its long axis along world X, fingers on +Y,
// thumb on -Y, gravity -Z.
//
// Placement (the URDF's, see the comment there for the search that chose it): the
// Allegro base_link sits at (0, 0.010, 0.085) m with rotation rpy = (pi, 1.40, -pi/2)
// (URDF convention, fixed axes X, Y, Z): the hand tilted 1.40 rad about X from
// fingers-down, palm facing down over the object, fingers pointing out to +Y and curling
// down onto the object's +Y side, the thumb reaching under the palm to its -Y side;
// index on -X, ring on +X.
// Every finger's base is that pose; joint 0's frame is the Allegro's knuckle origin
// from base_link. Joint limits are the published ones; the URDF gives no velocity
// limit, so the preset uses the reader's default (2 rad/s).
//
// Finger roles: index (0), middle (1), ring (2) on +Y, touching the object at
// x = -28, 0, +28 mm (the knuckles are 43.5 mm apart; 28 mm keeps the contacts on the
// 80 mm box under the +-5 mm / +-0.2 rad offsets and the 12 mm spheres apart); thumb (3)
// on -Y at x = 0. The grasp configuration puts each fingertip centre halfway between its
// nominal contacts on the two paper objects: found by the position IK of
// tests/sim/presets_test.cpp from 100 random starts (0.1 rad inside the limits), keeping
// the solution (rounded to 1 mrad) with the best worst-case joint-limit margin, Jacobian
// singular value and link clearance over the object offsets that test checks. The open
// configuration is the same IK from the grasp one to the fingertip withdrawn 15 mm along
// the approach direction and 20 mm down (14.5 mm clear of the cylinder, 21.5 mm of the
// box).
#pragma once

#include <cmath>

#include "inhand/sim/presets.hpp"

namespace inhand::plant {

namespace detail {
/// A URDF <origin xyz rpy>: the rotation through the quaternion urdfdom computes from
/// roll-pitch-yaw (fixed axes X, Y, Z), so that it equals the reader's to the last bits.
inline Pose<double, 3> urdf_origin(const Eigen::Vector3d& xyz, const Eigen::Vector3d& rpy) {
  const double phi = rpy.x() / 2.0, the = rpy.y() / 2.0, psi = rpy.z() / 2.0;
  const Eigen::Quaterniond q(
      std::cos(phi) * std::cos(the) * std::cos(psi) + std::sin(phi) * std::sin(the) * std::sin(psi),
      std::sin(phi) * std::cos(the) * std::cos(psi) - std::cos(phi) * std::sin(the) * std::sin(psi),
      std::cos(phi) * std::sin(the) * std::cos(psi) + std::sin(phi) * std::cos(the) * std::sin(psi),
      std::cos(phi) * std::cos(the) * std::sin(psi) -
          std::sin(phi) * std::sin(the) * std::cos(psi));
  Pose<double, 3> p;
  p.position = xyz;
  p.rotation = q.normalized().toRotationMatrix();
  return p;
}
}  // namespace detail

/// Allegro-like hand: index (0), middle (1), ring (2) on +Y, thumb (3) on -Y.
inline HandPreset allegro_like_hand() {
  using detail::make_joint;
  using V = Eigen::Vector3d;
  constexpr double kVel = 2.0;  // the reader's default: the URDF gives none
  const V ux = V::UnitX(), uy = V::UnitY(), uz = V::UnitZ(), zero = V::Zero();
  HandPreset p;
  p.name = "allegro_like_hand";
  p.object_pose.rotation = detail::long_axis_along_x();
  const Pose<double, 3> base =
      detail::urdf_origin(V(0, 0.010, 0.085), V(3.141592653589793, 1.40, -1.5707963267948966));
  // Fingers: knuckle origin and roll in base_link; abduction about z, three flexions
  // about y; links 16.4, 54, 38.4 mm, fingertip sphere centre 26.7 mm further.
  const V knuckle[3] = {V(0, 0.0435, -0.001542), V(0, 0, 0.0007), V(0, -0.0435, -0.001542)};
  const double roll[3] = {-0.08726646255, 0.0, 0.08726646255};
  const double xs[3] = {-0.028, 0.0, 0.028};
  const char* names[3] = {"index", "middle", "ring"};
  for (int k = 0; k < 3; ++k) {
    PlantFinger f;
    f.joints.resize(4);
    f.base = base;
    f.joints[0] = make_joint(zero, uz, -0.47, 0.47, kVel);
    f.joints[0].parent_to_joint = detail::urdf_origin(knuckle[k], V(roll[k], 0, 0));
    f.joints[1] = make_joint(V(0, 0, 0.0164), uy, -0.196, 1.61, kVel);
    f.joints[2] = make_joint(V(0, 0, 0.054), uy, -0.174, 1.709, kVel);
    f.joints[3] = make_joint(V(0, 0, 0.0384), uy, -0.227, 1.618, kVel);
    f.joint_to_tip.position = V(0, 0, 0.0267);
    f.fingertip_radius = 0.012;
    p.fingers.push_back(f);
    p.finger_names.emplace_back(names[k]);
    p.approach_directions.push_back(uy);
    p.approach_points.push_back(V(xs[k], 0.0, 0.0));
  }
  p.open_configuration = {detail::joint_vector({-0.200, 0.738, 0.795, 0.361}),
                          detail::joint_vector({0.000, 0.738, 0.707, 0.613}),
                          detail::joint_vector({0.200, 0.726, 0.860, 0.246})};
  p.grasp_configuration = {detail::joint_vector({-0.222, 0.573, 1.248, 0.658}),
                           detail::joint_vector({0.000, 0.610, 1.126, 0.938}),
                           detail::joint_vector({0.222, 0.550, 1.327, 0.521})};
  // Thumb: rotation about -x, then about z, then two flexions about y; links 17.7,
  // 51.4 mm, fingertip sphere centre 42.3 mm further.
  PlantFinger t;
  t.joints.resize(4);
  t.base = base;
  t.joints[0] = make_joint(zero, -ux, 0.263, 1.396, kVel);
  t.joints[0].parent_to_joint =
      detail::urdf_origin(V(-0.0182, 0.019333, -0.045987), V(0, -1.65806278845, -1.5707963259));
  t.joints[1] = make_joint(V(-0.027, 0.005, 0.0399), uz, -0.105, 1.163, kVel);
  t.joints[2] = make_joint(V(0, 0, 0.0177), uy, -0.189, 1.644, kVel);
  t.joints[3] = make_joint(V(0, 0, 0.0514), uy, -0.162, 1.719, kVel);
  t.joint_to_tip.position = V(0, 0, 0.0423);
  t.fingertip_radius = 0.012;
  p.fingers.push_back(t);
  p.finger_names.emplace_back("thumb");
  p.open_configuration.push_back(detail::joint_vector({1.301, 0.916, 0.474, 0.681}));
  p.grasp_configuration.push_back(detail::joint_vector({1.164, 0.862, 0.714, 0.986}));
  p.approach_directions.push_back(-uy);
  p.approach_points.push_back(V(0.0, 0.0, 0.0));
  p.thumb = 3;
  p.opposing_pairs = {{3, 0}, {3, 1}, {3, 2}};
  return p;
}

}  // namespace inhand::plant
