// The shipped hand models (models/urdf/*.urdf) read by inhand::urdf, checked against
// KDL reading the same files through kdl_parser, and against the in-code presets.
//
// Finger specs (name, root link, tip link): tests/common/urdf_hand_models.hpp.
// KDL's chain (tree.getChain(root, tip)) ends at the tip link frame; inhand's fingertip
// frame is that frame moved to the fingertip sphere centre (`sphere` below, in the tip
// link frame). KDL treats mimic joints as independent joints, so the comparison is over
// the full joint vector. Units: metres, radians.
#include <gtest/gtest.h>

#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <kdl/tree.hpp>
#include <kdl_parser/kdl_parser.hpp>
#include <string>
#include <vector>

#include "common/test_support.hpp"
#include "common/urdf_hand_models.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/presets_allegro.hpp"
#include "inhand/sim/presets_coupled.hpp"
#include "inhand/urdf.hpp"

namespace {

using Chain = inhand::FingerChain<double, 3, inhand::Dynamic>;

using HandModel = inhand_test::UrdfHandModel;
using inhand_test::urdf_model_path;

std::vector<HandModel> hand_models() { return inhand_test::urdf_hand_models(); }

Eigen::Vector3d from_kdl(const KDL::Vector& v) { return Eigen::Vector3d(v.x(), v.y(), v.z()); }
Eigen::Matrix3d from_kdl(const KDL::Rotation& R) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) out(r, c) = R(r, c);
  return out;
}

// Fingertip frame (position of the sphere centre, orientation of the tip link) and the
// Jacobian of the sphere centre and of a random point on the sphere, at scaled(1000)
// random configurations per finger within the joint limits. Bound 1e-12 (m, m/rad,
// dimensionless): the hands are within 0.2 m of the palm frame, so ~ 50 ulps.
TEST(UrdfModels, AgreeWithKdlParser) {
  constexpr double kBound = 1e-12;
  auto rng = inhand_test::make_rng(701);
  double worst_fk = 0, worst_jac = 0;
  for (const HandModel& model : hand_models()) {
    SCOPED_TRACE(model.file);
    const auto hand = inhand::urdf::read_fingers_file(urdf_model_path(model.file), model.specs);
    ASSERT_TRUE(hand.ok()) << hand.error;
    KDL::Tree tree;
    ASSERT_TRUE(kdl_parser::treeFromFile(urdf_model_path(model.file), tree));
    for (std::size_t f = 0; f < model.specs.size(); ++f) {
      SCOPED_TRACE(model.specs[f].name);
      const Chain& chain = hand.fingers[f];
      KDL::Chain kdl;
      ASSERT_TRUE(tree.getChain(model.specs[f].root_link, model.specs[f].tip_link, kdl));
      ASSERT_EQ(kdl.getNrOfJoints(), static_cast<unsigned>(chain.dof()));
      KDL::ChainFkSolverPos_recursive fk(kdl);
      KDL::ChainJntToJacSolver jac_solver(kdl);
      KDL::Jacobian jac(kdl.getNrOfJoints());
      KDL::JntArray kq(kdl.getNrOfJoints());
      KDL::Frame tip;
      inhand::FingerKinematics<Chain> ws(chain);
      Chain::Jacobian J(3, chain.dof());
      for (int k = 0; k < inhand_test::scaled(1000); ++k) {
        const Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
        for (int i = 0; i < chain.dof(); ++i) kq(static_cast<unsigned>(i)) = q(i);
        inhand::forward_kinematics(chain, q, ws);
        ASSERT_GE(fk.JntToCart(kq, tip), 0);
        const Eigen::Matrix3d R = from_kdl(tip.M);
        const Eigen::Vector3d centre = from_kdl(tip.p) + R * model.sphere[f];
        const double fk_err = std::max((ws.fingertip.position - centre).cwiseAbs().maxCoeff(),
                                       (ws.fingertip.rotation - R).cwiseAbs().maxCoeff());
        worst_fk = std::max(worst_fk, fk_err);
        ASSERT_LE(fk_err, kBound) << "q " << q.transpose();
        ASSERT_GE(jac_solver.JntToJac(kq, jac), 0);
        const Eigen::Vector3d on_sphere =
            centre + chain.fingertip_radius * inhand_test::random_unit_vector<double>(rng);
        for (const Eigen::Vector3d& p : {centre, on_sphere}) {
          inhand::point_jacobian(ws, p, J);
          KDL::Jacobian moved = jac;
          const Eigen::Vector3d tip_to_p = p - from_kdl(tip.p);
          moved.changeRefPoint(KDL::Vector(tip_to_p.x(), tip_to_p.y(), tip_to_p.z()));
          const double jac_err = (moved.data.topRows(3) - J).cwiseAbs().maxCoeff();
          worst_jac = std::max(worst_jac, jac_err);
          ASSERT_LE(jac_err, kBound) << "q " << q.transpose();
        }
      }
    }
  }
  inhand_test::record("fingertip_frame_max_abs_error", worst_fk);
  inhand_test::record("point_jacobian_max_abs_error", worst_jac);
}

