// The two task phases of one controller tick, after the input checks and the sensor
// gates (reactive_controller.hpp): the grasp phase (object held; grasp.hpp) and the
// manipulation phase (layers 1-3 of docs/method.md section 7). Each takes this tick's
// values (configuration, input, gated object pose, dt), updates the controller's state and
// writes the Output (frames, units, signs: controller_io.hpp). noexcept, no allocation.
#pragma once

#include <cstddef>

#include "inhand/controller/tick_steps.hpp"
#include "inhand/controller/trajectory.hpp"
#include "inhand/controller/workspace_limits.hpp"
#include "inhand/kinematics/contact_kinematics.hpp"

namespace inhand {

/// Start of the grasp towards `targets` (validated): each finger's target, its pattern q_g
/// (the planner's over the targets' normals, all touching, grasp.hpp; planned once, which
/// primes the planner's filter), grasp force f_g = s_g q_g (s_g: release_grip_scale() over
/// the targets' normals; one scale keeps the pattern's balance), fresh memory.
template <typename Types, typename Targets>
void begin_grasp(const typename Types::Config& config, const Targets& targets,
                 ControllerState<Types>& st, TickScratch<Types>& sc) noexcept {
  const int n = static_cast<int>(st.fingers.size());
  for (int i = 0; i < n; ++i) {
    sc.touching(i) = 1;
    sc.normals.col(i) = targets[static_cast<std::size_t>(i)].normal.normalized();
  }
  typename Types::Vec residual;
  st.planner.reset();
  st.planner.plan(sc.touching, sc.normals, config.control_period, sc.pattern, residual);
  const auto r = release_grip_scale(sc.normals.leftCols(n), sc.pattern.head(n), config.force_layer,
                                    config.force_planner.min_force, config.force_planner.max_force);
  st.begin_grasp_sizing(r.scale, r.capped);
  for (int i = 0; i < n; ++i) {
    FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    m.target = targets[static_cast<std::size_t>(i)];
    m.target.normal.normalize();
    m.grasp_pattern = sc.pattern(i);
    m.grasp_force = r.scale * sc.pattern(i);
    m.state = FingerState::approaching;
    m.touched = false;
    m.layer3.servo.reset();
    m.settle = SettleWindow<typename Types::ScalarType, Types::kDim>{};
  }
}

/// Grasp phase (grasp.hpp): approach, press with the grasp forces, settle.
template <typename Types>
ControllerStatus grasp_phase(const TickInput<Types>& t, ControllerState<Types>& st,
                             TickScratch<Types>& sc, typename Types::Output& out) noexcept {
  using Scalar = typename Types::ScalarType;
  const GraspParams<Scalar>& g = t.config.grasp;
  ControllerWarning w = out.warnings;
  detail::hand_kinematics(t, sc);
  w |= detail::size_grip_on_measured_normals(t.config, t.in, st, sc);
  detail::balance_grasp(t.config, t.in, st, sc);
  // A placed finger presses with its grasp force f_g, a finger not yet placed slides to
  // its target with slide_force_fraction of its pattern q_g (both set by start_grasp).
  for (int i = 0; i < static_cast<int>(st.fingers.size()); ++i) {
    const FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    sc.pattern(i) = m.settle.placed ? m.grasp_force : g.slide_force_fraction * m.grasp_pattern;
  }
  detail::run_force_layer(t, false, st, sc);
  using Vec = typename Types::Vec;
  bool all_placed = true, missed = false, newly_missed = false, balancing_placed = false;
  int placed = 0;
  for (int i = 0; i < static_cast<int>(st.fingers.size()); ++i) {
    FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    const typename Types::FingerInput& f = t.in.fingers[static_cast<std::size_t>(i)];
    typename Types::FingerOutput& fo = out.fingers[static_cast<std::size_t>(i)];
    const FingerPoints<Types> points = detail::finger_points(t, i, sc, fo, w);
    // A finger that misses (grasp.hpp): left out, commanded to stand still.
    if (m.state != FingerState::missed && !f.contact.touching && !m.touched &&
        passed_object_centre<Scalar, Types::kDim>(points.miss_point(), t.object.position,
                                                  m.target.normal)) {
      m.state = FingerState::missed;
      m.layer3.servo.reset();
      newly_missed = true;
    }
    if (m.state == FingerState::missed) {
      missed = true;
      w |= detail::command_finger(t, i, points, points.centre(), Vec(Vec::Zero()), false, st, sc,
                                  fo);
      continue;
    }
    if (f.contact.touching) {
      if (m.state == FingerState::approaching) m.layer3.servo.reset_force();
      m.state = FingerState::pressing;
      m.touched = true;
      m.remember_contact(f.contact, t.object);
      const PressStep<Scalar, Types::kDim> press =
          press_step(st.press_params(g, i), m.target, f.contact.contact_point, f.contact.normal,
                     gravity_unit<Scalar, Types::kDim>(t.config.force_layer.gravity_direction),
                     t.dt, m.settle);
      // Once placed, the finger presses still: sliding on under the full force would load
      // the object tangentially again (grasp.hpp).
      const typename Types::Vec v =
          m.settle.placed ? typename Types::Vec(Types::Vec::Zero()) : press.velocity;
      w |= detail::command_finger(t, i, points, points.centre(), v, true, st, sc, fo);
      // Complete with the full grasp force f_g. A placed finger stays placed: it no
      // longer moves along the object, so its contact no longer changes (sensor noise
      // alone would otherwise un-place it).
      m.settle.placed = m.settle.placed || press.placed;
      placed += m.settle.placed ? 1 : 0;
      balancing_placed = balancing_placed ||
                         (m.settle.placed && t.config.fingers[static_cast<std::size_t>(i)].role ==
                                                 FingerRole::balancing);
      all_placed =
          all_placed && m.settle.placed &&
          std::abs(m.force_gate.force() - m.grasp_force) <= g.force_tolerance * m.grasp_force;
    } else {
      if (m.state == FingerState::pressing) m.layer3.servo.reset_force();
      m.settle.start();
      m.state = FingerState::approaching;
      const Vec p_v = points.virtual_point(m.target.normal);
      // A finger that has touched comes back at creep speed (grasp.hpp surface_point).
      const Vec v = approach_velocity(
          g, p_v, m.touched ? surface_point(p_v, m.target) : m.target.contact_point,
          m.target.normal);
      w |= detail::command_finger(t, i, points, p_v, v, false, st, sc, fo);
      all_placed = false;
    }
  }
  if (newly_missed) detail::leave_out_missed(t.config, st, sc);
  if (missed) w |= ControllerWarning::grasp_finger_missed;
  // Without a finger left out, every finger placed; with one, at least two, one balancing.
  all_placed = all_placed && (!missed || (placed >= 2 && balancing_placed));
  out.warnings = w;
  out.desired_object_pose = t.object;
  out.commanded_twist.setZero();
  out.feedforward_twist.setZero();
  out.pose_error.setZero();
  // Complete once every finger has been placed for settle_time (0: the first such tick).
  st.settled_time = all_placed ? st.settled_time + t.dt : Scalar(0);
  if (all_placed && st.settled_time >= g.settle_time) st.phase = ControllerPhase::grasped;
  return st.phase == ControllerPhase::grasped ? ControllerStatus::grasped
                                              : ControllerStatus::grasping;
}

/// Manipulation phase: layer 1 (trajectory, pose loop), layer 2 (contact velocities,
/// force planner, force layer), layer 3 per finger; lost contacts are re-approached.
template <typename Types>
ControllerStatus manipulation_phase(
    const TickInput<Types>& t,
    const ObjectTrajectory<typename Types::ScalarType, Types::kDim>& trajectory,
    ControllerState<Types>& st, TickScratch<Types>& sc, typename Types::Output& out) noexcept {
  using Scalar = typename Types::ScalarType;
  using Vec = typename Types::Vec;
  ControllerWarning w = out.warnings;
  const int n = static_cast<int>(st.fingers.size());
  detail::hand_kinematics(t, sc);
  // Layer 1: desired pose, commanded twist.
  st.manipulation_time += t.dt;
  const TrajectorySample<Scalar, Types::kDim> sample = trajectory.evaluate(st.manipulation_time);
  out.desired_object_pose = sample.pose;
  out.feedforward_twist = sample.twist;
  out.segment = sample.segment;
  out.manipulation_time = st.manipulation_time;
  const PoseLoopStep<Scalar, Types::kDim> pose =
      st.pose_loop.update(t.config.pose_feedback, sample.pose, sample.twist, t.object, t.dt);
  if (pose.integral_limited) w |= ControllerWarning::pose_integral_limited;
  if (pose.twist_limited) w |= ControllerWarning::twist_limited;
  if (pose.astray) w |= ControllerWarning::object_astray;
  out.pose_error = pose.pose_error;
  out.pose_error_integral = st.pose_loop.integral();
  // Layer 2: the planner's force pattern, then the force layer.
  for (int i = 0; i < n; ++i) {
    const typename Types::TactileContact& c = t.in.fingers[static_cast<std::size_t>(i)].contact;
    sc.touching(i) = c.touching ? 1 : 0;
    if (c.touching) sc.normals.col(i) = c.normal.normalized();
  }
  out.force_plan_status =
      st.planner.plan(sc.touching, sc.normals, t.dt, sc.pattern, out.force_residual);
  if (has(out.force_plan_status, ForcePlanStatus::limited)) w |= ControllerWarning::force_limited;
  if (has(out.force_plan_status, ForcePlanStatus::no_balancing_contact))
    w |= ControllerWarning::no_balancing_contact;
  detail::run_force_layer(t, true, st, sc);
  out.load_estimate = sc.forces.load;
  out.grip = sc.forces.grip;
  out.force_layer_status = sc.forces.status;
  const ForceLayerStatus fs = sc.forces.status;
  if (has(fs, ForceLayerStatus::slipping)) w |= ControllerWarning::slipping;
  if (has(fs, ForceLayerStatus::grip_raised)) w |= ControllerWarning::grip_raised;
  if (has(fs, ForceLayerStatus::beyond_capacity)) w |= ControllerWarning::beyond_capacity;
  if (has(fs, ForceLayerStatus::integral_limited)) w |= ControllerWarning::force_integral_limited;
  if (has(fs, ForceLayerStatus::over_max_force)) w |= ControllerWarning::over_max_force;
  // Layers 2-3 per finger, the twist kept within reach (workspace_limits.hpp).
  typename Types::TwistT twist = pose.commanded_twist;
  w |= detail::cut_twist_at_edge<Types>(t, st, sc, pose,
                                        st.hold_risk(fs, t.config.at_risk_hold, t.dt), twist);
  out.commanded_twist = twist;
  bool lost = false;
  for (int i = 0; i < n; ++i) {
    FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    const typename Types::FingerInput& f = t.in.fingers[static_cast<std::size_t>(i)];
    typename Types::FingerOutput& fo = out.fingers[static_cast<std::size_t>(i)];
    const FingerPoints<Types> points = detail::finger_points(t, i, sc, fo, w);
    if (f.contact.touching) {
      if (m.state == FingerState::reacquiring) m.layer3.servo.reset_force();
      m.state = FingerState::in_contact;
      m.remember_contact(f.contact, t.object);
      const Vec v = contact_point_velocity<Scalar, Types::kDim>(twist, f.contact.contact_point,
                                                                t.object.position);
      w |= detail::command_finger(t, i, points, f.contact.contact_point, v, true, st, sc, fo);
    } else if (m.state == FingerState::missed) {  // left out until it touches (grasp.hpp)
      w |= ControllerWarning::grasp_finger_missed;
      w |= detail::command_finger(t, i, points, points.centre(), Vec(Vec::Zero()), false, st, sc,
                                  fo);
    } else {
      lost = true;
      if (m.state != FingerState::reacquiring) m.layer3.servo.reset_force();
      m.state = FingerState::reacquiring;
      // Aim at the last contact point carried with the measured object, along the
      // last normal; add the object's motion there (eq. 2) so the finger keeps up.
      const Vec nrm = t.object.rotation * m.last_normal_object;
      const Vec p_t = t.object.transform_point(m.last_contact_object);
      const Vec p_v = points.virtual_point(nrm);
      const Vec v = approach_velocity(t.config.grasp, p_v, p_t, nrm) +
                    contact_point_velocity<Scalar, Types::kDim>(twist, p_t, t.object.position);
      w |= detail::command_finger(t, i, points, p_v, v, false, st, sc, fo);
    }
  }
  out.warnings = w;
  return lost ? ControllerStatus::contact_lost : ControllerStatus::ok;
}

}  // namespace inhand
