// HandPlant sensing: zero noise reproduces the truth; configured noise has the
// configured mean and standard deviation; noise is held between samples and is
// determined by the seed; the touch threshold gates contact reports.
#include <gtest/gtest.h>

#include <cmath>

#include "inhand/sim/hand_plant.hpp"
#include "sim/test_util.hpp"

namespace {

using inhand::plant::HandPlant;
using inhand::plant::ObjectDef;
using inhand::plant::ObjectShape;
using inhand::plant::PlantParams;
using plant_test::probe;

/// A frozen, slightly rotated box with one fingertip pressing its +Y face at 1 N and a
/// second fingertip out of reach.
HandPlant pressed_box(const PlantParams& p) {
  ObjectDef o;
  o.shape = ObjectShape::box(0.04, 0.01, 0.01);
  o.mass = 0.05;
  o.pose.position = Eigen::Vector3d(0.01, -0.02, 0.03);
  HandPlant plant(
      {probe(o.pose.position + Eigen::Vector3d(0, 0.0195, 0), Eigen::Vector3d::UnitY(),
             -0.1 * Eigen::Vector3d::UnitX()),
       probe(Eigen::Vector3d(1, 1, 1), Eigen::Vector3d::UnitY(), -0.1 * Eigen::Vector3d::UnitX())},
      o, p);
  plant.set_frozen(true);
  return plant;
}

struct Stats {
  double sum = 0, sum2 = 0;
  int n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return sum / n; }
  double std() const { return std::sqrt((sum2 - sum * sum / n) / (n - 1)); }
};

TEST(HandPlantSensing, ZeroNoiseReadingsEqualTheTruth) {
  HandPlant plant = pressed_box(inhand::plant::default_plant_params());
  plant.step(0.01);
  plant.sample_sensors();
  const auto& c = plant.contact(0);
  ASSERT_TRUE(c.active);
  const auto t = plant.tactile(0);
  EXPECT_TRUE(t.touching);
  EXPECT_EQ(t.normal_force, c.normal_force);
  EXPECT_EQ(t.contact_point, c.point);
  EXPECT_EQ(t.normal, c.normal);
  const auto m = plant.measured_object_pose();
  EXPECT_EQ(m.position, plant.object_pose().position);
  EXPECT_EQ(m.rotation, plant.object_pose().rotation);
  // The far finger reports nothing.
  const auto far = plant.tactile(1);
  EXPECT_FALSE(far.touching);
  EXPECT_EQ(far.normal_force, 0.0);
  EXPECT_EQ(far.normal, Eigen::Vector3d::Zero());
}

TEST(HandPlantSensing, NoiseHasTheConfiguredStatistics) {
  PlantParams p = inhand::plant::default_plant_params();
  auto& s = p.sensing;
  s.normal_force_std = 0.05;
  s.normal_force_bias = 0.02;
  s.contact_point_std = 2e-4;
  s.normal_angle_std = 0.03;
  s.object_position_std = 5e-4;
  s.object_rotation_std = 0.01;
  p.seed = 2024;
  HandPlant plant = pressed_box(p);
  const auto& c = plant.contact(0);
  ASSERT_TRUE(c.active);
  ASSERT_GT(c.normal_force, 0.9);  // far above the noise: the clamp at 0 never acts
  const int n = 4000 * plant_test::test_scale();
  Stats force, point[3], angle[3], pos[3], rot[3];
  for (int k = 0; k < n; ++k) {
    plant.sample_sensors();
    const auto t = plant.tactile(0);
    ASSERT_TRUE(t.touching);
    force.add(t.normal_force - c.normal_force);
    const Eigen::Vector3d axis = c.normal.cross(t.normal);  // sin(angle) * unit axis
    const Eigen::Vector3d w = std::asin(axis.norm()) * axis.normalized();
    const auto m = plant.measured_object_pose();
    const Eigen::Vector3d rv = inhand::so3_log<double>(
        Eigen::Matrix3d(m.rotation * plant.object_pose().rotation.transpose()));
    for (int a = 0; a < 3; ++a) {
      point[a].add(t.contact_point(a) - c.point(a));
      angle[a].add(w(a));
      pos[a].add(m.position(a) - plant.object_pose().position(a));
      rot[a].add(rv(a));
    }
    EXPECT_NEAR(t.normal.norm(), 1.0, 1e-12);
  }
  // Sample std within 6 % (the std of a 4000-sample std estimate is 1.1 %); means within
  // 4 standard errors.
  const double se = 4.0 / std::sqrt(static_cast<double>(n));
  EXPECT_NEAR(force.std(), s.normal_force_std, 0.06 * s.normal_force_std);
  EXPECT_NEAR(force.mean(), s.normal_force_bias, se * s.normal_force_std);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(point[a].std(), s.contact_point_std, 0.06 * s.contact_point_std) << a;
    EXPECT_NEAR(point[a].mean(), 0.0, se * s.contact_point_std) << a;
    EXPECT_NEAR(pos[a].std(), s.object_position_std, 0.06 * s.object_position_std) << a;
    EXPECT_NEAR(pos[a].mean(), 0.0, se * s.object_position_std) << a;
    EXPECT_NEAR(rot[a].std(), s.object_rotation_std, 0.06 * s.object_rotation_std) << a;
    EXPECT_NEAR(rot[a].mean(), 0.0, se * s.object_rotation_std) << a;
  }
  // The normal turns about the two tangent axes (X and Z here), never about itself.
  EXPECT_NEAR(angle[0].std(), s.normal_angle_std, 0.06 * s.normal_angle_std);
  EXPECT_NEAR(angle[2].std(), s.normal_angle_std, 0.06 * s.normal_angle_std);
  EXPECT_LT(angle[1].std(), 1e-12);
}

TEST(HandPlantSensing, NoiseIsHeldBetweenSamplesAndSetByTheSeed) {
  PlantParams p = inhand::plant::default_plant_params();
  p.sensing.normal_force_std = 0.05;
  p.sensing.object_position_std = 1e-3;
  p.seed = 5;
  HandPlant a = pressed_box(p), b = pressed_box(p);
  p.seed = 6;
  HandPlant c = pressed_box(p);
  a.sample_sensors();
  b.sample_sensors();
  c.sample_sensors();
  const double fa = a.tactile(0).normal_force;
  EXPECT_EQ(a.tactile(0).normal_force, fa);  // held until the next sample
  EXPECT_EQ(b.tactile(0).normal_force, fa);  // same seed, same sequence
  EXPECT_NE(c.tactile(0).normal_force, fa);  // another seed, another sequence
  EXPECT_EQ(a.measured_object_pose().position, b.measured_object_pose().position);
  a.sample_sensors();
  EXPECT_NE(a.tactile(0).normal_force, fa);
}

TEST(HandPlantSensing, TouchThresholdGatesTheContactReport) {
  PlantParams p = inhand::plant::default_plant_params();
  p.sensing.touch_threshold = 1.5;  // the fingertip presses with 1 N
  HandPlant plant = pressed_box(p);
  plant.sample_sensors();
  ASSERT_TRUE(plant.contact(0).active);
  EXPECT_FALSE(plant.tactile(0).touching);
  EXPECT_EQ(plant.tactile(0).normal_force, 0.0);
  p.sensing.touch_threshold = 0.5;
  HandPlant lighter = pressed_box(p);
  lighter.sample_sensors();
  EXPECT_TRUE(lighter.tactile(0).touching);
}

}  // namespace
