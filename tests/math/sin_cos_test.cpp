// Properties of sin_cos() (math/sin_cos.hpp) in float and double: the stated accuracy
// against std::sin and std::cos (compared in double) over seeded sweeps of angles within a
// few turns, within the whole reduced range and near 0 (relative there); the quadrant
// boundaries k pi/2 and pi/4 either side of them; angles outside the reduced range, NaN
// and the infinities, which follow std::sin and std::cos; every element of arrays of
// lengths 0 to 19 (the vector loop and its remainder); and forward_kinematics against
// forward_kinematics_sincos given the sines and cosines it takes (sin_cos in double).
// The bound asserted is two units in the last place of 1 (eps), the header's one measured
// on x86-64 doubled: a compiler that fuses multiply-adds (-ffp-contract, AArch64) may
// round differently, and may do so differently in the vector loop and for one angle.
// INHAND_TEST_SCALE multiplies the sweeps.
#include "inhand/math/sin_cos.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace {

template <typename S>
class SinCosTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SinCosTest, Scalars, inhand_test::ScalarNames);

template <typename S>
std::string scalar_name() {
  return inhand_test::ScalarNames::GetName<S>(0);
}

template <typename S>
constexpr double kUlpOfOne = static_cast<double>(std::numeric_limits<S>::epsilon());
template <typename S>
constexpr double kBound = 2 * kUlpOfOne<S>;

template <typename S>
constexpr double kRange = static_cast<double>(inhand::detail::SinCosKernel<S>::kReducedRange);

/// The largest absolute error of sin_cos against std::sin / std::cos in double over
/// `count` angles drawn uniformly from [-range, range], taken in S.
template <typename S>
double max_abs_error(double range, int count, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-range, range);
  double worst = 0.0;
  for (int i = 0; i < count; ++i) {
    const S q = static_cast<S>(u(rng));
    S s, c;
    inhand::sin_cos(q, s, c);
    const double qd = static_cast<double>(q);
    worst = std::max(worst, std::abs(static_cast<double>(s) - std::sin(qd)));
    worst = std::max(worst, std::abs(static_cast<double>(c) - std::cos(qd)));
  }
  return worst;
}

TYPED_TEST(SinCosTest, WithinOneUlpOfOneOverJointAngles) {
  using S = TypeParam;
  const double err = max_abs_error<S>(8.0, inhand_test::scaled(200000), 11);
  inhand_test::record(std::string("max_abs_error_8rad_") + scalar_name<S>(), err);
  EXPECT_LE(err, kBound<S>);
}

TYPED_TEST(SinCosTest, WithinOneUlpOfOneOverTheReducedRange) {
  using S = TypeParam;
  const double err = max_abs_error<S>(kRange<S>, inhand_test::scaled(200000), 12);
  inhand_test::record(std::string("max_abs_error_range_") + scalar_name<S>(), err);
  EXPECT_LE(err, kBound<S>);
}

TYPED_TEST(SinCosTest, SineOfASmallAngleKeepsItsRelativeAccuracy) {
  using S = TypeParam;
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> exponent(-30.0, std::log2(0.78));
  double worst = 0.0;
  for (int i = 0; i < inhand_test::scaled(100000); ++i) {
    const S q = static_cast<S>((i % 2 ? 1.0 : -1.0) * std::exp2(exponent(rng)));
    S s, c;
    inhand::sin_cos(q, s, c);
    const double ref = std::sin(static_cast<double>(q));
    worst = std::max(worst, std::abs(static_cast<double>(s) - ref) / std::abs(ref));
  }
  inhand_test::record(std::string("max_rel_error_sin_") + scalar_name<S>(), worst);
  EXPECT_LE(worst, kBound<S>);
  S s, c;
  inhand::sin_cos(S(1e-9), s, c);
  EXPECT_EQ(s, S(1e-9));
  EXPECT_EQ(c, S(1));
}

TYPED_TEST(SinCosTest, QuadrantBoundariesAndTheirNeighbours) {
  using S = TypeParam;
  const double pi = 3.14159265358979323846;
  for (int k = -40; k <= 40; ++k) {
    for (const double offset : {-pi / 4, -1e-6, 0.0, 1e-6, pi / 4}) {
      const S q = static_cast<S>(k * pi / 2 + offset);
      S s, c;
      inhand::sin_cos(q, s, c);
      const double qd = static_cast<double>(q);
      EXPECT_NEAR(static_cast<double>(s), std::sin(qd), kBound<S>) << "q = " << qd;
      EXPECT_NEAR(static_cast<double>(c), std::cos(qd), kBound<S>) << "q = " << qd;
    }
  }
}

