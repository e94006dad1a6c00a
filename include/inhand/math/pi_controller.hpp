// Vector PI controller with anti-windup (the g1, g2 of eqs. 4 and 6).
//
//   u = kp * x + ki * I,   I += x * dt   (x is the controller input, any unit)
// Anti-windup, both documented and reported, never silent:
//  - the integral I is limited in Euclidean norm to `integral_limit` (scaled, so
//    its direction is kept);
//  - the output u is limited in norm to `output_limit` (scaled, direction kept); while
//    the output is saturated the integral is not advanced in the direction that
//    deepens saturation (conditional integration), so the integrator stops growing
//    and the output leaves saturation without overshoot once x changes sign.
// A limit of +infinity disables it. reset() zeroes the integral.
#pragma once

#include <cmath>
#include <limits>

#include "inhand/math/flags.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// Full names of the four PiGains fields, for validate(): string literals such as
/// "servo.force.kp", so that the error names the field wherever the gains live.
struct PiGainNames {
  const char* kp = "kp";
  const char* ki = "ki";
  const char* integral_limit = "integral_limit";
  const char* output_limit = "output_limit";
};

template <typename Scalar>
struct PiGains {
  Scalar kp = Scalar(1);
  Scalar ki = Scalar(0);
  /// Bound on the norm of the integral state (unit of x times seconds), > 0.
  Scalar integral_limit = std::numeric_limits<Scalar>::infinity();
  /// Bound on the norm of the output, > 0.
  Scalar output_limit = std::numeric_limits<Scalar>::infinity();

  Validation validate(const PiGainNames& names = PiGainNames{}) const noexcept {
    if (!is_finite(kp) || kp < Scalar(0))
      return Validation::invalid(names.kp, "must be finite and >= 0");
    if (!is_finite(ki) || ki < Scalar(0))
      return Validation::invalid(names.ki, "must be finite and >= 0");
    if (!(integral_limit > Scalar(0)))
      return Validation::invalid(names.integral_limit, "must be > 0");
    if (!(output_limit > Scalar(0))) return Validation::invalid(names.output_limit, "must be > 0");
    return Validation::valid();
  }
};

/// Bit flags describing what the anti-windup did on the last update.
enum class PiStatus : unsigned {
  ok = 0,
  integral_limited = 1u << 0,
  output_limited = 1u << 1,
  integral_limited_and_output_limited = 3u,
  invalid_input = 1u << 2,
};
template <>
struct is_flags<PiStatus> : std::true_type {};

template <typename Scalar, int N>
class PiController {
 public:
  using Vec = Eigen::Matrix<Scalar, N, 1>;

  PiController() noexcept { integral_.setZero(); }
  explicit PiController(const PiGains<Scalar>& gains) noexcept : gains_(gains) {
    integral_.setZero();
  }

  void set_gains(const PiGains<Scalar>& g) noexcept { gains_ = g; }
  const PiGains<Scalar>& gains() const noexcept { return gains_; }
  const Vec& integral() const noexcept { return integral_; }
  void reset() noexcept { integral_.setZero(); }

  /// One step with input x over dt seconds; writes the output to `u`.
  /// Non-finite x or dt <= 0: u = 0, integral frozen, invalid_input.
  PiStatus update(const Vec& x, Scalar dt, Vec& u) noexcept {
    if (!all_finite(x) || !is_finite(dt) || !(dt > Scalar(0))) {
      u.setZero();
      return PiStatus::invalid_input;
    }
    PiStatus status = PiStatus::ok;
    Vec candidate = integral_ + dt * x;
    const Scalar in = candidate.norm();
    if (in > gains_.integral_limit) {
      candidate *= gains_.integral_limit / in;
      status = status | PiStatus::integral_limited;
    }
    u = gains_.kp * x + gains_.ki * candidate;
    const Scalar un = u.norm();
    if (un > gains_.output_limit) {
      status = status | PiStatus::output_limited;
      // Conditional integration: keep the old integral unless the step reduces |u|.
      const Vec u_old = gains_.kp * x + gains_.ki * integral_;
      if (u_old.norm() <= un) candidate = integral_;
      u = gains_.kp * x + gains_.ki * candidate;
      const Scalar n2 = u.norm();
      if (n2 > gains_.output_limit) u *= gains_.output_limit / n2;
    }
    integral_ = candidate;
    return status;
  }

 private:
  PiGains<Scalar> gains_{};
  Vec integral_;
};

}  // namespace inhand
