// Per-stage summary of the force layer and the pose loop's integrator, for run
// summaries (summary.json "force_layer"): how far the grip rose, how long contacts
// slipped, whether the load was beyond the hand (and how long before the first contact
// the controller lost: `min_warning_lead`, expectations.hpp), and how the integrators moved.
//
// Drift of an integrator: the change of its state per second over the part of the
// stage after its first `settle_time` seconds (10 s by default), |x(end) - x(t0 + 10)| /
// (end - t0 - 10); null when the stage is not longer than that. A ramp (two
// integrators fighting along one direction) shows as a drift that does not vanish.
// Units: grip dimensionless; forces N, torques N m; force integrals N s; pose
// integrals m s (position) and rad s (orientation); drifts per second.
#pragma once

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/math/types.hpp"

namespace inhand::examples {

template <int Dim>
struct ForceLayerStageSummary {
  std::string stage;
  double duration = 0.0;  ///< s
  double max_grip = 1.0, final_grip = 1.0;
  long slip_ticks = 0;  ///< ticks with any finger slipping
  long beyond_capacity_ticks = 0;
  double first_beyond_capacity = -1.0;  ///< s into the stage, -1: never
  long object_astray_ticks = 0;         ///< ticks with ControllerWarning::object_astray
  double first_object_astray = -1.0;    ///< s into the stage, -1: never
  /// s into the stage of the first tick a finger was FingerState::reacquiring (the
  /// controller lost its contact: ControllerStatus::contact_lost), -1: never
  double first_contact_lost = -1.0;
  double max_abs_force_integral = 0.0;  ///< N s, over fingers and ticks
  Twist<double, Dim> final_load = Twist<double, Dim>::Zero();
  Twist<double, Dim> final_pose_integral = Twist<double, Dim>::Zero();
  double force_integral_drift = -1.0;  ///< N s per s (largest finger), -1: stage too short
  double pose_integral_drift = -1.0;   ///< (m s | rad s) per s, -1: stage too short
};

/// Accumulates ForceLayerStageSummary from the controller's Output tick by tick.
template <int Dim>
class ForceLayerSummaryAccumulator {
 public:
  explicit ForceLayerSummaryAccumulator(double settle_time = 10.0) : settle_(settle_time) {}

  /// One tick: stage index and name, time since the stage began [s], the Output.
  template <typename Output>
  void add(int stage, const std::string& name, double stage_time, const Output& out) {
    if (stages_.empty() || stage != current_) {
      stages_.emplace_back();
      stages_.back().stage = name;
      current_ = stage;
      marked_ = false;
    }
    ForceLayerStageSummary<Dim>& s = stages_.back();
    s.duration = stage_time;
    s.max_grip = std::max(s.max_grip, out.grip);
    s.final_grip = out.grip;
    if (has(out.warnings, ControllerWarning::slipping)) ++s.slip_ticks;
    if (has(out.warnings, ControllerWarning::beyond_capacity)) {
      if (s.beyond_capacity_ticks == 0) s.first_beyond_capacity = stage_time;
      ++s.beyond_capacity_ticks;
    }
    if (has(out.warnings, ControllerWarning::object_astray)) {
      if (s.object_astray_ticks == 0) s.first_object_astray = stage_time;
      ++s.object_astray_ticks;
    }
    for (const auto& f : out.fingers)
      if (f.state == FingerState::reacquiring && s.first_contact_lost < 0.0)
        s.first_contact_lost = stage_time;
    integrals_.resize(out.fingers.size());
    for (std::size_t i = 0; i < out.fingers.size(); ++i) {
      integrals_[i] = out.fingers[i].force_integral;
      s.max_abs_force_integral = std::max(s.max_abs_force_integral, std::abs(integrals_[i]));
    }
    s.final_load = out.load_estimate;
    s.final_pose_integral = out.pose_error_integral;
    if (!marked_ && stage_time >= settle_) {
      marked_ = true;
      mark_time_ = stage_time;
      mark_integrals_ = integrals_;
      mark_pose_ = out.pose_error_integral;
    }
    if (marked_ && stage_time > mark_time_) {
      const double dt = stage_time - mark_time_;
      double worst = 0.0;
      for (std::size_t i = 0; i < integrals_.size() && i < mark_integrals_.size(); ++i)
        worst = std::max(worst, std::abs(integrals_[i] - mark_integrals_[i]));
      s.force_integral_drift = worst / dt;
      s.pose_integral_drift = (out.pose_error_integral - mark_pose_).norm() / dt;
    }
  }
  const std::vector<ForceLayerStageSummary<Dim>>& stages() const noexcept { return stages_; }

 private:
  double settle_;
  std::vector<ForceLayerStageSummary<Dim>> stages_;
  int current_ = -1;
  bool marked_ = false;
  double mark_time_ = 0.0;
  std::vector<double> integrals_, mark_integrals_;
  Twist<double, Dim> mark_pose_ = Twist<double, Dim>::Zero();
};

}  // namespace inhand::examples
