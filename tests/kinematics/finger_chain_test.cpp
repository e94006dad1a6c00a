// Finger-chain kinematics (inhand/kinematics/finger_chain.hpp) over every chain
// flavour: planar 2- and 3-DOF, spatial 3-, 4- and 5-DOF with exact DOF, and the
// spatial fingers as run-time DOF chains (heap-sized and capacity 5), float and
// double. Checks the contact-point Jacobian against central finite differences of
// forward kinematics at a point fixed on the fingertip sphere, forward kinematics
// against an independent composition of poses, validate(), and
// fingertip_surface_point().
#include "inhand/kinematics/finger_chain.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "common/test_support.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;

template <typename Chain>
class FingerChainTest : public ::testing::Test {};
TYPED_TEST_SUITE(FingerChainTest, inhand_test::AllFingerChains, inhand_test::ChainNames);

template <typename Chain>
using Vec = inhand::Vector<typename Chain::Scalar, Chain::Dim>;

/// World position of a point given in fingertip-frame coordinates, at angles q.
template <typename Chain>
Vec<Chain> attached_point(const Chain& chain, const typename Chain::JointVector& q,
                          const Vec<Chain>& offset, inhand::FingerKinematics<Chain>& ws) {
  inhand::forward_kinematics(chain, q, ws);
  return ws.fingertip.transform_point(offset);
}

TYPED_TEST(FingerChainTest, BuiltInFingersAreValidAndStretchedAtZero) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  ASSERT_FALSE(inhand_test::supported_dofs<Chain>().empty());
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    const Chain chain = inhand_test::make_finger<Chain>(dof);
    ASSERT_EQ(chain.dof(), dof);
    const inhand::Validation v = chain.validate();
    ASSERT_TRUE(v.ok()) << v.field << ": " << v.reason;
    // At q = 0 the joint origins and the tip centre lie on the finger's long axis
    // (+x planar, +z spatial, in the base frame), in order, links of 0-5 cm.
    typename Chain::JointVector q(dof);
    q.setZero();
    inhand::FingerKinematics<Chain> ws(chain);
    inhand::forward_kinematics(chain, q, ws);
    Vec<Chain> dir = Vec<Chain>::Zero();
    dir(Chain::Dim == 2 ? 0 : 2) = S(1);
    dir = chain.base.rotation * dir;
    double along = 0;
    for (int i = 0; i <= dof; ++i) {
      const Vec<Chain> p = i < dof ? Vec<Chain>(ws.joint_origins.col(i)) : ws.fingertip.position;
      const Vec<Chain> r = p - chain.base.position;
      const double d = static_cast<double>(r.dot(dir));
      ASSERT_LE(static_cast<double>((r - S(d) * dir).norm()), tol) << "point " << i;
      ASSERT_GE(d, along - tol);
      ASSERT_LE(d, along + 0.05 + tol);
      along = d;
    }
    ASSERT_GT(along, 0.07);  // total length to the tip centre: 8 to 10.5 cm
  }
}

// FK against an independent evaluation with the Pose API:
// T = base * prod_i (parent_to_joint_i * Rot(axis_i, q_i)) * joint_to_tip.
TYPED_TEST(FingerChainTest, ForwardKinematicsMatchesPoseComposition) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  auto rng = make_rng(401);
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    const Chain chain = inhand_test::make_finger<Chain>(dof);
    inhand::FingerKinematics<Chain> ws(chain);
    for (int k = 0; k < scaled(200); ++k) {
      const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
      inhand::forward_kinematics(chain, q, ws);
      inhand::Pose<S, Dim> T = chain.base;
      for (int i = 0; i < dof; ++i) {
        const auto& j = chain.joints[i];
        T = T * j.parent_to_joint;
        ASSERT_LE(double((ws.joint_origins.col(i) - T.position).cwiseAbs().maxCoeff()), tol);
        inhand::Pose<S, Dim> joint_motion;
        if constexpr (Dim == 3) {
          ASSERT_LE(double((ws.joint_axes.col(i) - T.rotation * j.axis).cwiseAbs().maxCoeff()),
                    tol);
          joint_motion.rotation = Eigen::AngleAxis<S>(q(i), j.axis).toRotationMatrix();
        } else {
          ASSERT_EQ(ws.joint_axes(2, i), j.axis.z());
          joint_motion.rotation = inhand::so2_exp<S>(j.axis.z() * q(i));
        }
        T = T * joint_motion;
      }
      T = T * chain.joint_to_tip;
      ASSERT_LE(double((ws.fingertip.position - T.position).cwiseAbs().maxCoeff()), tol);
      ASSERT_LE(double((ws.fingertip.rotation - T.rotation).cwiseAbs().maxCoeff()), tol);
    }
  }
}

