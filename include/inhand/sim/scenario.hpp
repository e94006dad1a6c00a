// Closed-loop scenarios: the reactive controller driving a hand of the analytic plant
// through the paper's stages (method.md sections 8-9), with per-stage metrics.
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
// The controller runs every `control_period` on sensed data (plant.sample_sensors(),
// tactile(), measured_object_pose()); the plant integrates with its own smaller step.
// Metrics: sim/metrics.hpp (true pose against desired, true forces against the
// plan, slip, contact losses after the grasp, drop).
// Units SI, world frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
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

class ScenarioRunner {
 public:
  using TickObserver = std::function<void(const TickRecord&)>;

  /// Runs the scenario; throws std::invalid_argument on an invalid specification.
  ScenarioResult run(const ScenarioSpec& spec, const TickObserver& observer = {}) const {
    HandPlant plant(spec.hand.fingers, spec.object, spec.plant);
    for (int i = 0; i < plant.finger_count(); ++i)
      plant.set_joint_positions(i, spec.hand.open_configuration[static_cast<std::size_t>(i)]);
    HandController controller;
    const HandController::Config cfg = controller_config_for(spec.hand, spec.controller);
    const Validation v = controller.configure(cfg);
    if (!v.ok())
      throw std::invalid_argument(std::string("controller: ") + v.field + ": " + v.reason);
    const double dt = cfg.control_period;
    HandController::Input in = controller.make_input();
    HandController::Output out = controller.make_output();
    const int n = plant.finger_count();

    ScenarioResult result;
    Pose<double, 3> desired_end = spec.object.pose;  // desired pose the last stage ended on
    std::vector<FingerTruth> truth(static_cast<std::size_t>(n));
    auto read_truth = [&]() {
      for (int i = 0; i < n; ++i) {
        FingerTruth& ft = truth[static_cast<std::size_t>(i)];
        ft.touching = plant.contact(i).active;
        ft.normal_force = plant.contact(i).normal_force;
        ft.slip_distance = plant.contact(i).slip_distance;
        ft.desired_force = out.fingers[static_cast<std::size_t>(i)]
                               .force_target;  // what the force loop drives to (force_layer.hpp)
      }
    };
    read_truth();
    bool grasp_done = false;
    double t = 0.0;
    StageMetricsAccumulator acc;
    struct FaultTracking {
      long start_tick = -1, end_tick = -1;
      bool window_over = false, away = false;
    };
    std::vector<FaultTracking> fault_state(spec.faults.size());
    result.faults.resize(spec.faults.size());
    for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
      const FaultSpec& fs = spec.faults[fi];
      if (fs.finger < 0 || fs.finger >= n)
        throw std::invalid_argument("fault: finger index out of range");
      if (!(fs.duration >= 0.0) || !(fs.at >= 0.0))
        throw std::invalid_argument("fault: negative time");
      result.faults[fi].kind = fs.kind;
      result.faults[fi].finger = fs.finger;
    }
    long global_tick = 0;
    for (std::size_t si = 0; si < spec.stages.size(); ++si) {
      const StageSpec& st = spec.stages[si];
      acc.begin(st.name, st.kind, t, truth, spec.tolerances, grasp_done);
      double stage_duration = st.duration;
      if (st.kind == StageSpec::Kind::grasp) {
        plant.set_frozen(true);
        const auto targets = model_free_grasp_targets(spec.hand, plant.object_pose());
        const Validation g = controller.start_grasp(targets);
        if (!g.ok()) throw std::invalid_argument(std::string("grasp targets: ") + g.field);
      } else {
        if (st.release) plant.set_frozen(false);
        HandController::Trajectory traj;
        traj.reset(desired_end);
        if (st.kind == StageSpec::Kind::hold) {
          traj.append(TrajectorySegment<double, 3>::hold_for(st.duration));
        } else {
          stage_duration = st.settle;
          for (const auto& seg : st.segments) {
            if (!traj.append(seg))
              throw std::invalid_argument("invalid trajectory segment in " + st.name);
            stage_duration += seg.duration;
          }
        }
        const Validation s = controller.start_manipulation(traj);
        if (!s.ok()) {
          result.failure = "stage '" + st.name + "' could not start: " + s.reason;
          result.stages.push_back(acc.finish(t, false));
          break;
        }
      }
      const long ticks = std::lround(stage_duration / dt);
      const double stage_start = t;
      bool grasped = false;
      for (long k = 0; k < ticks; ++k) {
        plant.sample_sensors();
        in.time = t + dt;  // strictly increasing, starts at dt
        in.object_pose = plant.measured_object_pose();
        for (int i = 0; i < n; ++i) {
          auto& fi = in.fingers[static_cast<std::size_t>(i)];
          fi.joint_positions = plant.joint_positions(i);
          const TactileReading r = plant.tactile(i);
          fi.contact.touching = r.touching;
          if (r.touching) {
            fi.contact.contact_point = r.contact_point;
            fi.contact.normal = r.normal;
            fi.contact.normal_force = r.normal_force;
          }
        }
        // Injected faults: sensing corruption before the controller sees the data,
        // disturbances and overridden commands after.
        const double ts = t - stage_start;  // stage time at the start of this tick
        Eigen::Vector3d knock_force = Eigen::Vector3d::Zero();
        for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
          const FaultSpec& fs = spec.faults[fi];
          if (fs.stage != st.name || ts + 1e-12 < fs.at || ts >= fs.at + fs.duration) continue;
          auto& finger_in = in.fingers[static_cast<std::size_t>(fs.finger)];
          switch (fs.kind) {
            case FaultSpec::Kind::tactile_dropout:
              finger_in.contact.touching = false;
              break;
            case FaultSpec::Kind::force_spike:
              if (finger_in.contact.touching) finger_in.contact.normal_force += fs.magnitude;
              break;
            case FaultSpec::Kind::pose_outlier:
              in.object_pose.position += fs.vector;
              break;
            case FaultSpec::Kind::knock:
              knock_force += fs.vector;
              break;
            case FaultSpec::Kind::finger_away:
              break;
          }
          if (fault_state[fi].start_tick < 0) {
            fault_state[fi].start_tick = global_tick;
            result.faults[fi].start_time = t;
          }
        }
        plant.set_external_wrench(knock_force, Eigen::Vector3d::Zero());
        const ControllerStatus status = controller.update(in, out);
        for (int i = 0; i < n; ++i)
          plant.set_joint_velocity_command(
              i, out.fingers[static_cast<std::size_t>(i)].joint_velocities);
        for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
          const FaultSpec& fs = spec.faults[fi];
          FaultTracking& ft = fault_state[fi];
          FaultReport& fr = result.faults[fi];
          if (ft.start_tick < 0) continue;
          const bool active =
              fs.stage == st.name && ts + 1e-12 >= fs.at && ts < fs.at + fs.duration;
          if (fs.kind == FaultSpec::Kind::finger_away &&
              (active || fs.duration <= 0.0 || ft.away)) {
            ft.away = true;  // stays away for the rest of the run
            const int f = fs.finger;
            PlantFinger::JointVector qd =
                5.0 * (spec.hand.open_configuration[static_cast<std::size_t>(f)] -
                       plant.joint_positions(f));
            plant.set_joint_velocity_command(f, qd);
          }
          bool reported = false;
          switch (fs.kind) {
            case FaultSpec::Kind::pose_outlier:
              reported = has(out.warnings, ControllerWarning::pose_outlier);
              break;
            case FaultSpec::Kind::force_spike:
              reported = has(out.warnings, ControllerWarning::force_outlier);
              break;
            case FaultSpec::Kind::tactile_dropout:
              reported = out.fingers[static_cast<std::size_t>(fs.finger)].state ==
                         FingerState::reacquiring;
              break;
            default:
              reported = status == ControllerStatus::contact_lost;
              break;
          }
          if (reported && fr.detection_ticks < 0) fr.detection_ticks = global_tick - ft.start_tick;
          if (!active && !ft.window_over) {
            ft.window_over = true;
            ft.end_tick = global_tick;
          }
          if (ft.window_over && fr.reacquire_ticks < 0 && status == ControllerStatus::ok &&
              (fs.kind == FaultSpec::Kind::tactile_dropout || fs.kind == FaultSpec::Kind::knock))
            fr.reacquire_ticks = global_tick - ft.end_tick;
          fr.max_force_integral = std::max(fr.max_force_integral, controller.max_force_integral());
        }
        ++global_tick;
        plant.step(dt);
        t += dt;

