// Properties of the rotation layer (inhand/math/so3.hpp), in float and double:
// exp/log round trips including the small-angle and near-pi branches, the hat
// operator, the Euler convention R = Rz(psi) Ry(theta) Rx(phi) and its rate matrix E
// (checked against central finite differences of the rotation), gimbal-lock
// reporting, and the planar SO(2) functions.
#include "inhand/math/so3.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/test_support.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;

template <typename S>
using Vec3 = inhand::Vector<S, 3>;
template <typename S>
using Mat3 = Eigen::Matrix<S, 3, 3>;

template <typename S>
constexpr S kPi = S(3.14159265358979323846);

template <typename S>
constexpr S eps() {
  return std::numeric_limits<S>::epsilon();
}

template <typename Derived>
double max_abs(const Eigen::MatrixBase<Derived>& m) {
  return static_cast<double>(m.cwiseAbs().maxCoeff());
}

/// Orthonormal with determinant +1, to `tol` per entry.
template <typename S>
::testing::AssertionResult is_rotation(const Mat3<S>& R, double tol) {
  const double ortho = max_abs(Mat3<S>(R.transpose() * R - Mat3<S>::Identity()));
  const double det = std::abs(static_cast<double>(R.determinant()) - 1.0);
  if (ortho <= tol && det <= tol) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure()
         << "|R^T R - I|max = " << ortho << ", |det - 1| = " << det << " (tol " << tol << ")";
}

template <typename S>
class So3Test : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(So3Test, Scalars, inhand_test::ScalarNames);

TYPED_TEST(So3Test, ExpOfZeroAndLogOfIdentityAreExact) {
  using S = TypeParam;
  EXPECT_EQ(inhand::so3_exp<S>(Vec3<S>::Zero()), Mat3<S>::Identity());
  EXPECT_EQ(inhand::so3_log<S>(Mat3<S>::Identity()), Vec3<S>::Zero());
}

// log(exp(w)) == w for |w| < pi, covering both the atan2 branch and the
// symmetric-part branch (angles above ~2.35 rad).
TYPED_TEST(So3Test, LogOfExpRecoversRandomRotationVectors) {
  using S = TypeParam;
  auto rng = make_rng(101);
  const double tol = 32 * eps<S>();  // absolute, |w| <= pi
  double worst = 0;
  for (int k = 0; k < scaled(4000); ++k) {
    const Vec3<S> w = inhand_test::random_unit_vector<S>(rng) *
                      inhand_test::uniform<S>(rng, S(0), kPi<S> - S(1e-2));
    const Mat3<S> R = inhand::so3_exp<S>(w);
    ASSERT_TRUE(is_rotation<S>(R, 8 * eps<S>())) << "w = " << w.transpose();
    const double err = max_abs(Vec3<S>(inhand::so3_log<S>(R) - w));
    worst = std::max(worst, err);
    ASSERT_LE(err, tol) << "w = " << w.transpose();
  }
  inhand_test::record("max_abs_error", worst);
}

TYPED_TEST(So3Test, ExpOfLogRecoversRandomRotations) {
  using S = TypeParam;
  auto rng = make_rng(102);
  for (int k = 0; k < scaled(4000); ++k) {
    const Mat3<S> R = inhand_test::random_rotation<S>(rng);
    const Vec3<S> w = inhand::so3_log<S>(R);
    ASSERT_LE(static_cast<double>(w.norm()), static_cast<double>(kPi<S>) + 4 * eps<S>());
    ASSERT_LE(max_abs(Mat3<S>(inhand::so3_exp<S>(w) - R)), 32 * eps<S>()) << "R =\n" << R;
  }
}

