// Per-stage metrics of a manipulation run, shared by every plant (the analytic 3-D
// plant and the planar Box2D demo), so that their reports mean the same thing.
//
// Errors compare the TRUE object pose with the desired one: position error |p_d - p|
// (m), orientation error |log(R_d R^T)| (rad, planar: |angle difference|). Force error
// |f_true - f_desired| (N) over ticks on which a finger touches and its force is
// servoed (desired force > 0). Slip = growth of a finger's cumulative slip distance as
// reported by the plant (m). A contact loss is a touching -> not touching transition of
// the TRUE contact after `count_losses` was set. `dropped`: the position error exceeded
// the drop distance on some tick. settle_time: time from the stage start after which
// both errors stay within the settle tolerances until the stage end (+inf if never).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "inhand/math/pose.hpp"

namespace inhand::plant {

enum class StageKind { grasp, hold, manipulate };
inline const char* to_string(StageKind k) noexcept {
  switch (k) {
    case StageKind::grasp:
      return "grasp";
    case StageKind::hold:
      return "hold";
    case StageKind::manipulate:
      return "manipulate";
  }
  return "unknown";
}

struct FingerStageMetrics {
  double slip_distance = 0.0;  ///< m
  int contact_losses = 0;
  double max_force_error = 0.0;           ///< N
  double rms_force_error = 0.0;           ///< N
  double max_relative_force_error = 0.0;  ///< |f - f_d| / f_d
  double final_desired_force = 0.0;       ///< N
  double final_measured_force = 0.0;      ///< N
};

struct StageMetrics {
  std::string name;
  StageKind kind = StageKind::hold;
  double start_time = 0.0, end_time = 0.0;                                                ///< s
  double rms_position_error = 0.0, max_position_error = 0.0, final_position_error = 0.0;  ///< m
  double rms_orientation_error = 0.0, max_orientation_error = 0.0,
         final_orientation_error = 0.0;  ///< rad
  double max_force_error = 0.0, rms_force_error = 0.0, max_relative_force_error = 0.0;
  double settle_time = 0.0;           ///< s, see the file comment
  double final_force_residual = 0.0;  ///< |sum f_i n_i| of the plan at the end, N
  int contact_losses = 0;
  bool dropped = false;
  bool completed = true;  ///< grasp: reached `grasped` before the timeout
  std::vector<FingerStageMetrics> fingers;
};

struct MetricsTolerances {
  double drop_distance = 0.02;                 ///< m
  double settle_position_tolerance = 5e-4;     ///< m
  double settle_orientation_tolerance = 0.01;  ///< rad
};

/// What a plant reports about one finger after a tick (truth, not sensing).
struct FingerTruth {
  bool touching = false;
  double normal_force = 0.0;   ///< N, true
  double desired_force = 0.0;  ///< N, the controller's plan (0: not servoed)
  double slip_distance = 0.0;  ///< m, cumulative
};

class StageMetricsAccumulator {
 public:
  void begin(const std::string& name, StageKind kind, double start_time,
             const std::vector<FingerTruth>& fingers, const MetricsTolerances& tol,
             bool count_losses) {
    m_ = StageMetrics{};
    m_.name = name;
    m_.kind = kind;
    m_.start_time = start_time;
    m_.fingers.assign(fingers.size(), FingerStageMetrics{});
    tol_ = tol;
    count_losses_ = count_losses;
    slip0_.resize(fingers.size());
    was_touching_.resize(fingers.size());
    f2_.assign(fingers.size(), 0.0);
    fs_.assign(fingers.size(), 0);
    for (std::size_t i = 0; i < fingers.size(); ++i) {
      slip0_[i] = fingers[i].slip_distance;
      was_touching_[i] = fingers[i].touching;
    }
    sum_p2_ = sum_r2_ = sum_f2_ = 0.0;
    f_samples_ = ticks_ = 0;
    last_outside_ = 0.0;
    last_slip_ = slip0_;
  }

