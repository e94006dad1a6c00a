// inhand: reactive in-hand manipulation of unknown objects.
// Library version, kept in step with the CMake project version.
#pragma once

#define INHAND_VERSION_MAJOR 0
#define INHAND_VERSION_MINOR 1
#define INHAND_VERSION_PATCH 0

namespace inhand {
/// Version string "major.minor.patch".
inline constexpr const char* version_string() noexcept { return "0.1.0"; }
}  // namespace inhand