// The URDF versions of the presets have the presets' geometry exactly: bases, joint
// frames, axes, limits, velocity limits, fingertip radius and tip offset (to 1e-15),
// and equal forward kinematics (to 1e-12) at scaled(1000) random configurations per
// finger. The Allegro-like preset writes out its URDF's origins (roll-pitch-yaw through
// urdfdom's quaternion) and takes the reader's default velocity limit (2 rad/s). The
// Shadow-like file is compared with both Shadow-like presets; the coupled one also has
// its mimic joints (leader, ratio, offset).
TEST(UrdfModels, MatchTheInCodePresets) {
  const std::vector<HandModel> models = hand_models();
  const inhand::plant::HandPreset presets[4] = {
      inhand::plant::three_finger_hand(), inhand::plant::shadow_like_hand(),
      inhand::plant::allegro_like_hand(), inhand::plant::shadow_like_coupled_hand()};
  const std::size_t model_of[4] = {0, 1, 2, 1};
  auto rng = inhand_test::make_rng(702);
  for (int m = 0; m < 4; ++m) {
    const HandModel& model = models[model_of[m]];
    const bool with_coupling = m != 1;  // shadow_like_hand() leaves J1 actuated
    const inhand::plant::HandPreset& preset = presets[m];
    SCOPED_TRACE(model.file + " vs " + preset.name);
    const auto hand = inhand::urdf::read_fingers_file(urdf_model_path(model.file), model.specs);
    ASSERT_TRUE(hand.ok()) << hand.error;
    ASSERT_EQ(hand.fingers.size(), preset.fingers.size());
    for (std::size_t f = 0; f < preset.fingers.size(); ++f) {
      SCOPED_TRACE(preset.finger_names[f]);
      EXPECT_EQ(model.specs[f].name, preset.finger_names[f]);
      const Chain& ours = hand.fingers[f];
      const auto& theirs = preset.fingers[f];
      ASSERT_EQ(ours.dof(), theirs.dof());
      constexpr double kExact = 1e-15;
      EXPECT_LE((ours.base.position - theirs.base.position).cwiseAbs().maxCoeff(), kExact);
      EXPECT_LE((ours.base.rotation - theirs.base.rotation).cwiseAbs().maxCoeff(), kExact);
      EXPECT_LE((ours.joint_to_tip.position - theirs.joint_to_tip.position).cwiseAbs().maxCoeff(),
                kExact);
      EXPECT_LE((ours.joint_to_tip.rotation - theirs.joint_to_tip.rotation).cwiseAbs().maxCoeff(),
                kExact);
      EXPECT_EQ(ours.fingertip_radius, theirs.fingertip_radius);
      for (int i = 0; i < ours.dof(); ++i) {
        const auto& a = ours.joints[i];
        const auto& b = theirs.joints[i];
        EXPECT_LE((a.parent_to_joint.position - b.parent_to_joint.position).cwiseAbs().maxCoeff(),
                  kExact)
            << "joint " << i;
        EXPECT_LE((a.parent_to_joint.rotation - b.parent_to_joint.rotation).cwiseAbs().maxCoeff(),
                  kExact)
            << "joint " << i;
        EXPECT_EQ(a.axis, b.axis) << "joint " << i;
        EXPECT_EQ(a.lower, b.lower) << "joint " << i;
        EXPECT_EQ(a.upper, b.upper) << "joint " << i;
        EXPECT_EQ(a.max_velocity, b.max_velocity) << "joint " << i;
        if (with_coupling) {
          EXPECT_EQ(a.coupling.leader, b.coupling.leader) << "joint " << i;
          EXPECT_EQ(a.coupling.ratio, b.coupling.ratio) << "joint " << i;
          EXPECT_EQ(a.coupling.offset, b.coupling.offset) << "joint " << i;
        }
      }
      inhand::FingerKinematics<Chain> ws_ours(ours);
      inhand::FingerKinematics<inhand::plant::PlantFinger> ws_theirs(theirs);
      double worst = 0;
      for (int k = 0; k < inhand_test::scaled(1000); ++k) {
        const Chain::JointVector q = inhand_test::random_joint_angles(ours, rng);
        inhand::forward_kinematics(ours, q, ws_ours);
        inhand::forward_kinematics(theirs, q, ws_theirs);
        worst = std::max(
            {worst,
             (ws_ours.fingertip.position - ws_theirs.fingertip.position).cwiseAbs().maxCoeff(),
             (ws_ours.fingertip.rotation - ws_theirs.fingertip.rotation).cwiseAbs().maxCoeff()});
      }
      EXPECT_LE(worst, 1e-12);
    }
  }
}