        const Pose<double, 3>& actual = plant.object_pose();
        const Pose<double, 3>& desired =
            st.kind == StageSpec::Kind::grasp ? plant.object_pose() : out.desired_object_pose;
        double ep = 0.0, er = 0.0;
        pose_errors<3>(desired, actual, ep, er);
        read_truth();
        if (status == ControllerStatus::invalid_input)
          for (auto& ft : truth) ft.desired_force = 0.0;
        acc.add_tick(t - stage_start, ep, er, truth, out.force_residual.norm());
        if (observer) {
          TickRecord rec;
          rec.time = t;
          rec.stage = static_cast<int>(si);
          rec.desired = &desired;
          rec.actual = &actual;
          rec.input = &in;
          rec.output = &out;
          rec.status = status;
          rec.plant = &plant;
          observer(rec);
        }
        if (st.kind == StageSpec::Kind::grasp && status == ControllerStatus::grasped) {
          grasped = true;
          break;
        }
      }
      const bool completed = st.kind != StageSpec::Kind::grasp || grasped;
      StageMetrics m = acc.finish(t, completed);
      if (st.kind == StageSpec::Kind::grasp) {
        grasp_done = grasped;
      } else {
        desired_end = out.desired_object_pose;
        result.contact_losses += m.contact_losses;
      }
      result.dropped = result.dropped || m.dropped;
      result.stages.push_back(m);
      if (!completed) {
        result.failure = "grasp stage '" + st.name + "' timed out";
        break;
      }
    }
    return result;
  }
};

}  // namespace inhand::plant

