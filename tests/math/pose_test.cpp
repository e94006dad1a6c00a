// Properties of poses (inhand/math/pose.hpp), planar and spatial, float and double:
// the pose error's zero and sign (integrated as a twist for one second it carries
// the measured pose onto the desired one; as proportional feedback it converges),
// interpolation endpoints and constant angular speed along the geodesic, and
// composition / inverse.
#include "inhand/math/pose.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/test_support.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;

template <typename S, int D>
struct Case {
  using Scalar = S;
  static constexpr int Dim = D;
};

template <typename C>
class PoseTest : public ::testing::Test {
 public:
  using Scalar = typename C::Scalar;
  static constexpr int Dim = C::Dim;
  static constexpr int kRot = inhand::SpatialDim<Dim>::kRot;
  using P = inhand::Pose<Scalar, Dim>;
  using Tw = inhand::Twist<Scalar, Dim>;
  using Vec = inhand::Vector<Scalar, Dim>;
  using Rot = inhand::Rotation<Scalar, Dim>;
  using Ang = inhand::AngularVector<Scalar, Dim>;
  static constexpr double kEps = std::numeric_limits<Scalar>::epsilon();

  static double max_abs_rot(const Rot& a, const Rot& b) {
    return static_cast<double>((a - b).cwiseAbs().maxCoeff());
  }
  static double max_abs_vec(const Vec& a, const Vec& b) {
    return static_cast<double>((a - b).cwiseAbs().maxCoeff());
  }
  /// Geodesic distance (rotation angle) between two rotations.
  static double angle_between(const Rot& a, const Rot& b) {
    return static_cast<double>(inhand::rotation_log<Scalar>(Rot(a * b.transpose())).norm());
  }
  /// A random rotation vector with |w| in [lo, hi].
  static Ang random_rotation_vector(inhand_test::Rng& rng, Scalar lo, Scalar hi) {
    const Scalar angle = inhand_test::uniform<Scalar>(rng, lo, hi);
    if constexpr (Dim == 2) {
      return Ang(inhand_test::uniform<Scalar>(rng, Scalar(0), Scalar(1)) < Scalar(0.5) ? -angle
                                                                                       : angle);
    } else {
      return inhand_test::random_unit_vector<Scalar>(rng) * angle;
    }
  }
  /// `base` moved by at most `max_offset` metres and rotated by at most `max_angle` rad.
  static P perturbed(inhand_test::Rng& rng, const P& base, Scalar max_offset, Scalar max_angle) {
    P out;
    out.position =
        base.position + inhand_test::random_vector<Scalar, Dim>(rng, -max_offset, max_offset);
    out.rotation = inhand::rotation_exp<Scalar>(random_rotation_vector(rng, Scalar(0), max_angle)) *
                   base.rotation;
    return out;
  }
};

using Cases = ::testing::Types<Case<float, 2>, Case<double, 2>, Case<float, 3>, Case<double, 3>>;
struct CaseNames {
  template <typename C>
  static std::string GetName(int) {
    return std::string(C::Dim == 2 ? "planar_" : "spatial_") +
           (std::is_same<typename C::Scalar, float>::value ? "float" : "double");
  }
};
TYPED_TEST_SUITE(PoseTest, Cases, CaseNames);

TYPED_TEST(PoseTest, PoseErrorIsZeroAtEquality) {
  using T = TestFixture;
  auto rng = make_rng(201);
  for (int k = 0; k < scaled(1000); ++k) {
    const typename T::P p = inhand_test::random_pose<typename T::Scalar, T::Dim>(rng);
    const typename T::Tw e = inhand::pose_error(p, p);
    ASSERT_TRUE(e.template head<T::Dim>().isZero(0)) << "position part must be exactly zero";
    ASSERT_LE(static_cast<double>(e.norm()), 8 * T::kEps);
  }
}