// The Shadow-like hand's distal joints J1 follow J2 (ratio 1, offset 0), as on the real
// hand; the thumb and the other joints are actuated. The three-finger hand has no
// coupling.
TEST(UrdfModels, ShadowDistalJointsAreCoupledToTheMiddleJoints) {
  const HandModel model = hand_models()[1];
  const auto hand = inhand::urdf::read_fingers_file(urdf_model_path(model.file), model.specs);
  ASSERT_TRUE(hand.ok()) << hand.error;
  const char* prefixes[3] = {"FF", "MF", "RF"};
  for (int f = 0; f < 3; ++f) {
    const Chain& c = hand.fingers[static_cast<std::size_t>(f)];
    const auto& names = hand.joint_names[static_cast<std::size_t>(f)];
    ASSERT_EQ(c.dof(), 4);
    const std::string p = prefixes[f];
    EXPECT_EQ(names, (std::vector<std::string>{p + "J4", p + "J3", p + "J2", p + "J1"}));
    EXPECT_EQ(c.joints[3].coupling.leader, 2);
    EXPECT_EQ(c.joints[3].coupling.ratio, 1.0);
    EXPECT_EQ(c.joints[3].coupling.offset, 0.0);
    for (int i = 0; i < 3; ++i) EXPECT_FALSE(c.joints[i].coupling.coupled()) << names[i];
    EXPECT_EQ(c.actuated_dof(), 3);
  }
  const Chain& thumb = hand.fingers[3];
  EXPECT_EQ(thumb.actuated_dof(), 5);
  const auto three = inhand::urdf::read_fingers_file(urdf_model_path(hand_models()[0].file),
                                                     hand_models()[0].specs);
  ASSERT_TRUE(three.ok()) << three.error;
  for (const Chain& c : three.fingers) EXPECT_EQ(c.actuated_dof(), c.dof());
}