// Angles from 1e-10 to 1e-2 straddle the Taylor-series threshold; the round trip
// must hold to a RELATIVE error of a few ulps, so tiny rotations are not rounded away.
TYPED_TEST(So3Test, RoundTripIsRelativelyAccurateNearZero) {
  using S = TypeParam;
  auto rng = make_rng(103);
  for (int k = 0; k < scaled(2000); ++k) {
    const S angle = inhand_test::log_uniform<S>(rng, S(1e-10), S(1e-2));
    const Vec3<S> w = inhand_test::random_unit_vector<S>(rng) * angle;
    const Mat3<S> R = inhand::so3_exp<S>(w);
    // First-order behaviour: exp(w) = I + [w]x + O(|w|^2).
    ASSERT_LE(max_abs(Mat3<S>(R - Mat3<S>::Identity() - inhand::hat<S>(w))),
              0.5 * double(angle) * double(angle) + 4 * eps<S>());
    const Vec3<S> back = inhand::so3_log<S>(R);
    ASSERT_LE(static_cast<double>((back - w).norm()), 8 * eps<S>() * double(angle))
        << "angle " << angle;
  }
  // The "1e-8" case the controller meets every tick (tiny corrections).
  const Vec3<S> w(S(1e-8), S(-2e-8), S(0.5e-8));
  const Vec3<S> back = inhand::so3_log<S>(inhand::so3_exp<S>(w));
  EXPECT_LE(static_cast<double>((back - w).norm()), 8 * eps<S>() * double(w.norm()));
}

// pi - 1e-6 <= |w| < pi: the antisymmetric part is tiny, the axis comes from the
// symmetric part. exp(log(R)) == R always; in double the sign of the axis is also
// resolved (w itself comes back). In float, rotations within 1e-6 of pi round to
// the same matrices as their antipodes, so only w or -w can be asked for.
TYPED_TEST(So3Test, RoundTripNearPi) {
  using S = TypeParam;
  constexpr bool kDouble = std::is_same<S, double>::value;
  auto rng = make_rng(104);
  double worst = 0;
  for (int k = 0; k < scaled(2000); ++k) {
    const double delta = inhand_test::log_uniform<double>(rng, 1e-10, 1e-6);
    const Vec3<S> axis = inhand_test::random_unit_vector<S>(rng);
    const Vec3<S> w = axis * static_cast<S>(kPi<double> - delta);
    const Mat3<S> R = inhand::so3_exp<S>(w);
    const Vec3<S> back = inhand::so3_log<S>(R);
    ASSERT_LE(static_cast<double>(back.norm()), static_cast<double>(kPi<S>) + 4 * eps<S>());
    ASSERT_LE(max_abs(Mat3<S>(inhand::so3_exp<S>(back) - R)), 16 * eps<S>());
    const double err = kDouble ? max_abs(Vec3<S>(back - w))
                               : std::min(max_abs(Vec3<S>(back - w)), max_abs(Vec3<S>(back + w)));
    worst = std::max(worst, err);
    ASSERT_LE(err, (kDouble ? 32.0 : 16.0) * eps<S>())
        << "delta " << delta << " axis " << axis.transpose();
  }
  inhand_test::record("max_abs_error", worst);
}

// Exactly pi: w and -w are the same rotation; log must return one of them.
TYPED_TEST(So3Test, RotationByExactlyPi) {
  using S = TypeParam;
  auto rng = make_rng(105);
  std::vector<Vec3<S>> axes = {Vec3<S>::UnitX(),
                               Vec3<S>::UnitY(),
                               Vec3<S>::UnitZ(),
                               -Vec3<S>::UnitY(),
                               Vec3<S>(1, 1, 1).normalized(),
                               Vec3<S>(-1, 2, -3).normalized()};
  for (int k = 0; k < scaled(200); ++k) axes.push_back(inhand_test::random_unit_vector<S>(rng));
  for (const Vec3<S>& a : axes) {
    const Vec3<S> w = kPi<S> * a;
    const Mat3<S> R = inhand::so3_exp<S>(w);
    const Vec3<S> back = inhand::so3_log<S>(R);
    EXPECT_NEAR(double(back.norm()), double(kPi<S>), 8 * eps<S>()) << a.transpose();
    EXPECT_LE(std::min(max_abs(Vec3<S>(back - w)), max_abs(Vec3<S>(back + w))), 16 * eps<S>())
        << a.transpose();
    EXPECT_LE(max_abs(Mat3<S>(inhand::so3_exp<S>(back) - R)), 16 * eps<S>()) << a.transpose();
  }
  // Exactly representable half-turns: diag(1, -1, -1) etc.
  for (int i = 0; i < 3; ++i) {
    Mat3<S> R = -Mat3<S>::Identity();
    R(i, i) = S(1);
    const Vec3<S> back = inhand::so3_log<S>(R);
    EXPECT_NEAR(double(std::abs(back(i))), double(kPi<S>), 4 * eps<S>());
    EXPECT_EQ(back.norm(), std::abs(back(i)));
  }
}

