// HandPlant contacts: sign conventions, Coulomb friction with stiction (hold, creep,
// slide, stick-slip transition, the friction cone) and rolling.
#include <gtest/gtest.h>

#include <random>

#include "inhand/sim/presets.hpp"
#include "sim/test_util.hpp"

namespace {

using inhand::plant::HandPlant;
using inhand::plant::ObjectDef;
using inhand::plant::ObjectShape;
using inhand::plant::PlantFinger;
using inhand::plant::PlantParams;
using plant_test::one;
using plant_test::probe;

constexpr double kTip = 0.01;  // probe fingertip radius [m]

/// Two probes squeezing `o` (centred at the origin) along Y at x = z = 0, each indenting
/// its face by `indent`; their joints swing about Y so the tips move in the X-Z plane.
/// `half_width` is the object's half extent along Y.
std::vector<PlantFinger> pinch(double half_width, double indent) {
  std::vector<PlantFinger> f;
  // +Y probe: arm -0.1 X, so q_dot > 0 moves the tip along +Z (y x -x = +z).
  f.push_back(probe(Eigen::Vector3d(0, half_width + kTip - indent, 0), Eigen::Vector3d::UnitY(),
                    -0.1 * Eigen::Vector3d::UnitX(), kTip));
  // -Y probe: same axis and arm, so q_dot > 0 also moves its tip along +Z.
  f.push_back(probe(Eigen::Vector3d(0, -(half_width + kTip - indent), 0), Eigen::Vector3d::UnitY(),
                    -0.1 * Eigen::Vector3d::UnitX(), kTip));
  return f;
}

ObjectDef box(double hx, double hy, double hz, double mass = 0.05) {
  ObjectDef o;
  o.shape = ObjectShape::box(hx, hy, hz);
  o.mass = mass;
  return o;
}

TEST(HandPlantContact, SignConventionsOfAPressingFingertip) {
  PlantParams p = inhand::plant::default_plant_params();
  p.gravity.setZero();
  const double indent = 0.5e-3;
  HandPlant plant({probe(Eigen::Vector3d(0, 0.01 + kTip - indent, 0), Eigen::Vector3d::UnitY(),
                         -0.1 * Eigen::Vector3d::UnitX(), kTip)},
                  box(0.04, 0.01, 0.01), p);
  const auto& c = plant.contact(0);
  ASSERT_TRUE(c.active);
  EXPECT_NEAR(c.penetration, indent, 1e-15);
  // The object's outward normal at the contact, pointing towards the fingertip.
  EXPECT_LT((c.normal - Eigen::Vector3d::UnitY()).norm(), 1e-15);
  // Spring force at rest, pushing the object away from the fingertip (along -n).
  EXPECT_NEAR(c.normal_force, p.contact.normal_stiffness * indent, 1e-12);
  EXPECT_LT((c.force - Eigen::Vector3d(0, -c.normal_force, 0)).norm(), 1e-15);
  EXPECT_LT((plant.contact_force_sum() - c.force).norm(), 1e-15);
  // Contact point: the middle of the overlap.
  EXPECT_LT((c.point - Eigen::Vector3d(0, 0.01 - indent / 2, 0)).norm(), 1e-15);
  EXPECT_NEAR(plant.elastic_energy(), 0.5 * p.contact.normal_stiffness * indent * indent, 1e-18);
  // Noise-free tactile reading equals the truth.
  plant.sample_sensors();
  const auto t = plant.tactile(0);
  EXPECT_TRUE(t.touching);
  EXPECT_EQ(t.normal_force, c.normal_force);
  EXPECT_EQ(t.contact_point, c.point);
  EXPECT_EQ(t.normal, c.normal);
  // Unbalanced, the object is pushed along -Y.
  plant.step(0.01);
  EXPECT_LT(plant.object_twist()(1), -1e-3);
}

// A 50 g box pinched between two fingertips at 2 N each under gravity, mu = 0.8:
// friction capacity 3.2 N against a 0.49 N weight. After settling it must not creep.
TEST(HandPlantContact, PinchedBoxHoldsUnderGravityWithoutCreep) {
  PlantParams p = inhand::plant::default_plant_params();
  const double indent = 1e-3;  // 2 N at 2000 N/m
  HandPlant plant(pinch(0.01, indent), box(0.04, 0.01, 0.01), p);
  plant.step(0.3);  // settle
  const Eigen::Vector3d settled = plant.object_pose().position;
  const double slip_settled = plant.contact(0).slip_distance + plant.contact(1).slip_distance;
  bool any_sliding = false;
  for (int ms = 0; ms < 1700; ++ms) {
    plant.step(1e-3);
    any_sliding = any_sliding || plant.contact(0).sliding || plant.contact(1).sliding;
  }
  const double creep = (plant.object_pose().position - settled).norm();
  const double sag = -settled.z();
  const double weight = 0.05 * 9.81;
  std::printf("hold: sag %.3e m (elastic bound %.3e m), creep over 1.7 s %.3e m\n", sag,
              weight / (2 * p.contact.tangential_stiffness), creep);
  // Creep bound: 1e-9 m over 1.7 s (stiction holds exactly; only rounding moves it).
  EXPECT_LT(creep, 1e-9);
  EXPECT_FALSE(any_sliding);
  EXPECT_NEAR(plant.contact(0).slip_distance + plant.contact(1).slip_distance, slip_settled, 1e-12);
  // The sag is the elastic bristle deflection m g / (2 k_t), within 1 %.
  EXPECT_NEAR(sag, weight / (2 * p.contact.tangential_stiffness), 0.01 * sag);
  // The friction carries the weight.
  EXPECT_NEAR((plant.contact(0).friction_force + plant.contact(1).friction_force).z(), weight,
              1e-6);
}

// The same pinch with mu = 0.05 (capacity 0.2 N < 0.49 N weight) slides down with the
// Coulomb acceleration a = g - 2 mu f_n / m: the metric of the previous test can fail.
TEST(HandPlantContact, PinchedBoxSlidesWithTooLittleFriction) {
  PlantParams p = inhand::plant::default_plant_params();
  p.contact.friction = 0.05;
  const double indent = 1e-3;
  HandPlant plant(pinch(0.01, indent), box(0.04, 0.01, 0.01), p);
  // Past the elastic pre-sliding transient, measure the acceleration over 30 ms.
  plant.step(0.02);
  const double v1 = plant.object_twist()(2);
  plant.step(0.03);
  const double v2 = plant.object_twist()(2);
  const double fn = p.contact.normal_stiffness * indent;
  const double a = 9.81 - 2 * p.contact.friction * fn / 0.05;
  const double drop = -plant.object_pose().position.z();
  std::printf("slide: acceleration %.4f m/s^2, Coulomb %.4f m/s^2, drop after 50 ms %.2e m\n",
              -(v2 - v1) / 0.03, a, drop);
  EXPECT_NEAR(-(v2 - v1) / 0.03, a, 1e-3 * a);
  EXPECT_GT(drop, 5e-3);
  for (int i = 0; i < 2; ++i) {
    EXPECT_TRUE(plant.contact(i).active);
    EXPECT_TRUE(plant.contact(i).sliding);
    EXPECT_NEAR(plant.contact(i).friction_force.norm(),
                p.contact.friction * plant.contact(i).normal_force, 1e-12);
    EXPECT_NEAR(plant.contact(i).slip_distance, drop, 0.03 * drop);
  }
}

// No gravity; a pinch at 1 N per finger with mu = 0.5 (capacity 1 N) under a
// tangential load along Z: 0.8 N sticks (elastic deflection, no creep), 1.2 N slides
// with the kinetic friction deceleration.
TEST(HandPlantContact, TangentialLoadSticksBelowAndSlidesAboveTheFrictionLimit) {
  PlantParams p = inhand::plant::default_plant_params();
  p.gravity.setZero();
  p.contact.friction = 0.5;
  const double indent = 0.5e-3;  // 1 N
  for (const double load : {0.8, 1.2}) {
    HandPlant plant(pinch(0.01, indent), box(0.01, 0.01, 0.04), p);
    if (load < 1.0) {
      // Ramped over 0.2 s: a step load would overshoot the static deflection.
      for (int ms = 1; ms <= 200; ++ms) {
        plant.set_external_wrench(Eigen::Vector3d(0, 0, load * ms / 200.0),
                                  Eigen::Vector3d::Zero());
        plant.step(1e-3);
      }
      plant.step(0.1);
      const Eigen::Vector3d settled = plant.object_pose().position;
      plant.step(1.0);
      EXPECT_LT((plant.object_pose().position - settled).norm(), 1e-9) << load;
      EXPECT_NEAR(settled.z(), load / (2 * p.contact.tangential_stiffness), 1e-3 * settled.z());
      EXPECT_FALSE(plant.contact(0).sliding);
      EXPECT_LT(plant.contact(0).slip_distance, 1e-12);
    } else {
      plant.set_external_wrench(Eigen::Vector3d(0, 0, load), Eigen::Vector3d::Zero());
      plant.step(0.02);
      const double v1 = plant.object_twist()(2);
      plant.step(0.03);
      const double v2 = plant.object_twist()(2);
      const double a = (load - 2 * 0.5 * 1.0) / 0.05;  // kinetic friction mu f_n per contact
      EXPECT_NEAR((v2 - v1) / 0.03, a, 1e-3 * a);
      EXPECT_TRUE(plant.contact(0).sliding);
      EXPECT_TRUE(plant.contact(1).sliding);
    }
  }
}

// A fingertip pressed at 1 N on a frozen box and dragged along Z at 2 mm/s: the friction
// rises as the bristle spring k_t s (+ c_t v) while sticking, then saturates at mu f_n.
TEST(HandPlantContact, DraggedFingertipShowsStickThenSlip) {
  PlantParams p = inhand::plant::default_plant_params();
  p.contact.friction = 0.5;
  const double indent = 0.5e-3;
  HandPlant plant({probe(Eigen::Vector3d(0, 0.01 + kTip - indent, 0), Eigen::Vector3d::UnitY(),
                         -0.1 * Eigen::Vector3d::UnitX(), kTip)},
                  box(0.01, 0.01, 0.04), p);
  plant.set_frozen(true);
  const double v = 2e-3, arm = 0.1;
  plant.set_joint_velocity_command(0, one(v / arm));
  const double fn = p.contact.normal_stiffness * indent;
  const double limit = p.contact.friction * fn;
  const double stick_travel =
      (limit - p.contact.tangential_damping * v) / p.contact.tangential_stiffness;
  int stick_checks = 0, slip_checks = 0;
  for (int n = 1; n <= 4000; ++n) {
    plant.step_once();
    const auto& c = plant.contact(0);
    const double travel = arm * plant.joint_positions(0)(0);
    // Friction on the object drags it along with the fingertip (+Z), never beyond mu f_n.
    EXPECT_LE(c.friction_force.norm(), p.contact.friction * c.normal_force * (1 + 1e-12));
    if (travel < 0.95 * stick_travel) {
      EXPECT_FALSE(c.sliding) << travel;
      EXPECT_NEAR(c.friction_force.z(),
                  p.contact.tangential_stiffness * travel + p.contact.tangential_damping * v, 2e-3)
          << travel;
      ++stick_checks;
    } else if (travel > 1.05 * stick_travel) {
      EXPECT_TRUE(c.sliding) << travel;
      EXPECT_NEAR(c.friction_force.z(), limit, 1e-3 * limit) << travel;
      ++slip_checks;
    }
  }
  EXPECT_GT(stick_checks, 1000);
  EXPECT_GT(slip_checks, 1000);
  // Slip accumulates the travel beyond the elastic range (arc length, 8 mm total).
  EXPECT_NEAR(plant.contact(0).slip_distance,
              4000 * 1e-4 * v - limit / p.contact.tangential_stiffness, 2e-5);
}

// Two fingertips moving in opposite directions along Z roll a free cylinder (axis X)
// about its axis without slipping: angle = travel / radius to first order in
// travel / radius (1 % here), the centre stays, the contacts move over both surfaces.
TEST(HandPlantContact, OpposedFingertipsRollACylinder) {
  PlantParams p = inhand::plant::default_plant_params();
  p.gravity.setZero();
  ObjectDef o;
  o.shape = ObjectShape::cylinder(0.02, 0.05);
  o.mass = 0.05;
  o.pose.rotation =
      Eigen::AngleAxisd(1.5707963267948966, Eigen::Vector3d::UnitY()).toRotationMatrix();
  HandPlant plant(pinch(0.02, 0.5e-3), o, p);
  const Eigen::Vector3d start_on_object =
      o.pose.rotation.transpose() * (plant.contact(0).point - o.pose.position);
  const double v = 5e-3, arm = 0.1, T = 1.0;
  plant.set_joint_velocity_command(0, one(v / arm));   // +Y tip moves +Z
  plant.set_joint_velocity_command(1, one(-v / arm));  // -Y tip moves -Z
  plant.step(T);
  const Eigen::Vector3d rot = inhand::so3_log<double>(
      Eigen::Matrix3d(plant.object_pose().rotation * o.pose.rotation.transpose()));
  const double travel = arm * std::sin(v / arm * T);  // arc: Z component of the tip motion
  std::printf("roll: angle %.5f rad, expected %.5f rad, slip %.2e m, centre moved %.2e m\n",
              rot.x(), travel / 0.02, plant.contact(0).slip_distance,
              plant.object_pose().position.norm());
  EXPECT_NEAR(rot.x(), travel / 0.02, 0.01 * travel / 0.02);
  EXPECT_LT(std::abs(rot.y()) + std::abs(rot.z()), 1e-3);
  EXPECT_LT(plant.object_pose().position.norm(), 2e-4);
  for (int i = 0; i < 2; ++i) {
    EXPECT_TRUE(plant.contact(i).active);
    EXPECT_FALSE(plant.contact(i).sliding);
    EXPECT_LT(plant.contact(i).slip_distance, 1e-6);
  }
  // Rolling, not sticking in place: the contact moved over the object's surface.
  const auto& pose = plant.object_pose();
  const Eigen::Vector3d end_on_object =
      pose.rotation.transpose() * (plant.contact(0).point - pose.position);
  EXPECT_GT((end_on_object - start_on_object).norm(), 1e-3);
}

// Random finger motions on a free cylinder under gravity: every internal step, every
// friction force lies in the friction cone and in the tangent plane, normal forces are
// non-negative, and both sticking and sliding occur.
TEST(HandPlantContact, FrictionStaysInsideTheConeInRandomManipulation) {
  const auto hand = inhand::plant::shadow_like_hand();
  PlantParams p = inhand::plant::default_plant_params();
  p.contact.friction = 0.3;
  const int seeds = 4 * plant_test::test_scale();
  long stick = 0, slide = 0;
  double worst_ratio = 0.0;
  for (int seed = 0; seed < seeds; ++seed) {
    HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand), p);
    for (int i = 0; i < plant.finger_count(); ++i)
      plant.set_joint_positions(i, hand.grasp_configuration[i]);
    std::mt19937 rng(static_cast<std::uint32_t>(seed));
    std::uniform_real_distribution<double> U(-1.5, 1.5);
    for (int ms = 0; ms < 300; ++ms) {
      for (int i = 0; i < plant.finger_count(); ++i) {
        PlantFinger::JointVector qd(hand.fingers[i].dof());
        for (int j = 0; j < qd.size(); ++j) qd(j) = U(rng);
        plant.set_joint_velocity_command(i, qd);
      }
      for (int k = 0; k < 10; ++k) {
        plant.step_once();
        for (int i = 0; i < plant.finger_count(); ++i) {
          const auto& c = plant.contact(i);
          if (!c.active) continue;
          ASSERT_GE(c.normal_force, 0.0);
          const double ft = c.friction_force.norm();
          ASSERT_LE(ft, p.contact.friction * c.normal_force * (1 + 1e-12) + 1e-15);
          ASSERT_LE(std::abs(c.friction_force.dot(c.normal)), 1e-12 * (ft + 1e-12));
          if (c.normal_force > 1e-3)
            worst_ratio = std::max(worst_ratio, ft / (p.contact.friction * c.normal_force));
          (c.sliding ? slide : stick) += 1;
        }
      }
    }
  }
  std::printf(
      "random manipulation: %ld sticking and %ld sliding contact-steps, max |f_t| / (mu f_n) = "
      "%.15f\n",
      stick, slide, worst_ratio);
  EXPECT_GT(stick, 1000);
  EXPECT_GT(slide, 100);
}

TEST(HandPlantContact, SetObjectPoseResetsTheBristles) {
  PlantParams p = inhand::plant::default_plant_params();
  HandPlant plant(pinch(0.01, 1e-3), box(0.04, 0.01, 0.01), p);
  plant.step(0.2);
  ASSERT_GT(plant.contact(0).deflection.norm(), 1e-5);
  auto pose = plant.object_pose();
  pose.position.z() = 0.0;
  plant.set_object_pose(pose);
  EXPECT_EQ(plant.contact(0).deflection.norm(), 0.0);
  EXPECT_EQ(plant.object_pose().position, pose.position);
}

}  // namespace