TYPED_TEST(SinCosTest, OutsideTheRangeAndNonFiniteFollowTheStandardLibrary) {
  using S = TypeParam;
  const S inf = std::numeric_limits<S>::infinity();
  const S big = static_cast<S>(kRange<S>);
  const std::vector<S> q = {std::nextafter(big, inf),
                            -std::nextafter(big, inf),
                            S(3) * big,
                            S(1e30),
                            -S(1e30),
                            std::numeric_limits<S>::max(),
                            inf,
                            -inf,
                            std::numeric_limits<S>::quiet_NaN(),
                            big,
                            S(0.5)};
  std::vector<S> s(q.size()), c(q.size());
  inhand::sin_cos(q.data(), s.data(), c.data(), static_cast<int>(q.size()));
  for (std::size_t i = 0; i + 2 < q.size(); ++i) {
    if (std::isfinite(q[i])) {
      EXPECT_EQ(s[i], std::sin(q[i])) << "q = " << q[i];
      EXPECT_EQ(c[i], std::cos(q[i])) << "q = " << q[i];
    } else {
      EXPECT_TRUE(std::isnan(s[i]) && std::isnan(c[i])) << "q = " << q[i];
    }
  }
  // The last two are inside the range: the polynomial's values, within the bound.
  for (std::size_t i = q.size() - 2; i < q.size(); ++i) {
    EXPECT_NEAR(static_cast<double>(s[i]), std::sin(static_cast<double>(q[i])), kBound<S>);
    EXPECT_NEAR(static_cast<double>(c[i]), std::cos(static_cast<double>(q[i])), kBound<S>);
  }
}

TYPED_TEST(SinCosTest, EveryElementOfEveryLengthIsComputed) {
  using S = TypeParam;
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> u(-7.0, 7.0);
  for (int n = 0; n < 20; ++n) {
    std::vector<S> q(static_cast<std::size_t>(n) + 1), s(q.size(), S(9)), c(q.size(), S(9));
    for (S& v : q) v = static_cast<S>(u(rng));
    inhand::sin_cos(q.data(), s.data(), c.data(), n);
    for (int i = 0; i < n; ++i) {
      const std::size_t k = static_cast<std::size_t>(i);
      const double qd = static_cast<double>(q[k]);
      EXPECT_NEAR(static_cast<double>(s[k]), std::sin(qd), kBound<S>) << "n " << n << ", i " << i;
      EXPECT_NEAR(static_cast<double>(c[k]), std::cos(qd), kBound<S>) << "n " << n << ", i " << i;
    }
    EXPECT_EQ(s[static_cast<std::size_t>(n)], S(9)) << "written past n = " << n;
    EXPECT_EQ(c[static_cast<std::size_t>(n)], S(9)) << "written past n = " << n;
  }
}

TYPED_TEST(SinCosTest, ForwardKinematicsAgreesWithItsSinCosForm) {
  using S = TypeParam;
  using Chain = inhand::FingerChain<S, 3, inhand::Dynamic, 12>;
  std::mt19937_64 rng(15);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  Chain chain;
  ASSERT_TRUE(chain.joints.resize(11));  // more than one block of eight joints
  for (int i = 0; i < chain.dof(); ++i) {
    auto& j = chain.joints[i];
    j.parent_to_joint.position = inhand::Vector<S, 3>(S(0.01), S(0.002) * S(i), S(0));
    // Coordinate axes of either sign, and a general one.
    j.axis = i % 4 == 3 ? inhand::Vector<S, 3>(S(0.6), S(0), S(0.8))
                        : (i % 2 ? S(-1) : S(1)) * inhand::Vector<S, 3>::Unit(i % 3);
  }
  typename Chain::JointVector q(chain.dof()), sq(chain.dof()), cq(chain.dof());
  inhand::FingerKinematics<Chain> a(chain), b(chain);
  for (int trial = 0; trial < inhand_test::scaled(50); ++trial) {
    for (int i = 0; i < chain.dof(); ++i) q(i) = static_cast<S>(u(rng));
    // forward_kinematics' own choice: sin_cos in double, std::sin / std::cos in float.
    for (int i = 0; i < chain.dof(); ++i) inhand::detail::joint_sin_cos(q(i), sq(i), cq(i));
    inhand::forward_kinematics(chain, q, a);
    inhand::forward_kinematics_sincos(chain, sq, cq, b);
    // Equal on x86-64 (no fused multiply-add); a few eps where a compiler fuses.
    const double tol = 16 * kUlpOfOne<S>;
    EXPECT_LE((a.fingertip.position - b.fingertip.position).norm(), tol * 0.1);  // m
    EXPECT_LE((a.fingertip.rotation - b.fingertip.rotation).norm(), tol);
    EXPECT_LE((a.joint_axes - b.joint_axes).norm(), tol);
    EXPECT_LE((a.joint_origins - b.joint_origins).norm(), tol * 0.1);
  }
}

}  // namespace
