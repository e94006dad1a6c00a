// Reachability of the hand presets: every fingertip reaches its nominal contact on the
// paper's cylinder and slender box at the nominal object pose and with the object
// moved +-5 mm along X, Y, Z or turned +-0.2 rad about X, Y, Z, with margin from the
// joint limits and from singular configurations. Position IK iterates ContactIk (the
// library's eq. 3 solver) with small steps towards the fingertip-centre target.
#include "inhand/sim/presets.hpp"

#include <gtest/gtest.h>

#include <cstdio>

#include "inhand/controller/ik.hpp"
#include "inhand/sim/presets_allegro.hpp"
#include "inhand/sim/presets_coupled.hpp"

namespace {

using inhand::plant::HandPreset;
using inhand::plant::ObjectDef;
using inhand::plant::PlantFinger;
using Pose3 = inhand::Pose<double, 3>;

struct IkResult {
  PlantFinger::JointVector q;
  double error = 1.0;       // final |tip - target| [m]
  double limit_margin = 0;  // smallest distance of a joint from a limit [rad]
  double sigma_min = 0;     // smallest singular value of the 3 x n tip Jacobian [m/rad]
};

// Smallest signed distance from the object to the finger's link axes (joint origin to
// joint origin, then to the fingertip centre), ignoring points inside the fingertip sphere.
double link_clearance(const PlantFinger& chain, const PlantFinger::JointVector& q,
                      const ObjectDef& object, const Pose3& pose) {
  inhand::FingerKinematics<PlantFinger> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  double best = 1e9;
  const Eigen::Vector3d tip = ws.fingertip.position;
  for (int j = 0; j < chain.dof(); ++j) {
    const Eigen::Vector3d a = ws.joint_origins.col(j);
    const Eigen::Vector3d b =
        j + 1 < chain.dof() ? Eigen::Vector3d(ws.joint_origins.col(j + 1)) : tip;
    for (int s = 0; s <= 20; ++s) {
      const Eigen::Vector3d x = a + (b - a) * (s / 20.0);
      if ((x - tip).norm() < chain.fingertip_radius) continue;
      best = std::min(
          best, object.shape.signed_distance(pose.rotation.transpose() * (x - pose.position)));
    }
  }
  return best;
}

// Iterates q += J^+ (step towards the target) + null-space pull to the grasp posture,
// over the actuated joints: a follower (JointCoupling) moves ratio x its leader, its
// column folded into the leader's (C maps actuated to all joint velocities; C = I for
// an uncoupled finger). sigma_min is that of J C.
IkResult solve_tip_position(const PlantFinger& chain, const PlantFinger::JointVector& start,
                            const PlantFinger::JointVector& preferred,
                            const Eigen::Vector3d& target) {
  const int n = chain.dof(), na = chain.actuated_dof();
  std::vector<int> column(static_cast<std::size_t>(n));  // joint -> actuated index
  std::vector<int> actuated;
  for (int j = 0; j < n; ++j)
    if (!chain.joints[j].coupling.coupled()) {
      column[static_cast<std::size_t>(j)] = static_cast<int>(actuated.size());
      actuated.push_back(j);
    }
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, na);
  for (int j = 0; j < n; ++j) {
    const auto& c = chain.joints[j].coupling;
    if (c.coupled())
      C(j, column[static_cast<std::size_t>(c.leader)]) = c.ratio;
    else
      C(j, column[static_cast<std::size_t>(j)]) = 1.0;
  }
  inhand::ContactIk<double, 3, inhand::Dynamic, 6> ik(na);
  inhand::FingerKinematics<PlantFinger> ws(chain);
  PlantFinger::Jacobian J(3, n), Ja(3, na);
  PlantFinger::JointVector dq(na), unlimited(na), pull(na);
  unlimited.setConstant(1e9);
  IkResult r;
  r.q = start;
  for (int it = 0; it < 3000; ++it) {
    inhand::forward_kinematics(chain, r.q, ws);
    Eigen::Vector3d e = target - ws.fingertip.position;
    if (e.norm() < 1e-7) break;
    if (e.norm() > 1e-3) e *= 1e-3 / e.norm();  // small steps: at most 1 mm
    inhand::point_jacobian(ws, ws.fingertip.position, J);
    Ja = J * C;
    for (int k = 0; k < na; ++k) {
      const int j = actuated[static_cast<std::size_t>(k)];
      pull(k) = 0.05 * (preferred(j) - r.q(j));
    }
    ik.solve(Ja, e, unlimited, pull, dq);
    const PlantFinger::JointVector step = C * dq;
    r.q = (r.q + step).cwiseMax(chain.lower_limits()).cwiseMin(chain.upper_limits());
  }
  inhand::forward_kinematics(chain, r.q, ws);
  r.error = (target - ws.fingertip.position).norm();
  r.limit_margin =
      std::min((r.q - chain.lower_limits()).minCoeff(), (chain.upper_limits() - r.q).minCoeff());
  inhand::point_jacobian(ws, ws.fingertip.position, J);
  const Eigen::MatrixXd Jd = J * C;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(Jd);
  r.sigma_min = svd.singularValues()(2);
  return r;
}

