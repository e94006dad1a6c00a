// HandPlant: configuration checks, rigid-body integration (free tumbling, free fall),
// energy with damped contacts, frozen mode, determinism, the simulated joint hardware
// (velocity clamping, position limits, lag) and the step() clock.
#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <stdexcept>

#include "inhand/sim/presets.hpp"
#include "sim/test_util.hpp"

namespace {

using inhand::plant::HandPlant;
using inhand::plant::ObjectDef;
using inhand::plant::ObjectShape;
using inhand::plant::PlantFinger;
using inhand::plant::PlantParams;
using plant_test::far_probe;
using plant_test::one;
using plant_test::probe;

ObjectDef box_object(double mass = 0.05) {
  ObjectDef o;
  o.shape = ObjectShape::box(0.01, 0.01, 0.04);
  o.mass = mass;
  return o;
}

TEST(HandPlantConfig, ValidateNamesTheOffendingField) {
  const std::vector<PlantFinger> fingers{far_probe()};
  const PlantParams ok = inhand::plant::default_plant_params();
  EXPECT_TRUE(HandPlant::validate(fingers, box_object(), ok).ok());
  EXPECT_STREQ(HandPlant::validate({}, box_object(), ok).field, "fingers");
  EXPECT_STREQ(HandPlant::validate(fingers, box_object(0.0), ok).field, "mass");
  PlantParams p = ok;
  p.time_step = 2e-3;
  EXPECT_STREQ(HandPlant::validate(fingers, box_object(), p).field, "time_step");
  p = ok;
  p.contact.friction = -0.1;
  EXPECT_STREQ(HandPlant::validate(fingers, box_object(), p).field, "contact.friction");
  p = ok;
  p.sensing.normal_angle_std = -1.0;
  EXPECT_STREQ(HandPlant::validate(fingers, box_object(), p).field, "sensing.normal_angle_std");
  p = ok;
  p.gravity.x() = NAN;
  EXPECT_STREQ(HandPlant::validate(fingers, box_object(), p).field, "gravity");
  // Explicit-integration stability: a 1e7 N/m contact on a 50 g box at h = 1e-4 s.
  p = ok;
  p.contact.normal_stiffness = 1e7;
  const auto v = HandPlant::validate(fingers, box_object(), p);
  EXPECT_STREQ(v.field, "time_step");
  p.time_step = 1e-6;
  EXPECT_TRUE(HandPlant::validate(fingers, box_object(), p).ok());
  // A bad finger is attributed to its index.
  std::vector<PlantFinger> bad{far_probe(), far_probe()};
  bad[1].joints[0].max_velocity = 0.0;
  EXPECT_EQ(HandPlant::validate(bad, box_object(), ok).finger, 1);
  ObjectDef skewed = box_object();
  skewed.pose.rotation(0, 1) = 0.1;
  EXPECT_STREQ(HandPlant::validate(fingers, skewed, ok).field, "pose.rotation");
  EXPECT_THROW(HandPlant(fingers, box_object(-1.0), ok), std::invalid_argument);
  EXPECT_NO_THROW(HandPlant(fingers, box_object(), ok));
}

// Body-frame reference: I w_dot = -w x I w, R_dot = R [w]x, classical RK4 on a
// quaternion at a 10x smaller step.
struct RigidReference {
  Eigen::Quaterniond q;
  Eigen::Vector3d w;  // body frame
  Eigen::Vector3d I;

