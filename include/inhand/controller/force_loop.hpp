// One finger's normal-force loop command with its two limits (force_layer.hpp, the loop
// u = (w_c / k) (e + w_i z); docs/force_layer.md, "The loop's limits").
//
// Integral bound: |(w_c / k) w_i z| <= max_integral_velocity, z clamped there
// (integral_limited).
//
// max_force as a bound, not a target. Each loop is a PI whose zero w_i (10 rad/s) lies
// below its crossover w_c (40 rad/s) on a contact that integrates the velocity: from the
// target its closed loop is w_c (s + w_i) / (s^2 + w_c s + w_c w_i), (s + 20)^2 at the
// defaults, and the zero makes a step of the target overshoot by 14 %. A grasp's target
// at max_force (the Shadow-like thumb's 6 N) was so exceeded on every grasp, by 1.2-3 N.
// With `bound` finite the press is at most what a proportional loop on (bound - f_m)
// commands, u <= (w_c / k) (bound - f_m): a first-order approach to the bound at w_c. With
// one tick of command delay it is f_{n+1} = f_n + a (bound - f_{n-1}), a = rho w_c T (rho:
// the true stiffness over k), whose roots z^2 - z + a = 0 are real and positive, so the
// approach monotone, for a <= 1/4: an estimate up to 6 times low at the defaults (w_c T =
// 0.04; 25 times without the delay). A struck contact is not bounded so: an impact's
// spike comes before any command can answer it. While the bound holds the command, the integral is
// set back to what that command implies (back-calculation), z = (bound - f_m - e) / w_i, so nothing
// is stored to push once it lets go. The force layer applies it while the object is held (the
// grasp), where every direction is the loop's own; with the object free the measured force also
// carries the pose loop's rigid share, which a per-finger bound would fight, and the grip's cap
// (targets <= max_force) and the over_max_force status stand instead.
// Units: m/s, N, s, N/m. noexcept, no allocation.
#pragma once

#include <cmath>

namespace inhand {

/// The command of one force loop and which limit acted.
template <typename Scalar>
struct ForceLoopCommand {
  Scalar velocity = Scalar(0);    ///< u [m/s], fingertip velocity into the object along -n
  bool integral_limited = false;  ///< z was clamped to its bound
  bool force_bounded = false;     ///< the press was held to the approach to `bound`
};

/// u = kp (e + w_i z) with kp = w_c / k [m/(N s)], e [N] the loop's error, z [N s] its
/// integral (updated in place: clamped, or set back while the bound holds), w_i [rad/s]
/// the PI zero (0: proportional only), max_integral_velocity [m/s] the integral's bound
/// (0: none), f_m [N] the measured force, bound [N] the force not to be crossed (+inf:
/// none). kp > 0.
template <typename Scalar>
ForceLoopCommand<Scalar> force_loop_command(Scalar kp, Scalar e, Scalar& z, Scalar w_i,
                                            Scalar max_integral_velocity, Scalar f_m,
                                            Scalar bound) noexcept {
  ForceLoopCommand<Scalar> out;
  const Scalar zmax = w_i > Scalar(0) ? max_integral_velocity / (kp * w_i) : Scalar(0);
  if (std::abs(z) > zmax) {
    z = z > Scalar(0) ? zmax : -zmax;
    out.integral_limited = w_i > Scalar(0);
  }
  out.velocity = kp * (e + w_i * z);
  const Scalar approach = kp * (bound - f_m);
  if (out.velocity > approach) {
    out.velocity = approach;
    out.force_bounded = true;
    if (w_i > Scalar(0)) z = (bound - f_m - e) / w_i;
  }
  return out;
}

}  // namespace inhand
