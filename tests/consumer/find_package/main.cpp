// Consumer of an installed inhand: version, eq. 2 in space and in the plane, and the
// Euler convention. Returns non-zero on any mismatch.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <inhand/inhand.hpp>

namespace {
int failures = 0;

void check(bool ok, const char* what) {
  if (!ok) {
    std::printf("FAIL: %s\n", what);
    ++failures;
  }
}
}  // namespace

int main() {
  // The installed headers and the installed package version agree.
  check(std::strcmp(inhand::version_string(), INHAND_EXPECTED_VERSION) == 0, "version");

  // Eq. 2, spatial: v_c = v_o + omega x (p_c - p_o) = (0.1, 0, 0) + z x (1, 0, 0).
  inhand::Twist<double, 3> twist;
  twist << 0.1, 0.0, 0.0, 0.0, 0.0, 1.0;
  const inhand::Vector<double, 3> v3 = inhand::contact_point_velocity<double, 3>(
      twist, inhand::Vector<double, 3>(1.5, 0.0, 0.0), inhand::Vector<double, 3>(0.5, 0.0, 0.0));
  check((v3 - inhand::Vector<double, 3>(0.1, 1.0, 0.0)).norm() < 1e-12, "spatial eq. 2");

  // Eq. 2, planar twist (vx, vy, wz): 2 rad/s about +z at offset (0, 1) gives (-2, 0).
  const inhand::Twist<double, 2> planar(0.0, 0.0, 2.0);
  const inhand::Vector<double, 2> v2 = inhand::contact_point_velocity<double, 2>(
      planar, inhand::Vector<double, 2>(0.0, 1.0), inhand::Vector<double, 2>::Zero());
  check((v2 - inhand::Vector<double, 2>(-2.0, 0.0)).norm() < 1e-12, "planar eq. 2");

  // R = Rz(psi) Ry(theta) Rx(phi): a pure roll of 0.3 rad rotates +y towards +z.
  const inhand::Rotation<double, 3> R =
      inhand::rotation_from_euler<double>(inhand::Vector<double, 3>(0.3, 0.0, 0.0));
  const inhand::Vector<double, 3> y = R * inhand::Vector<double, 3>::UnitY();
  check(std::abs(y.z() - std::sin(0.3)) < 1e-12 && std::abs(y.y() - std::cos(0.3)) < 1e-12,
        "roll convention");

  std::printf("find_package consumer: inhand %s, %s\n", inhand::version_string(),
              failures == 0 ? "ok" : "FAILED");
  return failures == 0 ? 0 : 1;
}