TYPED_TEST(So3Test, HatIsTheCrossProductMatrix) {
  using S = TypeParam;
  auto rng = make_rng(106);
  for (int k = 0; k < scaled(500); ++k) {
    const Vec3<S> w = inhand_test::random_vector<S, 3>(rng, S(-2), S(2));
    const Vec3<S> r = inhand_test::random_vector<S, 3>(rng, S(-2), S(2));
    const Mat3<S> W = inhand::hat<S>(w);
    ASSERT_LE(max_abs(Vec3<S>(W * r - w.cross(r))), 16 * eps<S>());
    ASSERT_EQ(W.transpose(), Mat3<S>(-W));  // exactly antisymmetric
    ASSERT_LE(max_abs(Vec3<S>(W * w)), 16 * eps<S>());
    // Equivariance: R [w]x R^T = [R w]x.
    const Mat3<S> R = inhand_test::random_rotation<S>(rng);
    ASSERT_LE(max_abs(Mat3<S>(R * W * R.transpose() - inhand::hat<S>(Vec3<S>(R * w)))),
              32 * eps<S>());
    // exp([w]) is a rotation about w: it leaves w fixed.
    ASSERT_LE(max_abs(Vec3<S>(inhand::so3_exp<S>(w) * w - w)), 32 * eps<S>());
  }
}

TYPED_TEST(So3Test, EulerConventionIsFixedAxesXThenYThenZ) {
  using S = TypeParam;
  auto rng = make_rng(107);
  for (int k = 0; k < scaled(200); ++k) {
    const Vec3<S> rpy = inhand_test::random_vector<S, 3>(rng, S(-3), S(3));
    const Mat3<S> expected = inhand::so3_exp<S>(Vec3<S>(0, 0, rpy.z())) *
                             inhand::so3_exp<S>(Vec3<S>(0, rpy.y(), 0)) *
                             inhand::so3_exp<S>(Vec3<S>(rpy.x(), 0, 0));
    ASSERT_LE(max_abs(Mat3<S>(inhand::rotation_from_euler<S>(rpy) - expected)), 16 * eps<S>());
  }
  // phi alone is a right-handed rotation about world x (the paper's angle alpha):
  // +90 deg carries y onto z.
  const Mat3<S> Rx = inhand::rotation_from_euler<S>(Vec3<S>(kPi<S> / 2, 0, 0));
  EXPECT_LE(max_abs(Vec3<S>(Rx * Vec3<S>::UnitY() - Vec3<S>::UnitZ())), 4 * eps<S>());
}

