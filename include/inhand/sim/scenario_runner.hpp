// Closed-loop scenarios, the runner, for any plant behind the adapter interface of
// plant_interface.hpp: the reactive controller driving the plant's hand through the
// stages of a ScenarioSpec (scenario_spec.hpp), with per-stage metrics. Each control
// period (the controller's), in this order:
//   sense (joint angles, measured object pose, tactile) -> sensing faults ->
//   controller.update() -> fault bookkeeping -> joint-velocity commands (the plant's
//   own command faults inside command(), then finger_away) -> plant.step(control_period)
//   -> metrics.
// Metrics: sim/metrics.hpp (true pose against desired, true forces against the plan,
// slip, contact losses after the grasp, drop). Units and frames: the plant's.
#pragma once

#include <cmath>
#include <cstddef>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "inhand/sim/fault_injection.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/plant_interface.hpp"
#include "inhand/sim/scenario_spec.hpp"

namespace inhand::sim {

template <class Adapter>
class ScenarioRunner {
  static_assert(PlantAdapterCheck<Adapter>::value, "not a plant adapter");

 public:
  static constexpr int dim = Adapter::dim;
  using Controller = typename Adapter::Controller;
  using Spec = ScenarioSpec<Adapter>;
  using Record = TickRecord<Adapter>;
  using TickObserver = std::function<void(const Record&)>;

  /// Runs the scenario; throws std::invalid_argument on an invalid specification.
  ScenarioResult run(const Spec& spec, const TickObserver& observer = {}) const;

 private:
  /// Starts stage `st`: the grasp (object frozen) or the stage's trajectory from
  /// `desired_end`; sets the stage's duration. False (and result.failure) if the
  /// controller refuses the trajectory; throws on an invalid segment or grasp target.
  static bool start_stage(const StageSpec<dim>& st, Adapter& adapter, Controller& controller,
                          const Pose<double, dim>& desired_end, double& stage_duration,
                          ScenarioResult& result) {
    if (st.kind == plant::StageKind::grasp) {
      adapter.set_frozen(true);
      const Validation g = controller.start_grasp(adapter.grasp_targets());
      if (!g.ok()) throw std::invalid_argument(std::string("grasp targets: ") + g.field);
      return true;
    }
    if (st.release) adapter.set_frozen(false);
    typename Controller::Trajectory traj;
    traj.reset(desired_end);
    if (st.kind == plant::StageKind::hold) {
      traj.append(TrajectorySegment<double, dim>::hold_for(st.duration));
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
      return false;
    }
    return true;
  }
};

// Defined out of the class (not inline): a build may then compile ScenarioRunner<A>::run
// once, declaring it `extern template` elsewhere.
template <class Adapter>
ScenarioResult ScenarioRunner<Adapter>::run(const Spec& spec, const TickObserver& observer) const {
  Adapter adapter(spec);
  Controller controller;
  const typename Controller::Config cfg = adapter.controller_config(spec.controller);
  const Validation v = controller.configure(cfg);
  if (!v.ok()) throw std::invalid_argument(std::string("controller: ") + v.field + ": " + v.reason);
  const double dt = cfg.control_period;
  typename Controller::Input in = controller.make_input();
  typename Controller::Output out = controller.make_output();
  const int n = adapter.finger_count();

  ScenarioResult result;
  FaultInjector<dim> faults(spec.faults, spec.stages, n, Adapter::fault_conventions, result.faults);
  Pose<double, dim> desired_end = adapter.object_pose();  // the last stage's final desired pose
  std::vector<plant::FingerTruth> truth(static_cast<std::size_t>(n));
  auto read_truth = [&]() {
    for (int i = 0; i < n; ++i) {
      plant::FingerTruth& ft = truth[static_cast<std::size_t>(i)];
      ft = adapter.truth(i);
      ft.desired_force = out.fingers[static_cast<std::size_t>(i)]
                             .force_target;  // what the force loop drives to (force_layer.hpp)
    }
  };
  read_truth();
  bool grasp_done = false;
  double t = 0.0;
  long global_tick = 0;
  plant::StageMetricsAccumulator acc;
  for (std::size_t si = 0; si < spec.stages.size(); ++si) {
    const StageSpec<dim>& st = spec.stages[si];
    const bool grasp = st.kind == plant::StageKind::grasp;
    acc.begin(st.name, st.kind, t, truth, spec.tolerances, grasp_done);
    double stage_duration = st.duration;
    if (!start_stage(st, adapter, controller, desired_end, stage_duration, result)) {
      result.stages.push_back(acc.finish(t, false));
      break;
    }
    const long ticks = std::lround(stage_duration / dt);
    const double stage_start = t;
    bool grasped = false;
    for (long k = 0; k < ticks; ++k) {
      adapter.sense();
      in.time = t + dt;  // strictly increasing, starts at dt
      in.object_pose = adapter.measured_object_pose();
      for (int i = 0; i < n; ++i) {
        auto& fi = in.fingers[static_cast<std::size_t>(i)];
        fi.joint_positions = adapter.joint_positions(i);
        const auto r = adapter.tactile(i);
        fi.contact.touching = r.touching;
        if (r.touching) {
          fi.contact.contact_point = r.contact_point;
          fi.contact.normal = r.normal;
          fi.contact.normal_force = r.normal_force;
        }
      }
      const double ts = t - stage_start;  // stage time at the start of this tick
      adapter.set_object_force(faults.inject(in, st.name, ts, global_tick, t));
      const ControllerStatus status = controller.update(in, out);
      faults.observe(out, status, controller, st.name, ts, global_tick);
      ++global_tick;
      const TickClock clock{static_cast<int>(si), ts, dt};
      for (int i = 0; i < n; ++i)
        adapter.command(i, out.fingers[static_cast<std::size_t>(i)].joint_velocities, clock);
      faults.for_each_away([&](int f) { adapter.command_towards_open(f, 5.0); });
      adapter.step(dt);
      t += dt;

      const Pose<double, dim> actual = adapter.object_pose();
      const Pose<double, dim> desired = grasp ? actual : out.desired_object_pose;
      double ep = 0.0, er = 0.0;
      plant::pose_errors<dim>(desired, actual, ep, er);
      read_truth();
      if (status == ControllerStatus::invalid_input)
        for (auto& ft : truth) ft.desired_force = 0.0;
      acc.add_tick(t - stage_start, ep, er, truth, out.force_residual.norm());
      const bool done = grasp && status == ControllerStatus::grasped;
      if (observer) {
        Record rec;
        rec.time = t;
        rec.stage = static_cast<int>(si);
        rec.stage_time = t - stage_start;
        rec.stage_end = k + 1 == ticks || done;
        rec.desired = &desired;
        rec.actual = &actual;
        rec.input = &in;
        rec.output = &out;
        rec.status = status;
        rec.plant = &adapter.model();
        observer(rec);
      }
      if (done) {
        grasped = true;
        break;
      }
    }
    const bool completed = !grasp || grasped;
    plant::StageMetrics m = acc.finish(t, completed);
    if (grasp) {
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
  result.link_contacts = adapter.link_contacts();
  return result;
}

}  // namespace inhand::sim
