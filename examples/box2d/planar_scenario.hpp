// Closed-loop scenarios of the planar Box2D demo: the library's ReactiveController,
// instantiated for the plane (Dim = 2, two fingers of three joints), driving the Box2D
// hand of planar_world.hpp through the paper's stages, with the per-stage metrics of
// inhand/sim/metrics.hpp. It follows inhand/sim/scenario.hpp tick for tick:
//   sensing (joint angles, object pose, tactile) -> controller.update() -> joint motor
//   speeds -> world.step(control_period).
// Stages:
//   grasp      : the object is a static body; start_grasp() aims each finger at the
//                object's measured centre along the hand's approach normal (no object
//                geometry); ends when the controller reports `grasped` (timeout:
//                `duration`).
//   hold       : `release` makes the object dynamic; the task is to keep the pose it
//                had at the start of the stage (the paper's stage 1).
//   manipulate : the stage's trajectory segments from the desired pose the previous
//                stage ended on, then `settle` seconds of hold.
// Faults (FaultSpec, as in inhand/sim/scenario.hpp): sensing corruption applied to the
// controller's input before update(), a disturbance force on the object during the step;
// each gets a FaultReport (detection, reacquisition, force-integral windup).
// Units: see planar_world.hpp (1 u = 1 cm of the real hand, N, rad, s).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/metrics.hpp"
#include "planar_world.hpp"

namespace inhand::box2d_demo {

using plant::FingerTruth;
using plant::MetricsTolerances;
using plant::StageKind;
using plant::StageMetrics;

/// The library's controller for this hand: planar, two fingers, three joints each.
using PlanarController = ReactiveController<double, 2, kFingers, kLinks>;
using Segment = TrajectorySegment<double, 2>;

struct StageSpec {
  std::string name = "stage";
  StageKind kind = StageKind::hold;
  double duration = 1.0;          ///< grasp: timeout; hold: duration; manipulate: ignored
  bool release = false;           ///< hold: make the object dynamic when the stage starts
  std::vector<Segment> segments;  ///< manipulate
  double settle = 1.0;            ///< manipulate: hold time after the last segment (s)
};

/// Replaces one finger's joint-velocity command from `start` seconds into stage
/// `stage` on (a fault injected to show that the metrics can fail).
struct CommandOverride {
  int finger = -1;  ///< -1: none
  int stage = 0;
  double start = 0.0;
  JointVector joint_velocity = JointVector::Zero();  ///< rad/s
};

/// A fault injected into a run (the 3-D plant's FaultSpec, inhand/sim/scenario.hpp, in
/// the plane). Active from `at` s into the stage named `stage` for `duration` s:
///   tactile_dropout : finger's tactile signal reads "not touching"
///   force_spike     : finger's sensed normal force += `magnitude` N (while touching)
///   pose_outlier    : sensed object position += `vector` (u)
///   knock           : external force `vector` (N, world) on the object's centre
struct FaultSpec {
  enum class Kind { tactile_dropout, force_spike, pose_outlier, knock };
  Kind kind = Kind::tactile_dropout;
  std::string stage = "translate_x";
  double at = 1.0;         ///< s into the stage
  double duration = 0.05;  ///< s
  int finger = 0;
  double magnitude = 0.0;      ///< N, force_spike
  Vec2 vector = Vec2::Zero();  ///< u (pose_outlier) or N (knock)
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
  }
  return "unknown";
}

