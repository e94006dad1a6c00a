// 03_external_kinematics: the controller with kinematics it does not model. Two fingers on
// Cartesian stages (three prismatic joints each: fingertip centre = base + q) pinch a box
// and move it 5 mm along x and back (the paper's Fig. 3a). FingerChain has revolute
// joints only, so each tick the user hands in what the controller needs from the
// kinematics (KinematicsSource::external): the Jacobian of the point it servoes (here the
// identity) and the virtual contact point (the fingertip point facing the object, used
// while the finger does not touch). In this stand-in the box follows the commanded twist.
#include <cstdio>

#include "inhand/inhand.hpp"

using Hand = inhand::ReactiveController<double, 3, 2, 3>;  // Dim 3, 2 fingers, 3 joints
using Vec3 = Eigen::Vector3d;

int main() {
  Hand::Config config;
  for (auto& finger : config.fingers) {
    finger.kinematics = Hand::KinematicsSource::external;
    for (int j = 0; j < 3; ++j) finger.chain.joints[j].max_velocity = 0.1;  // m/s: prismatic
  }
  config.fingers[0].role = inhand::FingerRole::balancing;
  Hand hand;
  if (!hand.configure(config).ok()) return 1;

  const double radius = 0.01, half_width = 0.02;  // fingertip sphere; the box, unknown
  const Vec3 bases[2] = {Vec3(-0.05, 0, 0), Vec3(0.05, 0, 0)};  // stage origins, facing
  const Vec3 n_box[2] = {-Vec3::UnitX(), Vec3::UnitX()};        // the box's faces' normals
  std::array<inhand::GraspTarget<double, 3>, 2> targets;
  for (int i = 0; i < 2; ++i) targets[i] = {half_width * n_box[i], n_box[i]};
  if (!hand.start_grasp(targets).ok()) return 1;

  inhand::Pose<double, 3> box;
  std::array<Vec3, 2> q = {Vec3::Zero(), Vec3::Zero()};  // stage positions, m
  Hand::Input in = hand.make_input();
  Hand::Output out = hand.make_output();
  double peak = 0.0;
  for (int k = 0; k < 4000; ++k) {  // 4 s at 1 kHz
    in.time = 1e-3 * k;
    in.object_pose = box;
    for (int i = 0; i < 2; ++i) {
      const Vec3 centre = bases[i] + q[i], n = box.rotation * n_box[i];
      const double depth = radius - (centre - box.transform_point(half_width * n_box[i])).dot(n);
      in.fingers[i].joint_positions = q[i];
      in.fingers[i].contact = {depth > 0, centre - radius * n, n, 1000.0 * std::max(depth, 0.0)};
      in.fingers[i].jacobian.setIdentity();  // d(centre)/dq, the same for every point
      in.fingers[i].virtual_contact_point = centre - radius * targets[i].normal;
    }
    const inhand::ControllerStatus status = hand.update(in, out);
    for (int i = 0; i < 2; ++i) q[i] += 1e-3 * out.fingers[i].joint_velocities;
    if (hand.phase() == Hand::Phase::manipulating) {
      box = inhand::integrate(box, out.commanded_twist, 1e-3);
      peak = std::max(peak, box.position.x());
      if (status != inhand::ControllerStatus::ok) return 1;  // a finger lost its contact
    } else if (status == inhand::ControllerStatus::grasped) {
      Hand::Trajectory task;  // 5 mm along x and back in 2 s, then hold
      task.reset(box);
      task.append(Hand::Trajectory::Segment::reciprocate(
          (Hand::TwistT() << 0.005, 0, 0, 0, 0, 0).finished(), 2.0));
      if (!hand.start_manipulation(task).ok()) return 1;
    }
  }
  const double f0 = in.fingers[0].contact.normal_force, f1 = in.fingers[1].contact.normal_force;
  std::printf("peak %.2f mm, final x %.4f mm, forces %.3f N and %.3f N\n", peak * 1e3,
              box.position.x() * 1e3, f0, f1);
  // Both fingers at 1 N times the grip (raised at release, decaying back to 1).
  const double g = out.grip;
  return std::abs(peak - 0.005) < 1e-4 && std::abs(box.position.x()) < 1e-5 &&
                 std::abs(f0 - g) < 0.02 * g && std::abs(f1 - g) < 0.02 * g
             ? 0
             : 1;
}
