// Closed loop on MuJoCo: the paper's cylinder translation (include/inhand/sim/
// paper_scenarios.hpp: grasp with the object frozen, release and hold 2 s, 5 mm along
// X and back in 4 s, 1 s settle) by the library's controller on the MJCF three-finger
// hand (models/three_finger_cylinder.xml) through examples/mujoco/mujoco_adapter.hpp.
// Units: m, rad, N, s.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/controller_instances.hpp"
#include "common/test_support.hpp"
#include "inhand/sim/paper_scenarios.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "mujoco_adapter.hpp"

namespace {

namespace md = inhand::mujoco_demo;
namespace ip = inhand::plant;
using Spec = inhand::sim::ScenarioSpec<md::MujocoAdapter>;

Spec cylinder_experiment(ip::PaperTask task, int axis) {
  const ip::ScenarioSpec paper = ip::paper_scenario(ip::PaperObject::cylinder, task, axis);
  Spec s;
  s.name = paper.name;
  s.stages = paper.stages;
  s.tolerances = paper.tolerances;
  // INHAND_MUJOCO_KP=<1/s>: the servo's position gain (MujocoSetup::position_gain).
  if (const char* kp = std::getenv("INHAND_MUJOCO_KP")) s.position_gain = std::atof(kp);
  // The force layer's defaults, release_grip 2 included (1 was needed while the models'
  // servo torque was capped at kv x 3 rad/s = 0.15 N m: docs/mujoco.md).
  return s;
}

void record_stage(const ip::StageMetrics& m) {
  const std::string p = m.name + "_";
  inhand_test::record(p + "rms_position_error_m", m.rms_position_error);
  inhand_test::record(p + "max_position_error_m", m.max_position_error);
  inhand_test::record(p + "final_position_error_m", m.final_position_error);
  inhand_test::record(p + "rms_orientation_error_rad", m.rms_orientation_error);
  inhand_test::record(p + "max_force_error_N", m.max_force_error);
  inhand_test::record(p + "rms_force_error_N", m.rms_force_error);
  inhand_test::record(p + "contact_losses", m.contact_losses);
}

inhand::sim::ScenarioResult run(const Spec& spec, double* grasp_displacement = nullptr) {
  // INHAND_MUJOCO_TRACE=<n>: print every n-th tick (stage, status, per finger: state,
  // touching, force / target, joint angles and commands; the object position).
  const char* trace_env = std::getenv("INHAND_MUJOCO_TRACE");
  const long every = trace_env != nullptr ? std::max(1L, std::atol(trace_env)) : 0;
  return inhand::sim::ScenarioRunner<md::MujocoAdapter>().run(
      spec, [&](const inhand::sim::TickRecord<md::MujocoAdapter>& rec) {
        if (grasp_displacement != nullptr && rec.stage == 0)
          *grasp_displacement = std::max(*grasp_displacement, rec.actual->position.norm());
        if (every == 0 || std::lround(rec.time * 1000) % every != 0) return;
        std::printf("t %.3f st %d status %d |", rec.time, rec.stage, static_cast<int>(rec.status));
        for (std::size_t i = 0; i < 3; ++i) {
          const auto& fi = rec.input->fingers[i];
          const auto& fo = rec.output->fingers[i];
          std::printf(" [%d %d f %.3f/%.3f q %.3f %.3f %.3f qd %.2f %.2f %.2f]",
                      static_cast<int>(fo.state), fi.contact.touching, fi.contact.normal_force,
                      fo.force_target, fi.joint_positions(0), fi.joint_positions(1),
                      fi.joint_positions(2), fo.joint_velocities(0), fo.joint_velocities(1),
                      fo.joint_velocities(2));
        }
        std::printf(" obj %.5f %.5f %.5f\n", rec.actual->position.x(), rec.actual->position.y(),
                    rec.actual->position.z());
      });
}

// What holds today: the run goes through the adapter end to end, the weld keeps the
// object still while the hand closes, and the figures are recorded.
TEST(MujocoCylinder, GraspStageRunsWithTheObjectHeld) {
  double displacement = 0.0;  // m, of the object from its start (the origin)
  const inhand::sim::ScenarioResult r =
      run(cylinder_experiment(ip::PaperTask::translate, 0), &displacement);
  for (const ip::StageMetrics& m : r.stages) record_stage(m);
  inhand_test::record("link_contact_ticks", r.link_contacts);
  inhand_test::record("grasp_object_displacement_m", displacement);
  ASSERT_GE(r.stages.size(), 1u);
  EXPECT_LT(displacement, 1e-4);  // m, held by the weld under gravity and the fingertips
  EXPECT_FALSE(r.stages[0].dropped);
}

// The paper's bounds on MuJoCo, with the hand's servo holding the integrated command
// (position_gain 30 /s, the adapter's default; INHAND_MUJOCO_KP overrides it). With a pure
// velocity servo (0) the contact chatters: made and lost every 3-6 ms at 0.06-0.6 N
// against the 1 N target (docs/mujoco.md).
TEST(MujocoCylinder, TranslationAlongXWithinThePaperBounds) {
  const inhand::sim::ScenarioResult r = run(cylinder_experiment(ip::PaperTask::translate, 0));
  for (const ip::StageMetrics& m : r.stages) record_stage(m);
  ASSERT_EQ(r.failure, "");
  ASSERT_EQ(r.stages.size(), 3u);
  EXPECT_TRUE(r.stages[0].completed);
  EXPECT_FALSE(r.dropped);
  EXPECT_EQ(r.contact_losses, 0);
  EXPECT_LT(r.stages[2].rms_position_error, 5e-4);     // m, the paper's translation bound
  EXPECT_LT(r.stages[2].rms_orientation_error, 1e-2);  // rad
  EXPECT_LT(r.stages[2].final_position_error, 5e-4);   // m
  EXPECT_LT(r.stages[2].rms_force_error, 0.2);         // N
}

// The hand's servo over x100 in stiffness: position_gain 5-500 /s, i.e. 0.25-25 N m/rad
// with the model's kv 0.05 N m s/rad, the controller told each (MujocoAdapter::
// controller_config: ForceLayerParams::servo_stiffness, servo_damping). Translate X within
// the paper bounds from 10 /s up (x50), the hold settling within the paper files' 1 s (the
// softer the servo, the more the release rolls the cylinder and the longer the hold takes to
// settle: measured 0.86 s at 10 /s, 0.51 s at 15 /s, 0.12 s at 50 /s, 0 from 150 /s; a
// release_load of 6 N took 10 /s to 1.89 s, docs/force_layer.md); each run recorded.
// Measured, not reached: 5 /s turns the cylinder 57 mrad RMS, the grasp pressing at 2.18 for
// release_load (docs/mujoco.md; 13 mrad before the press direction used the secant
// stiffness; it passed with release_grip 1).
// (Before the force loop saw the servo, only 20-150 /s passed: at 10 and 200 /s the grasp
// timed out.)
TEST(MujocoCylinder, ServoStiffnessSweep) {
  for (double gain : {10.0, 15.0, 50.0, 150.0, 500.0, 5.0}) {  // 5 /s last: recorded only
    Spec spec = cylinder_experiment(ip::PaperTask::translate, 0);
    spec.position_gain = gain;
    SCOPED_TRACE("position_gain " + std::to_string(gain));
    const inhand::sim::ScenarioResult r = run(spec);
    ASSERT_EQ(r.failure, "");
    ASSERT_EQ(r.stages.size(), 3u);
    const ip::StageMetrics& m = r.stages[2];
    const std::string p = "servo_gain_" + std::to_string(static_cast<int>(gain));
    inhand_test::record(p + "_rms_position_m", m.rms_position_error);
    inhand_test::record(p + "_rms_orientation_rad", m.rms_orientation_error);
    inhand_test::record(p + "_hold_settle_s", r.stages[1].settle_time);
    if (gain < 10.0) continue;
    EXPECT_LE(r.stages[1].settle_time, 1.0);  // s, the paper files' hold bound
    EXPECT_TRUE(r.stages[0].completed);
    EXPECT_FALSE(r.dropped);
    EXPECT_EQ(r.contact_losses, 0);
    EXPECT_LT(m.rms_position_error, 5e-4);
    EXPECT_LT(m.rms_orientation_error, 1e-2);
    EXPECT_LT(m.final_position_error, 5e-4);
  }
}

// The hand's firmware limits the commanded joint velocity to the actuator's control range
// (3 rad/s), and MuJoCo clips only the torque, at the force range (1 N m): ctrl, which also
// carries the servo's position term, is not clipped (ctrllimited false; clipped at 3 rad/s it
// capped the torque at kv x 3 = 0.15 N m). The first finger's abduction, commanded at 10 rad/s
// from 0: its set-point moves at 3 rad/s and the joint, behind it, never passes it (it moves
// faster than 3 rad/s for a while as it closes its lag); held at its limit (0.5 rad) while
// the set-point runs on, the actuator's torque reaches the force range.
TEST(MujocoCylinder, FirmwareLimitsTheCommandMujocoTheTorque) {
  const md::MujocoSetup setup{};  // the adapter keeps a reference to it
  md::MujocoAdapter plant(setup);
  const mjModel& m = plant.model();
  const int a = mj_name2id(&m, mjOBJ_ACTUATOR, "left_abduction");
  ASSERT_GE(a, 0);
  md::MujocoAdapter::JointVector qd = plant.joint_positions(0);
  qd.setZero();
  qd(0) = 10.0;
  const double q0 = plant.joint_positions(0)(0);
  double ahead = -1.0;  // largest q - q0 - 3 t over the free motion [rad]
  for (int tick = 1; tick <= 600; ++tick) {
    plant.command(0, qd, inhand::sim::TickClock{});
    plant.step(1e-3);
    const double q = plant.joint_positions(0)(0);
    if (tick <= 150) ahead = std::max(ahead, q - q0 - 3.0 * 1e-3 * tick);
    if (tick == 100) {
      inhand_test::record("abduction_after_100_ms_rad", q - q0);
      EXPECT_GT(q - q0, 0.25);
    }
  }
  inhand_test::record("abduction_ahead_of_3_rad_per_s_rad", ahead);
  inhand_test::record("abduction_torque_at_limit_N_m", plant.data().actuator_force[a]);
  EXPECT_LE(ahead, 1e-9);
  EXPECT_GT(plant.joint_positions(0)(0), 0.49);
  EXPECT_NEAR(plant.data().actuator_force[a], 1.0, 1e-9);
}

// The other five cylinder experiments and the four fault scenarios run from the scenario
// files of scenarios/mujoco/ (ctest scenario.mujoco.*: inhand_scenario --check, the paper's
// bounds and the fault files' bounds; figures in docs/mujoco.md).

// Sweeps over the contact and the load (MujocoSetup::friction, torsional_friction,
// object_mass): friction 0.3-1.0 with torsional friction off and on (rotation about Y,
// the task that turns the object about its contacts' common axis), and object mass
// 0.02-0.4 kg (translate X and rotate Y). Each run is recorded; the region that passes
// the paper bounds is asserted (must_pass; docs/mujoco.md gives the whole table).
// Measured, not reached: with torsional friction (0.005 m) the rotation about Y turns the
// cylinder against its contacts (RMS 0.38 rad with 9 contact losses at friction 0.3, 24 mrad
// at 0.5, 17 mrad at 1.0, against the 10 mrad bound): the torsional friction a contact can
// exert grows with the grip, and the no-slip friction no longer lets it creep (1.0 passed at
// 2.8 mrad with creeping friction and release_grip 1). 0.4 kg passes since the models' servo
// torque reaches the force range (it was dropped at release while capped at 0.15 N m).
struct SweepCase {
  const char* name;
  ip::PaperTask task;
  int axis;
  double friction, torsional, mass;
  bool must_pass;
};

TEST(MujocoCylinder, FrictionTorsionAndMassSweep) {
  const SweepCase cases[] = {
      {"rotate_y_mu0.3", ip::PaperTask::rotate, 1, 0.3, 0.0, 0.0, true},
      {"rotate_y_mu0.5", ip::PaperTask::rotate, 1, 0.5, 0.0, 0.0, true},
      {"rotate_y_mu1.0", ip::PaperTask::rotate, 1, 1.0, 0.0, 0.0, true},
      {"rotate_y_mu0.3_torsion", ip::PaperTask::rotate, 1, 0.3, 0.005, 0.0, false},
      {"rotate_y_mu0.5_torsion", ip::PaperTask::rotate, 1, 0.5, 0.005, 0.0, false},
      {"rotate_y_mu1.0_torsion", ip::PaperTask::rotate, 1, 1.0, 0.005, 0.0, false},
      {"translate_x_m0.02", ip::PaperTask::translate, 0, 0.0, 0.0, 0.02, true},
      {"translate_x_m0.2", ip::PaperTask::translate, 0, 0.0, 0.0, 0.2, true},
      {"translate_x_m0.4", ip::PaperTask::translate, 0, 0.0, 0.0, 0.4, true},
      {"rotate_y_m0.02", ip::PaperTask::rotate, 1, 0.0, 0.0, 0.02, true},
      {"rotate_y_m0.2", ip::PaperTask::rotate, 1, 0.0, 0.0, 0.2, true},
      {"rotate_y_m0.4", ip::PaperTask::rotate, 1, 0.0, 0.0, 0.4, true},
  };
  for (const SweepCase& c : cases) {
    SCOPED_TRACE(c.name);
    Spec spec = cylinder_experiment(c.task, c.axis);
    spec.friction = c.friction;
    spec.torsional_friction = c.torsional;
    spec.object_mass = c.mass;
    const inhand::sim::ScenarioResult r = run(spec);
    const bool complete = r.failure.empty() && r.stages.size() == 3u;
    const std::string p = std::string(c.name) + "_";
    inhand_test::record(p + "dropped", r.dropped ? 1.0 : 0.0);
    inhand_test::record(p + "contact_losses", static_cast<double>(r.contact_losses));
    if (complete) {
      inhand_test::record(p + "rms_position_error_m", r.stages[2].rms_position_error);
      inhand_test::record(p + "rms_orientation_error_rad", r.stages[2].rms_orientation_error);
      inhand_test::record(p + "final_position_error_m", r.stages[2].final_position_error);
    } else {
      inhand_test::record(p + "stages", static_cast<double>(r.stages.size()));
      std::printf("%s: %s\n", c.name, r.failure.c_str());
    }
    if (!c.must_pass) continue;
    ASSERT_TRUE(complete) << r.failure;
    EXPECT_FALSE(r.dropped);
    EXPECT_EQ(r.contact_losses, 0);
    EXPECT_LT(r.stages[2].rms_position_error, 5e-4);
    EXPECT_LT(r.stages[2].rms_orientation_error, 1e-2);
  }
}

// The sweep's settings are checked before the world is built, the field named.
TEST(MujocoCylinder, ContactAndMassSettingsAreValidated) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Bad {
    const char* field;
    double friction, torsional, mass;
  };
  for (const Bad& b :
       {Bad{"setup.friction", nan, 0.0, 0.0}, Bad{"setup.friction", -0.1, 0.0, 0.0},
        Bad{"setup.torsional_friction", 0.0, inf, 0.0}, Bad{"setup.object_mass", 0.0, 0.0, -1.0}}) {
    Spec spec = cylinder_experiment(ip::PaperTask::translate, 0);
    spec.friction = b.friction;
    spec.torsional_friction = b.torsional;
    spec.object_mass = b.mass;
    std::string message;
    try {
      (void)run(spec);
    } catch (const std::invalid_argument& e) {
      message = e.what();
    }
    EXPECT_NE(message.find(b.field), std::string::npos) << b.field << ": " << message;
  }
}

