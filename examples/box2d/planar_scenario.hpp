// Closed-loop scenarios of the planar Box2D demo: the shipped scenarios (the paper's
// stages in the plane, the negative case, the fault cases) and the controller settings
// for this hand. They run on the library's generic scenario runner
// (inhand/sim/scenario_runner.hpp), the same as the analytic 3-D plant's, with the
// Box2D world behind its plant adapter (planar_adapter.hpp: what differs from the 3-D
// plant, and why). Stages and faults: inhand/sim/scenario_spec.hpp.
// Units: see planar_world.hpp (1 u = 1 cm of the real hand, N, rad, s).
#pragma once

#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "inhand/sim/scenario_spec.hpp"
#include "planar_adapter.hpp"
#include "planar_world.hpp"

namespace inhand::box2d_demo {

using plant::FingerTruth;
using plant::MetricsTolerances;
using plant::StageKind;
using plant::StageMetrics;
using sim::FaultReport;
using sim::ScenarioResult;
using sim::to_string;

using Segment = TrajectorySegment<double, 2>;

// The scenario types: the generic ones (inhand/sim/scenario_spec.hpp) for this plant.
using StageSpec = sim::StageSpec<2>;
using FaultSpec = sim::FaultSpec<2>;
using ScenarioSpec = sim::ScenarioSpec<PlanarAdapter>;
using TickRecord = sim::TickRecord<PlanarAdapter>;
using ScenarioRunner = sim::ScenarioRunner<PlanarAdapter>;

/// The controller configuration for the Box2D hand. The library's defaults are in SI
/// metres: lengths and speeds are scaled by kLengthScale, forces stay in N. Tuned on
/// this plant (the four shipped scenarios):
///  - pose feedback: integral gains 10 -> 30 1/s^2. Under gravity the weight is carried
///    by friction; when the object is turned, the tilted faces turn part of it into a
///    force along the normals, which the preset forces (equal, collinear) do not
///    balance, so the force servos' integrators and the pose integrator pull against each
///    other: with 10 the object strayed up to 0.083 u in x during the rotation (final
///    0.006 u), with 30 up to 0.032 u (final < 1e-4 u). Position gain 8 -> 10 1/s.
///  - force servo (g2) kept at the scaled defaults, kp 2 (u/s)/N, ki 20 (u/s)/(N s):
///    a lower ki trades force error for pose error (ki 10: max force error 0.07 N
///    instead of 0.05 N).
///  - IK damping: the scaled defaults (threshold and damping 0.5 u/rad); the fingers
///    stay far from singular postures (smallest singular value > 3 u/rad).
inline PlanarController::Config box2d_controller_config() {
  PlanarController::Config c;
  const double s = kLengthScale;
  c.control_period = 1e-3;
  c.max_tick = 1e-2;
  c.pose_feedback.position_gain = 10.0;
  c.pose_feedback.orientation_gain = 8.0;
  c.pose_feedback.position_integral_gain = 30.0;
  c.pose_feedback.orientation_integral_gain = 30.0;
  c.pose_feedback.max_linear_speed = 0.05 * s;
  c.pose_feedback.max_angular_speed = 1.0;
  c.pose_feedback.position_integral_limit = 2e-3 * s;
  c.pose_feedback.orientation_integral_limit = 2e-2;
  c.servo.motion = PiGains<double>{1.0, 0.0};
  c.servo.force =
      PiGains<double>{0.02 * s, 0.2 * s};  // HybridServo's own; the controller uses force_layer
  c.ik.damping.singular_threshold = 5e-3 * s;
  c.ik.damping.max_damping = 5e-3 * s;
  c.force_planner.nominal_force = 1.0;
  c.force_planner.min_force = 0.2;
  c.force_planner.max_force = 6.0;
  // The force layer's lengths in u (its stiffness bounds in N/u).
  c.force_layer.min_stiffness /= s;
  c.force_layer.max_stiffness /= s;
  c.force_layer.min_excitation *= s;
  c.force_layer.max_integral_velocity *= s;
  c.force_layer.slip_distance *= s;
  c.force_layer.contact_damping /= s;  // N s/u
  // No raised grip at release and a slow grip rise: the planar objects are light (the
  // weight is carried by the table or, with gravity, well inside the friction cone), and
  // the demo holds the measured forces within 0.1 N of their targets throughout.
  c.force_layer.release_grip = 1.0;
  c.force_layer.release_load = 0.0;
  // A slip raises the grip as a ramp (no step at its onset), at a rate the force loop
  // follows within 0.1 N.
  c.force_layer.friction_margin = 1.0;
  c.force_layer.grip_rise_rate = 5.0;
  c.grasp.approach_speed = 0.03 * s;
  c.grasp.creep_speed = 0.005 * s;
  c.grasp.position_tolerance = 1e-3 * s;
  c.grasp.alignment_speed = 0.1 * s;
  return c;
}

/// Finger 0 comes from the left (-x), finger 1 from the right; both bases lie below
/// the object, the fingers curl up and in. Finger 0 balances the forces (the thumb).
/// The open posture puts each pad centre 5.5 u from the nominal object centre, level
/// with it, the distal link along the approach direction: the approach is then a
/// straight push along -n, and the pads touch where they are meant to, without the
/// tangential sliding that would leave their springs loaded by friction.
inline HandSpec default_hand() {
  HandSpec h;
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  FingerSpec& l = h.fingers[0];
  l.base = Vec2(-7.7, -6.9);
  l.base_angle = 90.0 * kDeg;
  l.q_open = JointVector(28.84 * kDeg, -61.15 * kDeg, -57.69 * kDeg);
  l.lower = JointVector(-0.5, -1.8, -1.8);
  l.upper = JointVector(1.2, 0.3, 0.3);
  l.approach_normal = -Vec2::UnitX();
  FingerSpec& r = h.fingers[1];
  r = l;
  r.base = Vec2(7.7, -6.9);
  r.q_open = -l.q_open;
  r.lower = -l.upper;
  r.upper = -l.lower;
  r.approach_normal = Vec2::UnitX();
  return h;
}

inline ObjectSpec default_object(ObjectShape shape) {
  ObjectSpec o;
  o.shape = shape;
  o.half_extents = Vec2(2.2, 2.8);  // 4.4 x 5.6 u box, 49 g
  o.radius = 2.6;                   // 5.2 u disc, 42 g
  o.density = 2e-5;
  o.friction = 0.8;
  return o;
}

/// The paper's stages for the plane: grasp, release and hold, translate +-0.5 u along
/// x, then along y (5 mm of the real hand), rotate 0 -> -0.2 rad -> 0.
inline std::vector<StageSpec> paper_stages(double cycle = 4.0) {
  StageSpec grasp;
  grasp.name = "grasp";
  grasp.kind = StageKind::grasp;
  grasp.duration = 3.0;
  StageSpec hold;
  hold.name = "hold";
  hold.kind = StageKind::hold;
  hold.release = true;
  hold.duration = 2.0;
  std::vector<StageSpec> s{grasp, hold};
  const double amplitude = 0.005 * kLengthScale;
  for (int axis = 0; axis < 2; ++axis) {
    StageSpec m;
    m.name = axis == 0 ? "translate_x" : "translate_y";
    m.kind = StageKind::manipulate;
    m.settle = 1.0;
    Twist<double, 2> d = Twist<double, 2>::Zero();
    d(axis) = amplitude;
    m.segments.push_back(Segment::reciprocate(d, cycle, 1));
    m.segments.push_back(Segment::reciprocate(Twist<double, 2>(-d), cycle, 1));
    s.push_back(m);
  }
  StageSpec rot;
  rot.name = "rotate";
  rot.kind = StageKind::manipulate;
  rot.settle = 1.0;
  rot.segments.push_back(Segment::reciprocate(Twist<double, 2>(0.0, 0.0, -0.2), cycle, 1));
  s.push_back(rot);
  return s;
}

/// One shipped scenario: box or circle, gravity off (horizontal hand) or on (-y).
inline ScenarioSpec paper_scenario(ObjectShape shape, bool gravity) {
  ScenarioSpec s;
  s.name = std::string(to_string(shape)) + (gravity ? "_gravity" : "_flat");
  s.hand = default_hand();
  s.object = default_object(shape);
  s.world.gravity = gravity ? kGravity : 0.0;
  s.controller = box2d_controller_config();
  s.stages = paper_stages();
  s.tolerances.drop_distance = 0.02 * kLengthScale;
  // "Settled": within 2 % of the object's size and 0.01 rad.
  s.tolerances.settle_position_tolerance = 0.02 * s.object.size();
  s.tolerances.settle_orientation_tolerance = 0.01;
  return s;
}

/// The negative case: box under gravity; 0.5 s into the hold, finger 1 is commanded
/// to open (its joints turn back towards the open posture at 1.5 rad/s).
inline ScenarioSpec dropped_object_scenario() {
  ScenarioSpec s = paper_scenario(ObjectShape::box, true);
  s.name = "box_gravity_finger_away";
  s.stages.resize(2);
  s.stages[1].duration = 1.0;
  s.command_override.finger = 1;
  s.command_override.stage = 1;
  s.command_override.start = 0.5;
  s.command_override.joint_velocity = JointVector(-1.5, -1.5, -1.5);  // finger 1 uncurls
  s.expect_drop = true;
  return s;
}

/// The outlier gates of the fault scenarios: those of the 3-D fault scenarios
/// (scenarios/faults/*.json: 0.2 m/s, 5 rad/s, 200 N/s, a reading held for at most 5 ms), lengths
/// scaled to u. The shipped scenarios run without gates (the library default, +inf).
inline OutlierGates<double> box2d_outlier_gates() {
  OutlierGates<double> g;
  g.max_object_speed = 0.2 * kLengthScale;  // 20 u/s
  g.max_object_angular_speed = 5.0;
  g.max_force_rate = 200.0;
  g.contact_stiffness = 1e5 / kLengthScale;  // N/u, the library default's 1e5 N/m
  g.max_rejection_time = 0.005;              // s: 5 ticks at the demo's 1 kHz
  return g;
}

/// One fault scenario, as the 3-D ones (scenarios/faults/*.json): box under gravity,
/// grasp, release and hold 2 s, translate_x (+-0.5 u, 2 x 4 s, 1 s of settle), the
/// outlier gates on, and one fault 1 s into translate_x (the object at its fastest):
///   tactile_dropout : finger 1's tactile signal drops out for 50 ms
///   force_spike     : +3 N on finger 0's sensed force for 4 ms
///   pose_outlier    : the sensed position jumps by 1 u (1 cm) along x for 3 ms
///   knock           : 3 N along +x (towards finger 1) for 10 ms
///   finger_away     : finger 1 turns back to its open posture from then on (not in
///                     fault_scenarios(): the shipped negative case is
///                     dropped_object_scenario())
inline ScenarioSpec fault_scenario(FaultSpec::Kind kind) {
  ScenarioSpec s = paper_scenario(ObjectShape::box, true);
  s.name = std::string("box_gravity_") + to_string(kind);
  s.stages.resize(3);  // grasp, hold, translate_x
  s.controller.outlier_gates = box2d_outlier_gates();
  FaultSpec f;
  f.kind = kind;
  f.stage = "translate_x";
  f.at = 1.0;
  switch (kind) {
    case FaultSpec::Kind::tactile_dropout:
      f.finger = 1;
      f.duration = 0.05;
      break;
    case FaultSpec::Kind::force_spike:
      f.finger = 0;
      f.duration = 0.004;
      f.magnitude = 3.0;
      break;
    case FaultSpec::Kind::pose_outlier:
      f.duration = 0.003;
      f.vector = Vec2(0.01 * kLengthScale, 0.0);
      break;
    case FaultSpec::Kind::knock:
      f.duration = 0.01;
      f.vector = Vec2(3.0, 0.0);
      break;
    case FaultSpec::Kind::finger_away:
      f.finger = 1;
      f.duration = 0.0;
      break;
  }
  s.faults.push_back(f);
  return s;
}

inline std::vector<ScenarioSpec> fault_scenarios() {
  return {fault_scenario(FaultSpec::Kind::tactile_dropout),
          fault_scenario(FaultSpec::Kind::force_spike),
          fault_scenario(FaultSpec::Kind::pose_outlier), fault_scenario(FaultSpec::Kind::knock)};
}

inline std::vector<ScenarioSpec> shipped_scenarios() {
  return {paper_scenario(ObjectShape::box, false), paper_scenario(ObjectShape::circle, false),
          paper_scenario(ObjectShape::box, true), paper_scenario(ObjectShape::circle, true)};
}

}  // namespace inhand::box2d_demo
