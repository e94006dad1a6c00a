// Closed-loop scenarios on the analytic plant (hand_plant.hpp): its adapter for the
// generic runner (plant_interface.hpp) and the names the plant's users know:
// plant::ScenarioSpec, StageSpec, FaultSpec, FaultReport, ScenarioResult, TickRecord,
// ScenarioRunner.
// The hand is a HandPreset (presets.hpp), any finger count, up to 6 joints each; the
// thumb balances the forces, the others are preset. Sensing is the plant's: noisy
// tactile readings and "vision" (measured_object_pose()), sampled once per control
// period; the joint angles are exact. Units SI (s, m, N, rad), world frame.
#pragma once

#include <cstddef>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/hand_plant.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/plant_interface.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "inhand/sim/scenario_spec.hpp"

namespace inhand::plant {

/// The controller type used with plant hands: any finger count, up to 6 joints each.
using HandController = ReactiveController<double, 3, Dynamic, Dynamic, 6>;

/// Fills controller.fingers from the hand (the thumb balances, the others are preset).
inline HandController::Config controller_config_for(const HandPreset& hand,
                                                    HandController::Config base) {
  base.fingers.clear();
  for (std::size_t i = 0; i < hand.fingers.size(); ++i) {
    HandController::FingerConfig f;
    f.chain = hand.fingers[i];
    f.role = static_cast<int>(i) == hand.thumb ? FingerRole::balancing : FingerRole::preset;
    base.fingers.push_back(f);
  }
  return base;
}

/// Grasp targets that need no object model: each finger aims at its approach point
/// (on the object's central plane) along the preset's nominal normal.
inline std::vector<GraspTarget<double, 3>> model_free_grasp_targets(const HandPreset& hand,
                                                                    const Pose<double, 3>& object) {
  std::vector<GraspTarget<double, 3>> t(hand.fingers.size());
  for (std::size_t i = 0; i < t.size(); ++i) {
    // The preset's approach geometry is given for its nominal object pose; carry it
    // with the object's actual pose.
    const Pose<double, 3> rel = object * hand.object_pose.inverse();
    t[i].contact_point = rel.transform_point(hand.approach_points[i]);
    t[i].normal = rel.rotation * hand.approach_directions[i];
  }
  return t;
}

/// The analytic plant's part of a scenario.
struct HandSetup {
  HandPreset hand = shadow_like_hand();
  ObjectDef object{};  ///< pose relative to nothing: world frame
  PlantParams plant = default_plant_params();
};

/// The analytic plant behind the runner's interface (plant_interface.hpp).
class HandPlantAdapter : public sim::PlantTypes<3, HandController, HandSetup, HandPlant> {
 public:
  static constexpr sim::FaultConventions fault_conventions{0.0, false, 0.0};

  /// The plant with every finger in the hand's open configuration.
  explicit HandPlantAdapter(const Setup& s) : setup_(s), plant_(s.hand.fingers, s.object, s.plant) {
    for (int i = 0; i < plant_.finger_count(); ++i)
      plant_.set_joint_positions(i, s.hand.open_configuration[static_cast<std::size_t>(i)]);
  }

  Controller::Config controller_config(const Controller::Config& base) const {
    return controller_config_for(setup_.hand, base);
  }
  std::vector<GraspTarget<double, 3>> grasp_targets() const {
    return model_free_grasp_targets(setup_.hand, plant_.object_pose());
  }
  int finger_count() const noexcept { return plant_.finger_count(); }

  void sense() noexcept { plant_.sample_sensors(); }
  Pose<double, 3> measured_object_pose() const noexcept { return plant_.measured_object_pose(); }
  const HandPlant::JointVector& joint_positions(int i) const noexcept {
    return plant_.joint_positions(i);
  }
  TactileReading tactile(int i) const noexcept { return plant_.tactile(i); }

  void set_object_force(const Eigen::Vector3d& f) noexcept {
    plant_.set_external_wrench(f, Eigen::Vector3d::Zero());
  }
  template <class V>
  void command(int i, const V& qd, const sim::TickClock& /*clock*/) noexcept {
    plant_.set_joint_velocity_command(i, qd);
  }
  void command_towards_open(int i, double gain) noexcept {
    const PlantFinger::JointVector qd =
        gain *
        (setup_.hand.open_configuration[static_cast<std::size_t>(i)] - plant_.joint_positions(i));
    plant_.set_joint_velocity_command(i, qd);
  }
  void step(double dt) noexcept { plant_.step(dt); }
  void set_frozen(bool frozen) noexcept { plant_.set_frozen(frozen); }

  const Pose<double, 3>& object_pose() const noexcept { return plant_.object_pose(); }
  FingerTruth truth(int i) const noexcept {
    FingerTruth t;
    t.touching = plant_.contact(i).active;
    t.normal_force = plant_.contact(i).normal_force;
    t.slip_distance = plant_.contact(i).slip_distance;
    return t;
  }
  int link_contacts() const noexcept { return 0; }  ///< fingertip contacts only
  const HandPlant& model() const noexcept { return plant_; }

 private:
  const Setup& setup_;
  HandPlant plant_;
};

using StageSpec = sim::StageSpec<3>;
using FaultSpec = sim::FaultSpec<3>;
using sim::FaultReport;
using sim::ScenarioResult;
using sim::to_string;
using ScenarioSpec = sim::ScenarioSpec<HandPlantAdapter>;
using TickRecord = sim::TickRecord<HandPlantAdapter>;
using ScenarioRunner = sim::ScenarioRunner<HandPlantAdapter>;

}  // namespace inhand::plant
