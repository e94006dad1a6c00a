// Hand presets for the plant: a Shadow-like hand (thumb opposing three fingers) and a
// three-finger hand (one finger opposing two), with the paper's test objects.
//
// Units: metres, radians, rad/s, kilograms. Frame: the world (hand) frame, with the
// nominal object centre at the origin.
//
// Geometry shared by both presets (docs/method.md section 9, the paper's Fig. 5):
//  - The object's long axis (object z, the cylinder axis) lies along world X; the
//    nominal object rotation is Ry(+pi/2), which maps object z to world +X.
//  - The fingers sit on the +Y side of the object, the thumb (opposing finger) on the
//    -Y side, so every nominal contact normal is along +-Y.
//  - Finger bases are above the object (+Z). A straight finger points along -Z; the
//    first joint abducts about world Y (moves the tip along X); the flexion joints turn
//    about -X for the fingers and +X for the thumb, so positive flexion curls the tip
//    towards the object (towards -Y for the fingers, +Y for the thumb).
//  - Gravity (plant default) is along -Z: the object hangs between the fingertips.
//
// Shadow-like hand (joint limits after the Shadow hand E series, velocity limits
// 3 rad/s; link lengths to the next joint, the distal one to the fingertip sphere
// centre; fingertip sphere radius 10 mm):
//   finger k in {first, middle, ring} at x_k = +22, 0, -22 mm, base (x_k, 72.5, 40) mm:
//     J4 abduction  axis +Y  [-0.35, 0.35]
//     J3 MCP flex   axis -X  [-0.26, 1.57]   proximal 45 mm
//     J2 PIP flex   axis -X  [ 0.00, 1.57]   middle   25 mm
//     J1 DIP flex   axis -X  [ 0.00, 1.57]   distal   26 mm
//   thumb at x = 0, base (0, -92.5, 0) mm (level with the object, reaching up and in):
//     THJ5 rotation axis +Z  [-1.05, 1.05]
//     THJ4 flex     axis +X  [-0.20, 1.22]   metacarpal 38 mm
//     THJ3 sideways axis +Y  [-0.50, 0.50]
//     THJ2 flex     axis +X  [-0.70, 1.20]   proximal   32 mm
//     THJ1 flex     axis +X  [-0.26, 1.57]   distal     27 mm
// Three-finger hand (3 DOF each, velocity limits 3 rad/s, fingertip radius 10 mm):
//   two fingers at x = +-20 mm, base (x, 67.5, 45) mm; one opposing finger at x = 0, base
//   (0, -67.5, 45) mm; each: abduction axis +Y [-0.5, 0.5], flexion [-0.3, 1.6] with a
//   50 mm proximal link, flexion [0.1, 2.0] with a 40 mm distal link.
// The bases come from a 2.5 mm grid search that maximised the worst joint-limit margin
// and the smallest singular value of the fingertip Jacobian over all the object poses
// below, for both paper objects (the 20 mm radius cylinder and the 20 x 20 x 80 mm box).
// The grasp configuration puts each fingertip centre halfway between its nominal
// contacts on the two objects; the open configuration withdraws it 15 mm along the
// approach direction and 20 mm down (10-25 mm clear). tests/sim/presets_test.cpp checks
// numerically that every fingertip reaches its contact on both objects, at the nominal
// pose and with the object moved +-5 mm along X, Y, Z or turned +-0.2 rad about X, Y, Z,
// away from the joint limits and from singular configurations.
#pragma once

#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "inhand/sim/hand_plant.hpp"