  /// One tick at stage-relative time `t` (end of the tick), with position and
  /// orientation errors already computed (see pose_errors()).
  void add_tick(double t, double position_error, double orientation_error,
                const std::vector<FingerTruth>& fingers, double force_residual) {
    ++ticks_;
    sum_p2_ += position_error * position_error;
    sum_r2_ += orientation_error * orientation_error;
    m_.max_position_error = std::max(m_.max_position_error, position_error);
    m_.max_orientation_error = std::max(m_.max_orientation_error, orientation_error);
    m_.final_position_error = position_error;
    m_.final_orientation_error = orientation_error;
    if (!(position_error <= tol_.drop_distance)) m_.dropped = true;
    if (!(position_error <= tol_.settle_position_tolerance) ||
        !(orientation_error <= tol_.settle_orientation_tolerance))
      last_outside_ = t;
    last_t_ = t;
    for (std::size_t i = 0; i < fingers.size() && i < m_.fingers.size(); ++i) {
      const FingerTruth& f = fingers[i];
      FingerStageMetrics& fm = m_.fingers[i];
      if (count_losses_ && was_touching_[i] && !f.touching) ++fm.contact_losses;
      was_touching_[i] = f.touching;
      if (f.touching && f.desired_force > 0.0) {
        const double fe = std::abs(f.normal_force - f.desired_force);
        fm.max_force_error = std::max(fm.max_force_error, fe);
        fm.max_relative_force_error = std::max(fm.max_relative_force_error, fe / f.desired_force);
        f2_[i] += fe * fe;
        ++fs_[i];
        sum_f2_ += fe * fe;
        ++f_samples_;
      }
      fm.final_desired_force = f.desired_force;
      fm.final_measured_force = f.normal_force;
      last_slip_[i] = f.slip_distance;
    }
    m_.final_force_residual = force_residual;
  }

  StageMetrics finish(double end_time, bool completed) {
    const double count = static_cast<double>(std::max<long>(ticks_, 1));
    m_.rms_position_error = std::sqrt(sum_p2_ / count);
    m_.rms_orientation_error = std::sqrt(sum_r2_ / count);
    m_.rms_force_error =
        f_samples_ > 0 ? std::sqrt(sum_f2_ / static_cast<double>(f_samples_)) : 0.0;
    m_.end_time = end_time;
    m_.completed = completed;
    // Outside tolerance on the last tick: never settled.
    m_.settle_time = (ticks_ > 0 && last_outside_ >= last_t_)
                         ? std::numeric_limits<double>::infinity()
                         : last_outside_;
    for (std::size_t i = 0; i < m_.fingers.size(); ++i) {
      FingerStageMetrics& fm = m_.fingers[i];
      fm.slip_distance = last_slip_[i] - slip0_[i];
      fm.rms_force_error = fs_[i] > 0 ? std::sqrt(f2_[i] / static_cast<double>(fs_[i])) : 0.0;
      m_.contact_losses += fm.contact_losses;
      m_.max_force_error = std::max(m_.max_force_error, fm.max_force_error);
      m_.max_relative_force_error =
          std::max(m_.max_relative_force_error, fm.max_relative_force_error);
    }
    return m_;
  }

 private:
  StageMetrics m_{};
  MetricsTolerances tol_{};
  bool count_losses_ = false;
  std::vector<double> slip0_, last_slip_, f2_;
  std::vector<long> fs_;
  std::vector<bool> was_touching_;
  double sum_p2_ = 0.0, sum_r2_ = 0.0, sum_f2_ = 0.0;
  long f_samples_ = 0, ticks_ = 0;
  double last_outside_ = 0.0, last_t_ = 0.0;
};

/// Position and orientation error between a desired and an actual pose.
template <int Dim>
inline void pose_errors(const Pose<double, Dim>& desired, const Pose<double, Dim>& actual,
                        double& position_error, double& orientation_error) noexcept {
  position_error = (desired.position - actual.position).norm();
  orientation_error =
      rotation_log<double>(Rotation<double, Dim>(desired.rotation * actual.rotation.transpose()))
          .norm();
}

}  // namespace inhand::plant
