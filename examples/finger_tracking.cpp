// finger_tracking: one spatial 3-DOF finger slides its contact point around a small
// circle on a flat, springy surface while pressing on it with 1 N.
//
// This is the lowest layer of the method (docs/method.md section 6, Fig. 2 layer 3) run on
// its own, in a purely kinematic loop at 1 kHz for 2 s:
//   1. desired contact velocity v_d = circle feed-forward + tangential position feedback
//   2. HybridServo (eqs. 4-7):  e = g1(v_d) - g2(f_d - f_m) n
//   3. ContactIk (eq. 3):       theta_dot = J_F^+ e, J_F the Jacobian of the contact point
//   4. q += theta_dot * dt      (the "plant" is perfect joint-velocity tracking)
// The surface is the plane z = surface_z with outward normal n = +z (pointing towards
// the fingertip). It is a spring, k = 500 N/m: the measured normal force is
// k * penetration of the fingertip sphere. Units: SI throughout (m, rad, s, N).
//
// What to expect: the force settles at the desired 1 N (2 mm of spring compression) and
// the contact point follows the circle to within a fraction of a millimetre. The
// residual tracking error is mostly rolling: the Jacobian moves the point of the
// fingertip that is in contact NOW, while the contact itself rolls over the fingertip
// as the finger flexes (the R*S_dot term of eq. 1 that the method leaves to feedback).
//
// The program exits with status 0 only if it converged (see the thresholds in main()).
#include <cmath>
#include <cstdio>

#include "inhand/inhand.hpp"

namespace {

using Chain = inhand::FingerChain<double, 3, 3>;
using Vec3 = inhand::Vector<double, 3>;

constexpr double kPi = 3.14159265358979323846;

// A finger shaped like a simple human finger: abduction about the base z axis, then
// two flexion joints about y (a positive angle curls the finger down, towards -z).
Chain make_finger() {
  Chain chain;
  chain.joints[0].axis = Vec3::UnitZ();  // abduction, at the base
  chain.joints[0].lower = -0.6;
  chain.joints[0].upper = 0.6;
  chain.joints[1].axis = Vec3::UnitY();  // proximal flexion, at the base
  chain.joints[1].lower = -0.3;
  chain.joints[1].upper = 1.6;
  chain.joints[2].parent_to_joint.position = Vec3(0.05, 0.0, 0.0);  // 5 cm proximal link
  chain.joints[2].axis = Vec3::UnitY();                             // distal flexion
  chain.joints[2].lower = 0.0;
  chain.joints[2].upper = 1.8;
  chain.joint_to_tip.position = Vec3(0.04, 0.0, 0.0);  // 4 cm distal link to sphere centre
  chain.fingertip_radius = 0.01;
  for (int i = 0; i < 3; ++i) chain.joints[i].max_velocity = 3.0;  // rad/s
  return chain;
}

// Contact model of the flat surface: penetration depth of the sphere and spring force.
struct SpringSurface {
  double height = 0.0;          // z of the undeformed surface [m]
  double stiffness = 500.0;     // [N/m]
  Vec3 normal = Vec3::UnitZ();  // outward normal of the object surface

  // Measured normal force for a fingertip sphere centred at `centre` with radius r.
  double force(const Vec3& centre, double r) const {
    const double penetration = height - (centre.z() - r);
    return penetration > 0.0 ? stiffness * penetration : 0.0;
  }
};

}  // namespace

