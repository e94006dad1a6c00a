// Finger model of the analytic plant: velocity-driven, kinematic fingers (infinitely
// stiff position servos): contact forces never move a joint. Commands are clamped to
// the joint velocity limits (counted), optionally delayed by whole commands and passed
// through a first-order lag, and joints stop at their position limits (counted). Only
// the fingertip SPHERES touch the object; links, the palm and finger-finger contacts
// are not modelled. Forward kinematics is the library's (kinematics/finger_chain.hpp).
//
// Units: rad, rad/s, s, m. Frame: WORLD (fingertip velocity and link angular
// velocity). Joint angles turn about the chain's joint axes by the right-hand rule.
// Coupled joints (JointCoupling, e.g. a tendon-driven distal joint) are not driven:
// a follower's command is replaced by ratio x its leader's (after the leader's clamp),
// and its angle is kept at ratio * q_leader + offset (clamped into its own limits)
// whenever the joints are set or move, so the plant's fingers always satisfy their
// couplings.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <utility>

#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/sim/plant_params.hpp"
#include "inhand/sim/plant_readings.hpp"
#include "inhand/sim/sensing.hpp"

namespace inhand::plant::detail {

/// One finger of the plant: joint state, kinematics, fingertip motion, contact state,
/// pending commands and the tactile sensor's sampled noise.
struct FingerModel {
  using JointVector = PlantFinger::JointVector;
  /// Integration steps between exact recomputations of sin/cos q.
  static constexpr int kResyncSteps = 1000;

  explicit FingerModel(PlantFinger c)
      : chain(std::move(c)),
        plan(chain),
        ws(chain),
        q(JointVector::Zero(chain.dof())),
        qd(JointVector::Zero(chain.dof())),
        qd_cmd(JointVector::Zero(chain.dof())),
        sin_q(JointVector::Zero(chain.dof())),
        cos_q(JointVector::Ones(chain.dof())),
        sin_dq(JointVector::Zero(chain.dof())),
        cos_dq(JointVector::Ones(chain.dof())),
        trig_qd(JointVector::Zero(chain.dof())) {
    for (JointVector& p : pending) p = JointVector::Zero(chain.dof());
  }

  PlantFinger chain;
  ChainPlan<PlantFinger> plan;  ///< of chain, which the plant does not change
  FingerKinematics<PlantFinger> ws;
  JointVector q, qd, qd_cmd;
  // sin/cos of q, advanced by the angle-addition formula with the sin/cos of h qd
  // (computed for the joint velocity trig_qd) while qd stays constant, recomputed
  // exactly whenever qd changes and every kResyncSteps steps.
  JointVector sin_q, cos_q, sin_dq, cos_dq, trig_qd;
  int steps_since_sync = 0;
  Eigen::Vector3d tip_velocity = Eigen::Vector3d::Zero();  // of the sphere centre
  Eigen::Vector3d tip_omega = Eigen::Vector3d::Zero();     // of the distal link
  ContactState contact{};
  FingerCounters counters{};
  TactileNoise noise{};
  /// Commands not yet in effect (ring buffer; see PlantParams::command_delay).
  std::array<JointVector, PlantParams::kMaxCommandDelay + 1> pending{};
  int pending_head = 0;

  /// Exact sin/cos of q (followers first put on their leaders), forward kinematics and
  /// the fingertip's rigid-body velocity.
  void update_kinematics() noexcept {
    couple_positions();
    for (int j = 0; j < chain.dof(); ++j) {
      sin_q(j) = std::sin(q(j));
      cos_q(j) = std::cos(q(j));
    }
    forward_kinematics_sincos(chain, plan, sin_q, cos_q, ws);
    update_tip_velocity();
  }

  /// Velocity of the fingertip sphere centre and angular velocity of the distal link.
  void update_tip_velocity() noexcept {
    tip_velocity.setZero();
    tip_omega.setZero();
    const Eigen::Vector3d& c = ws.fingertip.position;
    for (int j = 0; j < chain.dof(); ++j) {
      const Eigen::Vector3d a = ws.joint_axes.col(j) * qd(j);
      tip_omega += a;
      tip_velocity += a.cross(c - ws.joint_origins.col(j));
    }
  }

