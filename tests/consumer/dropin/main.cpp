// Header drop-in consumer: compiled with nothing but
//   c++ -std=c++17 -I <inhand>/include -I <eigen include dir> main.cpp
// (and, in the pkg-config test, with the flags of `pkg-config --cflags inhand`).
// Exercises the servo's force sign, SO(3) exp/log and a run-time-DOF finger with
// ContactIk. Returns non-zero on mismatch.
#include <cmath>
#include <cstdio>

#include "inhand/inhand.hpp"

int main() {
  int failures = 0;

  // Force below desired (0.4 N < 1 N) moves the fingertip along -n, into the object.
  inhand::HybridServo<double, 3> servo;
  inhand::ServoCommand<double, 3> cmd;
  const inhand::Vector<double, 3> n = inhand::Vector<double, 3>::UnitY();
  servo.update(inhand::Vector<double, 3>::Zero(), 1.0, 0.4, n, true, 1e-3, cmd);
  if (!(cmd.total.dot(n) < 0.0)) ++failures;

  // exp and log are inverse for a rotation of 1 rad.
  const inhand::Vector<double, 3> w(0.6, 0.0, -0.8);
  if ((inhand::so3_log<double>(inhand::so3_exp<double>(w)) - w).norm() > 1e-12) ++failures;

  // A 3-joint finger with run-time DOF (capacity 4): J * theta_dot reproduces x_dot.
  using Chain = inhand::FingerChain<double, 3, inhand::Dynamic, 4>;
  Chain chain;
  chain.joints.resize(3);
  chain.joints[0].axis = inhand::Vector<double, 3>::UnitZ();
  chain.joints[1].axis = inhand::Vector<double, 3>::UnitY();
  chain.joints[2].parent_to_joint.position = inhand::Vector<double, 3>(0.05, 0.0, 0.0);
  chain.joints[2].axis = inhand::Vector<double, 3>::UnitY();
  chain.joint_to_tip.position = inhand::Vector<double, 3>(0.04, 0.0, 0.0);
  Chain::JointVector q(3);
  q << 0.1, 0.5, 0.8;
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  const inhand::Vector<double, 3> contact = inhand::fingertip_surface_point(chain, ws, n);
  Chain::Jacobian J(3, 3);
  inhand::point_jacobian(ws, contact, J);
  inhand::ContactIk<double, 3, inhand::Dynamic, 4> ik(3);
  Chain::JointVector theta_dot(3);
  const inhand::Vector<double, 3> x_dot(0.01, -0.02, 0.005);
  const auto report = ik.solve(J, x_dot, chain.velocity_limits(), theta_dot);
  if (report.status != inhand::IkStatus::ok) ++failures;
  if ((J * theta_dot - x_dot).norm() > 1e-12) ++failures;

  std::printf("header drop-in consumer: %s\n", failures == 0 ? "ok" : "FAILED");
  return failures == 0 ? 0 : 1;
}
