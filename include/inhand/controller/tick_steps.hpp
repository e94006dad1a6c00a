// The steps the two task phases of a tick (controller_phases.hpp) share: this tick's
// values, the force layer's update over the touching fingers, one finger's kinematics and
// command (layers 2-3), and leaving a finger that missed the object out of the grasp
// (grasp.hpp, "A finger that misses"). Frames, units and signs: controller_io.hpp.
// noexcept, no allocation.
#pragma once

#include <cstddef>

#include "inhand/controller/controller_state.hpp"
#include "inhand/controller/finger_motion.hpp"
#include "inhand/kinematics/contact_kinematics.hpp"

namespace inhand {

/// This tick's values, shared by its steps.
template <typename Types>
struct TickInput {
  const typename Types::Config& config;
  const typename Types::Input& in;
  const typename Types::PoseT& object;  ///< the gated measured object pose
  typename Types::ScalarType dt;        ///< s
};

namespace detail {

/// Layer 2's force layer: the touching fingers' contacts (unit normals), gated forces
/// and fingertip steps since the last tick; `object_free` false while grasping.
template <typename Types>
void run_force_layer(const TickInput<Types>& t, bool object_free, ControllerState<Types>& st,
                     TickScratch<Types>& sc) noexcept {
  using Scalar = typename Types::ScalarType;
  for (int i = 0; i < static_cast<int>(st.fingers.size()); ++i) {
    const typename Types::FingerInput& f = t.in.fingers[static_cast<std::size_t>(i)];
    FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    sc.touching(i) = f.contact.touching ? 1 : 0;
    sc.tip_steps.col(i).setZero();
    sc.servo_gain(i) = Scalar(0);
    if (f.contact.touching) {
      sc.normals.col(i) = f.contact.normal.normalized();
      sc.servo_gain(i) = servo_normal_gain<Scalar>(m.jacobian, sc.normals.col(i));
      sc.points.col(i) = f.contact.contact_point;
      sc.measured(i) = m.force_gate.force();
      // Fingertip displacement since the last tick, through the last tick's Jacobian.
      if (m.has_q_prev) {
        m.q_prev = f.joint_positions - m.q_prev;  // the joint step (no temporary)
        sc.tip_steps.col(i) = columns_times(m.jacobian, m.q_prev);
      }
    }
    m.q_prev = f.joint_positions;
    m.has_q_prev = true;
  }
  typename ForceLayer<Scalar, Types::kDim, Types::kNumFingers>::Step step;
  step.touching = &sc.touching;
  step.points = &sc.points;
  step.normals = &sc.normals;
  step.measured = &sc.measured;
  step.pattern = &sc.pattern;
  step.tip_steps = &sc.tip_steps;
  step.servo_gain = &sc.servo_gain;
  step.object_position = t.object.position;
  step.object_rotation = t.object.rotation;
  step.min_force = t.config.force_planner.min_force;
  step.max_force = t.config.force_planner.max_force;
  step.object_free = object_free;
  step.release_grip = st.grasp_grip;
  step.dt = t.dt;
  st.forces.update(step, sc.forces);
}

/// Layers 2-3 for finger i at the point p of `points`: contact velocity v, the force
/// layer's velocity when `force_active` (the finger touches), servo, IK, continuity.
template <typename Types>
ControllerWarning command_finger(const TickInput<Types>& t, int i,
                                 const FingerPoints<Types>& points, const typename Types::Vec& p,
                                 const typename Types::Vec& v, bool force_active,
                                 ControllerState<Types>& st, TickScratch<Types>& sc,
                                 typename Types::FingerOutput& fo) noexcept {
  using Scalar = typename Types::ScalarType;
  FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
  const typename Types::FingerInput& f = t.in.fingers[static_cast<std::size_t>(i)];
  points.jacobian(p, m.jacobian);
  fo.desired_contact_velocity = v;
  fo.desired_normal_force = force_active ? sc.forces.grip * sc.pattern(i) : Scalar(0);
  fo.force_target = force_active ? sc.forces.target(i) : Scalar(0);
  using Vec = typename Types::Vec;
  Vec force = Vec::Zero();
  if (force_active)  // stores a force along n through servo and contact (joint_servo.hpp)
    force = -sc.forces.velocity(i) *
            servo_press_direction<Scalar, Types::kDim>(m.jacobian, sc.normals.col(i),
                                                       st.forces.press_stiffness()(i),
                                                       t.config.force_layer.servo_stiffness);
  const ControllerWarning w = sc.fingers[static_cast<std::size_t>(i)].layer3.command(
      m.layer3, m.jacobian, f.joint_positions, v, f.contact.normal, force_active ? &force : nullptr,
      t.config.max_joint_acceleration, t.dt, fo, m.state == FingerState::pressing);
  fo.stiffness_estimate = st.forces.stiffness_estimate()(i);
  fo.force_integral = st.forces.integral()(i);
  fo.slipping = sc.forces.slipping(i) != 0;
  fo.state = m.state;
  return w;
}

/// Forward kinematics of every chain finger at this tick's joint positions, into each
/// finger's sc.fingers[i].kinematics (hand_kinematics.hpp: the fingers of one design side
/// by side). First in each phase: every finger's points below read it.
template <typename Types>
void hand_kinematics(const TickInput<Types>& t, TickScratch<Types>& sc) noexcept {
  sc.lanes.run(
      t.config, t.in,
      [&](int i) -> const ChainPlan<typename Types::Chain>& {
        return sc.fingers[static_cast<std::size_t>(i)].plan;
      },
      [&](int i) -> FingerKinematics<typename Types::Chain>& {
        return sc.fingers[static_cast<std::size_t>(i)].kinematics;
      });
}

/// Finger i's kinematics this tick (hand_kinematics() has run); its contact's plausibility
/// flagged in fo and w.
template <typename Types>
FingerPoints<Types> finger_points(const TickInput<Types>& t, int i, TickScratch<Types>& sc,
                                  typename Types::FingerOutput& fo, ControllerWarning& w) noexcept {
  const auto k = static_cast<std::size_t>(i);
  const FingerPoints<Types> points(t.config.fingers[k], t.in.fingers[k], sc.fingers[k].kinematics);
  fo.implausible_contact = points.implausible_contact(t.config.contact_tolerance);
  if (fo.implausible_contact) w |= ControllerWarning::implausible_contact;
  return points;
}

/// A finger that misses (grasp.hpp): the grasp goes on with the fingers not missed. Their
/// grasp pattern is planned again over their targets' normals (a missed finger's is 0) and
/// s_g sized over it, as begin_grasp() does; the sizing over the measured normals and the
/// balancing shift are taken again once they are placed (begin_grasp_sizing). Uses
/// sc.touching, sc.normals and sc.pattern as its workspace.
template <typename Types>
void leave_out_missed(const typename Types::Config& config, ControllerState<Types>& st,
                      TickScratch<Types>& sc) noexcept {
  using Scalar = typename Types::ScalarType;
  const int n = static_cast<int>(st.fingers.size());
  for (int i = 0; i < n; ++i) {
    const FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    sc.touching(i) = m.state == FingerState::missed ? 0 : 1;
    if (sc.touching(i))
      sc.normals.col(i) = m.target.normal;
    else
      sc.normals.col(i).setZero();
  }
  typename Types::Vec residual;
  st.planner.reset();
  st.planner.plan(sc.touching, sc.normals, config.control_period, sc.pattern, residual);
  for (int i = 0; i < n; ++i)
    if (!sc.touching(i)) sc.pattern(i) = Scalar(0);
  const auto r = release_grip_scale(sc.normals.leftCols(n), sc.pattern.head(n), config.force_layer,
                                    config.force_planner.min_force, config.force_planner.max_force);
  st.begin_grasp_sizing(r.scale, r.capped);
  for (int i = 0; i < n; ++i) {
    FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    m.grasp_pattern = sc.pattern(i);
    m.grasp_force = r.scale * sc.pattern(i);
  }
}

}  // namespace detail

}  // namespace inhand
