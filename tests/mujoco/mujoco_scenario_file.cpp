// The scenario file's MuJoCo plant (examples/scenario/scenario_json.hpp: MujocoPlantFile,
// parsed without MuJoCo's headers) against the adapter it configures
// (examples/mujoco/mujoco_adapter.hpp: MujocoSetup): the same defaults, and the file's
// model name resolving to the adapter's default model.
#include <gtest/gtest.h>

#include "mujoco_adapter.hpp"
#include "scenario_json.hpp"

namespace {

namespace md = inhand::mujoco_demo;
namespace ex = inhand::examples;

TEST(MujocoScenarioFile, DefaultsAreTheAdaptersDefaults) {
  const ex::MujocoPlantFile file;
  const md::MujocoSetup setup;
  EXPECT_EQ(md::model_path(file.model), setup.model_file);
  EXPECT_EQ(file.position_gain, setup.position_gain);
  EXPECT_EQ(file.friction, setup.friction);
  EXPECT_EQ(file.torsional_friction, setup.torsional_friction);
  EXPECT_EQ(file.touch_threshold, setup.touch_threshold);
  EXPECT_EQ(file.object_mass, setup.object_mass);
  EXPECT_EQ(file.gravity_from_model, setup.gravity_from_model);
  // The hand the files name ("three_finger") is the adapter's default preset.
  EXPECT_EQ(setup.hand.finger_names, inhand::plant::three_finger_hand().finger_names);
}

// gravity_from_model tells the controller the model's opt.gravity (every shipped scene:
// 9.81 m/s^2 along -Z), replacing what the caller set; off, the caller's is kept.
TEST(MujocoScenarioFile, GravityFromModelTellsTheModelsGravity) {
  md::MujocoSetup setup;
  setup.gravity_from_model = true;
  inhand::plant::HandController::Config base{};
  base.force_layer.gravity_direction = Eigen::Vector3d(1.0, 0.0, 0.0);
  const md::MujocoAdapter told(setup);
  EXPECT_EQ(told.controller_config(base).force_layer.gravity_direction,
            Eigen::Vector3d(0.0, 0.0, -9.81));
  setup.gravity_from_model = false;
  const md::MujocoAdapter kept(setup);
  EXPECT_EQ(kept.controller_config(base).force_layer.gravity_direction,
            Eigen::Vector3d(1.0, 0.0, 0.0));
}

}  // namespace