TYPED_TEST(So3Test, EulerRoundTrip) {
  using S = TypeParam;
  auto rng = make_rng(108);
  // Away from gimbal lock and from the +-pi wrap, the angles themselves come back.
  // The error in phi and psi grows like eps / cos(theta).
  for (int k = 0; k < scaled(3000); ++k) {
    const Vec3<S> rpy(inhand_test::uniform<S>(rng, -kPi<S> + S(1e-2), kPi<S> - S(1e-2)),
                      inhand_test::uniform<S>(rng, -kPi<S> / 2 + S(1e-2), kPi<S> / 2 - S(1e-2)),
                      inhand_test::uniform<S>(rng, -kPi<S> + S(1e-2), kPi<S> - S(1e-2)));
    const Vec3<S> back = inhand::euler_from_rotation<S>(inhand::rotation_from_euler<S>(rpy));
    const double tol = 16 * eps<S>() / std::cos(double(rpy.y()));
    ASSERT_LE(max_abs(Vec3<S>(back - rpy)), tol) << "rpy = " << rpy.transpose();
  }
  // Any rotation: the matrix comes back.
  double worst = 0;
  for (int k = 0; k < scaled(3000); ++k) {
    const Mat3<S> R = inhand_test::random_rotation<S>(rng);
    const Vec3<S> rpy = inhand::euler_from_rotation<S>(R);
    ASSERT_LE(double(std::abs(rpy.y())), double(kPi<S> / 2) + 4 * eps<S>());
    const double err = max_abs(Mat3<S>(inhand::rotation_from_euler<S>(rpy) - R));
    worst = std::max(worst, err);
    ASSERT_LE(err, 32 * eps<S>()) << "theta " << rpy.y();
  }
  inhand_test::record("matrix_round_trip_max_abs_error", worst);
}

// At theta = +-pi/2 only phi -+ psi is observable: phi is reported as 0 and the
// whole rotation about z goes to psi; the matrix must still come back.
TYPED_TEST(So3Test, EulerAtGimbalLock) {
  using S = TypeParam;
  auto rng = make_rng(109);
  for (int k = 0; k < scaled(500); ++k) {
    const S theta = (k % 2 == 0) ? kPi<S> / 2 : -kPi<S> / 2;
    const Vec3<S> rpy(inhand_test::uniform<S>(rng, S(-3), S(3)), theta,
                      inhand_test::uniform<S>(rng, S(-3), S(3)));
    const Mat3<S> R = inhand::rotation_from_euler<S>(rpy);
    const Vec3<S> back = inhand::euler_from_rotation<S>(R);
    ASSERT_EQ(back.x(), S(0)) << rpy.transpose();
    ASSERT_NEAR(double(back.y()), double(theta), 4 * eps<S>());
    ASSERT_LE(max_abs(Mat3<S>(inhand::rotation_from_euler<S>(back) - R)), 32 * eps<S>())
        << rpy.transpose();
  }
  // Just off gimbal lock (1e-15 .. 1e-3 rad) phi and psi are individually
  // ill-conditioned (error ~ eps / cos(theta)), but the returned angles must still
  // reproduce the matrix to a few ulps.
  double worst = 0;
  for (int k = 0; k < scaled(2000); ++k) {
    const double delta = inhand_test::log_uniform<double>(rng, 1e-15, 1e-3);
    const double theta = (k % 2 == 0 ? 1.0 : -1.0) * (kPi<double> / 2 - delta);
    const Vec3<S> rpy(inhand_test::uniform<S>(rng, S(-3), S(3)), static_cast<S>(theta),
                      inhand_test::uniform<S>(rng, S(-3), S(3)));
    const Mat3<S> R = inhand::rotation_from_euler<S>(rpy);
    const double err =
        max_abs(Mat3<S>(inhand::rotation_from_euler<S>(inhand::euler_from_rotation<S>(R)) - R));
    worst = std::max(worst, err);
    // 64 ulps: below cos(theta) = 16 eps the gimbal-lock branch drops cos(theta).
    ASSERT_LE(err, 64 * eps<S>()) << "delta " << delta << " rpy " << rpy.transpose();
  }
  inhand_test::record("near_lock_matrix_round_trip_max_abs_error", worst);
}