// Every tick's record, flattened: time, stage, status, the object's true pose, and per
// finger the joint angles, the measured contact (touching, normal force, point, normal)
// and the commanded joint velocities.
std::vector<double> trace_of(const Spec& spec, inhand::sim::ScenarioResult& result) {
  std::vector<double> t;
  result = inhand::sim::ScenarioRunner<md::MujocoAdapter>().run(
      spec, [&](const inhand::sim::TickRecord<md::MujocoAdapter>& rec) {
        t.push_back(rec.time);
        t.push_back(rec.stage);
        t.push_back(static_cast<double>(rec.status));
        t.insert(t.end(), rec.actual->position.data(), rec.actual->position.data() + 3);
        t.insert(t.end(), rec.actual->rotation.data(), rec.actual->rotation.data() + 9);
        for (std::size_t i = 0; i < rec.input->fingers.size(); ++i) {
          const auto& fi = rec.input->fingers[i];
          const auto& qd = rec.output->fingers[i].joint_velocities;
          t.insert(t.end(), fi.joint_positions.data(),
                   fi.joint_positions.data() + fi.joint_positions.size());
          t.push_back(fi.contact.touching ? 1.0 : 0.0);
          t.push_back(fi.contact.normal_force);
          t.insert(t.end(), fi.contact.contact_point.data(), fi.contact.contact_point.data() + 3);
          t.insert(t.end(), fi.contact.normal.data(), fi.contact.normal.data() + 3);
          t.insert(t.end(), qd.data(), qd.data() + qd.size());
        }
      });
  return t;
}

