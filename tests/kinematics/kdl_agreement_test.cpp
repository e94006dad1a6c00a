// Agreement with Orocos KDL, an independent kinematics implementation.
//
// Every double-precision test finger (planar fingers embedded in the world x-y
// plane) is translated into a KDL::Chain:
//   segment 0: fixed joint, f_tip = base pose;
//   segment i: KDL::Joint(origin, axis, RotAxis) with origin = parent_to_joint.position
//              and axis = parent_to_joint.rotation * axis (both in the previous
//              segment's tip frame), f_tip = parent_to_joint (the joint frame at
//              q = 0), times joint_to_tip for the last joint.
// A KDL RotAxis joint rotates the segment about the line through `origin` along `axis`,
// so segment i's tip frame is T_{i-1} * parent_to_joint * Rot(axis, q_i), exactly
// inhand's joint frame, and the last tip frame is inhand's fingertip frame.
// KDL's Jacobian is that of the tip frame origin, expressed in the base (world)
// frame; changeRefPoint(p - tip) moves it to the contact point p, whose linear rows
// must equal inhand's point Jacobian.
#include <gtest/gtest.h>

#include <Eigen/SVD>
#include <cmath>
#include <iostream>
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <limits>

#include "common/test_support.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;

/// A planar or spatial pose as a 3-D pose (planar: rotation about z, z = 0).
inline inhand::Pose<double, 3> to_spatial(const inhand::Pose<double, 3>& p) { return p; }
inline inhand::Pose<double, 3> to_spatial(const inhand::Pose<double, 2>& p) {
  inhand::Pose<double, 3> out;
  out.position.head<2>() = p.position;
  out.rotation.topLeftCorner<2, 2>() = p.rotation;
  return out;
}

/// A planar or spatial point as a 3-D point.
inline Eigen::Vector3d to_spatial(const Eigen::Vector3d& p) { return p; }
inline Eigen::Vector3d to_spatial(const Eigen::Vector2d& p) {
  return Eigen::Vector3d(p.x(), p.y(), 0);
}

inline KDL::Vector to_kdl(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }
inline KDL::Frame to_kdl(const inhand::Pose<double, 3>& p) {
  const Eigen::Matrix3d& R = p.rotation;
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0),
                                  R(2, 1), R(2, 2)),
                    to_kdl(p.position));
}
inline Eigen::Vector3d from_kdl(const KDL::Vector& v) {
  return Eigen::Vector3d(v.x(), v.y(), v.z());
}
inline Eigen::Matrix3d from_kdl(const KDL::Rotation& R) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = R(r, c);
  return out;
}

template <typename Chain>
KDL::Chain to_kdl_chain(const Chain& chain) {
  KDL::Chain k;
  k.addSegment(KDL::Segment("base", KDL::Joint(KDL::Joint::None), to_kdl(to_spatial(chain.base))));
  for (int i = 0; i < chain.dof(); ++i) {
    const auto& j = chain.joints[i];
    const inhand::Pose<double, 3> p = to_spatial(j.parent_to_joint);
    const Eigen::Vector3d axis_in_parent = p.rotation * j.axis;
    inhand::Pose<double, 3> tip = p;
    if (i + 1 == chain.dof()) tip = p * to_spatial(chain.joint_to_tip);
    k.addSegment(KDL::Segment("joint" + std::to_string(i),
                              KDL::Joint("joint" + std::to_string(i), to_kdl(p.position),
                                         to_kdl(axis_in_parent), KDL::Joint::RotAxis),
                              to_kdl(tip)));
  }
  return k;
}

template <typename Vec>
KDL::JntArray to_jnt(const Vec& q) {
  KDL::JntArray out(static_cast<unsigned>(q.size()));
  for (int i = 0; i < q.size(); ++i) out(static_cast<unsigned>(i)) = q(i);
  return out;
}

template <typename Chain>
class KdlAgreementTest : public ::testing::Test {};
TYPED_TEST_SUITE(KdlAgreementTest, inhand_test::DoubleFingerChains, inhand_test::ChainNames);

