// Validation results shared by every configuration struct.
//
// Configuration is validated once, up front, by a `validate()` call that names the
// offending field (and the finger or joint index where one applies). Per-tick calls
// never throw; they return status enums documented next to them.
#pragma once

namespace inhand {

/// Marker for run-time sized dimensions (finger count, DOF): Eigen's Dynamic.
inline constexpr int Dynamic = -1;

/// Outcome of a configuration check: `ok()` or the first field found invalid.
struct Validation {
  /// Name of the offending field, e.g. "joints[2].max_velocity"; nullptr when valid.
  const char* field = nullptr;
  /// Finger index the field belongs to, or -1.
  int finger = -1;
  /// Joint (or other element) index within the field, or -1.
  int index = -1;
  /// Why the field was rejected, e.g. "must be finite and > 0".
  const char* reason = nullptr;

  constexpr bool ok() const noexcept { return field == nullptr; }
  static constexpr Validation valid() noexcept { return Validation{}; }
  static constexpr Validation invalid(const char* f, const char* why, int idx = -1,
                                      int fng = -1) noexcept {
    return Validation{f, fng, idx, why};
  }
  /// Same failure attributed to a finger.
  constexpr Validation for_finger(int fng) const noexcept {
    return Validation{field, fng, index, reason};
  }
};

}  // namespace inhand
