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
#include <string>

#include "common/test_support.hpp"
#include "inhand/sim/paper_scenarios.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "mujoco_adapter.hpp"

namespace {

namespace md = inhand::mujoco_demo;
namespace ip = inhand::plant;
using Spec = inhand::sim::ScenarioSpec<md::MujocoAdapter>;

Spec cylinder_translation(int axis) {
  const ip::ScenarioSpec paper =
      ip::paper_scenario(ip::PaperObject::cylinder, ip::PaperTask::translate, axis);
  Spec s;
  s.name = paper.name;
  s.stages = paper.stages;
  s.tolerances = paper.tolerances;
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
  const inhand::sim::ScenarioResult r = run(cylinder_translation(0), &displacement);
  for (const ip::StageMetrics& m : r.stages) record_stage(m);
  inhand_test::record("link_contact_ticks", r.link_contacts);
  inhand_test::record("grasp_object_displacement_m", displacement);
  ASSERT_GE(r.stages.size(), 1u);
  EXPECT_LT(displacement, 1e-4);  // m, held by the weld under gravity and the fingertips
  EXPECT_FALSE(r.stages[0].dropped);
}

// The paper's bounds on MuJoCo. Disabled: the controller does not complete the grasp on
// this hand yet. Measured (kv 0.05, the model's): every fingertip reaches the cylinder
// (about 0.5 s), then its contact is made and lost every 3-6 ms (touching toggles, the
// finger state between approaching and pressing) with normal forces of 0.06-0.6 N against
// the 1 N target; the grasp stage times out at 3 s with an RMS force error of 0.92 N.
// Freezing the object by restoring its pose each step instead of the weld: the same
// (0.89 N). With kv 0.5 (ten times stiffer servos) the RMS force error is 0.61 N and the
// grasp still times out; with kv 0.005 the servos do not bring the fingertips to the
// object within 3 s.
TEST(MujocoCylinder, DISABLED_TranslationAlongXWithinThePaperBounds) {
  const inhand::sim::ScenarioResult r = run(cylinder_translation(0));
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

}  // namespace