// Fingertip frame and contact-point Jacobian at scaled(1000) random configurations
// per finger, contact point random on the fingertip sphere. Bound: 1e-12 (m, m/rad,
// and dimensionless for the rotation entries); links are <= 0.2 m from the origin,
// so this is ~ 50 ulps.
TYPED_TEST(KdlAgreementTest, FingertipFrameAndContactJacobianMatchKdl) {
  using Chain = TypeParam;
  constexpr int Dim = Chain::Dim;
  constexpr double kBound = 1e-12;
  auto rng = make_rng(501);
  double worst_fk = 0, worst_jac = 0;
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    const Chain chain = inhand_test::make_finger<Chain>(dof);
    const KDL::Chain kdl = to_kdl_chain(chain);
    ASSERT_EQ(kdl.getNrOfJoints(), static_cast<unsigned>(dof));
    KDL::ChainFkSolverPos_recursive fk(kdl);
    KDL::ChainJntToJacSolver jac_solver(kdl);
    inhand::FingerKinematics<Chain> ws(chain);
    typename Chain::Jacobian J(Dim, dof);
    KDL::Jacobian jac(static_cast<unsigned>(dof));
    KDL::Frame tip;
    for (int k = 0; k < scaled(1000); ++k) {
      const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
      const KDL::JntArray kq = to_jnt(q);
      inhand::forward_kinematics(chain, q, ws);
      ASSERT_GE(fk.JntToCart(kq, tip), 0);
      const inhand::Pose<double, 3> ours = to_spatial(ws.fingertip);
      const double fk_err = std::max((ours.position - from_kdl(tip.p)).cwiseAbs().maxCoeff(),
                                     (ours.rotation - from_kdl(tip.M)).cwiseAbs().maxCoeff());
      worst_fk = std::max(worst_fk, fk_err);
      ASSERT_LE(fk_err, kBound) << "dof " << dof << " q " << q.transpose();

      const inhand::Vector<double, Dim> p =
          ws.fingertip.transform_point(inhand_test::random_fingertip_offset(chain, rng));
      inhand::point_jacobian(ws, p, J);
      ASSERT_GE(jac_solver.JntToJac(kq, jac), 0);
      const Eigen::Vector3d tip_to_p = to_spatial(p) - ours.position;
      jac.changeRefPoint(to_kdl(tip_to_p));
      const Eigen::MatrixXd linear = jac.data.topRows(3);
      const double jac_err = (linear.topRows(Dim) - J).cwiseAbs().maxCoeff();
      worst_jac = std::max(worst_jac, jac_err);
      ASSERT_LE(jac_err, kBound) << "dof " << dof << " q " << q.transpose() << "\ninhand\n"
                                 << J << "\nKDL\n"
                                 << linear;
      if constexpr (Dim == 2) {
        // Planar motion: no out-of-plane velocity, no rotation about x or y.
        ASSERT_LE(jac.data.row(2).cwiseAbs().maxCoeff(), kBound);
        ASSERT_LE(jac.data.middleRows(3, 2).cwiseAbs().maxCoeff(), kBound);
      }
    }
  }
  inhand_test::record("fingertip_frame_max_abs_error", worst_fk);
  inhand_test::record("contact_jacobian_max_abs_error", worst_jac);
}

// Square fingers (as many joints as task dimensions: the spatial 3-joint finger as
// exact, heap and capacity-5 run-time DOF chains, the planar 2-joint finger): generate qdot, form
// the full tip twist with KDL's Jacobian, give KDL's pseudo-inverse solver the full twist and
// inhand's ContactIk the linear part (the velocity of the contact point = tip centre). Both must
// return qdot. Configurations with sigma_min < 1.5 x the damping threshold (7.5 mm/rad
// by default; near the stretched singularity, where inhand damps by design) are
// skipped and counted.
// Bound: |qdot_solved - qdot|_inf <= 1e-9 |qdot|_inf (cond(J) <= ~40 here).
template <typename Chain>
class KdlSquareIkTest : public ::testing::Test {};
using SquareChains =
    ::testing::Types<inhand_test::Planar2<double>, inhand_test::Spatial3<double>,
                     inhand_test::SpatialDynamic<double>, inhand_test::SpatialBounded<double>>;
TYPED_TEST_SUITE(KdlSquareIkTest, SquareChains, inhand_test::ChainNames);