std::vector<std::pair<std::string, Pose3>> offset_poses(const Pose3& nominal) {
  std::vector<std::pair<std::string, Pose3>> out;
  out.emplace_back("nominal", nominal);
  const char* axis_names[3] = {"X", "Y", "Z"};
  for (int a = 0; a < 3; ++a)
    for (double s : {-1.0, 1.0}) {
      Pose3 p = nominal;
      p.position(a) += s * 0.005;
      out.emplace_back(std::string(s > 0 ? "+" : "-") + "5mm " + axis_names[a], p);
      Pose3 r = nominal;
      r.rotation = inhand::so3_exp<double>(Eigen::Vector3d(s * 0.2 * Eigen::Vector3d::Unit(a))) *
                   nominal.rotation;
      out.emplace_back(std::string(s > 0 ? "+" : "-") + "0.2rad " + axis_names[a], r);
    }
  return out;
}

constexpr double kReachTol = 1e-5;           // m
constexpr double kMinLimitMargin = 0.1;      // rad
constexpr double kMinSigma = 0.02;           // m/rad (4x the IK damping threshold)
constexpr double kMinLinkClearance = 0.006;  // m: link axes stay a finger half-width clear

void check_preset(const HandPreset& hand, const ObjectDef& object, const char* object_name) {
  const int nf = static_cast<int>(hand.fingers.size());
  // Contacts as material points of the object, carried along with it.
  std::vector<Eigen::Vector3d> c_obj(nf), n_obj(nf);
  for (int i = 0; i < nf; ++i) {
    const auto c = inhand::plant::nominal_contact(hand, i, object.shape, object.pose);
    ASSERT_TRUE(c.found) << hand.finger_names[i];
    EXPECT_NEAR(c.normal.dot(hand.approach_directions[i]), 1.0, 1e-9);
    c_obj[i] = object.pose.rotation.transpose() * (c.point - object.pose.position);
    n_obj[i] = object.pose.rotation.transpose() * c.normal;
  }
  double worst_margin = 1e9, worst_sigma = 1e9, worst_gap = 1e9, worst_clearance = 1e9;
  for (const auto& [label, pose] : offset_poses(object.pose)) {
    std::vector<Eigen::Vector3d> tips(nf);
    for (int i = 0; i < nf; ++i) {
      const auto& chain = hand.fingers[i];
      tips[i] =
          pose.transform_point(c_obj[i]) + chain.fingertip_radius * (pose.rotation * n_obj[i]);
      const IkResult r = solve_tip_position(chain, hand.grasp_configuration[i],
                                            hand.grasp_configuration[i], tips[i]);
      EXPECT_LT(r.error, kReachTol)
          << hand.name << " " << object_name << " " << label << " " << hand.finger_names[i];
      EXPECT_GT(r.limit_margin, kMinLimitMargin)
          << hand.name << " " << object_name << " " << label << " " << hand.finger_names[i]
          << " q=" << r.q.transpose();
      EXPECT_GT(r.sigma_min, kMinSigma)
          << hand.name << " " << object_name << " " << label << " " << hand.finger_names[i];
      for (int j = 0; j < chain.dof(); ++j) {  // the IK keeps followers on their leaders
        const auto& c = chain.joints[j].coupling;
        if (c.coupled()) {
          EXPECT_NEAR(r.q(j), c.ratio * r.q(c.leader) + c.offset, 1e-12);
        }
      }
      const double clearance = link_clearance(chain, r.q, object, pose);
      EXPECT_GT(clearance, kMinLinkClearance)
          << hand.name << " " << object_name << " " << label << " " << hand.finger_names[i];
      worst_clearance = std::min(worst_clearance, clearance);
      worst_margin = std::min(worst_margin, r.limit_margin);
      worst_sigma = std::min(worst_sigma, r.sigma_min);
    }
    // Fingertip spheres must not overlap one another.
    for (int i = 0; i < nf; ++i)
      for (int j = i + 1; j < nf; ++j) {
        const double gap = (tips[i] - tips[j]).norm() - hand.fingers[i].fingertip_radius -
                           hand.fingers[j].fingertip_radius;
        worst_gap = std::min(worst_gap, gap);
        EXPECT_GT(gap, 0.5e-3) << hand.name << " " << object_name << " " << label;
      }
  }
  std::printf(
      "%s / %s: worst joint-limit margin %.3f rad, worst sigma_min %.4f m/rad, "
      "closest fingertip gap %.1f mm, link clearance %.1f mm\n",
      hand.name.c_str(), object_name, worst_margin, worst_sigma, worst_gap * 1e3,
      worst_clearance * 1e3);
}

