// The plant's sensing noise generator: deterministic from its seed and independent of
// the standard library (own xoshiro256++ generator and Box-Muller transform).
// Dimensionless draws: uniform in (0, 1) and standard normal.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <cstdint>

namespace inhand::plant {

namespace detail {
/// xoshiro256++ with splitmix64 seeding and Box-Muller normals: a fixed, portable
/// sequence for a given seed.
class NoiseSource {
 public:
  explicit NoiseSource(std::uint64_t seed = 1) noexcept { reseed(seed); }
  void reseed(std::uint64_t seed) noexcept {
    std::uint64_t x = seed;
    for (auto& s : s_) {
      x += 0x9E3779B97F4A7C15ull;
      std::uint64_t z = x;
      z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
      z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
      s = z ^ (z >> 31);
    }
    has_spare_ = false;
  }
  std::uint64_t next() noexcept {
    const std::uint64_t result = rotl(s_[0] + s_[3], 23) + s_[0];
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }
  /// Uniform in (0, 1): 53 random bits, offset by half a unit so 0 never occurs.
  double uniform() noexcept { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }
  /// Standard normal.
  double normal() noexcept {
    if (has_spare_) {
      has_spare_ = false;
      return spare_;
    }
    constexpr double kTwoPi = 6.283185307179586476925;
    const double r = std::sqrt(-2.0 * std::log(uniform()));
    const double a = kTwoPi * uniform();
    spare_ = r * std::sin(a);
    has_spare_ = true;
    return r * std::cos(a);
  }
  Eigen::Vector3d normal3() noexcept {
    const double x = normal(), y = normal(), z = normal();
    return Eigen::Vector3d(x, y, z);
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) noexcept { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4] = {0, 0, 0, 0};
  double spare_ = 0.0;
  bool has_spare_ = false;
};
}  // namespace detail

}  // namespace inhand::plant