TYPED_TEST(KdlSquareIkTest, RecoversJointVelocityLikeKdlPinv) {
  using Chain = TypeParam;
  constexpr int Dim = Chain::Dim;
  const Chain chain = inhand_test::make_finger<Chain>(Dim);
  const KDL::Chain kdl = to_kdl_chain(chain);
  KDL::ChainJntToJacSolver jac_solver(kdl);
  KDL::ChainIkSolverVel_pinv kdl_ik(kdl);
  inhand::ContactIk<double, Dim, Chain::Dof, Chain::MaxDof> ik(Dim);
  inhand::FingerKinematics<Chain> ws(chain);
  typename Chain::Jacobian J(Dim, Dim);
  typename Chain::JointVector limits(Dim), solved(Dim);
  limits.setConstant(std::numeric_limits<double>::infinity());
  KDL::Jacobian jac(static_cast<unsigned>(Dim));
  KDL::JntArray kdl_qdot(static_cast<unsigned>(Dim));

  // 1.5 x the damping threshold: these samples are solved undamped.
  const double min_sigma = 1.5 * ik.params().damping.singular_threshold;
  auto rng = make_rng(502);
  double worst_inhand = 0, worst_kdl = 0, worst_between = 0;
  int solved_count = 0, skipped = 0;
  while (solved_count < scaled(1000)) {
    const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
    const typename Chain::JointVector qdot = inhand_test::random_joint_velocities(chain, rng);
    inhand::forward_kinematics(chain, q, ws);
    inhand::point_jacobian(ws, ws.fingertip.position, J);
    if (Eigen::JacobiSVD<Eigen::MatrixXd>(Eigen::MatrixXd(J)).singularValues().minCoeff() <
        min_sigma) {
      ++skipped;
      ASSERT_LT(skipped, scaled(1000)) << "too many near-singular samples";
      continue;
    }
    const KDL::JntArray kq = to_jnt(q);
    ASSERT_GE(jac_solver.JntToJac(kq, jac), 0);
    Eigen::Matrix<double, 6, 1> twist6 = Eigen::Matrix<double, 6, 1>::Zero();
    for (int i = 0; i < Dim; ++i) twist6 += jac.data.col(i) * qdot(i);
    const KDL::Twist twist(KDL::Vector(twist6(0), twist6(1), twist6(2)),
                           KDL::Vector(twist6(3), twist6(4), twist6(5)));
    ASSERT_EQ(kdl_ik.CartToJnt(kq, twist, kdl_qdot), KDL::SolverI::E_NOERROR);

    const Eigen::Matrix<double, Dim, 1> x_dot = twist6.head<Dim>();
    const inhand::IkReport<double> report = ik.solve(J, x_dot, limits, solved);
    ASSERT_EQ(report.status, inhand::IkStatus::ok) << inhand::to_string(report.status);

    double scale = 0, e_inhand = 0, e_kdl = 0, e_between = 0;
    for (int i = 0; i < Dim; ++i) {
      const double kdl_i = kdl_qdot(static_cast<unsigned>(i));
      scale = std::max(scale, std::abs(qdot(i)));
      e_inhand = std::max(e_inhand, std::abs(solved(i) - qdot(i)));
      e_kdl = std::max(e_kdl, std::abs(kdl_i - qdot(i)));
      e_between = std::max(e_between, std::abs(kdl_i - solved(i)));
    }
    e_inhand /= scale;
    e_kdl /= scale;
    e_between /= scale;
    worst_inhand = std::max(worst_inhand, e_inhand);
    worst_kdl = std::max(worst_kdl, e_kdl);
    worst_between = std::max(worst_between, e_between);
    ASSERT_LE(e_inhand, 1e-9) << "q " << q.transpose();
    ASSERT_LE(e_kdl, 1e-9) << "q " << q.transpose();
    ++solved_count;
  }
  inhand_test::record("inhand_qdot_max_relative_error", worst_inhand);
  inhand_test::record("kdl_qdot_max_relative_error", worst_kdl);
  inhand_test::record("inhand_vs_kdl_max_relative_difference", worst_between);
  inhand_test::record("skipped_near_singular", skipped);
}

