// contact_point_velocity (eq. 2: v_c = v_o + omega_o x (p_c - p_o)) against a
// rigid-body reference: a body whose reference point is at p_o moves with a known
// world twist (v_o ; omega_o); the world position of any point fixed in the body,
// x(t) = R(t) b + p_o(t) with the pose integrated by integrate() (the SO(3)/SO(2)
// exponential of the twist), is differenced centrally over a small step. Planar
// and spatial, float and double.
#include "inhand/kinematics/contact_kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "common/test_support.hpp"
#include "inhand/math/pose.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;

template <typename S, int D>
struct Case {
  using Scalar = S;
  static constexpr int Dim = D;
};

template <typename C>
class ContactKinematicsTest : public ::testing::Test {};

using Cases = ::testing::Types<Case<float, 2>, Case<double, 2>, Case<float, 3>, Case<double, 3>>;
struct CaseNames {
  template <typename C>
  static std::string GetName(int) {
    return std::string(C::Dim == 2 ? "planar_" : "spatial_") +
           (std::is_same<typename C::Scalar, float>::value ? "float" : "double");
  }
};
TYPED_TEST_SUITE(ContactKinematicsTest, Cases, CaseNames);

// Central difference of a body point under the exact rigid motion: the truncation
// error is (1 - sinc(|omega| h)) |omega x r| <= (|omega| h)^2 / 6 |omega| |r| and the
// rounding error ~ eps |x| / h. Steps: 1e-5 s (double), 1e-3 s (float), with
// |v| <= 0.5 m/s, |omega| <= 3 rad/s, |r| <= 0.3 m.
TYPED_TEST(ContactKinematicsTest, MatchesDifferencedRigidBodyMotion) {
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::Dim;
  constexpr int kRot = inhand::SpatialDim<Dim>::kRot;
  constexpr bool kDouble = std::is_same<S, double>::value;
  const S h = kDouble ? S(1e-5) : S(1e-3);
  const double tol = kDouble ? 1e-9 : 2e-4;  // m/s, absolute
  auto rng = make_rng(301);
  double worst = 0;
  for (int k = 0; k < scaled(3000); ++k) {
    const inhand::Pose<S, Dim> body = inhand_test::random_pose<S, Dim>(rng, S(0.2));
    inhand::Twist<S, Dim> twist;
    twist.template head<Dim>() =
        inhand_test::random_unit_vector<S, Dim>(rng) * inhand_test::uniform<S>(rng, S(0), S(0.5));
    if constexpr (Dim == 2) {
      twist(2) = inhand_test::uniform<S>(rng, S(-3), S(3));
    } else {
      twist.template tail<3>() =
          inhand_test::random_unit_vector<S>(rng) * inhand_test::uniform<S>(rng, S(0), S(3));
    }
    // A point fixed in the body, up to 0.3 m from the reference point.
    const inhand::Vector<S, Dim> b =
        inhand_test::random_unit_vector<S, Dim>(rng) * inhand_test::uniform<S>(rng, S(0), S(0.3));
    const inhand::Vector<S, Dim> p_c = body.transform_point(b);

    const inhand::Vector<S, Dim> after = inhand::integrate(body, twist, h).transform_point(b);
    const inhand::Vector<S, Dim> before = inhand::integrate(body, twist, -h).transform_point(b);
    const inhand::Vector<S, Dim> v_fd = (after - before) / (S(2) * h);

    const inhand::Vector<S, Dim> v = inhand::contact_point_velocity(twist, p_c, body.position);
    const double err = static_cast<double>((v - v_fd).norm());
    worst = std::max(worst, err);
    ASSERT_LE(err, tol) << "twist " << twist.transpose() << " r "
                        << (p_c - body.position).transpose() << " (kRot " << kRot << ")";
  }
  inhand_test::record("max_abs_error_m_per_s", worst);
}

// The contact velocity is a property of the body motion, not of the reference
// point chosen to describe it: moving the reference point to p' and the linear
// part to v' = v + omega x (p' - p) must give the same contact velocity.
TYPED_TEST(ContactKinematicsTest, IndependentOfTheReferencePoint) {
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::Dim;
  constexpr int kRot = inhand::SpatialDim<Dim>::kRot;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  auto rng = make_rng(302);
  for (int k = 0; k < scaled(2000); ++k) {
    const inhand::Twist<S, Dim> twist = inhand_test::random_vector<S, Dim + kRot>(rng, S(-2), S(2));
    const inhand::Vector<S, Dim> p = inhand_test::random_vector<S, Dim>(rng, S(-0.2), S(0.2));
    const inhand::Vector<S, Dim> p2 = inhand_test::random_vector<S, Dim>(rng, S(-0.2), S(0.2));
    const inhand::Vector<S, Dim> c = inhand_test::random_vector<S, Dim>(rng, S(-0.2), S(0.2));
    inhand::Twist<S, Dim> moved = twist;
    moved.template head<Dim>() = inhand::contact_point_velocity(twist, p2, p);
    ASSERT_LE(static_cast<double>((inhand::contact_point_velocity(moved, c, p2) -
                                   inhand::contact_point_velocity(twist, c, p))
                                      .cwiseAbs()
                                      .maxCoeff()),
              tol);
    // At the reference point itself the contact moves with v_o, exactly.
    ASSERT_EQ(inhand::contact_point_velocity(twist, p, p), twist.template head<Dim>().eval());
  }
}

// Pure rotation: the contact point moves perpendicular to its offset from the
// reference point (spatial: also perpendicular to omega) with speed |omega| |r_perp|.
TYPED_TEST(ContactKinematicsTest, PureRotationIsTangential) {
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::Dim;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  auto rng = make_rng(303);
  for (int k = 0; k < scaled(1000); ++k) {
    inhand::Twist<S, Dim> twist = inhand::Twist<S, Dim>::Zero();
    twist.template tail<inhand::SpatialDim<Dim>::kRot>() =
        inhand_test::random_vector<S, inhand::SpatialDim<Dim>::kRot>(rng, S(-3), S(3));
    const inhand::Vector<S, Dim> p = inhand_test::random_vector<S, Dim>(rng, S(-0.2), S(0.2));
    const inhand::Vector<S, Dim> r = inhand_test::random_vector<S, Dim>(rng, S(-0.2), S(0.2));
    const inhand::Vector<S, Dim> v =
        inhand::contact_point_velocity(twist, inhand::Vector<S, Dim>(p + r), p);
    ASSERT_LE(std::abs(static_cast<double>(v.dot(r))), tol);
    if constexpr (Dim == 2) {
      ASSERT_NEAR(double(v.norm()), std::abs(double(twist(2))) * double(r.norm()), tol);
      // Counter-clockwise for omega > 0: v = omega * (-r_y, r_x).
      ASSERT_NEAR(double(v.x()), -double(twist(2)) * double(r.y()), tol);
    } else {
      const inhand::Vector<S, 3> w = twist.template tail<3>();
      ASSERT_LE(std::abs(static_cast<double>(v.dot(w))), tol);
      const double r_perp = double((r - r.dot(w) / w.squaredNorm() * w).norm());
      ASSERT_NEAR(double(v.norm()), double(w.norm()) * r_perp, tol);
    }
  }
}

}  // namespace
