// Closed-loop scenarios, the specification, for any plant (plant_interface.hpp): the
// stages (docs/method.md sections 8-9), injected faults, what a run reports and what a
// trace writer sees each tick. The plant's own part of a scenario (hand, object, plant
// settings) is the adapter's Setup, a base of ScenarioSpec; scenario_runner.hpp runs one.
//
// Stages, each a StageSpec:
//   grasp      : the object is frozen; start_grasp() towards the adapter's model-free
//                targets (one per finger); ends when the controller reports `grasped`, or
//                fails at `duration` (grasp timeout).
//   hold       : `release` unfreezes the object at the stage start; the task is to keep
//                the pose the object had when the stage began (the paper's stage 1).
//   manipulate : the stage's trajectory segments (layer 1), from the desired pose the
//                previous stage ended on, then `settle` seconds of hold.
// Units: the plant's (SI for the analytic plant; the Box2D demo's lengths in u), world
// frame; fault times are relative to their stage's start.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/metrics.hpp"

namespace inhand::sim {

template <int Dim>
struct StageSpec {
  using Kind = plant::StageKind;
  std::string name = "stage";
  Kind kind = Kind::hold;
  /// grasp: timeout; hold: duration; manipulate: ignored (segments + settle).
  double duration = 1.0;
  bool release = false;  ///< hold: unfreeze the object when the stage starts
  std::vector<TrajectorySegment<double, Dim>> segments;  ///< manipulate
  double settle = 0.5;  ///< manipulate: hold time after the last segment [s]
};

/// The kinds of injected fault (method robustness: sensing faults and disturbances).
///   tactile_dropout : finger's tactile signal reads "not touching" for `duration`
///   force_spike     : finger's sensed normal force += `magnitude` N (while touching)
///   pose_outlier    : sensed object position += `vector` (length) for `duration`
///   knock           : external force `vector` (N, world) on the object's centre
///   finger_away     : finger's command replaced by a motion back to its open posture,
///                     from the fault's start to the end of the run (the object should
///                     drop: the negative test)
enum class FaultKind { tactile_dropout, force_spike, pose_outlier, knock, finger_away };

inline const char* to_string(FaultKind k) noexcept {
  switch (k) {
    case FaultKind::tactile_dropout:
      return "tactile_dropout";
    case FaultKind::force_spike:
      return "force_spike";
    case FaultKind::pose_outlier:
      return "pose_outlier";
    case FaultKind::knock:
      return "knock";
    case FaultKind::finger_away:
      return "finger_away";
  }
  return "unknown";
}

/// A fault injected into a run, active from `at` s into the stage named `stage` for
/// `duration` s (the window's end follows the plant's FaultConventions).
template <int Dim>
struct FaultSpec {
  using Kind = FaultKind;
  using Vector = Eigen::Matrix<double, Dim, 1>;
  Kind kind = Kind::tactile_dropout;
  std::string stage = "manipulate";
  double at = 0.5;         ///< s into the stage
  double duration = 0.05;  ///< s
  int finger = 0;
  double magnitude = 0.0;          ///< N, force_spike
  Vector vector = Vector::Zero();  ///< length (pose_outlier) or N (knock)
};

/// Where the two plants' fault bookkeeping has always differed; each adapter states its
/// own (plant_interface.hpp), so that a run reproduces the plant's earlier results.
struct FaultConventions {
  /// A fault is active while at <= ts + 1e-12 and ts + end_slack < at + duration
  /// (ts: stage time at the start of the tick). Analytic plant 0, Box2D 1e-12.
  double end_slack = 0.0;
  /// Reacquisition counts only once the fault was detected (Box2D: a knock's contact
  /// loss may come after its window, and an "ok" before it is no reacquisition).
  bool reacquire_after_detection = false;
  /// FaultReport::start_time of a fault that never became active (analytic 0, Box2D -1).
  double never_started_time = 0.0;
};

/// What the controller made of an injected fault.
struct FaultReport {
  FaultKind kind = FaultKind::tactile_dropout;
  int finger = 0;
  /// s, scenario time of the fault's first tick (never active: FaultConventions).
  double start_time = 0.0;
  /// Ticks from the fault's first tick to the first tick the controller reported it:
  /// tactile_dropout: that finger `reacquiring`; force_spike: the force_outlier warning;
  /// pose_outlier: the pose_outlier warning; knock, finger_away: status contact_lost.
  /// -1: never reported.
  long detection_ticks = -1;
  /// Dropout/knock: ticks after the fault window until the status is `ok` again (every
  /// finger in contact). -1: not within the run.
  long reacquire_ticks = -1;
  /// Largest |force integral| of any finger's servo seen from the start of the fault (N s).
  double max_force_integral = 0.0;
  /// Ticks on which the fault's report (as for detection_ticks) was raised.
  long reported_ticks = 0;
};

/// A scenario: the plant's Setup (its hand, object and settings) and what every plant
/// shares. Controller::Config::fingers is filled by the adapter from the Setup.
template <class Adapter>
struct ScenarioSpec : Adapter::Setup {
  static constexpr int dim = Adapter::dim;
  using Controller = typename Adapter::Controller;
  std::string name = "scenario";
  typename Controller::Config controller{};
  std::vector<StageSpec<dim>> stages;
  std::vector<FaultSpec<dim>> faults;
  plant::MetricsTolerances tolerances{};
};

struct ScenarioResult {
  std::vector<plant::StageMetrics> stages;
  bool dropped = false;
  int contact_losses = 0;  ///< after the grasp stage
  /// Ticks on which a non-sensing link touched the object, for plants that tell links
  /// from the sensing pads (Box2D; 0 for the others).
  int link_contacts = 0;
  std::string failure;              ///< empty on success; otherwise why the run stopped early
  std::vector<FaultReport> faults;  ///< one per ScenarioSpec::faults entry
};

/// One control tick as seen by trace writers and snapshot takers.
template <class Adapter>
struct TickRecord {
  using Controller = typename Adapter::Controller;
  double time = 0.0;  ///< s, end of the tick
  int stage = 0;
  double stage_time = 0.0;  ///< s since the stage started
  bool stage_end = false;   ///< last tick of the stage
  const Pose<double, Adapter::dim>* desired = nullptr;
  const Pose<double, Adapter::dim>* actual = nullptr;
  const typename Controller::Input* input = nullptr;
  const typename Controller::Output* output = nullptr;
  ControllerStatus status = ControllerStatus::idle;
  const typename Adapter::Model* plant = nullptr;  ///< the simulated plant itself
};

}  // namespace inhand::sim