  /// Takes a joint velocity command: each component clamped to +-max_velocity
  /// (counted), a wrong size or non-finite command replaced by zero (counted, returns
  /// false). The command given `delay` commands ago takes effect.
  bool command(const JointVector& v, int delay) noexcept {
    const int n = chain.dof();
    JointVector& slot = pending[static_cast<std::size_t>(pending_head)];
    if (v.size() != n || !all_finite(v)) {
      slot.setZero();
      apply_delayed(delay);
      ++counters.invalid_commands;
      return false;
    }
    for (int j = 0; j < n; ++j) {
      const double lim = chain.joints[j].max_velocity;
      double x = v(j);
      if (x > lim || x < -lim) {
        x = x > lim ? lim : -lim;
        ++counters.velocity_clamped;
      }
      slot(j) = x;
    }
    for (int j = 0; j < n; ++j) {
      const auto& c = chain.joints[j].coupling;
      if (c.coupled()) slot(j) = c.ratio * slot(c.leader);
    }
    apply_delayed(delay);
    return true;
  }

  /// One integration step of length h: lagged velocity (lag_alpha = 1 - exp(-h / tau),
  /// 1 without lag), q += h qd stopped at the limits, sin/cos, kinematics.
  void advance(double h, double lag_alpha) noexcept {
    const int n = chain.dof();
    bool moved = false;
    const bool resync = ++steps_since_sync >= kResyncSteps;
    if (resync) steps_since_sync = 0;
    for (int j = 0; j < n; ++j) {
      double v = qd(j) + lag_alpha * (qd_cmd(j) - qd(j));
      if (v != 0.0) {
        double x = q(j) + h * v;
        const auto& jd = chain.joints[j];
        bool exact = resync || v != qd(j);
        if (x > jd.upper || x < jd.lower) {
          x = x > jd.upper ? jd.upper : jd.lower;
          v = 0.0;
          exact = true;
          ++counters.position_limited;
        }
        if (x != q(j)) moved = true;
        q(j) = x;
        if (exact) {
          sin_q(j) = std::sin(x);
          cos_q(j) = std::cos(x);
        } else {
          if (v != trig_qd(j)) {
            sin_dq(j) = std::sin(h * v);
            cos_dq(j) = std::cos(h * v);
            trig_qd(j) = v;
          }
          const double s0 = sin_q(j), c0 = cos_q(j);
          sin_q(j) = s0 * cos_dq(j) + c0 * sin_dq(j);
          cos_q(j) = c0 * cos_dq(j) - s0 * sin_dq(j);
        }
      }
      qd(j) = v;
    }
    if (moved && couple_positions()) {
      for (int j = 0; j < n; ++j) {
        if (!chain.joints[j].coupling.coupled()) continue;
        sin_q(j) = std::sin(q(j));
        cos_q(j) = std::cos(q(j));
      }
    }
    if (moved) forward_kinematics_sincos(chain, plan, sin_q, cos_q, ws);
    update_tip_velocity();
  }

 private:
  /// Puts every follower at ratio * q_leader + offset (clamped into its limits) and its
  /// velocity at ratio * qd_leader; true if a follower's angle changed. Followers
  /// integrated from consistent commands already agree (ratio 1, offset 0: bit for bit).
  bool couple_positions() noexcept {
    bool changed = false;
    for (int j = 0; j < chain.dof(); ++j) {
      const auto& jd = chain.joints[j];
      if (!jd.coupling.coupled()) continue;
      const double x = std::clamp(jd.coupling.ratio * q(jd.coupling.leader) + jd.coupling.offset,
                                  jd.lower, jd.upper);
      if (x != q(j)) changed = true;
      q(j) = x;
      qd(j) = jd.coupling.ratio * qd(jd.coupling.leader);
    }
    return changed;
  }

  /// The command written at pending_head goes in the ring; the one given `delay`
  /// commands ago takes effect.
  void apply_delayed(int delay) noexcept {
    constexpr int kRing = PlantParams::kMaxCommandDelay + 1;
    qd_cmd = pending[static_cast<std::size_t>((pending_head - delay + kRing) % kRing)];
    pending_head = (pending_head + 1) % kRing;
  }
};

}  // namespace inhand::plant::detail