/// What the controller made of an injected fault (as the 3-D plant's FaultReport).
struct FaultReport {
  FaultSpec::Kind kind = FaultSpec::Kind::tactile_dropout;
  int finger = 0;
  double start_time = -1.0;  ///< s, scenario time of the fault's first tick (-1: never active)
  /// Ticks from the fault's first tick to the first tick the controller reported it:
  /// tactile_dropout: that finger `reacquiring`; force_spike: the force_outlier warning;
  /// pose_outlier: the pose_outlier warning; knock: status contact_lost. -1: never.
  long detection_ticks = -1;
  /// Dropout/knock, once detected: ticks after the fault window until the status is
  /// `ok` again (every finger in contact). -1: not within the run.
  long reacquire_ticks = -1;
  /// Largest |force integral| of any finger's force PI from the fault's start on (N s).
  double max_force_integral = 0.0;
  /// Ticks on which the fault's report (as for detection_ticks) was raised.
  long reported_ticks = 0;
};

struct ScenarioSpec {
  std::string name = "scenario";
  HandSpec hand{};
  ObjectSpec object{};
  WorldParams world{};
  PlanarController::Config controller{};  ///< fingers are filled from `hand`
  std::vector<StageSpec> stages;
  MetricsTolerances tolerances{};
  CommandOverride command_override{};
  std::vector<FaultSpec> faults;
  bool expect_drop = false;  ///< the negative case: it is expected to drop
};

struct ScenarioResult {
  std::vector<StageMetrics> stages;
  bool dropped = false;
  int contact_losses = 0;           ///< after the grasp stage
  int link_contacts = 0;            ///< a non-sensing link touched the object
  std::string failure;              ///< empty when every stage ran
  std::vector<FaultReport> faults;  ///< one per ScenarioSpec::faults entry
};

/// One control tick, as seen by trace writers and snapshot takers.
struct TickRecord {
  double time = 0.0;  ///< s, end of the tick
  int stage = 0;
  double stage_time = 0.0;  ///< s since the stage started
  bool stage_end = false;   ///< last tick of the stage
  const Pose<double, 2>* desired = nullptr;
  const Pose<double, 2>* actual = nullptr;
  const PlanarController::Input* input = nullptr;
  const PlanarController::Output* output = nullptr;
  ControllerStatus status = ControllerStatus::idle;
  const PlanarWorld* world = nullptr;
};

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
/// (scenarios/faults/*.json: 0.2 m/s, 5 rad/s, 200 N/s, 5 rejections in a row), lengths
/// scaled to u. The shipped scenarios run without gates (the library default, +inf).
inline OutlierGates<double> box2d_outlier_gates() {
  OutlierGates<double> g;
  g.max_object_speed = 0.2 * kLengthScale;  // 20 u/s
  g.max_object_angular_speed = 5.0;
  g.max_force_rate = 200.0;
  g.max_consecutive_rejections = 5;
  return g;
}

/// One fault scenario, as the 3-D ones (scenarios/faults/*.json): box under gravity,
/// grasp, release and hold 2 s, translate_x (+-0.5 u, 2 x 4 s, 1 s of settle), the
/// outlier gates on, and one fault 1 s into translate_x (the object at its fastest):
///   tactile_dropout : finger 1's tactile signal drops out for 50 ms
///   force_spike     : +3 N on finger 0's sensed force for 4 ms
///   pose_outlier    : the sensed position jumps by 1 u (1 cm) along x for 3 ms
///   knock           : 3 N along +x (towards finger 1) for 10 ms
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

class ScenarioRunner {
 public:
  using TickObserver = std::function<void(const TickRecord&)>;