int main() {
  const Chain chain = make_finger();
  const inhand::Validation valid = chain.validate();
  if (!valid.ok()) {
    std::printf("invalid finger: %s (%s)\n", valid.field, valid.reason);
    return 2;
  }

  // ---- Loop parameters ----------------------------------------------------------
  const double dt = 1e-3;                // 1 kHz servo
  const int steps = 2000;                // 2 s
  const int print_every = 250;           // a table row every 0.25 s
  const double desired_force = 1.0;      // f_d [N]
  const double circle_radius = 0.008;    // [m]
  const double circle_rate = 2.0 * kPi;  // [rad/s]: one lap per second
  const double position_gain = 30.0;     // [1/s], tangential position feedback

  // g1 passes the desired velocity through (kp = 1, ki = 0). g2 is chosen for the
  // spring: with stiffness k the force loop is s^2 + k kp s + k ki = 0, so kp = 0.04
  // (m/s)/N, ki = 0.2 (m/s)/(N s) give s^2 + 20 s + 100: critically damped at 10 rad/s.
  inhand::ServoGains<double> gains;
  gains.motion = {1.0, 0.0};
  gains.force = {0.04, 0.2};
  gains.force.output_limit = 0.05;  // never approach faster than 5 cm/s
  inhand::HybridServo<double, 3> servo(gains);
  inhand::IkParams<double> ik_params;
  ik_params.exact_min_singular_value = true;  // the table prints sigma_min on every row
  inhand::ContactIk<double, 3, 3> ik(3, ik_params);

  // ---- Initial state: fingertip resting on the surface with zero force -----------
  Chain::JointVector q(0.0, 0.5, 0.8);
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  SpringSurface surface;
  surface.height = ws.fingertip.position.z() - chain.fingertip_radius;
  const Vec3 n = surface.normal;
  const Vec3 start = inhand::fingertip_surface_point(chain, ws, n);
  // The circle starts at the initial contact point and runs counter-clockwise about +z.
  const Vec3 centre = start - circle_radius * Vec3::UnitX();
  const Eigen::Matrix3d tangent_projector = Eigen::Matrix3d::Identity() - n * n.transpose();

  Chain::Jacobian J;
  Chain::JointVector theta_dot;
  const Chain::JointVector velocity_limits = chain.velocity_limits();
  inhand::ServoCommand<double, 3> command;

  double sum_sq_error = 0.0, sum_sq_error_late = 0.0, max_error = 0.0;
  int late_samples = 0, damped_ticks = 0, limited_ticks = 0, clamped_ticks = 0;
  double force = 0.0;

  std::printf(
      "finger_tracking: 3-DOF finger, 1 kHz, 2 s; circle r = %.0f mm at 1 Hz; "
      "spring k = %.0f N/m; f_d = %.1f N\n",
      circle_radius * 1e3, surface.stiffness, desired_force);
  std::printf("%6s  %10s  %10s  %10s  %9s  %s\n", "t [s]", "err [mm]", "f_m [N]", "f_d [N]",
              "smin[mm]", "IK status");

  for (int k = 0; k <= steps; ++k) {
    const double t = k * dt;
    // Sense: fingertip frame, contact point, measured normal force.
    inhand::forward_kinematics(chain, q, ws);
    const Vec3 contact = inhand::fingertip_surface_point(chain, ws, n);
    force = surface.force(ws.fingertip.position, chain.fingertip_radius);

    // Reference on the circle, and the tangential part of the position error (the
    // normal coordinate is left to the force loop).
    const Vec3 reference =
        centre + circle_radius * Vec3(std::cos(circle_rate * t), std::sin(circle_rate * t), 0.0);
    const Vec3 reference_velocity =
        circle_radius * circle_rate *
        Vec3(-std::sin(circle_rate * t), std::cos(circle_rate * t), 0.0);
    const Vec3 error = tangent_projector * (reference - contact);
    const double e = error.norm();
    sum_sq_error += e * e;
    max_error = std::max(max_error, e);
    if (t >= 1.0) {
      sum_sq_error_late += e * e;
      ++late_samples;
    }

    // Layer 3: desired contact velocity -> hybrid servo -> contact-point IK.
    const Vec3 desired_velocity = reference_velocity + position_gain * error;
    servo.update(desired_velocity, desired_force, force, n, /*force_active=*/true, dt, command);
    inhand::point_jacobian(ws, contact, J);
    const inhand::IkReport<double> report = ik.solve(J, command.total, velocity_limits, theta_dot);
    if (inhand::has(report.status, inhand::IkStatus::damped)) ++damped_ticks;
    if (inhand::has(report.status, inhand::IkStatus::limited)) ++limited_ticks;

    if (k % print_every == 0) {
      std::printf("%6.2f  %10.4f  %10.4f  %10.4f  %9.2f  %s\n", t, e * 1e3, force, desired_force,
                  report.min_singular_value * 1e3, inhand::to_string(report.status));
    }
    if (k == steps) break;

    // Kinematic plant: the joints follow the commanded velocity exactly.
    q += theta_dot * dt;
    const Chain::JointVector clamped =
        q.cwiseMax(chain.lower_limits()).cwiseMin(chain.upper_limits());
    if (clamped != q) ++clamped_ticks;
    q = clamped;
  }

  const double rms = std::sqrt(sum_sq_error / (steps + 1));
  const double rms_late = std::sqrt(sum_sq_error_late / late_samples);
  const double force_error = std::abs(force - desired_force);
  std::printf("summary: RMS tracking error %.4f mm (t >= 1 s: %.4f mm), max %.4f mm\n", rms * 1e3,
              rms_late * 1e3, max_error * 1e3);
  std::printf("summary: final force %.4f N, final force error %.5f N\n", force, force_error);
  std::printf("summary: IK damped on %d ticks, velocity-limited on %d, joint limits hit on %d\n",
              damped_ticks, limited_ticks, clamped_ticks);

  // Convergence criteria: force within 1 % of f_d at the end, tracking within 0.5 mm RMS.
  const bool converged = force_error < 0.01 && rms_late < 0.5e-3 && clamped_ticks == 0;
  std::printf("result: %s\n", converged ? "converged" : "NOT converged");
  return converged ? 0 : 1;
}