// omega = E(rpy) rpy_dot against the central difference
//   omega_fd = log(R(t + h) R(t - h)^T) / (2 h),  R(t) = R(rpy + t rpy_dot),
// whose truncation error is O(h^2). Steps: 1e-5 (double), 3e-3 (float).
TYPED_TEST(So3Test, EulerRateMatrixMatchesFiniteDifferences) {
  using S = TypeParam;
  constexpr bool kDouble = std::is_same<S, double>::value;
  const S h = kDouble ? S(1e-5) : S(3e-3);
  // Relative to |rpy_dot| in [0.5, 2] rad/s: truncation ~ h^2 |rate|^2, rounding
  // ~ few eps / (h |rate|).
  const double tol = kDouble ? 1e-9 : 5e-4;
  auto rng = make_rng(110);
  double worst = 0;
  for (int k = 0; k < scaled(2000); ++k) {
    const Vec3<S> rpy(inhand_test::uniform<S>(rng, -kPi<S>, kPi<S>),
                      inhand_test::uniform<S>(rng, -S(1.5), S(1.5)),
                      inhand_test::uniform<S>(rng, -kPi<S>, kPi<S>));
    const Vec3<S> rate =
        inhand_test::random_unit_vector<S>(rng) * inhand_test::uniform<S>(rng, S(0.5), S(2));
    const Mat3<S> Rp = inhand::rotation_from_euler<S>(Vec3<S>(rpy + h * rate));
    const Mat3<S> Rm = inhand::rotation_from_euler<S>(Vec3<S>(rpy - h * rate));
    const Vec3<S> omega_fd = inhand::so3_log<S>(Mat3<S>(Rp * Rm.transpose())) / (S(2) * h);
    const Vec3<S> omega = inhand::euler_rate_matrix<S>(rpy) * rate;
    const double err = double((omega - omega_fd).norm()) / double(rate.norm());
    worst = std::max(worst, err);
    ASSERT_LE(err, tol) << "rpy " << rpy.transpose() << " rate " << rate.transpose();
  }
  inhand_test::record("max_relative_error", worst);
}

TYPED_TEST(So3Test, EulerRateMatrixTimesInverseIsIdentity) {
  using S = TypeParam;
  auto rng = make_rng(111);
  for (int k = 0; k < scaled(2000); ++k) {
    const Vec3<S> rpy(inhand_test::uniform<S>(rng, -kPi<S>, kPi<S>),
                      inhand_test::uniform<S>(rng, -S(1.5), S(1.5)),
                      inhand_test::uniform<S>(rng, -kPi<S>, kPi<S>));
    const Mat3<S> E = inhand::euler_rate_matrix<S>(rpy);
    Mat3<S> Einv;
    ASSERT_TRUE(inhand::euler_rate_matrix_inverse<S>(rpy, Einv));
    const double tol = 16 * eps<S>() / std::abs(std::cos(double(rpy.y())));
    ASSERT_LE(max_abs(Mat3<S>(E * Einv - Mat3<S>::Identity())), tol) << rpy.transpose();
    ASSERT_LE(max_abs(Mat3<S>(Einv * E - Mat3<S>::Identity())), tol) << rpy.transpose();
    // det E = cos(theta): the singularity is exactly gimbal lock.
    ASSERT_NEAR(double(E.determinant()), std::cos(double(rpy.y())), 8 * eps<S>());
  }
}

TYPED_TEST(So3Test, RateInverseReportsGimbalLockAndLeavesOutputUntouched) {
  using S = TypeParam;
  const Mat3<S> sentinel = Mat3<S>::Constant(S(42));
  for (const S theta : {kPi<S> / 2, -kPi<S> / 2}) {
    Mat3<S> out = sentinel;
    EXPECT_FALSE(inhand::euler_rate_matrix_inverse<S>(Vec3<S>(S(0.3), theta, S(-1.2)), out));
    EXPECT_EQ(out, sentinel);
    // E is singular there.
    EXPECT_LE(std::abs(double(inhand::euler_rate_matrix<S>(Vec3<S>(0, theta, 0)).determinant())),
              4 * eps<S>());
  }
  // A custom margin: |cos(theta)| = 0.05 is refused with min_cos = 0.1, accepted with 0.01.
  const S theta = static_cast<S>(std::acos(0.05));
  Mat3<S> out = sentinel;
  EXPECT_FALSE(inhand::euler_rate_matrix_inverse<S>(Vec3<S>(0, theta, 0), out, S(0.1)));
  EXPECT_EQ(out, sentinel);
  EXPECT_TRUE(inhand::euler_rate_matrix_inverse<S>(Vec3<S>(0, theta, 0), out, S(0.01)));
  EXPECT_TRUE(inhand::euler_rate_matrix_inverse<S>(Vec3<S>(0, -theta, 0), out, S(0.01)));
  // NaN angles are refused too.
  out = sentinel;
  EXPECT_FALSE(inhand::euler_rate_matrix_inverse<S>(
      Vec3<S>(0, std::numeric_limits<S>::quiet_NaN(), 0), out));
  EXPECT_EQ(out, sentinel);
}