void check_open_configuration(const HandPreset& hand, const ObjectDef& object) {
  for (std::size_t i = 0; i < hand.fingers.size(); ++i) {
    const auto& chain = hand.fingers[i];
    inhand::FingerKinematics<PlantFinger> ws(chain);
    inhand::forward_kinematics(chain, hand.open_configuration[i], ws);
    const Eigen::Vector3d local =
        object.pose.rotation.transpose() * (ws.fingertip.position - object.pose.position);
    const double clearance = object.shape.signed_distance(local) - chain.fingertip_radius;
    EXPECT_GT(clearance, 0.010) << hand.name << " " << hand.finger_names[i];
    EXPECT_LT(clearance, 0.025) << hand.name << " " << hand.finger_names[i];
    EXPECT_TRUE((hand.open_configuration[i].array() >= chain.lower_limits().array()).all());
    EXPECT_TRUE((hand.open_configuration[i].array() <= chain.upper_limits().array()).all());
  }
}

TEST(Presets, ShadowLikeHandIsValidAndConsistent) {
  const HandPreset hand = inhand::plant::shadow_like_hand();
  ASSERT_EQ(hand.fingers.size(), 4u);
  EXPECT_EQ(hand.thumb, 3);
  EXPECT_EQ(hand.fingers[3].dof(), 5);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(hand.fingers[i].dof(), 4);
  for (const auto& f : hand.fingers) EXPECT_TRUE(f.validate().ok());
  for (const auto& [t, f] : hand.opposing_pairs)
    EXPECT_NEAR(hand.approach_directions[t].dot(hand.approach_directions[f]), -1.0, 1e-12);
  const auto obj = inhand::plant::paper_cylinder(hand);
  EXPECT_TRUE(
      inhand::plant::HandPlant::validate(hand.fingers, obj, inhand::plant::default_plant_params())
          .ok());
}

TEST(Presets, ThreeFingerHandIsValidAndConsistent) {
  const HandPreset hand = inhand::plant::three_finger_hand();
  ASSERT_EQ(hand.fingers.size(), 3u);
  for (const auto& f : hand.fingers) EXPECT_EQ(f.dof(), 3);
  for (const auto& [t, f] : hand.opposing_pairs)
    EXPECT_NEAR(hand.approach_directions[t].dot(hand.approach_directions[f]), -1.0, 1e-12);
  const auto obj = inhand::plant::paper_slender_box(hand);
  EXPECT_TRUE(
      inhand::plant::HandPlant::validate(hand.fingers, obj, inhand::plant::default_plant_params())
          .ok());
}

TEST(Presets, AllegroLikeHandIsValidAndConsistent) {
  const HandPreset hand = inhand::plant::allegro_like_hand();
  ASSERT_EQ(hand.fingers.size(), 4u);
  EXPECT_EQ(hand.thumb, 3);
  for (const auto& f : hand.fingers) {
    EXPECT_EQ(f.dof(), 4);
    EXPECT_EQ(f.fingertip_radius, 0.012);
    EXPECT_TRUE(f.validate().ok());
  }
  for (const auto& [t, f] : hand.opposing_pairs)
    EXPECT_NEAR(hand.approach_directions[t].dot(hand.approach_directions[f]), -1.0, 1e-12);
  EXPECT_EQ(hand.opposing_pairs.size(), 3u);
  for (const auto& obj :
       {inhand::plant::paper_cylinder(hand), inhand::plant::paper_slender_box(hand)})
    EXPECT_TRUE(
        inhand::plant::HandPlant::validate(hand.fingers, obj, inhand::plant::default_plant_params())
            .ok());
}