// Determinism: the same scenario run twice gives the same trace, value for value (MuJoCo
// steps single-threaded; the adapter and the controller keep no state between runs).
// Rotation about Y, the task that rolls the cylinder on its contacts the most.
TEST(MujocoCylinder, TheSameScenarioTwiceGivesTheSameTrace) {
  const Spec spec = cylinder_experiment(ip::PaperTask::rotate, 1);
  inhand::sim::ScenarioResult first, second;
  const std::vector<double> a = trace_of(spec, first);
  const std::vector<double> b = trace_of(spec, second);
  ASSERT_EQ(first.failure, "");
  ASSERT_EQ(first.stages.size(), 3u);
  EXPECT_GT(a.size(), 7000u * 3u);  // every tick of the 7 s of hold and task was recorded
  ASSERT_EQ(a.size(), b.size());
  std::size_t first_difference = a.size();
  for (std::size_t k = 0; k < a.size() && first_difference == a.size(); ++k)
    if (!(a[k] == b[k])) first_difference = k;
  EXPECT_EQ(first_difference, a.size())
      << "the traces differ first at value " << first_difference << ": " << a[first_difference]
      << " against " << b[first_difference];
  EXPECT_EQ(first.stages[2].rms_orientation_error, second.stages[2].rms_orientation_error);
}

}  // namespace