// Sign of the error: for a pure translation along +x, or a pure positive rotation,
// the error is that displacement (desired minus measured), not its negative.
TYPED_TEST(PoseTest, PoseErrorPointsFromMeasuredToDesired) {
  using T = TestFixture;
  using S = typename T::Scalar;
  typename T::P measured;
  measured.position.setConstant(S(0.1));
  typename T::P desired = measured;
  desired.position.x() += S(0.01);
  typename T::Tw e = inhand::pose_error(desired, measured);
  EXPECT_NEAR(double(e(0)), 0.01, 4 * T::kEps);
  EXPECT_LE(double(e.template tail<T::Dim + T::kRot - 1>().cwiseAbs().maxCoeff()), 4 * T::kEps);

  // Desired is measured rotated by +0.1 rad about world z.
  typename T::Ang w = T::Ang::Zero();
  w(T::kRot - 1) = S(0.1);
  desired = measured;
  desired.rotation = inhand::rotation_exp<S>(w) * measured.rotation;
  e = inhand::pose_error(desired, measured);
  EXPECT_NEAR(double(e(T::Dim + T::kRot - 1)), 0.1, 8 * T::kEps);
}

// (p_d - p_m ; log(R_d R_m^T)) held as a world twist for one second moves the
// measured pose exactly onto the desired one (integrate() applies exp(w) on the
// left), for small and for large (up to pi - 0.05) errors.
TYPED_TEST(PoseTest, IntegratingTheErrorForOneSecondReachesDesired) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(202);
  const double tol = T::kEps * 64;
  for (int k = 0; k < scaled(2000); ++k) {
    const typename T::P measured = inhand_test::random_pose<S, T::Dim>(rng);
    const bool small = (k % 2 == 0);
    const typename T::P desired = small ? T::perturbed(rng, measured, S(0.01), S(0.1))
                                        : T::perturbed(rng, measured, S(0.2), S(3.09));
    const typename T::Tw e = inhand::pose_error(desired, measured);
    const typename T::P reached = inhand::integrate(measured, e, S(1));
    ASSERT_LE(T::max_abs_vec(reached.position, desired.position), tol);
    ASSERT_LE(T::max_abs_rot(reached.rotation, desired.rotation), tol) << "small " << small;
  }
}

// Proportional feedback twist = gain * pose_error, integrated in small steps,
// must shrink the error like exp(-gain t). With the opposite sign it would grow.
TYPED_TEST(PoseTest, ProportionalFeedbackOnTheErrorConverges) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(203);
  const S gain = S(2), dt = S(0.01);
  const int steps = 500;  // 5 s: exp(-10) ~ 4.5e-5
  for (int trial = 0; trial < scaled(20); ++trial) {
    const typename T::P desired = inhand_test::random_pose<S, T::Dim>(rng);
    typename T::P x = T::perturbed(rng, desired, S(0.05), S(1.0));
    const double e0 = static_cast<double>(inhand::pose_error(desired, x).norm());
    double previous = e0;
    for (int i = 0; i < steps; ++i) {
      x = inhand::integrate(x, typename T::Tw(gain * inhand::pose_error(desired, x)), dt);
      const double now = static_cast<double>(inhand::pose_error(desired, x).norm());
      ASSERT_LT(now, previous + 16 * T::kEps) << "step " << i;
      previous = now;
    }
    EXPECT_LE(previous, 1e-4 * e0 + 1e3 * T::kEps);
  }
}

TYPED_TEST(PoseTest, InterpolateHitsTheEndpoints) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(204);
  for (int k = 0; k < scaled(1000); ++k) {
    const typename T::P a = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::P b = T::perturbed(rng, a, S(0.2), S(3.0));
    const typename T::P at0 = inhand::interpolate(a, b, S(0));
    const typename T::P at1 = inhand::interpolate(a, b, S(1));
    ASSERT_EQ(at0.position, a.position);
    ASSERT_LE(T::max_abs_rot(at0.rotation, a.rotation), 4 * T::kEps);
    ASSERT_LE(T::max_abs_vec(at1.position, b.position), 4 * T::kEps);
    ASSERT_LE(T::max_abs_rot(at1.rotation, b.rotation), 64 * T::kEps);
  }
}

