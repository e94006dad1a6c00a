// The damping schedule of the damped least-squares inverse (damped_least_squares.hpp):
// lambda^2 = 0 for sigma_min >= epsilon (singular_threshold), and
// lambda^2 = max_damping^2 * (1 - (sigma_min / epsilon)^2) below it, so the damping
// rises continuously from 0 inside the singular region only. Units: sigma and epsilon
// in the Jacobian's units (m/rad for a contact Jacobian), lambda likewise.
#pragma once

#include <cmath>

#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

/// Full names of the DampingSchedule fields, for validate(): string literals such as
/// "ik.damping.max_damping".
struct DampingScheduleNames {
  const char* singular_threshold = "singular_threshold";
  const char* max_damping = "max_damping";
};

template <typename Scalar>
struct DampingSchedule {
  /// Singular-value threshold epsilon (units of J, m/rad for a contact Jacobian), > 0.
  Scalar singular_threshold = Scalar(5e-3);
  /// Damping lambda reached at sigma_min = 0 (same units), >= 0.
  Scalar max_damping = Scalar(5e-3);

  Validation validate(const DampingScheduleNames& names = DampingScheduleNames{}) const noexcept {
    if (!is_finite(singular_threshold) || !(singular_threshold > Scalar(0)))
      return Validation::invalid(names.singular_threshold, "must be finite and > 0");
    if (!is_finite(max_damping) || !(max_damping >= Scalar(0)))
      return Validation::invalid(names.max_damping, "must be finite and >= 0");
    return Validation::valid();
  }
  /// lambda^2 for a given smallest singular value.
  Scalar damping_squared(Scalar sigma_min) const noexcept {
    if (sigma_min >= singular_threshold) return Scalar(0);
    const Scalar r = sigma_min / singular_threshold;
    return max_damping * max_damping * (Scalar(1) - r * r);
  }
  /// sup over sigma >= 0 of sigma / (sigma^2 + lambda^2(sigma)): |x| <= this * |b|.
  /// Infinite when max_damping == 0 (no damping: no bound near singularity).
  Scalar gain_bound() const noexcept {
    const Scalar e = singular_threshold, l = max_damping;
    if (!(l > Scalar(0))) return std::numeric_limits<Scalar>::infinity();
    // For sigma < e: f = sigma / (l^2 + c sigma^2), c = 1 - l^2/e^2.
    const Scalar c = Scalar(1) - (l * l) / (e * e);
    Scalar best = Scalar(1) / e;  // undamped region and the boundary
    if (c > Scalar(0)) {
      const Scalar s_star = l / std::sqrt(c);
      if (s_star < e) best = std::max(best, Scalar(1) / (Scalar(2) * l * std::sqrt(c)));
    }
    return best;
  }
};

}  // namespace inhand
