// 01_finger_servo: the lowest layer for one finger. Each tick: the desired contact-point
// velocity from an object twist (eq. 2), the hybrid position/force servo (eqs. 4-7) and
// the contact-point IK (eq. 3). The finger presses on a springy plane z = const (outward
// normal +z, 500 N/m) while the object twist asks its contact point to slide along x.
// examples/finger_tracking.cpp is the longer version of this loop (a circle, a table).
#include <cstdio>

#include "inhand/inhand.hpp"

int main() {
  using Finger = inhand::FingerChain<double, 3, 3>;  // scalar, Dim = 3, 3 joints
  Finger finger;  // abduction about z, then two flexion joints about y (SI units)
  finger.joints[0].axis = Eigen::Vector3d::UnitZ();
  finger.joints[1].axis = finger.joints[2].axis = Eigen::Vector3d::UnitY();
  finger.joints[2].parent_to_joint.position = Eigen::Vector3d(0.05, 0.0, 0.0);
  finger.joint_to_tip.position = Eigen::Vector3d(0.04, 0.0, 0.0);  // fingertip sphere centre
  finger.fingertip_radius = 0.01;
  if (!finger.validate().ok()) return 1;

  Finger::JointVector q(0.1, 0.5, 0.8), theta_dot;
  inhand::FingerKinematics<Finger> kin(finger);
  inhand::forward_kinematics(finger, q, kin);
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // the object's OUTWARD normal
  const double surface_z = kin.fingertip.position.z() - finger.fingertip_radius;  // touching
  const Eigen::Vector3d x0 = inhand::fingertip_surface_point(finger, kin, normal);
  inhand::Twist<double, 3> object_twist;
  object_twist << 0.005, 0.0, 0.0, 0.0, 0.0, 0.0;  // the object: 5 mm/s along x

  inhand::HybridServo<double, 3> servo;  // default ServoGains: g1 passes v through
  inhand::ContactIk<double, 3, 3> ik;
  inhand::ServoCommand<double, 3> command;
  Finger::Jacobian J;
  double force = 0.0;
  for (int k = 0; k < 1000; ++k) {  // 1 s at 1 kHz
    inhand::forward_kinematics(finger, q, kin);
    const Eigen::Vector3d contact = inhand::fingertip_surface_point(finger, kin, normal);
    force = 500.0 * std::max(0.0, surface_z - contact.z());  // the measured normal force
    // Eq. 2 plus feedback on where the contact should be by now (along x): the contact
    // rolls over the fingertip as the finger flexes, which eq. 2 leaves to feedback.
    const Eigen::Vector3d v =
        inhand::contact_point_velocity<double, 3>(object_twist, contact, Eigen::Vector3d::Zero()) +
        20.0 * (x0.x() + 0.005 * k * 1e-3 - contact.x()) * Eigen::Vector3d::UnitX();
    servo.update(v, 1.0, force, normal, /*force_active=*/true, 1e-3, command);  // 1 N wanted
    inhand::point_jacobian(kin, contact, J);
    const inhand::IkReport<double> report =
        ik.solve(J, command.total, finger.velocity_limits(), theta_dot);
    if (report.status != inhand::IkStatus::ok) return 1;          // no damping, no limits here
    if ((J * theta_dot - command.total).norm() > 1e-9) return 1;  // J theta_dot = e
    q += 1e-3 * theta_dot;                                        // the joints follow the command
  }
  inhand::forward_kinematics(finger, q, kin);
  const double slid = inhand::fingertip_surface_point(finger, kin, normal).x() - x0.x();
  std::printf("force %.3f N (1 N wanted), contact moved %.2f mm (5 mm wanted)\n", force,
              slid * 1e3);
  return std::abs(force - 1.0) < 0.05 && std::abs(slid - 0.005) < 2e-4 ? 0 : 1;
}