namespace inhand::plant {

enum class PaperObject { cylinder, slender_box };
enum class PaperTask { translate, rotate };

/// One of the paper's 12 experiments (method.md section 9): object x {translate,
/// rotate} x axis (0 = X, 1 = Y, 2 = Z of the reference frame). Stage 0 grasps at the
/// nominal force with the object frozen, stage 1 releases and holds, stage 2 moves
/// 5 mm along the axis and back, or rotates 0 -> -0.2 rad -> 0 about it.
inline ScenarioSpec paper_scenario(PaperObject object, PaperTask task, int axis,
                                   double cycle_duration = 4.0) {
  ScenarioSpec s;
  s.hand = shadow_like_hand();
  s.object = object == PaperObject::cylinder ? paper_cylinder(s.hand) : paper_slender_box(s.hand);
  static const char* names[] = {"x", "y", "z"};
  s.name = std::string(object == PaperObject::cylinder ? "cylinder" : "box") + "_" +
           (task == PaperTask::translate ? "translate_" : "rotate_") + names[axis];
  StageSpec grasp;
  grasp.name = "grasp";
  grasp.kind = StageSpec::Kind::grasp;
  grasp.duration = 3.0;
  StageSpec hold;
  hold.name = "hold";
  hold.kind = StageSpec::Kind::hold;
  hold.release = true;
  hold.duration = 2.0;
  StageSpec manip;
  manip.name = "manipulate";
  manip.kind = StageSpec::Kind::manipulate;
  manip.settle = 1.0;
  Twist<double, 3> d = Twist<double, 3>::Zero();
  if (task == PaperTask::translate)
    d(axis) = 0.005;
  else
    d(3 + axis) = -0.2;
  manip.segments.push_back(TrajectorySegment<double, 3>::reciprocate(d, cycle_duration, 1));
  s.stages = {grasp, hold, manip};
  return s;
}

}  // namespace inhand::plant