// ---------------------------------------------------------------------------
// SO(2)

TYPED_TEST(So3Test, So2ExpLogRoundTripAndWrap) {
  using S = TypeParam;
  auto rng = make_rng(112);
  for (int k = 0; k < scaled(2000); ++k) {
    const S a = inhand_test::uniform<S>(rng, -kPi<S> + S(1e-3), kPi<S> - S(1e-3));
    const inhand::Rotation<S, 2> R = inhand::so2_exp<S>(a);
    ASSERT_LE(
        max_abs(Eigen::Matrix<S, 2, 2>(R.transpose() * R - Eigen::Matrix<S, 2, 2>::Identity())),
        4 * eps<S>());
    ASSERT_NEAR(double(R.determinant()), 1.0, 4 * eps<S>());
    ASSERT_NEAR(double(inhand::so2_log<S>(R)), double(a), 8 * eps<S>());
    // Angles outside (-pi, pi] come back wrapped by a multiple of 2 pi.
    const S wrapped = inhand::so2_log<S>(inhand::so2_exp<S>(a + S(4) * kPi<S>));
    ASSERT_NEAR(double(wrapped), double(a), 64 * eps<S>());
    // Homomorphism: exp(a) exp(b) = exp(a + b).
    const S b = inhand_test::uniform<S>(rng, S(-3), S(3));
    ASSERT_LE(max_abs(Eigen::Matrix<S, 2, 2>(inhand::so2_exp<S>(a) * inhand::so2_exp<S>(b) -
                                             inhand::so2_exp<S>(a + b))),
              8 * eps<S>());
  }
  // Counter-clockwise positive: +90 deg carries x onto y.
  EXPECT_LE(
      max_abs(inhand::Vector<S, 2>(inhand::so2_exp<S>(kPi<S> / 2) * inhand::Vector<S, 2>::UnitX() -
                                   inhand::Vector<S, 2>::UnitY())),
      4 * eps<S>());
  EXPECT_NEAR(std::abs(double(inhand::so2_log<S>(inhand::so2_exp<S>(kPi<S>)))), double(kPi<S>),
              4 * eps<S>());
}

// The planar functions are the z-rotation block of the spatial ones, and the
// dimension-generic wrappers dispatch to them.
TYPED_TEST(So3Test, So2AgreesWithSo3AboutZ) {
  using S = TypeParam;
  auto rng = make_rng(113);
  for (int k = 0; k < scaled(500); ++k) {
    const S a = inhand_test::uniform<S>(rng, S(-3), S(3));
    const Mat3<S> R3 = inhand::so3_exp<S>(Vec3<S>(0, 0, a));
    const inhand::Rotation<S, 2> R2 = inhand::so2_exp<S>(a);
    ASSERT_LE(max_abs(Eigen::Matrix<S, 2, 2>(R3.template topLeftCorner<2, 2>() - R2)),
              8 * eps<S>());
    const inhand::AngularVector<S, 2> w(a);
    ASSERT_EQ(inhand::rotation_exp<S>(w), R2);
    ASSERT_EQ(inhand::rotation_log<S>(R2)(0), inhand::so2_log<S>(R2));
    ASSERT_NEAR(double(inhand::so3_log<S>(R3).z()), double(inhand::so2_log<S>(R2)), 16 * eps<S>());
    const Vec3<S> w3 = inhand_test::random_unit_vector<S>(rng) * a;
    ASSERT_EQ(inhand::rotation_exp<S>(w3), inhand::so3_exp<S>(w3));
  }
}

}  // namespace