  /// Runs the scenario; throws std::invalid_argument on an invalid specification.
  ScenarioResult run(const ScenarioSpec& spec, const TickObserver& observer = {}) const {
    PlanarWorld world(spec.hand, spec.object, spec.world);
    PlanarController controller;
    PlanarController::Config cfg = spec.controller;
    for (int i = 0; i < kFingers; ++i) {
      auto& f = cfg.fingers[static_cast<std::size_t>(i)];
      f.chain = finger_chain(spec.hand, i);
      f.kinematics = PlanarController::KinematicsSource::chain;
      f.role = i == 0 ? FingerRole::balancing : FingerRole::preset;
    }
    const Validation v = controller.configure(cfg);
    if (!v.ok())
      throw std::invalid_argument(std::string("controller: ") + v.field + ": " + v.reason);
    const double dt = cfg.control_period;
    PlanarController::Input in = controller.make_input();
    PlanarController::Output out = controller.make_output();

    ScenarioResult result;
    struct FaultTracking {
      long start_tick = -1, end_tick = -1;
      bool window_over = false;
    };
    std::vector<FaultTracking> fault_state(spec.faults.size());
    result.faults.resize(spec.faults.size());
    for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
      const FaultSpec& fs = spec.faults[fi];
      if (fs.finger < 0 || fs.finger >= kFingers)
        throw std::invalid_argument("fault: finger index out of range");
      if (!(fs.duration >= 0.0) || !(fs.at >= 0.0))
        throw std::invalid_argument("fault: negative or NaN time");
      if (!fs.vector.allFinite() || !std::isfinite(fs.magnitude))
        throw std::invalid_argument("fault: non-finite magnitude or vector");
      if (std::none_of(spec.stages.begin(), spec.stages.end(),
                       [&](const StageSpec& st) { return st.name == fs.stage; }))
        throw std::invalid_argument("fault: no stage named '" + fs.stage + "'");
      result.faults[fi].kind = fs.kind;
      result.faults[fi].finger = fs.finger;
    }
    long global_tick = 0;
    Pose<double, 2> desired_end = world.object_pose();
    std::vector<FingerTruth> truth(kFingers);
    auto read_truth = [&]() {
      for (int i = 0; i < kFingers; ++i) {
        const TactileReading r = world.tactile(i);
        FingerTruth& ft = truth[static_cast<std::size_t>(i)];
        ft.touching = r.touching;
        ft.normal_force = r.normal_force;
        ft.slip_distance = world.slip_distance(i);
        ft.desired_force = out.fingers[static_cast<std::size_t>(i)]
                               .force_target;  // what the force loop drives to (force_layer.hpp)
      }
    };
    read_truth();
    bool grasp_done = false;
    double t = 0.0;
    plant::StageMetricsAccumulator acc;
    for (std::size_t si = 0; si < spec.stages.size(); ++si) {
      const StageSpec& st = spec.stages[si];
      acc.begin(st.name, st.kind, t, truth, spec.tolerances, grasp_done);
      double stage_duration = st.duration;
      if (st.kind == StageKind::grasp) {
        world.set_object_frozen(true);
        const Pose<double, 2> object = world.object_pose();
        std::array<GraspTarget<double, 2>, kFingers> targets{};
        for (int i = 0; i < kFingers; ++i) {
          targets[static_cast<std::size_t>(i)].contact_point = object.position;
          targets[static_cast<std::size_t>(i)].normal =
              object.rotation * spec.hand.fingers[static_cast<std::size_t>(i)].approach_normal;
        }
        const Validation g = controller.start_grasp(targets);
        if (!g.ok()) throw std::invalid_argument(std::string("grasp targets: ") + g.field);
      } else {
        if (st.release) world.set_object_frozen(false);
        PlanarController::Trajectory traj;
        traj.reset(desired_end);
        if (st.kind == StageKind::hold) {
          traj.append(Segment::hold_for(st.duration));
        } else {
          stage_duration = st.settle;
          for (const Segment& seg : st.segments) {
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
        in.time = t + dt;  // strictly increasing, starts at dt
        in.object_pose = world.object_pose();
        for (int i = 0; i < kFingers; ++i) {
          auto& fi = in.fingers[static_cast<std::size_t>(i)];
          fi.joint_positions = world.joint_angles(i);
          const TactileReading r = world.tactile(i);
          fi.contact.touching = r.touching;
          if (r.touching) {
            fi.contact.contact_point = r.contact_point;
            fi.contact.normal = r.normal;
            fi.contact.normal_force = r.normal_force;
          }
        }
        // Injected faults: sensing corruption before the controller sees the data, the
        // knock force during the step (as inhand/sim/scenario.hpp).
        const double ts = t - stage_start;  // stage time at the start of this tick
        auto fault_active = [&](const FaultSpec& fs) {
          return fs.stage == st.name && ts + 1e-12 >= fs.at && ts + 1e-12 < fs.at + fs.duration;
        };
        Vec2 knock_force = Vec2::Zero();
        for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
          const FaultSpec& fs = spec.faults[fi];
          if (!fault_active(fs)) continue;
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
          }
          if (fault_state[fi].start_tick < 0) {
            fault_state[fi].start_tick = global_tick;
            result.faults[fi].start_time = t;
          }
        }
        world.set_object_force(knock_force);
        const ControllerStatus status = controller.update(in, out);
        for (std::size_t fi = 0; fi < spec.faults.size(); ++fi) {
          const FaultSpec& fs = spec.faults[fi];
          FaultTracking& ft = fault_state[fi];
          FaultReport& fr = result.faults[fi];
          if (ft.start_tick < 0) continue;
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
            case FaultSpec::Kind::knock:
              reported = status == ControllerStatus::contact_lost;
              break;
          }
          if (reported) ++fr.reported_ticks;
          if (reported && fr.detection_ticks < 0) fr.detection_ticks = global_tick - ft.start_tick;
          if (!fault_active(fs) && !ft.window_over) {
            ft.window_over = true;
            ft.end_tick = global_tick;
          }
          // Unlike the 3-D runner, only once detected: a knock's contact loss may come
          // after its window, and an "ok" before it is no reacquisition.
          if (ft.window_over && fr.detection_ticks >= 0 && fr.reacquire_ticks < 0 &&
              status == ControllerStatus::ok &&
              (fs.kind == FaultSpec::Kind::tactile_dropout || fs.kind == FaultSpec::Kind::knock))
            fr.reacquire_ticks = global_tick - ft.end_tick;
          fr.max_force_integral = std::max(fr.max_force_integral, controller.max_force_integral());
        }
        ++global_tick;
        const CommandOverride& co = spec.command_override;
        for (int i = 0; i < kFingers; ++i) {
          const bool overridden = co.finger == i && co.stage == static_cast<int>(si) &&
                                  t - stage_start >= co.start - 0.5 * dt;
          world.set_joint_velocity(
              i, overridden
                     ? co.joint_velocity
                     : JointVector(out.fingers[static_cast<std::size_t>(i)].joint_velocities));
        }
        world.step(dt);
        t += dt;

        const Pose<double, 2> actual = world.object_pose();
        const Pose<double, 2> desired =
            st.kind == StageKind::grasp ? actual : out.desired_object_pose;
        double ep = 0.0, er = 0.0;
        plant::pose_errors<2>(desired, actual, ep, er);
        read_truth();
        if (status == ControllerStatus::invalid_input)
          for (auto& ft : truth) ft.desired_force = 0.0;
        acc.add_tick(t - stage_start, ep, er, truth, out.force_residual.norm());
        const bool last =
            k + 1 == ticks || (st.kind == StageKind::grasp && status == ControllerStatus::grasped);
        if (observer) {
          TickRecord rec;
          rec.time = t;
          rec.stage = static_cast<int>(si);
          rec.stage_time = t - stage_start;
          rec.stage_end = last;
          rec.desired = &desired;
          rec.actual = &actual;
          rec.input = &in;
          rec.output = &out;
          rec.status = status;
          rec.world = &world;
          observer(rec);
        }
        if (st.kind == StageKind::grasp && status == ControllerStatus::grasped) {
          grasped = true;
          break;
        }
      }
      const bool completed = st.kind != StageKind::grasp || grasped;
      StageMetrics m = acc.finish(t, completed);
      if (st.kind == StageKind::grasp) {
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
    result.link_contacts = world.link_contacts();
    return result;
  }
};

}  // namespace inhand::box2d_demo