  static Eigen::Vector3d wdot(const Eigen::Vector3d& I, const Eigen::Vector3d& w) {
    return -(w.cross(I.cwiseProduct(w))).cwiseQuotient(I);
  }
  static Eigen::Vector4d qdot(const Eigen::Vector4d& q, const Eigen::Vector3d& w) {
    // q = (w, x, y, z) as a 4-vector; q_dot = q * (0, w) / 2
    Eigen::Quaterniond a(q(0), q(1), q(2), q(3)), b(0.0, w.x(), w.y(), w.z());
    const Eigen::Quaterniond c = a * b;
    return 0.5 * Eigen::Vector4d(c.w(), c.x(), c.y(), c.z());
  }
  void step(double h) {
    Eigen::Vector4d y(q.w(), q.x(), q.y(), q.z());
    const Eigen::Vector3d w0 = w;
    const Eigen::Vector4d k1 = qdot(y, w0);
    const Eigen::Vector3d l1 = wdot(I, w0);
    const Eigen::Vector4d k2 = qdot(y + 0.5 * h * k1, w0 + 0.5 * h * l1);
    const Eigen::Vector3d l2 = wdot(I, w0 + 0.5 * h * l1);
    const Eigen::Vector4d k3 = qdot(y + 0.5 * h * k2, w0 + 0.5 * h * l2);
    const Eigen::Vector3d l3 = wdot(I, w0 + 0.5 * h * l2);
    const Eigen::Vector4d k4 = qdot(y + h * k3, w0 + h * l3);
    const Eigen::Vector3d l4 = wdot(I, w0 + h * l3);
    y += h / 6.0 * (k1 + 2 * k2 + 2 * k3 + k4);
    w += h / 6.0 * (l1 + 2 * l2 + 2 * l3 + l4);
    y.normalize();
    q = Eigen::Quaterniond(y(0), y(1), y(2), y(3));
  }
};

TEST(HandPlantDynamics, FreeTumblingBoxConservesEnergyAndMomentum) {
  // Asymmetric box spun near its intermediate axis (y): it flips over within 2 s.
  ObjectDef o;
  o.shape = ObjectShape::box(0.01, 0.02, 0.04);
  o.mass = 0.1;
  o.pose.position = Eigen::Vector3d(0.1, -0.2, 0.3);
  o.pose.rotation = inhand::so3_exp<double>(Eigen::Vector3d(0.3, -0.2, 0.5));
  PlantParams p = inhand::plant::default_plant_params();
  p.gravity.setZero();
  HandPlant plant({far_probe()}, o, p);
  const Eigen::Vector3d w_body(0.1, 4.0, 0.1);
  const Eigen::Vector3d v0(0.01, -0.02, 0.03);
  inhand::Twist<double, 3> twist;
  twist << v0, o.pose.rotation * w_body;
  plant.set_object_twist(twist);
  const double E0 = plant.kinetic_energy();
  const Eigen::Vector3d L0 = plant.object_angular_momentum();
  RigidReference ref{Eigen::Quaterniond(o.pose.rotation), w_body, plant.principal_inertia()};

  double max_rel_energy_error = 0.0, max_momentum_error = 0.0;
  Eigen::Vector3d initial_y = o.pose.rotation.col(1);
  double min_y_alignment = 1.0;
  for (int ms = 1; ms <= 2000; ++ms) {
    plant.step(1e-3);
    for (int k = 0; k < 100; ++k) ref.step(1e-5);
    max_rel_energy_error =
        std::max(max_rel_energy_error, std::abs(plant.kinetic_energy() - E0) / E0);
    const auto& pose = plant.object_pose();
    const Eigen::Vector3d I = plant.principal_inertia();
    const Eigen::Vector3d w = plant.object_twist().tail<3>();
    const Eigen::Vector3d L = pose.rotation * I.cwiseProduct(pose.rotation.transpose() * w);
    max_momentum_error = std::max(max_momentum_error, (L - L0).norm() / L0.norm());
    min_y_alignment = std::min(min_y_alignment, pose.rotation.col(1).dot(initial_y));
  }
  const double t = plant.time();
  EXPECT_NEAR(t, 2.0, 1e-12);
  // The box really tumbled: its y axis turned more than 90 degrees at some point.
  EXPECT_LT(min_y_alignment, 0.0);
  // Bounds: kinetic energy to 1e-6 relative, angular momentum to 1e-12 relative.
  EXPECT_LT(max_rel_energy_error, 1e-6);
  EXPECT_LT(max_momentum_error, 1e-12);
  // The stored momentum is untouched without torque.
  EXPECT_EQ(plant.object_angular_momentum(), L0);
  // Free flight of the centre of mass.
  EXPECT_LT((plant.object_pose().position - (o.pose.position + v0 * t)).norm(), 1e-12);
  // Orientation against the RK4 reference: second-order integrator, 1e-4 s step.
  const Eigen::Matrix3d dR = plant.object_pose().rotation.transpose() * ref.q.toRotationMatrix();
  const double angle = inhand::so3_log<double>(dR).norm();
  EXPECT_LT(angle, 1e-4);
  std::printf(
      "tumbling box, 2 s: max |dE|/E %.2e, max |dL|/|L| %.2e, rotation error vs RK4 %.2e rad\n",
      max_rel_energy_error, max_momentum_error, angle);
}

TEST(HandPlantDynamics, FreeFallFollowsSymplecticEuler) {
  ObjectDef o = box_object();
  o.pose.position = Eigen::Vector3d(0.0, 0.0, 1.0);
  HandPlant plant({far_probe()}, o);
  const double g = -9.81, h = plant.time_step();
  plant.step(1.0);
  const double t = plant.time();
  // Symplectic Euler: v_n = g t_n, z_n = z0 + g h^2 n (n + 1) / 2 = z0 + g t^2/2 + g h t/2.
  EXPECT_NEAR(plant.object_twist()(2), g * t, 1e-12);
  EXPECT_NEAR(plant.object_pose().position.z(), 1.0 + 0.5 * g * t * t + 0.5 * g * h * t, 1e-12);
  EXPECT_NEAR(plant.object_pose().position.x(), 0.0, 1e-15);
  EXPECT_EQ(plant.object_pose().rotation, o.pose.rotation);
}

// A box squeezed by four probes, kicked, fingers still: kinetic + potential + elastic
// energy must never exceed its initial value by more than the integrator's
// oscillation, and the damping must dissipate most of the kick.
TEST(HandPlantDynamics, TotalEnergyDoesNotGrowWithDampedContacts) {
  for (const bool with_gravity : {false, true}) {
    ObjectDef o = box_object();
    const double indent = 0.5e-3, r = 0.01;
    std::vector<PlantFinger> fingers;
    for (double x : {-0.02, 0.02})
      for (double s : {-1.0, 1.0})
        fingers.push_back(probe(Eigen::Vector3d(x, s * (0.01 + r - indent), 0.0),
                                Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitX() * 0.1, r));
    PlantParams p = inhand::plant::default_plant_params();
    if (!with_gravity) p.gravity.setZero();
    HandPlant plant(fingers, o, p);
    inhand::Twist<double, 3> kick;
    kick << 0.02, 0.01, -0.03, 1.0, -0.5, 2.0;
    plant.set_object_twist(kick);
    const double E0 = plant.total_energy();
    const double K0 = plant.kinetic_energy();
    double max_excess = -1e9;
    for (int n = 0; n < 20000; ++n) {
      plant.step_once();
      max_excess = std::max(max_excess, plant.total_energy() - E0);
    }
    const double final_change = plant.total_energy() - E0;
    std::printf(
        "gravity %d: K0 %.3e J, max energy excess %.3e J (%.2e K0), change after 2 s %.3e J\n",
        with_gravity, K0, max_excess, max_excess / K0, final_change);
    // Bound: 1 % of the kick's kinetic energy.
    EXPECT_LT(max_excess, 0.01 * K0);
    EXPECT_LT(final_change, -0.5 * K0);
  }
}

TEST(HandPlantDynamics, FrozenObjectStaysExactlyWhileFingersPress) {
  const auto hand = inhand::plant::shadow_like_hand();
  const ObjectDef o = inhand::plant::paper_cylinder(hand);
  HandPlant plant(hand.fingers, o);
  for (int i = 0; i < plant.finger_count(); ++i) {
    ASSERT_TRUE(plant.set_joint_positions(i, hand.open_configuration[i]));
  }
  plant.set_frozen(true);
  // Close towards the grasp posture: the fingertips run into the cylinder.
  for (int ms = 0; ms < 600; ++ms) {
    for (int i = 0; i < plant.finger_count(); ++i)
      plant.set_joint_velocity_command(
          i, 2.0 * (hand.grasp_configuration[i] - hand.open_configuration[i]));
    plant.step(1e-3);
    ASSERT_EQ(plant.object_pose().position, o.pose.position);
    ASSERT_EQ(plant.object_pose().rotation, o.pose.rotation);
    ASSERT_TRUE(plant.object_twist().isZero(0.0));
  }
  for (int i = 0; i < plant.finger_count(); ++i) {
    EXPECT_TRUE(plant.contact(i).active) << i;
    EXPECT_GT(plant.contact(i).normal_force, 0.1) << i;
    plant.sample_sensors();
    EXPECT_TRUE(plant.tactile(i).touching) << i;
  }
  // Released, the unbalanced squeeze moves it.
  for (int i = 0; i < plant.finger_count(); ++i)
    plant.set_joint_velocity_command(i, PlantFinger::JointVector::Zero(hand.fingers[i].dof()));
  plant.set_frozen(false);
  plant.step(0.01);
  EXPECT_GT((plant.object_pose().position - o.pose.position).norm(), 1e-6);
}

// Random commands, noisy sensing: two plants fed the same inputs agree bit for bit.
TEST(HandPlantDynamics, SameInputsGiveBitIdenticalTrajectories) {
  const auto hand = inhand::plant::shadow_like_hand();
  PlantParams p = inhand::plant::default_plant_params();
  p.sensing.normal_force_std = 0.05;
  p.sensing.contact_point_std = 1e-4;
  p.sensing.normal_angle_std = 0.02;
  p.sensing.object_position_std = 1e-4;
  p.sensing.object_rotation_std = 1e-3;
  p.seed = 42;
  p.joint_velocity_lag = 0.005;
  auto run = [&](std::vector<double>& log) {
    HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand), p);
    for (int i = 0; i < plant.finger_count(); ++i)
      plant.set_joint_positions(i, hand.grasp_configuration[i]);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> U(-0.5, 0.5);
    for (int ms = 0; ms < 500; ++ms) {
      for (int i = 0; i < plant.finger_count(); ++i) {
        PlantFinger::JointVector qd(hand.fingers[i].dof());
        for (int j = 0; j < qd.size(); ++j) qd(j) = U(rng);
        plant.set_joint_velocity_command(i, qd);
      }
      plant.step(1e-3);
      plant.sample_sensors();
      const auto m = plant.measured_object_pose();
      log.insert(log.end(), m.position.data(), m.position.data() + 3);
      log.insert(log.end(), plant.object_pose().rotation.data(),
                 plant.object_pose().rotation.data() + 9);
      for (int i = 0; i < plant.finger_count(); ++i) {
        const auto t = plant.tactile(i);
        log.push_back(t.normal_force);
        log.insert(log.end(), t.contact_point.data(), t.contact_point.data() + 3);
        log.insert(log.end(), t.normal.data(), t.normal.data() + 3);
      }
    }
  };
  std::vector<double> a, b;
  run(a);
  run(b);
  ASSERT_EQ(a.size(), b.size());
  EXPECT_EQ(std::memcmp(a.data(), b.data(), a.size() * sizeof(double)), 0);
}

