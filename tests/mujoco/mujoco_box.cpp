// Closed loop on MuJoCo: the paper's slender box (include/inhand/sim/paper_scenarios.hpp:
// grasp with the object frozen by a weld, release and hold 2 s, 0.2 rad about X and back
// in 4 s, 1 s settle) by the library's controller on the MJCF three-finger hand
// (models/three_finger_box.xml) through examples/mujoco/mujoco_adapter.hpp, over the
// box's mass and the contacts' friction. Units: m, rad, N, s, kg.
#include <gtest/gtest.h>

#include <string>

#include "common/controller_instances.hpp"
#include "common/test_support.hpp"
#include "inhand/sim/paper_scenarios.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "mujoco_adapter.hpp"

namespace {

namespace md = inhand::mujoco_demo;
namespace ip = inhand::plant;

// What the fixture lets go at release is the friction the grasp stored while the weld
// held the box; released, the box rolls on its contacts and the pose loop brings it
// back (docs/force_layer.md, the MuJoCo boxes at release). The press direction is
// computed from the secant contact stiffness until the stiffness fit is trusted
// (contact_observers.hpp, StiffnessEstimator::press); pressed along the servo's
// direction alone (the fit's initial max_stiffness), the hold settled in 1.09, 1.15,
// 1.39 and 1.25 s in four of these nine cases (friction 0.5 at 50, 150 and 300 g, the
// model's 0.8 at 300 g), over the paper files' 1 s; now in 0.10-0.86 s.
TEST(MujocoBox, ReleasedBoxSettlesWithinTheBoundOverMassAndFriction) {
  for (double mass : {0.05, 0.15, 0.3}) {
    for (double friction : {0.0, 0.5, 1.0}) {  // 0: the model's 0.8
      const std::string name =
          "m" + std::to_string(mass).substr(0, 4) + "_mu" + std::to_string(friction).substr(0, 3);
      SCOPED_TRACE(name);
      const ip::ScenarioSpec paper =
          ip::paper_scenario(ip::PaperObject::slender_box, ip::PaperTask::rotate, 0);
      inhand::sim::ScenarioSpec<md::MujocoAdapter> spec;
      spec.name = paper.name;
      spec.stages = paper.stages;
      spec.tolerances = paper.tolerances;
      spec.model_file = md::model_path("three_finger_box.xml");
      spec.object_mass = mass;
      spec.friction = friction;
      const inhand::sim::ScenarioResult r =
          inhand::sim::ScenarioRunner<md::MujocoAdapter>().run(spec);
      ASSERT_EQ(r.failure, "");
      ASSERT_EQ(r.stages.size(), 3u);
      inhand_test::record(name + "_hold_settle_time_s", r.stages[1].settle_time);
      inhand_test::record(name + "_hold_max_orientation_error_rad",
                          r.stages[1].max_orientation_error);
      EXPECT_FALSE(r.dropped);
      EXPECT_EQ(r.contact_losses, 0);
      EXPECT_LE(r.stages[1].settle_time, 1.0);             // s, the paper files' bound
      EXPECT_LT(r.stages[2].rms_orientation_error, 1e-2);  // rad, the paper's bound
    }
  }
}

}  // namespace
