// A thumb and two fingers grasp a box, then turn it about x to -0.2 rad and back (the
// paper's Fig. 3b). A stand-in closes the loop: the joints follow the commanded
// velocities, each fingertip presses on its face like a 1000 N/m spring, and the box
// moves with the commanded twist plus a drift under the fingers' net force.
#include <cstdio>

#include "inhand/inhand.hpp"

using Hand = inhand::ReactiveController<double, 3, 3, 3>;  // scalar, Dim, fingers, joints
using Vec3 = Eigen::Vector3d;

int main() {
  Hand::Config config;  // library defaults: 1 ms tick, 1 N per finger, ...
  const Vec3 bases[3] = {{-0.1, 0, 0}, {0.1, -0.015, 0}, {0.1, 0.015, 0}};  // thumb first
  for (std::size_t i = 0; i < 3; ++i) {  // abduction about z, then two flexions about y
    Hand::Chain& c = config.fingers[i].chain;
    c.base.position = bases[i];
    if (i > 0) c.base.rotation = Vec3(-1, -1, 1).asDiagonal();  // facing the thumb
    c.joints[0].axis = Vec3::UnitZ();
    c.joints[1].axis = c.joints[2].axis = Vec3::UnitY();
    c.joints[2].parent_to_joint.position = Vec3(0.05, 0, 0);
    c.joint_to_tip.position = Vec3(0.04, 0, 0);  // the fingertip sphere's centre
    c.fingertip_radius = 0.01;
  }
  config.fingers[0].role = inhand::FingerRole::balancing;  // the thumb balances the others
  Hand hand;
  if (!hand.configure(config).ok()) return 1;
  inhand::Pose<double, 3> box;  // faces at x = -+3 cm from its centre; unknown to the hand
  box.position = Vec3(0, 0, -0.06);
  std::array<inhand::GraspTarget<double, 3>, 3> targets;  // where to touch, outward normal
  std::array<Vec3, 3> q, n_box;  // joint angles; each finger's face normal (box frame)
  for (std::size_t i = 0; i < 3; ++i) {
    n_box[i] = (i == 0 ? -1.0 : 1.0) * Vec3::UnitX();
    targets[i] = {box.position + 0.03 * n_box[i] + Vec3(0, bases[i].y(), 0), n_box[i]};
    q[i] = Vec3(0, 0.5, 0.8);
  }
  if (!hand.start_grasp(targets).ok()) return 1;
  Hand::Input in = hand.make_input();
  Hand::Output out = hand.make_output();
  inhand::FingerKinematics<Hand::Chain> kin;
  bool ok = true;
  for (int k = 0; k < 5000; ++k) {  // 5 s at 1 kHz
    in.time = 1e-3 * k;             // sense: joint angles, box pose, tactile contacts
    in.object_pose = box;
    inhand::Twist<double, 3> box_twist = inhand::Twist<double, 3>::Zero();
    for (std::size_t i = 0; i < 3; ++i) {
      inhand::forward_kinematics(config.fingers[i].chain, q[i], kin);
      const Vec3 n = box.rotation * n_box[i], tip = kin.fingertip.position;
      const double depth = 0.01 - (tip - box.transform_point(0.03 * n_box[i])).dot(n);
      const double force = 1000.0 * std::max(depth, 0.0);
      in.fingers[i].joint_positions = q[i];
      in.fingers[i].contact = {depth > 0, tip - (0.01 - depth) * n, n, force};
      box_twist.head<3>() -= force * n / 50.0;  // 2 cm/s per newton of net push
    }
    const inhand::ControllerStatus status = hand.update(in, out);  // one control tick
    for (std::size_t i = 0; i < 3; ++i) q[i] += 1e-3 * out.fingers[i].joint_velocities;
    if (hand.phase() == Hand::Phase::manipulating) {  // the grasp released the box
      box = inhand::integrate(box, Hand::TwistT(box_twist + out.commanded_twist), 1e-3);
      ok = ok && status == inhand::ControllerStatus::ok;  // every finger kept its contact
    } else if (status == inhand::ControllerStatus::grasped) {
      Hand::Trajectory turn;  // 0 -> -0.2 rad about x -> 0 in 2 s, then hold 1 s
      turn.reset(box);
      turn.append(Hand::Trajectory::Segment::reciprocate(
          (Hand::TwistT() << 0, 0, 0, -0.2, 0, 0).finished(), 2.0));
      turn.append(Hand::Trajectory::Segment::hold_for(1.0));
      ok = ok && hand.start_manipulation(turn).ok();
      std::printf("grasped after %.3f s\n", in.time);
    }
  }
  const double error = out.pose_error.norm(), thumb = in.fingers[0].contact.normal_force;
  std::printf("final pose error %.1e, forces %.3f (thumb), %.3f, %.3f N\n", error, thumb,
              in.fingers[1].contact.normal_force, in.fingers[2].contact.normal_force);
  ok = ok && hand.phase() == Hand::Phase::manipulating && error < 1e-4;
  // The thumb balances two fingers of 1 N each, times the grip (raised at release and
  // held while the object is free, force_layer.hpp).
  return ok && std::abs(thumb - 2.0 * out.grip) < 0.05 * out.grip ? 0 : 1;
}