TEST(HandPlantJoints, CommandsAreClampedAndJointsStopAtLimits) {
  const auto hand = inhand::plant::shadow_like_hand();
  HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand));
  const int f = 1;
  plant.set_joint_positions(f, hand.open_configuration[f]);
  PlantFinger::JointVector cmd(4);
  cmd << 0.0, -10.0, 0.5, 0.0;  // J3 beyond its 3 rad/s limit
  ASSERT_TRUE(plant.set_joint_velocity_command(f, cmd));
  EXPECT_EQ(plant.counters(f).velocity_clamped, 1u);
  EXPECT_DOUBLE_EQ(plant.joint_velocity_command(f)(1), -3.0);
  // J3 from -0.188 to its -0.26 limit in ~24 ms; then stays there.
  plant.step(0.1);
  EXPECT_EQ(plant.joint_positions(f)(1), hand.fingers[f].joints[1].lower);
  EXPECT_EQ(plant.joint_velocities(f)(1), 0.0);
  EXPECT_GT(plant.counters(f).position_limited, 0u);
  EXPECT_NEAR(plant.joint_positions(f)(2), hand.open_configuration[f](2) + 0.05, 1e-12);
  // The finger's forward kinematics follow the joints.
  inhand::FingerKinematics<PlantFinger> ws(hand.fingers[f]);
  inhand::forward_kinematics(hand.fingers[f], plant.joint_positions(f), ws);
  EXPECT_LT((ws.fingertip.position - plant.fingertip_pose(f).position).norm(), 1e-12);
  // A non-finite or wrong-size command stops the finger and is counted.
  cmd(2) = NAN;
  EXPECT_FALSE(plant.set_joint_velocity_command(f, cmd));
  EXPECT_FALSE(plant.set_joint_velocity_command(f, PlantFinger::JointVector::Zero(3)));
  EXPECT_EQ(plant.counters(f).invalid_commands, 2u);
  EXPECT_EQ(plant.joint_velocity_command(f), PlantFinger::JointVector::Zero(4));
  // Out-of-range positions are clamped; wrong sizes rejected.
  PlantFinger::JointVector q(4);
  q << 5.0, 0.3, 0.3, 0.3;
  EXPECT_TRUE(plant.set_joint_positions(f, q));
  EXPECT_EQ(plant.joint_positions(f)(0), hand.fingers[f].joints[0].upper);
  EXPECT_FALSE(plant.set_joint_positions(f, Eigen::VectorXd::Zero(2)));
}