// Point Jacobian against central differences of forward kinematics, at scaled(1000)
// random configurations per finger, at a random point fixed on the fingertip sphere
// (it moves with the distal link). Per-entry bound, relative to the Jacobian's
// Frobenius norm (~0.1 m/rad):
//   double: step 1e-5 rad, truncation ~ h^2/6 * 0.2 m ~ 3e-12, rounding ~ eps 0.2 m / h
//           ~ 2e-12  ->  bound 1e-9;
//   float : step 2e-3 rad, truncation ~ 1.3e-7, rounding ~ 1e-7 m / 4e-3 ~ 3e-5
//           ->  bound 2e-3.
// A wrong lever arm (tip centre instead of the contact point) errs by ~10%.
TYPED_TEST(FingerChainTest, PointJacobianMatchesCentralDifferences) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr bool kDouble = std::is_same<S, double>::value;
  const S h = kDouble ? S(1e-5) : S(2e-3);
  const double bound = kDouble ? 1e-9 : 2e-3;
  auto rng = make_rng(402);
  double worst = 0;
  int checked = 0;
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    const Chain chain = inhand_test::make_finger<Chain>(dof);
    inhand::FingerKinematics<Chain> ws(chain);
    typename Chain::Jacobian J(Chain::Dim, dof), J_fd(Chain::Dim, dof);
    for (int k = 0; k < scaled(1000); ++k) {
      const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
      const Vec<Chain> offset = inhand_test::random_fingertip_offset(chain, rng);
      for (int i = 0; i < dof; ++i) {
        typename Chain::JointVector qp = q, qm = q;
        qp(i) += h;
        qm(i) -= h;
        J_fd.col(i) =
            (attached_point(chain, qp, offset, ws) - attached_point(chain, qm, offset, ws)) /
            (S(2) * h);
      }
      const Vec<Chain> p = attached_point(chain, q, offset, ws);
      J.setConstant(std::numeric_limits<S>::quiet_NaN());
      inhand::point_jacobian(ws, p, J);
      ASSERT_TRUE(inhand::all_finite(J));
      const double err =
          static_cast<double>((J - J_fd).cwiseAbs().maxCoeff()) / static_cast<double>(J.norm());
      worst = std::max(worst, err);
      ++checked;
      ASSERT_LE(err, bound) << "dof " << dof << " q " << q.transpose() << "\nJ\n"
                            << J << "\nfinite differences\n"
                            << J_fd;
    }
  }
  EXPECT_GE(checked, scaled(1000));
  inhand_test::record("max_relative_error", worst);
}

// Contact point on the fingertip sphere for an object whose outward normal at the
// contact is n: it is the point where a sphere object touching the fingertip from
// the -n side meets it, i.e. on both surfaces at once.
TYPED_TEST(FingerChainTest, FingertipSurfacePointTouchesTheObject) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  auto rng = make_rng(403);
  Chain chain = inhand_test::make_finger<Chain>();
  inhand::FingerKinematics<Chain> ws(chain);
  for (int k = 0; k < scaled(500); ++k) {
    inhand::forward_kinematics(chain, inhand_test::random_joint_angles(chain, rng), ws);
    const Vec<Chain> n = inhand_test::random_unit_vector<S, Chain::Dim>(rng);
    const S r = chain.fingertip_radius;
    const S object_radius = inhand_test::uniform<S>(rng, S(0.01), S(0.1));
    const Vec<Chain> object_centre = ws.fingertip.position - (r + object_radius) * n;
    const Vec<Chain> p = inhand::fingertip_surface_point(chain, ws, n);
    ASSERT_NEAR(double((p - ws.fingertip.position).norm()), double(r), tol);
    ASSERT_NEAR(double((p - object_centre).norm()), double(object_radius), tol);
    ASSERT_LE(double(((p - object_centre) / object_radius - n).cwiseAbs().maxCoeff()), 1e3 * tol);
  }
  // A point fingertip (radius 0) touches at its centre.
  chain.fingertip_radius = S(0);
  ASSERT_TRUE(chain.validate().ok());
  const Vec<Chain> n = inhand_test::random_unit_vector<S, Chain::Dim>(rng);
  EXPECT_EQ(inhand::fingertip_surface_point(chain, ws, n), ws.fingertip.position);
}