// The 4-joint finger fully stretched (q = 0): every column of the contact Jacobian
// is perpendicular to the finger, so motion along the finger is unreachable
// (sigma_min = 0). inhand must damp, stay finite and bounded, produce no motion
// along the finger, and reproduce the reachable component: with the SVD
// J = sum sigma_k u_k v_k^T and damping lambda, J qdot = sum sigma_k^2 /
// (sigma_k^2 + lambda^2) (u_k . x) u_k, which differs from the reachable component
// by at most lambda^2 / (sigma_2^2 + lambda^2) of it (sigma_2 the smallest
// non-zero singular value).
TEST(KdlAgreementSingular, DampedSolveOfStretchedFourJointFinger) {
  using Chain = inhand_test::Spatial4<double>;
  const Chain chain = inhand_test::make_finger<Chain>();
  inhand::FingerKinematics<Chain> ws(chain);
  const Chain::JointVector q = Chain::JointVector::Zero();
  inhand::forward_kinematics(chain, q, ws);
  const Eigen::Vector3d along = (ws.fingertip.position - chain.base.position).normalized();
  const Eigen::Vector3d contact = ws.fingertip.position + chain.fingertip_radius * along;

  // Cross-check that KDL sees the same singular Jacobian.
  const KDL::Chain kdl = to_kdl_chain(chain);
  KDL::ChainJntToJacSolver jac_solver(kdl);
  KDL::Jacobian jac(4);
  ASSERT_GE(jac_solver.JntToJac(to_jnt(q), jac), 0);
  jac.changeRefPoint(to_kdl(Eigen::Vector3d(contact - ws.fingertip.position)));

  Chain::Jacobian J;
  inhand::point_jacobian(ws, contact, J);
  ASSERT_LE((jac.data.topRows(3) - J).cwiseAbs().maxCoeff(), 1e-12);
  ASSERT_LE((along.transpose() * J).cwiseAbs().maxCoeff(), 1e-14);

  const Eigen::JacobiSVD<Eigen::Matrix<double, 3, 4>> svd(J, Eigen::ComputeFullU);
  const Eigen::Vector3d sigma = svd.singularValues();
  ASSERT_LE(sigma(2), 1e-12);
  ASSERT_GT(sigma(1), 0.01);

  inhand::ContactIk<double, 3, 4> ik;
  Chain::JointVector limits = Chain::JointVector::Constant(std::numeric_limits<double>::infinity());
  Chain::JointVector qdot;
  auto rng = make_rng(503);
  double worst = 0, worst_reachable = 0;
  for (int k = 0; k < scaled(200); ++k) {
    const Eigen::Vector3d x = inhand_test::random_unit_vector<double>(rng) *
                              inhand_test::uniform<double>(rng, 0.001, 0.1);
    const inhand::IkReport<double> report = ik.solve(J, x, limits, qdot);
    ASSERT_TRUE(inhand::has(report.status, inhand::IkStatus::damped));
    ASSERT_FALSE(inhand::has(report.status, inhand::IkStatus::invalid_input));
    ASSERT_TRUE(inhand::all_finite(qdot));
    ASSERT_GT(report.damping, 0.0);
    ASSERT_LE(qdot.norm(), ik.gain_bound() * x.norm() * (1 + 1e-12));

    const double l2 = report.damping * report.damping;
    Eigen::Vector3d expected = Eigen::Vector3d::Zero();
    for (int i = 0; i < 3; ++i) {
      const double s2 = sigma(i) * sigma(i);
      expected += s2 / (s2 + l2) * svd.matrixU().col(i).dot(x) * svd.matrixU().col(i);
    }
    const Eigen::Vector3d achieved = J * qdot;
    const double err = (achieved - expected).norm() / x.norm();
    worst = std::max(worst, err);
    ASSERT_LE(err, 1e-9);
    ASSERT_LE(std::abs(achieved.dot(along)), 1e-12 * x.norm());
    const Eigen::Vector3d reachable = x - x.dot(along) * along;
    const double shortfall = (achieved - reachable).norm();
    const double bound = l2 / (sigma(1) * sigma(1) + l2) * reachable.norm();
    worst_reachable = std::max(worst_reachable, shortfall / std::max(reachable.norm(), 1e-300));
    ASSERT_LE(shortfall, bound * (1 + 1e-9) + 1e-15);
  }
  inhand_test::record("damped_vs_svd_prediction_max_relative_error", worst);
  inhand_test::record("reachable_component_max_relative_shortfall", worst_reachable);
  inhand_test::record("sigma_2", sigma(1));
  inhand_test::record("lambda", std::sqrt(ik.params().damping.damping_squared(0.0)));
}

}  // namespace
