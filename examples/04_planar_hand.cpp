// 04_planar_hand: the same controller in the plane (Dim = 2: positions (x, y), twists
// (vx, vy, wz), every joint about +z). Two 3-joint fingers hold a box by its sides and
// turn it by 0.2 rad about z and back. The box's size is unknown to the controller.
// A stand-in closes the loop: the joints follow the commanded velocities, each fingertip
// presses on its face like a 1000 N/m spring, and the box moves with the commanded twist
// plus a drift under the fingers' net force.
#include <cstdio>

#include "inhand/inhand.hpp"

using Hand = inhand::ReactiveController<double, 2, 2, 3>;  // Dim 2, 2 fingers, 3 joints
using Vec2 = Eigen::Vector2d;

int main() {
  Hand::Config config;
  const Vec2 bases[2] = {Vec2(-0.1, -0.03), Vec2(0.1, -0.03)};
  for (int i = 0; i < 2; ++i) {  // links of 5, 4 and 3 cm; the right finger mirrored
    Hand::Chain& c = config.fingers[i].chain;
    c.base.position = bases[i];
    c.base.rotation = inhand::so2_exp(i == 0 ? 0.0 : 3.14159265358979);
    c.joints[1].parent_to_joint.position = Vec2(0.05, 0);
    c.joints[2].parent_to_joint.position = Vec2(0.04, 0);
    c.joint_to_tip.position = Vec2(0.03, 0);
    c.fingertip_radius = 0.008;
  }
  config.fingers[0].role = inhand::FingerRole::balancing;
  Hand hand;
  if (!hand.configure(config).ok()) return 1;

  inhand::Pose<double, 2> box;  // sides at x = -+18 mm
  box.position = Vec2(0, 0.058);
  // Where to touch (world frame), with the outward normal: also the box-frame normals.
  std::array<inhand::GraspTarget<double, 2>, 2> targets = {
      {{Vec2(-0.018, 0.058), -Vec2::UnitX()}, {Vec2(0.018, 0.058), Vec2::UnitX()}}};
  std::array<Hand::JointVector, 2> q = {Hand::JointVector(0.5, 0.5, 0.5),
                                        Hand::JointVector(-0.5, -0.5, -0.5)};
  if (!hand.start_grasp(targets).ok()) return 1;

  Hand::Input in = hand.make_input();
  Hand::Output out = hand.make_output();
  inhand::FingerKinematics<Hand::Chain> kin;
  double largest_error = 0.0;
  for (int k = 0; k < 6000; ++k) {  // 6 s at 1 kHz
    in.time = 1e-3 * k;
    in.object_pose = box;
    Hand::TwistT drift = Hand::TwistT::Zero();  // 2 cm/s per newton of net push
    for (int i = 0; i < 2; ++i) {
      inhand::forward_kinematics(config.fingers[i].chain, q[i], kin);
      const Vec2 n = box.rotation * targets[i].normal, tip = kin.fingertip.position;
      const double depth = 0.008 - (tip - box.transform_point(0.018 * targets[i].normal)).dot(n);
      in.fingers[i].joint_positions = q[i];
      in.fingers[i].contact = {depth > 0, tip - (0.008 - depth) * n, n, 1e3 * std::max(depth, 0.0)};
      drift.head<2>() -= in.fingers[i].contact.normal_force * n / 50.0;
    }
    const inhand::ControllerStatus status = hand.update(in, out);
    for (int i = 0; i < 2; ++i) q[i] += 1e-3 * out.fingers[i].joint_velocities;
    if (hand.phase() == Hand::Phase::manipulating) {
      box = inhand::integrate(box, Hand::TwistT(out.commanded_twist + drift), 1e-3);
      largest_error = std::max(largest_error, out.pose_error.norm());
      if (status != inhand::ControllerStatus::ok) return 1;  // a finger lost its contact
    } else if (status == inhand::ControllerStatus::grasped) {
      Hand::Trajectory task;  // 0 -> 0.2 rad about z -> 0 in 4 s, then hold
      task.reset(box);
      task.append(Hand::Trajectory::Segment::reciprocate(Hand::TwistT(0, 0, 0.2), 4.0));
      if (!hand.start_manipulation(task).ok()) return 1;
      std::printf("grasped after %.3f s\n", in.time);
    }
  }
  const double angle = inhand::so2_log(box.rotation), f0 = in.fingers[0].contact.normal_force;
  std::printf("largest pose error %.1e, final angle %.1e rad, forces %.3f N and %.3f N\n",
              largest_error, angle, f0, in.fingers[1].contact.normal_force);
  // Both fingers at 1 N times the grip (raised at release, decaying back to 1).
  const double g = out.grip;
  const bool balanced =
      std::abs(f0 - g) < 0.02 * g && std::abs(in.fingers[1].contact.normal_force - g) < 0.02 * g;
  const bool moved = hand.phase() == Hand::Phase::manipulating && largest_error < 1e-3;
  return moved && std::abs(angle) < 1e-4 && balanced ? 0 : 1;
}