// The Allegro-like hand: 4 joints per finger, the Allegro's 12 mm fingertip spheres
// (from the tip links' collision spheres), the published joint limits, and the
// reader's default velocity limit (the source URDF writes velocity="0").
TEST(UrdfModels, AllegroLikeHandHasThePublishedJoints) {
  const HandModel model = hand_models()[2];
  inhand::urdf::ReadOptions options;
  options.default_velocity = 2.5;
  const auto hand =
      inhand::urdf::read_fingers_file(urdf_model_path(model.file), model.specs, options);
  ASSERT_TRUE(hand.ok()) << hand.error;
  for (const Chain& c : hand.fingers) {
    ASSERT_EQ(c.dof(), 4);
    EXPECT_EQ(c.fingertip_radius, 0.012);
    for (int i = 0; i < 4; ++i) EXPECT_EQ(c.joints[i].max_velocity, 2.5);
  }
  EXPECT_EQ(hand.fingers[0].joints[0].lower, -0.47);
  EXPECT_EQ(hand.fingers[0].joints[0].upper, 0.47);
  EXPECT_EQ(hand.fingers[3].joints[0].lower, 0.263);
  EXPECT_EQ(hand.fingers[3].joints[0].upper, 1.396);
  EXPECT_EQ(hand.joint_names[3],
            (std::vector<std::string>{"joint_12.0", "joint_13.0", "joint_14.0", "joint_15.0"}));
  // The same hand into a fixed-capacity chain in float.
  using Bounded = inhand::FingerChain<float, 3, inhand::Dynamic, 5>;
  const auto small =
      inhand::urdf::read_fingers_file<Bounded>(urdf_model_path(model.file), model.specs);
  ASSERT_TRUE(small.ok()) << small.error;
  EXPECT_EQ(small.fingers[2].dof(), 4);
  const auto too_small =
      inhand::urdf::read_fingers_file<inhand::FingerChain<double, 3, inhand::Dynamic, 3>>(
          urdf_model_path(model.file), model.specs);
  ASSERT_FALSE(too_small.ok());
  EXPECT_NE(too_small.error.find("link_3.0_tip"), std::string::npos) << too_small.error;
}

// The Allegro-like hand's placement lets every finger touch the paper's cylinder
// (radius 20 mm, along X through the origin) on its side: among 40000 random
// configurations per finger, 0.1 rad inside the joint limits, some put the fingertip
// sphere on the cylinder (+-2 mm) with the contact normal within 20 deg of +Y (fingers)
// or -Y (thumb), |x| <= 45 mm. (With the current placement: >= 179 such samples for each finger.)
TEST(UrdfModels, AllegroLikeHandReachesTheCylinder) {
  const HandModel model = hand_models()[2];
  const auto hand = inhand::urdf::read_fingers_file(urdf_model_path(model.file), model.specs);
  ASSERT_TRUE(hand.ok()) << hand.error;
  auto rng = inhand_test::make_rng(703);
  const double reach = 0.020 + 0.012;
  for (int f = 0; f < 4; ++f) {
    const Chain& c = hand.fingers[static_cast<std::size_t>(f)];
    const double side = f == 3 ? -1.0 : 1.0;
    inhand::FingerKinematics<Chain> ws(c);
    int hits = 0;
    for (int k = 0; k < 40000; ++k) {
      Chain::JointVector q(c.dof());
      for (int i = 0; i < c.dof(); ++i)
        q(i) = inhand_test::uniform<double>(rng, c.joints[i].lower + 0.1, c.joints[i].upper - 0.1);
      inhand::forward_kinematics(c, q, ws);
      const Eigen::Vector3d p = ws.fingertip.position;
      const double r = std::hypot(p.y(), p.z());
      if (std::abs(r - reach) <= 0.002 && std::abs(p.x()) <= 0.045 &&
          side * p.y() / r >= std::cos(20.0 * 3.14159265358979 / 180.0))
        ++hits;
    }
    EXPECT_GT(hits, 0) << model.specs[static_cast<std::size_t>(f)].name;
    inhand_test::record(model.specs[static_cast<std::size_t>(f)].name + "_contact_samples", hits);
  }
}

}  // namespace
