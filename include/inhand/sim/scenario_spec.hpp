// Closed-loop scenarios, the specification: the hand, the object, the plant and
// controller settings, the stages (docs/method.md sections 8-9), injected faults and what a
// run reports (scenario_runner.hpp runs one).
//
// Stages, each a StageSpec:
//   grasp      : the object is frozen; start_grasp() towards one target per finger
//                (the preset's approach point on the object's central plane, approached
//                along the preset's nominal normal: the controller does not use the
//                object's geometry); ends when the controller reports `grasped`, or
//                fails at `duration` (grasp timeout).
//   hold       : `release` unfreezes the object at the stage start; the task is to keep
//                the pose the object had when the stage began (the paper's stage 1).
//   manipulate : the stage's trajectory segments (layer 1), from the desired pose the
//                previous stage ended on, then `settle` seconds of hold.
// Units SI (s, m, N, rad), world frame; fault times are relative to their stage's start.
#pragma once

#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/hand_plant.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/presets.hpp"

namespace inhand::plant {

/// The controller type used with plant hands: any finger count, up to 6 joints each.
using HandController = ReactiveController<double, 3, Dynamic, Dynamic, 6>;

struct StageSpec {
  using Kind = StageKind;
  std::string name = "stage";
  Kind kind = Kind::hold;
  /// grasp: timeout; hold: duration; manipulate: ignored (segments + settle).
  double duration = 1.0;
  bool release = false;  ///< hold: unfreeze the object when the stage starts
  std::vector<TrajectorySegment<double, 3>> segments;  ///< manipulate
  double settle = 0.5;  ///< manipulate: hold time after the last segment [s]
};

/// A fault injected into a run (method robustness: sensing faults and disturbances).
/// Times are relative to the start of the named stage.
///   tactile_dropout : finger's tactile signal reads "not touching" for `duration`
///   force_spike     : finger's measured normal force += `magnitude` N for `duration`
///   pose_outlier    : measured object position += `vector` (m) for `duration`
///   knock           : external force `vector` (N, world) on the object for `duration`
///   finger_away     : finger's command replaced by a motion back to its open posture
///                     (the object should drop: the negative test)
struct FaultSpec {
  enum class Kind { tactile_dropout, force_spike, pose_outlier, knock, finger_away };
  Kind kind = Kind::tactile_dropout;
  std::string stage = "manipulate";
  double at = 0.5;         ///< s into the stage
  double duration = 0.05;  ///< s
  int finger = 0;
  double magnitude = 0.0;
  Eigen::Vector3d vector = Eigen::Vector3d::Zero();
};
inline const char* to_string(FaultSpec::Kind k) noexcept {
  switch (k) {
    case FaultSpec::Kind::tactile_dropout:
      return "tactile_dropout";
    case FaultSpec::Kind::force_spike:
      return "force_spike";
    case FaultSpec::Kind::pose_outlier:
      return "pose_outlier";
    case FaultSpec::Kind::knock:
      return "knock";
    case FaultSpec::Kind::finger_away:
      return "finger_away";
  }
  return "unknown";
}

/// What the controller made of an injected fault.
struct FaultReport {
  FaultSpec::Kind kind = FaultSpec::Kind::tactile_dropout;
  int finger = 0;
  double start_time = 0.0;  ///< s, scenario time
  /// Ticks from the fault's start until the controller reported it: the finger in
  /// `reacquiring` (dropout, knock, finger away: any finger), or the pose_outlier /
  /// force_outlier warning. -1: never reported.
  long detection_ticks = -1;
  /// Dropout/knock: ticks after the fault window until every finger was in contact
  /// again (-1: not within the run).
  long reacquire_ticks = -1;
  /// Largest |force integral| of any finger's servo seen from the start of the fault (N s).
  double max_force_integral = 0.0;
};

struct ScenarioSpec {
  std::string name = "scenario";
  HandPreset hand = shadow_like_hand();
  ObjectDef object{};  ///< pose relative to nothing: world frame
  PlantParams plant = default_plant_params();
  HandController::Config controller{};  ///< fingers are filled from `hand`
  std::vector<StageSpec> stages;
  std::vector<FaultSpec> faults;
  MetricsTolerances tolerances{};
};

struct ScenarioResult {
  std::vector<StageMetrics> stages;
  bool dropped = false;
  int contact_losses = 0;  ///< after the grasp stage
  std::string failure;     ///< empty on success; otherwise why the run stopped early
  std::vector<FaultReport> faults;
};

/// One control tick as seen by a trace writer.
struct TickRecord {
  double time = 0.0;
  int stage = 0;
  const Pose<double, 3>* desired = nullptr;
  const Pose<double, 3>* actual = nullptr;
  const HandController::Input* input = nullptr;
  const HandController::Output* output = nullptr;
  ControllerStatus status = ControllerStatus::idle;
  const HandPlant* plant = nullptr;
};

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
}  // namespace inhand::plant
