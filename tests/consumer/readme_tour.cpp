#include <cstdio>
#include <inhand/inhand.hpp>

int main() {
  // A spatial finger: abduction about z, then two flexion joints about y (SI units).
  using Finger = inhand::FingerChain<double, 3, 3>;  // scalar, Dim = 3, 3 joints
  Finger finger;
  finger.joints[0].axis = Eigen::Vector3d::UnitZ();
  finger.joints[1].axis = Eigen::Vector3d::UnitY();
  finger.joints[2].parent_to_joint.position = Eigen::Vector3d(0.05, 0.0, 0.0);
  finger.joints[2].axis = Eigen::Vector3d::UnitY();
  finger.joint_to_tip.position = Eigen::Vector3d(0.04, 0.0, 0.0);  // fingertip sphere centre
  finger.fingertip_radius = 0.01;
  if (!finger.validate().ok()) return 1;

  // Sensing: forward kinematics and the contact point. The normal is the object's
  // OUTWARD normal at the contact, pointing towards the fingertip (world frame).
  const Eigen::Vector3d q(0.1, 0.5, 0.8);
  inhand::FingerKinematics<Finger> kin(finger);
  inhand::forward_kinematics(finger, q, kin);
  const Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d contact = inhand::fingertip_surface_point(finger, kin, normal);

  // Desired object twist (v; omega) -> desired contact-point velocity (eq. 2).
  inhand::Twist<double, 3> object_twist;
  object_twist << 0.01, 0.0, 0.0, 0.0, 0.0, 0.2;  // 1 cm/s along x, 0.2 rad/s about z
  const Eigen::Vector3d object_origin(0.05, 0.0, -0.1);
  const Eigen::Vector3d v_contact =
      inhand::contact_point_velocity<double, 3>(object_twist, contact, object_origin);

  // Hybrid position/force servo (eqs. 4-7): 0.8 N measured, 1 N desired, 1 kHz.
  inhand::HybridServo<double, 3> servo;  // default ServoGains
  inhand::ServoCommand<double, 3> command;
  servo.update(v_contact, 1.0, 0.8, normal, /*force_active=*/true, 1e-3, command);

  // Contact-point IK (eq. 3), damped near singularities, within the joint speed limits.
  Finger::Jacobian J = Finger::Jacobian::Zero();
  inhand::point_jacobian(kin, contact, J);
  inhand::ContactIk<double, 3, 3> ik;
  Finger::JointVector theta_dot;
  const inhand::IkReport<double> report =
      ik.solve(J, command.total, finger.velocity_limits(), theta_dot);

  std::printf("theta_dot = (%.4f, %.4f, %.4f) rad/s, IK %s\n", theta_dot(0), theta_dot(1),
              theta_dot(2), inhand::to_string(report.status));
  // Too little force pushes into the object (along -n); the joints realise the command.
  const bool pushes_in = command.force.dot(normal) < 0.0;
  const bool realised = (J * theta_dot - command.total).norm() < 1e-12;
  return pushes_in && realised && report.status == inhand::IkStatus::ok ? 0 : 1;
}
