// Closed-loop scenarios, the runner: the reactive controller driving a hand of the
// analytic plant through the stages of a ScenarioSpec (scenario_spec.hpp), with
// per-stage metrics. The controller runs every `control_period` on sensed data
// (plant.sample_sensors(), tactile(), measured_object_pose()); the plant integrates
// with its own smaller step. Injected faults corrupt the sensed data before the
// controller sees it, or add disturbances and override commands after.
// Metrics: sim/metrics.hpp (true pose against desired, true forces against the plan,
// slip, contact losses after the grasp, drop).
// Units SI (s, m, N, rad), world frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "inhand/sim/hand_plant.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/scenario_spec.hpp"

namespace inhand::plant {

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