// The coupled Shadow-like hand: the fingers' J1 follows J2 (ratio 1, offset 0), its
// configurations satisfy that, and the plant keeps it: started there, driven by
// commands whose follower part is wrong, the follower stays on its leader.
TEST(Presets, ShadowLikeCoupledHandKeepsItsCoupling) {
  const HandPreset hand = inhand::plant::shadow_like_coupled_hand();
  ASSERT_EQ(hand.fingers.size(), 4u);
  for (int k = 0; k < 3; ++k) {
    const auto& f = hand.fingers[static_cast<std::size_t>(k)];
    EXPECT_EQ(f.joints[3].coupling.leader, 2);
    EXPECT_EQ(f.joints[3].coupling.ratio, 1.0);
    EXPECT_EQ(f.joints[3].coupling.offset, 0.0);
    EXPECT_EQ(f.actuated_dof(), 3);
    EXPECT_EQ(hand.open_configuration[static_cast<std::size_t>(k)](3),
              hand.open_configuration[static_cast<std::size_t>(k)](2));
    EXPECT_EQ(hand.grasp_configuration[static_cast<std::size_t>(k)](3),
              hand.grasp_configuration[static_cast<std::size_t>(k)](2));
  }
  EXPECT_EQ(hand.fingers[3].actuated_dof(), 5);
  inhand::plant::HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand));
  PlantFinger::JointVector q = hand.open_configuration[0];
  q(3) = 0.3;  // inconsistent: the plant puts J1 on J2
  ASSERT_TRUE(plant.set_joint_positions(0, q));
  EXPECT_EQ(plant.joint_positions(0)(3), plant.joint_positions(0)(2));
  PlantFinger::JointVector qd(4);
  qd << 0.0, 0.2, 0.5, -1.0;  // the follower's part is replaced by the leader's
  ASSERT_TRUE(plant.set_joint_velocity_command(0, qd));
  for (int s = 0; s < 500; ++s) plant.step_once();
  EXPECT_EQ(plant.joint_positions(0)(3), plant.joint_positions(0)(2));
  EXPECT_EQ(plant.joint_velocities(0)(3), plant.joint_velocities(0)(2));
  EXPECT_GT(plant.joint_positions(0)(2), hand.open_configuration[0](2) + 0.01);  // it moved
}

// The hands added after the first two, both objects in one test each.
class LaterPresets : public ::testing::TestWithParam<HandPreset (*)()> {};
TEST_P(LaterPresets, ReachBothObjectsUnderOffsets) {
  const HandPreset hand = GetParam()();
  check_preset(hand, inhand::plant::paper_cylinder(hand), "cylinder");
  check_preset(hand, inhand::plant::paper_slender_box(hand), "box");
}
INSTANTIATE_TEST_SUITE_P(Presets, LaterPresets,
                         ::testing::Values(&inhand::plant::allegro_like_hand,
                                           &inhand::plant::shadow_like_coupled_hand));

TEST(Presets, ShadowLikeHandReachesCylinderUnderOffsets) {
  const HandPreset hand = inhand::plant::shadow_like_hand();
  check_preset(hand, inhand::plant::paper_cylinder(hand), "cylinder");
}
TEST(Presets, ShadowLikeHandReachesBoxUnderOffsets) {
  const HandPreset hand = inhand::plant::shadow_like_hand();
  check_preset(hand, inhand::plant::paper_slender_box(hand), "box");
}
TEST(Presets, ThreeFingerHandReachesCylinderUnderOffsets) {
  const HandPreset hand = inhand::plant::three_finger_hand();
  check_preset(hand, inhand::plant::paper_cylinder(hand), "cylinder");
}
TEST(Presets, ThreeFingerHandReachesBoxUnderOffsets) {
  const HandPreset hand = inhand::plant::three_finger_hand();
  check_preset(hand, inhand::plant::paper_slender_box(hand), "box");
}

TEST(Presets, OpenConfigurationsClearTheObjects) {
  for (const HandPreset& hand :
       {inhand::plant::shadow_like_hand(), inhand::plant::three_finger_hand(),
        inhand::plant::allegro_like_hand()}) {
    check_open_configuration(hand, inhand::plant::paper_cylinder(hand));
    check_open_configuration(hand, inhand::plant::paper_slender_box(hand));
  }
}

}  // namespace
