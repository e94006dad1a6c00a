// Simulator consumer compiled with strict warnings as errors (see main.cpp): the
// analytic plant with the preset hand on the paper's cylinder, and the scenario
// runner's types. Returns non-zero unless the plant advanced and touched the object.
#include <inhand/sim/scenario.hpp>

int main() {
  const inhand::plant::HandPreset hand = inhand::plant::shadow_like_hand();
  inhand::plant::HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand));
  for (int i = 0; i < plant.finger_count(); ++i)
    plant.set_joint_velocity_command(i, inhand::plant::PlantFinger::JointVector::Constant(
                                            hand.fingers[static_cast<std::size_t>(i)].dof(), 0.1));
  plant.sample_sensors();
  const int steps = plant.step(0.01);
  const inhand::plant::TactileReading reading = plant.tactile(0);
  const inhand::plant::ScenarioSpec spec = inhand::plant::paper_scenario(
      inhand::plant::PaperObject::cylinder, inhand::plant::PaperTask::translate, 0);
  (void)inhand::plant::ScenarioRunner{};
  return steps > 0 && reading.normal_force >= 0.0 && spec.stages.size() == 3 ? 0 : 1;
}