// Along the geodesic the rotation advances by the same world rotation vector in every
// equal step of s: constant angular speed about a fixed axis; the position moves
// linearly. Total angle up to pi - 0.1.
TYPED_TEST(PoseTest, InterpolateHasConstantAngularSpeedAlongTheGeodesic) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(205);
  const int n = 10;
  const double tol = 256 * T::kEps;
  for (int k = 0; k < scaled(300); ++k) {
    const typename T::P a = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::P b = T::perturbed(rng, a, S(0.2), S(3.04));
    const double total = T::angle_between(b.rotation, a.rotation);
    typename T::Ang first_step = T::Ang::Zero();
    typename T::P prev = a;
    for (int i = 1; i <= n; ++i) {
      const typename T::P cur = inhand::interpolate(a, b, S(i) / S(n));
      const typename T::Ang step =
          inhand::rotation_log<S>(typename T::Rot(cur.rotation * prev.rotation.transpose()));
      ASSERT_NEAR(double(step.norm()), total / n, tol) << "step " << i;
      if (i == 1) first_step = step;
      ASSERT_LE(double((step - first_step).cwiseAbs().maxCoeff()), tol) << "step " << i;
      ASSERT_LE(T::max_abs_vec(typename T::Vec(cur.position - prev.position),
                               typename T::Vec((b.position - a.position) / S(n))),
                tol);
      ASSERT_NEAR(T::angle_between(cur.rotation, a.rotation), total * i / n, tol);
      prev = cur;
    }
  }
}

TYPED_TEST(PoseTest, ComposeAndInverse) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(206);
  const double tol = 64 * T::kEps;
  for (int k = 0; k < scaled(1000); ++k) {
    const typename T::P a = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::P b = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::P c = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::Vec x = inhand_test::random_vector<S, T::Dim>(rng, S(-0.3), S(0.3));
    // Composition maps b's frame through a.
    ASSERT_LE(T::max_abs_vec((a * b).transform_point(x), a.transform_point(b.transform_point(x))),
              tol);
    // Inverse undoes the transform, on both sides.
    ASSERT_LE(T::max_abs_vec(a.inverse().transform_point(a.transform_point(x)), x), tol);
    const typename T::P left = a.inverse() * a, right = a * a.inverse();
    for (const typename T::P& id : {left, right}) {
      ASSERT_LE(T::max_abs_vec(id.position, T::Vec::Zero()), tol);
      ASSERT_LE(T::max_abs_rot(id.rotation, T::Rot::Identity()), tol);
    }
    // Associativity and (a b)^-1 = b^-1 a^-1.
    const typename T::P abc1 = (a * b) * c, abc2 = a * (b * c);
    ASSERT_LE(T::max_abs_vec(abc1.position, abc2.position), tol);
    ASSERT_LE(T::max_abs_rot(abc1.rotation, abc2.rotation), tol);
    const typename T::P inv1 = (a * b).inverse(), inv2 = b.inverse() * a.inverse();
    ASSERT_LE(T::max_abs_vec(inv1.position, inv2.position), tol);
    ASSERT_LE(T::max_abs_rot(inv1.rotation, inv2.rotation), tol);
    // The identity is neutral, exactly.
    const typename T::P ai = a * T::P::identity();
    ASSERT_EQ(ai.position, a.position);
    ASSERT_EQ(ai.rotation, a.rotation);
  }
}

TYPED_TEST(PoseTest, IntegrateForwardThenBackwardReturns) {
  using T = TestFixture;
  using S = typename T::Scalar;
  auto rng = make_rng(207);
  for (int k = 0; k < scaled(500); ++k) {
    const typename T::P p = inhand_test::random_pose<S, T::Dim>(rng);
    const typename T::Tw v = inhand_test::random_vector<S, T::Dim + T::kRot>(rng, S(-1), S(1));
    const typename T::P there = inhand::integrate(p, v, S(0.3));
    const typename T::P back = inhand::integrate(there, typename T::Tw(-v), S(0.3));
    ASSERT_LE(T::max_abs_vec(back.position, p.position), 16 * T::kEps);
    ASSERT_LE(T::max_abs_rot(back.rotation, p.rotation), 16 * T::kEps);
    ASSERT_TRUE(there.is_finite());
  }
  typename T::P bad;
  bad.position(0) = std::numeric_limits<S>::quiet_NaN();
  EXPECT_FALSE(bad.is_finite());
}

}  // namespace
