// Consumer of inhand through add_subdirectory: a planar two-link finger, forward
// kinematics, the contact-point Jacobian and ContactIk. Returns non-zero on mismatch.
#include <cmath>
#include <cstdio>
#include <inhand/inhand.hpp>

int main() {
  // Links of 5 cm and 4 cm along the x axis of their joints, point fingertip.
  using Chain = inhand::FingerChain<double, 2, 2>;
  Chain chain;
  chain.joints[1].parent_to_joint.position = inhand::Vector<double, 2>(0.05, 0.0);
  chain.joint_to_tip.position = inhand::Vector<double, 2>(0.04, 0.0);
  chain.fingertip_radius = 0.0;
  if (!chain.validate().ok()) return 1;

  // q = (0, pi/2): the second link points along +y, so the tip is at (0.05, 0.04).
  const Chain::JointVector q(0.0, 1.5707963267948966);
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  const inhand::Vector<double, 2> tip = ws.fingertip.position;
  int failures = 0;
  if ((tip - inhand::Vector<double, 2>(0.05, 0.04)).norm() > 1e-12) ++failures;

  // J = [z x (tip - o0), z x (tip - o1)] = [(-0.04, 0.05), (-0.04, 0)].
  Chain::Jacobian J;
  inhand::point_jacobian(ws, tip, J);
  // Solving J theta_dot = (0.01, 0.02) by hand: theta_dot = (0.4, -0.65) rad/s.
  inhand::ContactIk<double, 2, 2> ik;
  Chain::JointVector theta_dot;
  const inhand::IkReport<double> report =
      ik.solve(J, inhand::Vector<double, 2>(0.01, 0.02), chain.velocity_limits(), theta_dot);
  if (report.status != inhand::IkStatus::ok) ++failures;
  if ((theta_dot - Chain::JointVector(0.4, -0.65)).norm() > 1e-9) ++failures;

  std::printf("add_subdirectory consumer: tip (%.4f, %.4f), theta_dot (%.4f, %.4f): %s\n", tip.x(),
              tip.y(), theta_dot(0), theta_dot(1), failures == 0 ? "ok" : "FAILED");
  return failures == 0 ? 0 : 1;
}