TEST(HandPlantJoints, LongRunsKeepTheKinematicsExact) {
  // Constant joint velocities for 20 s: the incrementally advanced sin/cos of the plant's
  // forward kinematics stay on the exact forward kinematics.
  const auto hand = inhand::plant::shadow_like_hand();
  HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand));
  const int f = 3;
  PlantFinger::JointVector cmd(5);
  cmd << 0.05, -0.01, 0.02, 0.03, -0.04;
  plant.set_joint_velocity_command(f, cmd);
  plant.step(20.0);
  inhand::FingerKinematics<PlantFinger> ws(hand.fingers[f]);
  inhand::forward_kinematics(hand.fingers[f], plant.joint_positions(f), ws);
  EXPECT_LT((ws.fingertip.position - plant.fingertip_pose(f).position).norm(), 1e-13);
  EXPECT_LT((ws.fingertip.rotation - plant.fingertip_pose(f).rotation).norm(), 1e-12);
  EXPECT_LT((ws.joint_axes - plant.kinematics(f).joint_axes).norm(), 1e-12);
  EXPECT_NEAR(plant.joint_positions(f)(0), 1.0, 1e-10);
}

TEST(HandPlantJoints, FirstOrderLagReachesTheCommand) {
  PlantParams p = inhand::plant::default_plant_params();
  p.joint_velocity_lag = 0.01;
  HandPlant plant({far_probe()}, box_object(), p);
  plant.set_joint_velocity_command(0, one(1.0));
  plant.step(0.01);  // one time constant
  EXPECT_NEAR(plant.joint_velocities(0)(0), 1.0 - std::exp(-1.0), 1e-12);
  plant.step(0.09);
  EXPECT_NEAR(plant.joint_velocities(0)(0), 1.0 - std::exp(-10.0), 1e-12);
}

TEST(HandPlantClock, StepTakesWholeInternalStepsWithoutDrift) {
  HandPlant plant({far_probe()}, box_object());
  int n = 0;
  for (int k = 0; k < 1000; ++k) n += plant.step(1e-3);
  EXPECT_EQ(n, 10000);
  EXPECT_EQ(plant.step_count(), 10000);
  EXPECT_NEAR(plant.time(), 1.0, 1e-12);
  EXPECT_EQ(plant.step(0.25e-4), 0);  // rounds to the nearest step: not yet
  EXPECT_EQ(plant.step(0.5e-4), 1);   // 0.75e-4 requested in total -> 1 step
  EXPECT_EQ(plant.step(-1.0), 0);
  EXPECT_EQ(plant.step(NAN), 0);
  plant.step_once();
  EXPECT_EQ(plant.step(1e-3), 10);
  EXPECT_EQ(plant.step_count(), 10012);
}

}  // namespace