namespace inhand::plant {

/// A hand with its posture and the object pose it was designed around.
struct HandPreset {
  std::string name;
  std::vector<PlantFinger> fingers;
  std::vector<std::string> finger_names;
  /// Pre-grasp (open) joint angles per finger: fingertips 10-25 mm clear of the objects.
  std::vector<PlantFinger::JointVector> open_configuration;
  /// Joint angles placing each fingertip centre halfway between its nominal contacts on
  /// the two paper objects (a good IK starting point).
  std::vector<PlantFinger::JointVector> grasp_configuration;
  /// Nominal object pose (centre of mass frame): origin, object z along world X.
  Pose<double, 3> object_pose{};
  /// Index of the thumb (the finger opposing all others).
  int thumb = 0;
  /// (thumb, finger) pairs whose nominal contact normals are opposite.
  std::vector<std::pair<int, int>> opposing_pairs;
  /// Per finger: world unit vector from the object towards the finger (the nominal
  /// outward contact normal) and a world point on the nominal object's central plane
  /// the approach line passes through; see nominal_contact().
  std::vector<Eigen::Vector3d> approach_directions;
  std::vector<Eigen::Vector3d> approach_points;
};

namespace detail {
inline PlantFinger::Joint make_joint(const Eigen::Vector3d& offset, const Eigen::Vector3d& axis,
                                     double lower, double upper, double max_velocity) {
  PlantFinger::Joint j;
  j.parent_to_joint.position = offset;
  j.axis = axis;
  j.lower = lower;
  j.upper = upper;
  j.max_velocity = max_velocity;
  return j;
}
inline PlantFinger::JointVector joint_vector(std::initializer_list<double> v) {
  PlantFinger::JointVector out(static_cast<Eigen::Index>(v.size()));
  Eigen::Index i = 0;
  for (double x : v) out(i++) = x;
  return out;
}
/// Nominal object rotation: object z along world +X.
inline Eigen::Matrix3d long_axis_along_x() {
  return Eigen::AngleAxisd(1.5707963267948966, Eigen::Vector3d::UnitY()).toRotationMatrix();
}
}  // namespace detail

/// Shadow-like hand: fingers first (0), middle (1), ring (2) on +Y, thumb (3) on -Y.
inline HandPreset shadow_like_hand() {
  using detail::make_joint;
  const Eigen::Vector3d ux = Eigen::Vector3d::UnitX(), uy = Eigen::Vector3d::UnitY(),
                        uz = Eigen::Vector3d::UnitZ(), zero = Eigen::Vector3d::Zero();
  constexpr double kVel = 3.0;
  HandPreset p;
  p.name = "shadow_like_hand";
  p.object_pose.rotation = detail::long_axis_along_x();
  const double xs[3] = {0.022, 0.0, -0.022};
  const char* names[3] = {"first", "middle", "ring"};
  for (int k = 0; k < 3; ++k) {
    PlantFinger f;
    f.joints.resize(4);
    f.base.position = Eigen::Vector3d(xs[k], 0.0725, 0.040);
    f.joints[0] = make_joint(zero, uy, -0.35, 0.35, kVel);
    f.joints[1] = make_joint(zero, -ux, -0.26, 1.57, kVel);
    f.joints[2] = make_joint(Eigen::Vector3d(0, 0, -0.045), -ux, 0.0, 1.57, kVel);
    f.joints[3] = make_joint(Eigen::Vector3d(0, 0, -0.025), -ux, 0.0, 1.57, kVel);
    f.joint_to_tip.position = Eigen::Vector3d(0, 0, -0.026);
    f.fingertip_radius = 0.010;
    p.fingers.push_back(f);
    p.finger_names.emplace_back(names[k]);
    p.open_configuration.push_back(detail::joint_vector({0.0, -0.188, 0.844, 1.071}));
    p.grasp_configuration.push_back(detail::joint_vector({0.0, 0.102, 1.007, 1.122}));
    p.approach_directions.push_back(uy);
    p.approach_points.push_back(Eigen::Vector3d(xs[k], 0.0, 0.0));
  }
  PlantFinger t;
  t.joints.resize(5);
  t.base.position = Eigen::Vector3d(0.0, -0.0925, 0.0);
  t.joints[0] = make_joint(zero, uz, -1.05, 1.05, kVel);
  t.joints[1] = make_joint(zero, ux, -0.20, 1.22, kVel);
  t.joints[2] = make_joint(Eigen::Vector3d(0, 0, -0.038), uy, -0.50, 0.50, kVel);
  t.joints[3] = make_joint(zero, ux, -0.70, 1.20, kVel);
  t.joints[4] = make_joint(Eigen::Vector3d(0, 0, -0.032), ux, -0.26, 1.57, kVel);
  t.joint_to_tip.position = Eigen::Vector3d(0, 0, -0.027);
  t.fingertip_radius = 0.010;
  p.fingers.push_back(t);
  p.finger_names.emplace_back("thumb");
  p.open_configuration.push_back(detail::joint_vector({0.0, 0.310, 0.0, 0.981, 1.465}));
  p.grasp_configuration.push_back(detail::joint_vector({0.0, 0.762, 0.0, 0.876, 1.150}));
  p.approach_directions.push_back(-uy);
  p.approach_points.push_back(Eigen::Vector3d(0.0, 0.0, 0.0));
  p.thumb = 3;
  p.opposing_pairs = {{3, 0}, {3, 1}, {3, 2}};
  return p;
}

/// Three-finger hand: fingers 0 (x = +20 mm) and 1 (x = -20 mm) on +Y, the opposing
/// finger 2 on -Y; 3 DOF each (square contact Jacobians).
inline HandPreset three_finger_hand() {
  using detail::make_joint;
  const Eigen::Vector3d ux = Eigen::Vector3d::UnitX(), uy = Eigen::Vector3d::UnitY(),
                        zero = Eigen::Vector3d::Zero();
  constexpr double kVel = 3.0;
  HandPreset p;
  p.name = "three_finger_hand";
  p.object_pose.rotation = detail::long_axis_along_x();
  const double xs[3] = {0.020, -0.020, 0.0};
  const double side[3] = {1.0, 1.0, -1.0};
  const char* names[3] = {"left", "right", "thumb"};
  for (int k = 0; k < 3; ++k) {
    PlantFinger f;
    f.joints.resize(3);
    f.base.position = Eigen::Vector3d(xs[k], side[k] * 0.0675, 0.045);
    const Eigen::Vector3d flex = -side[k] * ux;  // curls the tip towards the object
    f.joints[0] = make_joint(zero, uy, -0.5, 0.5, kVel);
    f.joints[1] = make_joint(zero, flex, -0.3, 1.6, kVel);
    f.joints[2] = make_joint(Eigen::Vector3d(0, 0, -0.050), flex, 0.1, 2.0, kVel);
    f.joint_to_tip.position = Eigen::Vector3d(0, 0, -0.040);
    f.fingertip_radius = 0.010;
    p.fingers.push_back(f);
    p.finger_names.emplace_back(names[k]);
    p.open_configuration.push_back(detail::joint_vector({0.0, -0.186, 1.349}));
    p.grasp_configuration.push_back(detail::joint_vector({0.0, 0.056, 1.638}));
    p.approach_directions.push_back(side[k] * uy);
    p.approach_points.push_back(Eigen::Vector3d(xs[k], 0.0, 0.0));
  }
  p.thumb = 2;
  p.opposing_pairs = {{2, 0}, {2, 1}};
  return p;
}

/// The paper's cylinder: radius 20 mm, length 100 mm, 50 g, axis along world X at the
/// preset's nominal pose.
inline ObjectDef paper_cylinder(const HandPreset& preset) {
  ObjectDef o;
  o.shape = ObjectShape::cylinder(0.020, 0.050);
  o.mass = 0.05;
  o.pose = preset.object_pose;
  return o;
}
/// The paper's slender cube: 20 x 20 x 80 mm, 50 g, long axis along world X.
inline ObjectDef paper_slender_box(const HandPreset& preset) {
  ObjectDef o;
  o.shape = ObjectShape::box(0.010, 0.010, 0.040);
  o.mass = 0.05;
  o.pose = preset.object_pose;
  return o;
}

/// A contact point on an object surface (world frame) with the outward unit normal.
struct SurfacePoint {
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  bool found = false;
};

/// Where finger i's approach line (from approach_points[i] along approach_directions[i])
/// leaves `object` at pose `pose`: the finger's nominal contact. Sphere tracing on the
/// signed distance, inward from 0.5 m out; exact to 1e-10 m for the convex shapes.
inline SurfacePoint nominal_contact(const HandPreset& preset, int i, const ObjectShape& shape,
                                    const Pose<double, 3>& pose) {
  SurfacePoint out;
  const Eigen::Vector3d dir = preset.approach_directions[static_cast<std::size_t>(i)];
  const Eigen::Vector3d start = preset.approach_points[static_cast<std::size_t>(i)] + 0.5 * dir;
  double t = 0.0;
  for (int it = 0; it < 200; ++it) {
    const Eigen::Vector3d x = start - t * dir;
    const SurfaceQuery q = shape.query(pose.rotation.transpose() * (x - pose.position));
    if (q.distance < 1e-10) {
      out.point = x;
      out.normal = pose.rotation * q.normal;
      out.found = q.distance > -1e-6;
      return out;
    }
    t += q.distance;
  }
  return out;
}

}  // namespace inhand::plant