/// Expects `v` to reject field `field` (at joint `index`, -1 for none) with a reason.
inline ::testing::AssertionResult rejects(const inhand::Validation& v, const char* field,
                                          int index) {
  if (v.ok()) return ::testing::AssertionFailure() << "accepted, expected " << field;
  if (std::strcmp(v.field, field) != 0 || v.index != index || v.reason == nullptr)
    return ::testing::AssertionFailure()
           << "rejected " << v.field << "[" << v.index << "] ("
           << (v.reason ? v.reason : "no reason") << "), expected " << field << "[" << index << "]";
  return ::testing::AssertionSuccess();
}

TYPED_TEST(FingerChainTest, ValidateNamesTheOffendingField) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  const S nan = std::numeric_limits<S>::quiet_NaN();
  const S inf = std::numeric_limits<S>::infinity();
  const Chain good = inhand_test::make_finger<Chain>();
  const int last = good.dof() - 1;
  ASSERT_TRUE(good.validate().ok());

  {  // Non-unit axis (10% too long), zero axis, NaN axis.
    Chain c = good;
    c.joints[last].axis *= S(1.1);
    EXPECT_TRUE(rejects(c.validate(), "joints.axis", last));
    c = good;
    c.joints[0].axis.setZero();
    EXPECT_TRUE(rejects(c.validate(), "joints.axis", 0));
    c = good;
    c.joints[0].axis.x() = nan;
    EXPECT_TRUE(rejects(c.validate(), "joints.axis", 0));
  }
  {  // A unit axis off z: fine in space, rejected in the plane.
    Chain c = good;
    c.joints[last].axis = inhand::Vector<S, 3>(S(0.6), S(0), S(0.8));
    if (Chain::Dim == 2) {
      EXPECT_TRUE(rejects(c.validate(), "joints.axis", last));
      c.joints[last].axis = inhand::Vector<S, 3>::UnitX();
      EXPECT_TRUE(rejects(c.validate(), "joints.axis", last));
    } else {
      EXPECT_TRUE(c.validate().ok());
    }
  }
  {  // Limits out of order or not finite; equal limits are allowed (a locked joint).
    Chain c = good;
    c.joints[last].lower = S(1);
    c.joints[last].upper = S(0.5);
    EXPECT_TRUE(rejects(c.validate(), "joints.lower/upper", last));
    c = good;
    c.joints[0].lower = nan;
    EXPECT_TRUE(rejects(c.validate(), "joints.lower/upper", 0));
    c = good;
    c.joints[0].upper = inf;
    EXPECT_TRUE(rejects(c.validate(), "joints.lower/upper", 0));
    c = good;
    c.joints[0].lower = c.joints[0].upper = S(0.2);
    EXPECT_TRUE(c.validate().ok());
  }
  {  // Speeds must be finite and > 0.
    for (const S bad : {S(0), S(-1), nan, inf}) {
      Chain c = good;
      c.joints[last].max_velocity = bad;
      EXPECT_TRUE(rejects(c.validate(), "joints.max_velocity", last)) << "value " << bad;
    }
  }
  {  // Fingertip radius must be finite and >= 0.
    for (const S bad : {S(-1e-3), nan, inf}) {
      Chain c = good;
      c.fingertip_radius = bad;
      EXPECT_TRUE(rejects(c.validate(), "fingertip_radius", -1)) << "value " << bad;
    }
  }
  {  // Non-finite transforms.
    Chain c = good;
    c.base.position(0) = nan;
    EXPECT_TRUE(rejects(c.validate(), "base", -1));
    c = good;
    c.joint_to_tip.rotation(0, 0) = inf;
    EXPECT_TRUE(rejects(c.validate(), "joint_to_tip", -1));
    c = good;
    c.joints[last].parent_to_joint.position(0) = nan;
    EXPECT_TRUE(rejects(c.validate(), "joints.parent_to_joint", last));
  }
  {  // Joint count: run-time chains may be empty (rejected) and are bounded by their capacity.
    Chain c = good;
    if (Chain::Dof == inhand::Dynamic) {
      ASSERT_TRUE(c.joints.resize(0));
      EXPECT_TRUE(rejects(c.validate(), "joints", -1));
      if (Chain::MaxDof != inhand::Dynamic) {
        EXPECT_FALSE(c.joints.resize(Chain::MaxDof + 1));
      }
    } else {
      EXPECT_FALSE(c.joints.resize(Chain::Dof + 1));
      EXPECT_TRUE(c.joints.resize(Chain::Dof));
    }
  }
}

}  // namespace
