// Injected faults during a scenario run (scenario_spec.hpp: FaultSpec, FaultReport):
// sensing corruption applied to the controller's input before update(), the knock force
// handed to the plant for the step, and after update() what the controller made of each
// fault (detection, reacquisition, force-integral windup) and which fingers are sent
// away. Used by scenario_runner.hpp, one tick at a time; plant-independent.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/scenario_spec.hpp"

namespace inhand::sim {

template <int Dim>
class FaultInjector {
 public:
  using Spec = FaultSpec<Dim>;
  using Vector = typename Spec::Vector;

  /// Checks the faults against the scenario (std::invalid_argument) and prepares one
  /// report each in `reports`.
  FaultInjector(const std::vector<Spec>& faults, const std::vector<StageSpec<Dim>>& stages,
                int finger_count, const FaultConventions& conventions,
                std::vector<FaultReport>& reports)
      : faults_(faults), conv_(conventions), reports_(reports), state_(faults.size()) {
    reports_.resize(faults_.size());
    for (std::size_t fi = 0; fi < faults_.size(); ++fi) {
      const Spec& fs = faults_[fi];
      if (fs.finger < 0 || fs.finger >= finger_count)
        throw std::invalid_argument("fault: finger index out of range");
      if (!(fs.duration >= 0.0) || !(fs.at >= 0.0))
        throw std::invalid_argument("fault: negative or NaN time");
      if (!fs.vector.allFinite() || !std::isfinite(fs.magnitude))
        throw std::invalid_argument("fault: non-finite magnitude or vector");
      if (std::none_of(stages.begin(), stages.end(),
                       [&](const StageSpec<Dim>& st) { return st.name == fs.stage; }))
        throw std::invalid_argument("fault: no stage named '" + fs.stage + "'");
      reports_[fi].kind = fs.kind;
      reports_[fi].finger = fs.finger;
      reports_[fi].start_time = conv_.never_started_time;
    }
  }

  /// Whether fault `fs` is active in stage `stage` at stage time `ts` (start of the tick).
  bool active(const Spec& fs, const std::string& stage, double ts) const noexcept {
    return fs.stage == stage && ts + 1e-12 >= fs.at && ts + conv_.end_slack < fs.at + fs.duration;
  }

  /// Corrupts the controller's input `in` with the active sensing faults and returns the
  /// knock force for this tick [N, world]. `tick`: ticks since the run began; `t`: time.
  template <class Input>
  Vector inject(Input& in, const std::string& stage, double ts, long tick, double t) {
    Vector knock = Vector::Zero();
    for (std::size_t fi = 0; fi < faults_.size(); ++fi) {
      const Spec& fs = faults_[fi];
      if (!active(fs, stage, ts)) continue;
      auto& finger_in = in.fingers[static_cast<std::size_t>(fs.finger)];
      switch (fs.kind) {
        case FaultKind::tactile_dropout:
          finger_in.contact.touching = false;
          break;
        case FaultKind::force_spike:
          if (finger_in.contact.touching) finger_in.contact.normal_force += fs.magnitude;
          break;
        case FaultKind::pose_outlier:
          in.object_pose.position += fs.vector;
          break;
        case FaultKind::knock:
          knock += fs.vector;
          break;
        case FaultKind::finger_away:
          break;
      }
      if (state_[fi].start_tick < 0) {
        state_[fi].start_tick = tick;
        reports_[fi].start_time = t;
      }
    }
    return knock;
  }

  /// After the controller's update: detection, reacquisition, windup; marks the fingers
  /// sent away (finger_away stays in force for the rest of the run).
  template <class Output, class Controller>
  void observe(const Output& out, ControllerStatus status, const Controller& controller,
               const std::string& stage, double ts, long tick) {
    for (std::size_t fi = 0; fi < faults_.size(); ++fi) {
      const Spec& fs = faults_[fi];
      Tracking& ft = state_[fi];
      FaultReport& fr = reports_[fi];
      if (ft.start_tick < 0) continue;
      const bool is_active = active(fs, stage, ts);
      if (fs.kind == FaultKind::finger_away && (is_active || fs.duration <= 0.0 || ft.away))
        ft.away = true;
      bool reported = false;
      switch (fs.kind) {
        case FaultKind::pose_outlier:
          reported = has(out.warnings, ControllerWarning::pose_outlier);
          break;
        case FaultKind::force_spike:
          reported = has(out.warnings, ControllerWarning::force_outlier);
          break;
        case FaultKind::tactile_dropout:
          reported =
              out.fingers[static_cast<std::size_t>(fs.finger)].state == FingerState::reacquiring;
          break;
        case FaultKind::knock:
        case FaultKind::finger_away:
          reported = status == ControllerStatus::contact_lost;
          break;
      }
      if (reported) ++fr.reported_ticks;
      if (reported && fr.detection_ticks < 0) fr.detection_ticks = tick - ft.start_tick;
      if (!is_active && !ft.window_over) {
        ft.window_over = true;
        ft.end_tick = tick;
      }
      if (ft.window_over && (!conv_.reacquire_after_detection || fr.detection_ticks >= 0) &&
          fr.reacquire_ticks < 0 && status == ControllerStatus::ok &&
          (fs.kind == FaultKind::tactile_dropout || fs.kind == FaultKind::knock))
        fr.reacquire_ticks = tick - ft.end_tick;
      fr.max_force_integral = std::max(fr.max_force_integral, controller.max_force_integral());
    }
  }

  /// Calls f(finger) for each finger_away fault in force, in the order of the faults.
  template <class F>
  void for_each_away(F&& f) const {
    for (std::size_t fi = 0; fi < faults_.size(); ++fi)
      if (state_[fi].away) f(faults_[fi].finger);
  }

 private:
  struct Tracking {
    long start_tick = -1, end_tick = -1;
    bool window_over = false, away = false;
  };
  const std::vector<Spec>& faults_;
  FaultConventions conv_;
  std::vector<FaultReport>& reports_;
  std::vector<Tracking> state_;
};

}  // namespace inhand::sim
