// What one solve of the contact-point IK (controller/ik.hpp) reports: its status flags and
// the figures behind them. Units: m/rad for singular values and damping, m/s for the task
// error; bit i of held_joints is joint i.
#pragma once

#include <cstdint>

#include "inhand/math/flags.hpp"

namespace inhand {

/// Bit flags of an IK solve. `ok` is 0; damped and limited may be combined.
enum class IkStatus : unsigned {
  ok = 0,
  damped = 1u << 0,   ///< sigma_min below the threshold: damped least squares used
  limited = 1u << 1,  ///< joint velocities scaled down to respect their limits
  damped_and_limited = 3u,
  invalid_input = 1u << 2,     ///< non-finite input; output is zero
  position_limited = 1u << 3,  ///< joints held at their position limits (see held_joints)
};
template <>
struct is_flags<IkStatus> : std::true_type {};
inline const char* to_string(IkStatus s) noexcept {
  switch (s) {
    case IkStatus::ok:
      return "ok";
    case IkStatus::damped:
      return "damped";
    case IkStatus::limited:
      return "limited";
    case IkStatus::damped_and_limited:
      return "damped_and_limited";
    case IkStatus::invalid_input:
      return "invalid_input";
    case IkStatus::position_limited:
      return "position_limited";
  }
  switch (static_cast<unsigned>(s)) {
    case 9u:
      return "damped_and_position_limited";
    case 10u:
      return "limited_and_position_limited";
    case 11u:
      return "damped_limited_and_position_limited";
    default:
      return "unknown";
  }
}

template <typename Scalar>
struct IkReport {
  IkStatus status = IkStatus::ok;
  /// sigma_min of J (m/rad) when min_singular_value_exact; otherwise (IkParams::
  /// exact_min_singular_value false and sigma_min certified above the threshold) the
  /// threshold epsilon, a lower bound.
  Scalar min_singular_value = Scalar(0);
  bool min_singular_value_exact = true;
  Scalar damping = Scalar(0);      ///< lambda used (0 when not damped)
  Scalar limit_scale = Scalar(1);  ///< s applied for the velocity limits
  std::uint32_t held_joints = 0;   ///< bit i: joint i held at its position limit (i < 32)
  Scalar task_error = Scalar(0);   ///< |J theta_dot - x_dot| [m/s] of the returned command
};

}  // namespace inhand
