// Scenario files of the analytic 3-D plant: JSON -> inhand::plant::ScenarioSpec plus
// the expectations checked after the run. The format is documented in docs/scenarios.md
// ("The scenario file"); every key not given takes the library default (the default
// member values of PlantParams, ReactiveController::Config, StageSpec, ...).
//
// Strictness: unknown keys, wrong types, values outside the documented ranges (which
// also bound "huge" values), non-unique stage names, a first stage that is not a grasp
// and configurations the plant or the controller reject (HandPlant::validate,
// ReactiveController::validate, e.g. a time step too large for the contact stiffness)
// all throw JsonError naming the key path, e.g. "plant.time_step: ...".
//
// Units SI (m, rad, s, kg, N). The object pose is given as an offset from the hand
// preset's nominal object pose: position p = p_nominal + position, orientation
// R = rotation_from_euler(rpy) * R_nominal (a rotation about world axes through the
// object centre, R = Rz(yaw) Ry(pitch) Rx(roll)).
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "common/expectations.hpp"
#include "common/json_reader.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/presets_allegro.hpp"
#include "inhand/sim/presets_coupled.hpp"
#include "inhand/sim/scenario.hpp"

namespace inhand::examples {

/// Bounds on what the controller made of one injected fault (the fault's optional
/// "expect" object), checked against plant::FaultReport after the run.
struct FaultExpectation {
  /// Ticks from the fault's start until the controller reported it (a fault never
  /// reported violates any bound).
  std::optional<long long> max_detection_ticks;
  /// Dropout / knock: ticks after the fault window until every finger touched again
  /// (never is a violation).
  std::optional<long long> max_reacquire_ticks;
  /// Largest |force integral| of any finger's servo from the fault's start [N s].
  std::optional<double> max_force_integral;
};

/// The MuJoCo plant of a scenario file ("plant": {"engine": "mujoco", ...}; docs/mujoco.md):
/// the MJCF model and the settings of examples/mujoco's MujocoSetup, with its names and
/// defaults (tests/mujoco holds them equal), kept free of MuJoCo's headers so that the
/// format parses in a build without MuJoCo.
struct MujocoPlantFile {
  /// MJCF file: a name in the project's models/ folder, or a path (with a '/'). A file
  /// that does not name one gets "<hand>_cylinder.xml" (the hand's cylinder scene); the
  /// default here is the three-finger hand's, as MujocoSetup's. Its hand must be the
  /// file's hand preset, with a body "palm", per finger a tip geom "<finger>_tip", a body
  /// "object" with a free joint and a weld "object_hold" (models/*.xml).
  std::string model = "three_finger_cylinder.xml";
  double position_gain = 30.0;      ///< 1/s, the hand servo's set-point gain
  double friction = 0.0;            ///< object's and fingertips' sliding friction; 0: the model's
  double torsional_friction = 0.0;  ///< m, on the object's geoms; 0: none (the model's)
  double touch_threshold = 0.02;    ///< N, touching above this normal force
  double object_mass = 0.0;         ///< kg ("object": {"mass"}); 0: the model's
  /// The controller is told the model's gravity (its opt.gravity, world frame) as
  /// ForceLayerParams::gravity_direction: ScenarioFile::gravity_from_plant.
  bool gravity_from_model = false;
};

struct ScenarioFile {
  /// The plant: spec.hand, spec.object and spec.plant describe the analytic plant; with
  /// engine "mujoco", `mujoco` describes the MuJoCo world (spec.hand is its hand preset,
  /// spec.object.pose its nominal object pose; spec.plant is unused).
  std::string engine = "analytic";
  MujocoPlantFile mujoco;
  plant::ScenarioSpec spec;
  Expectations expect;
  std::vector<FaultExpectation> fault_expect;  ///< one per spec.faults entry
  std::string
      hand_preset;  ///< "shadow_like", "three_finger", "allegro_like", "shadow_like_coupled"
  std::string description;
  /// controller.force_layer.gravity_direction left out or "plant" (the default): the
  /// controller knows which way the plant's gravity pulls, as a hand on an arm knows it from
  /// the arm's pose. The analytic plant's gravity is written into
  /// spec.controller.force_layer.gravity_direction here; MuJoCo's comes from the model
  /// (mujoco.gravity_from_model). A vector given there is taken as it is; [0, 0, 0]: the
  /// controller is not told (docs/scenarios.md).
  bool gravity_from_plant = true;
};

namespace scenario_detail {

constexpr double kPi = 3.14159265358979323846;
/// Longest simulated time a scenario may request [s].
constexpr double kMaxScenarioTime = 3600.0;

inline Eigen::Vector3d vec3(const std::vector<double>& v) {
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

inline PiGains<double> read_pi(ObjectReader r, const PiGains<double>& d) {
  PiGains<double> g = d;
  g.kp = r.number("kp", d.kp, Range::non_negative_up_to(1e6));
  g.ki = r.number("ki", d.ki, Range::non_negative_up_to(1e6));
  g.integral_limit = r.limit("integral_limit", d.integral_limit, Range::positive_up_to(1e9));
  g.output_limit = r.limit("output_limit", d.output_limit, Range::positive_up_to(1e9));
  r.finish();
  return g;
}

inline plant::ObjectDef read_object(ObjectReader r, const plant::HandPreset& hand) {
  plant::ObjectDef o;
  const std::string shape = r.choice("shape", "", {"cylinder", "box", "sphere"}, true);
  const Range dim = Range::positive_up_to(1.0);
  if (shape == "cylinder") {
    const double radius = r.required_number("radius", dim);
    const double length = r.required_number("length", dim);
    o.shape = plant::ObjectShape::cylinder(radius, 0.5 * length);
  } else if (shape == "box") {
    const std::vector<double> size = r.numbers("size", {}, 3, dim, true);
    o.shape = plant::ObjectShape::box(0.5 * size[0], 0.5 * size[1], 0.5 * size[2]);
  } else {
    o.shape = plant::ObjectShape::sphere(r.required_number("radius", dim));
  }
  o.mass = r.number("mass", o.mass, Range::positive_up_to(100.0));
  ObjectReader off = r.object("pose_offset");
  const Eigen::Vector3d dp = vec3(off.numbers("position", {0, 0, 0}, 3, Range::closed(-0.5, 0.5)));
  const Eigen::Vector3d rpy = vec3(off.numbers("rpy", {0, 0, 0}, 3, Range::closed(-kPi, kPi)));
  off.finish();
  r.finish();
  o.pose.position = hand.object_pose.position + dp;
  o.pose.rotation = rotation_from_euler<double>(rpy) * hand.object_pose.rotation;
  return o;
}

inline plant::PlantParams read_plant(ObjectReader r) {
  plant::PlantParams p = plant::default_plant_params();
  p.time_step = r.number("time_step", p.time_step, Range::positive_up_to(1e-3));
  plant::ContactParams& c = p.contact;
  c.friction = r.number("friction", c.friction, Range::non_negative_up_to(10.0));
  c.normal_stiffness = r.number("normal_stiffness", c.normal_stiffness, Range::positive_up_to(1e7));
  c.normal_damping = r.number("normal_damping", c.normal_damping, Range::non_negative_up_to(1e5));
  c.tangential_stiffness =
      r.number("tangential_stiffness", c.tangential_stiffness, Range::positive_up_to(1e7));
  c.tangential_damping =
      r.number("tangential_damping", c.tangential_damping, Range::non_negative_up_to(1e5));
  p.gravity = vec3(r.numbers("gravity", {p.gravity.x(), p.gravity.y(), p.gravity.z()}, 3,
                             Range::closed(-100.0, 100.0)));
  p.joint_velocity_lag =
      r.number("joint_velocity_lag", p.joint_velocity_lag, Range::non_negative_up_to(10.0));
  p.command_delay = static_cast<int>(
      r.integer("command_delay", p.command_delay, 0, plant::PlantParams::kMaxCommandDelay));
  ObjectReader s = r.object("sensing");
  plant::SensorNoise& n = p.sensing;
  n.normal_force_std =
      s.number("normal_force_std", n.normal_force_std, Range::non_negative_up_to(100.0));
  n.normal_force_bias =
      s.number("normal_force_bias", n.normal_force_bias, Range::closed(-100.0, 100.0));
  n.normal_force_gain_error =
      s.number("normal_force_gain_error", n.normal_force_gain_error, Range::closed(-0.9, 10.0));
  n.normal_force_relative_std = s.number("normal_force_relative_std", n.normal_force_relative_std,
                                         Range::non_negative_up_to(1.0));
  n.contact_point_std =
      s.number("contact_point_std", n.contact_point_std, Range::non_negative_up_to(0.1));
  n.normal_angle_std =
      s.number("normal_angle_std", n.normal_angle_std, Range::non_negative_up_to(1.0));
  n.object_position_std =
      s.number("object_position_std", n.object_position_std, Range::non_negative_up_to(0.1));
  n.object_rotation_std =
      s.number("object_rotation_std", n.object_rotation_std, Range::non_negative_up_to(1.0));
  n.touch_threshold =
      s.number("touch_threshold", n.touch_threshold, Range::non_negative_up_to(100.0));
  s.finish();
  p.seed =
      static_cast<std::uint64_t>(r.integer("seed", static_cast<long long>(p.seed), 0, (1LL << 53)));
  r.finish();
  return p;
}

/// `hand`: the file's hand preset, whose cylinder scene (models/<hand>_cylinder.xml) is
/// the default model.
inline MujocoPlantFile read_mujoco_plant(ObjectReader r, const std::string& hand) {
  MujocoPlantFile p;
  p.model = r.string("model", hand + "_cylinder.xml");
  if (p.model.empty() || p.model.size() > 4096)
    throw JsonError(r.key_path("model"), "must have 1 to 4096 characters");
  p.position_gain = r.number("position_gain", p.position_gain, Range::non_negative_up_to(1e4));
  p.friction = r.number("friction", p.friction, Range::non_negative_up_to(10.0));
  p.torsional_friction =
      r.number("torsional_friction", p.torsional_friction, Range::non_negative_up_to(1.0));
  p.touch_threshold =
      r.number("touch_threshold", p.touch_threshold, Range::non_negative_up_to(100.0));
  r.finish();
  return p;
}

/// The object of a MuJoCo scenario is the model's: only its mass may be given.
inline double read_mujoco_object_mass(ObjectReader r) {
  for (const char* k : {"shape", "radius", "length", "size", "pose_offset"})
    if (r.has(k))
      throw JsonError(r.key_path(k),
                      "the object of plant.engine \"mujoco\" is the model's (plant.model); "
                      "only object.mass may be given");
  const double m = r.number("mass", 0.0, Range::positive_up_to(100.0));
  r.finish();
  return m;
}

/// `gravity_from_plant`: set to whether force_layer.gravity_direction is left out or "plant".
inline plant::HandController::Config read_controller(ObjectReader r, bool& gravity_from_plant) {
  plant::HandController::Config c{};
  c.control_period = r.number("control_period", c.control_period, Range::positive_up_to(0.1));
  c.max_tick = r.number("max_tick", c.max_tick, Range::positive_up_to(1.0));
  c.max_joint_acceleration =
      r.limit("max_joint_acceleration", c.max_joint_acceleration, Range::positive_up_to(1e9));
  c.keep_twist_in_reach = r.boolean("keep_twist_in_reach", c.keep_twist_in_reach);
  c.at_risk_hold = r.number("at_risk_hold", c.at_risk_hold, Range::non_negative_up_to(10.0));
  {
    ObjectReader f = r.object("pose_feedback");
    PoseFeedback<double>& pf = c.pose_feedback;
    pf.position_gain = f.number("position_gain", pf.position_gain, Range::non_negative_up_to(1e4));
    pf.orientation_gain =
        f.number("orientation_gain", pf.orientation_gain, Range::non_negative_up_to(1e4));
    pf.max_linear_speed =
        f.number("max_linear_speed", pf.max_linear_speed, Range::positive_up_to(10.0));
    pf.max_angular_speed =
        f.number("max_angular_speed", pf.max_angular_speed, Range::positive_up_to(100.0));
    pf.position_integral_gain = f.number("position_integral_gain", pf.position_integral_gain,
                                         Range::non_negative_up_to(1e6));
    pf.orientation_integral_gain = f.number(
        "orientation_integral_gain", pf.orientation_integral_gain, Range::non_negative_up_to(1e6));
    pf.position_integral_limit = f.number("position_integral_limit", pf.position_integral_limit,
                                          Range::positive_up_to(10.0));
    pf.orientation_integral_limit = f.number(
        "orientation_integral_limit", pf.orientation_integral_limit, Range::positive_up_to(100.0));
    pf.position_integral_band =
        f.limit("position_integral_band", pf.position_integral_band, Range::positive_up_to(10.0));
    pf.orientation_integral_band = f.limit(
        "orientation_integral_band", pf.orientation_integral_band, Range::positive_up_to(100.0));
    pf.astray_distance =
        f.limit("astray_distance", pf.astray_distance, Range::positive_up_to(10.0));
    pf.astray_angle = f.limit("astray_angle", pf.astray_angle, Range::positive_up_to(100.0));
    pf.astray_time = f.number("astray_time", pf.astray_time, Range::non_negative_up_to(3600.0));
    f.finish();
  }
  {
    ObjectReader s = r.object("servo");
    c.servo.motion = read_pi(s.object("motion"), c.servo.motion);
    c.servo.force = read_pi(s.object("force"), c.servo.force);
    s.finish();
  }
  {
    ObjectReader k = r.object("ik");
    DampingSchedule<double>& d = c.ik.damping;
    d.singular_threshold =
        k.number("singular_threshold", d.singular_threshold, Range::positive_up_to(1.0));
    d.max_damping = k.number("max_damping", d.max_damping, Range::non_negative_up_to(1.0));
    c.ik.limited_normal_weight =
        k.number("limited_normal_weight", c.ik.limited_normal_weight, Range::closed(1.0, 1000.0));
    k.finish();
  }
  {
    ObjectReader f = r.object("force_planner");
    ForcePlannerParams<double>& fp = c.force_planner;
    fp.nominal_force = f.number("nominal_force", fp.nominal_force, Range::positive_up_to(1000.0));
    fp.min_force = f.number("min_force", fp.min_force, Range::non_negative_up_to(1000.0));
    fp.max_force = f.number("max_force", fp.max_force, Range::non_negative_up_to(1000.0));
    fp.regularisation = f.number("regularisation", fp.regularisation, Range::positive_up_to(1e6));
    fp.filter_time = f.number("filter_time", fp.filter_time, Range::non_negative_up_to(10.0));
    f.finish();
  }
  {
    ObjectReader f = r.object("force_layer");
    ForceLayerParams<double>& fl = c.force_layer;
    fl.bandwidth = f.number("bandwidth", fl.bandwidth, Range::positive_up_to(1e4));
    fl.integral_corner =
        f.number("integral_corner", fl.integral_corner, Range::non_negative_up_to(1e4));
    fl.min_stiffness = f.number("min_stiffness", fl.min_stiffness, Range::positive_up_to(1e9));
    fl.max_stiffness = f.number("max_stiffness", fl.max_stiffness, Range::positive_up_to(1e9));
    fl.stiffness_window =
        f.number("stiffness_window", fl.stiffness_window, Range::positive_up_to(100.0));
    fl.min_excitation = f.number("min_excitation", fl.min_excitation, Range::positive_up_to(1.0));
    fl.min_fit = f.number("min_fit", fl.min_fit, Range::positive_up_to(1.0));
    fl.max_integral_velocity =
        f.number("max_integral_velocity", fl.max_integral_velocity, Range::positive_up_to(10.0));
    fl.slip_distance = f.number("slip_distance", fl.slip_distance, Range::positive_up_to(1.0));
    fl.grip_rise_rate =
        f.number("grip_rise_rate", fl.grip_rise_rate, Range::non_negative_up_to(1e4));
    fl.friction_margin = f.number("friction_margin", fl.friction_margin, Range::closed(1.0, 100.0));
    fl.grip_decay_time =
        f.number("grip_decay_time", fl.grip_decay_time, Range::positive_up_to(1e6));
    fl.release_grip = f.number("release_grip", fl.release_grip, Range::closed(1.0, 100.0));
    fl.hold_release_grip = f.boolean("hold_release_grip", fl.hold_release_grip);
    fl.release_load = f.number("release_load", fl.release_load, Range::closed(0.0, 1000.0));
    fl.rigid_tolerance =
        f.number("rigid_tolerance", fl.rigid_tolerance, Range::positive_up_to(1.0));
    fl.contact_damping =
        f.number("contact_damping", fl.contact_damping, Range::non_negative_up_to(1e6));
    fl.capacity_time = f.number("capacity_time", fl.capacity_time, Range::non_negative_up_to(10.0));
    fl.capacity_slide_ratio =
        f.number("capacity_slide_ratio", fl.capacity_slide_ratio, Range::closed(0.0, 1.0));
    fl.servo_stiffness =
        f.number("servo_stiffness", fl.servo_stiffness, Range::non_negative_up_to(1e6));
    fl.servo_damping = f.number("servo_damping", fl.servo_damping, Range::non_negative_up_to(1e6));
    const Json* gd = f.raw("gravity_direction");
    gravity_from_plant = gd == nullptr || gd->is_string();
    if (gravity_from_plant) {
      f.choice("gravity_direction", "plant", {"plant"});
    } else {
      const Eigen::Vector3d g = fl.gravity_direction;
      fl.gravity_direction =
          vec3(f.numbers("gravity_direction", {g.x(), g.y(), g.z()}, 3, Range::closed(-1e3, 1e3)));
    }
    f.finish();
  }
  {
    ObjectReader o = r.object("outlier_gates");
    OutlierGates<double>& og = c.outlier_gates;
    og.max_object_speed =
        o.limit("max_object_speed", og.max_object_speed, Range::positive_up_to(1e6));
    og.max_object_angular_speed = o.limit("max_object_angular_speed", og.max_object_angular_speed,
                                          Range::positive_up_to(1e6));
    og.max_force_rate = o.limit("max_force_rate", og.max_force_rate, Range::positive_up_to(1e9));
    og.contact_stiffness =
        o.number("contact_stiffness", og.contact_stiffness, Range::non_negative_up_to(1e9));
    if (o.has("max_consecutive_rejections"))
      throw JsonError(o.key_path("max_consecutive_rejections"),
                      "replaced by max_rejection_time, in seconds (5 ticks at 1 kHz: 0.005)");
    og.max_rejection_time =
        o.number("max_rejection_time", og.max_rejection_time, Range::non_negative_up_to(1e3));
    o.finish();
  }
  {
    ObjectReader g = r.object("grasp");
    GraspParams<double>& gp = c.grasp;
    gp.approach_gain = g.number("approach_gain", gp.approach_gain, Range::positive_up_to(1e4));
    gp.approach_speed = g.number("approach_speed", gp.approach_speed, Range::positive_up_to(10.0));
    gp.creep_speed = g.number("creep_speed", gp.creep_speed, Range::positive_up_to(10.0));
    gp.tangential_gain =
        g.number("tangential_gain", gp.tangential_gain, Range::non_negative_up_to(1e4));
    gp.force_tolerance =
        g.number("force_tolerance", gp.force_tolerance, Range::positive_up_to(10.0));
    gp.position_tolerance =
        g.number("position_tolerance", gp.position_tolerance, Range::positive_up_to(1.0));
    gp.alignment_speed =
        g.number("alignment_speed", gp.alignment_speed, Range::non_negative_up_to(10.0));
    gp.alignment_tolerance =
        g.number("alignment_tolerance", gp.alignment_tolerance, Range::positive_up_to(kPi));
    gp.settle_time = g.number("settle_time", gp.settle_time, Range::non_negative_up_to(100.0));
    gp.slide_force_fraction =
        g.number("slide_force_fraction", gp.slide_force_fraction, Range::positive_up_to(1.0));
    gp.gravity_tilt =
        g.number("gravity_tilt", gp.gravity_tilt, Range::non_negative_up_to(0.7853981633974483));
    gp.flat_curvature =
        g.number("flat_curvature", gp.flat_curvature, Range::non_negative_up_to(1e6));
    g.finish();
  }
  r.finish();
  return c;
}

inline TrajectorySegment<double, 3> read_segment(ObjectReader r) {
  TrajectorySegment<double, 3> s;
  const std::string kind = r.choice("kind", "", {"hold", "move", "rotate", "reciprocate"}, true);
  s.duration = r.number("duration", s.duration, Range::positive_up_to(kMaxScenarioTime));
  if (kind == "hold") {
    s.kind = SegmentKind::hold;
    r.finish();
    return s;
  }
  // reciprocate: "motion" says whether `amount` is a translation or a rotation.
  const std::string motion =
      kind == "reciprocate" ? r.choice("motion", "", {"move", "rotate"}, true) : kind;
  const Eigen::Vector3d axis = vec3(r.numbers("axis", {}, 3, Range::closed(-1e3, 1e3), true));
  if (!(axis.norm() > 1e-9)) throw JsonError(r.key_path("axis"), "must be a non-zero vector");
  const bool rot = motion == "rotate";
  const double amount = r.required_number(
      "amount", rot ? Range::closed(-2 * kPi, 2 * kPi) : Range::closed(-1.0, 1.0));
  Twist<double, 3> d = Twist<double, 3>::Zero();
  if (rot)
    d.tail<3>() = amount * axis.normalized();
  else
    d.head<3>() = amount * axis.normalized();
  if (kind == "reciprocate") {
    s.kind = SegmentKind::reciprocate;
    s.cycles = static_cast<int>(r.integer("cycles", s.cycles, 1, 1000));
  } else {
    s.kind = rot ? SegmentKind::rotate : SegmentKind::move;
  }
  s.displacement = d;
  r.finish();
  return s;
}

inline plant::StageSpec read_stage(ObjectReader r, std::size_t index) {
  plant::StageSpec st;
  st.name = r.string("name", "stage" + std::to_string(index));
  if (st.name.empty()) throw JsonError(r.key_path("name"), "must not be empty");
  if (st.name == all_stages_key())
    throw JsonError(r.key_path("name"), "\"all\" is reserved (it names every stage in \"expect\")");
  const std::string kind = r.choice("kind", "", {"grasp", "hold", "manipulate"}, true);
  if (kind == "grasp") {
    st.kind = plant::StageKind::grasp;
    st.duration = r.number("duration", st.duration, Range::positive_up_to(kMaxScenarioTime));
  } else if (kind == "hold") {
    st.kind = plant::StageKind::hold;
    st.duration = r.number("duration", st.duration, Range::positive_up_to(kMaxScenarioTime));
    st.release = r.boolean("release", st.release);
  } else {
    st.kind = plant::StageKind::manipulate;
    st.release = r.boolean("release", st.release);
    st.settle = r.number("settle", st.settle, Range::non_negative_up_to(kMaxScenarioTime));
    const Json& segs = r.array("segments", false);
    const std::string base = r.key_path("segments");
    if (segs.size() > 32) throw JsonError(base, "at most 32 segments per stage");
    for (std::size_t i = 0; i < segs.size(); ++i)
      st.segments.push_back(read_segment(ObjectReader(segs[i], index_path(base, i))));
  }
  r.finish();
  return st;
}

inline FaultExpectation read_fault_expectation(ObjectReader r) {
  FaultExpectation e;
  if (r.has("max_detection_ticks"))
    e.max_detection_ticks = r.integer("max_detection_ticks", 0, 0, 100000000);
  if (r.has("max_reacquire_ticks"))
    e.max_reacquire_ticks = r.integer("max_reacquire_ticks", 0, 0, 100000000);
  e.max_force_integral = r.optional_number("max_force_integral", Range::non_negative_up_to(1e6));
  r.finish();
  return e;
}

inline plant::FaultSpec read_fault(ObjectReader r, const std::vector<std::string>& stage_names,
                                   int fingers, FaultExpectation& expect) {
  using Kind = plant::FaultSpec::Kind;
  plant::FaultSpec f;
  const std::string kind = r.choice(
      "kind", "", {"tactile_dropout", "force_spike", "pose_outlier", "knock", "finger_away"}, true);
  f.kind = kind == "tactile_dropout" ? Kind::tactile_dropout
           : kind == "force_spike"   ? Kind::force_spike
           : kind == "pose_outlier"  ? Kind::pose_outlier
           : kind == "knock"         ? Kind::knock
                                     : Kind::finger_away;
  f.stage = r.string("stage", f.stage);
  bool known = false;
  for (const std::string& n : stage_names) known = known || n == f.stage;
  if (!known) throw JsonError(r.key_path("stage"), "no stage named \"" + f.stage + "\"");
  f.at = r.number("at", f.at, Range::non_negative_up_to(kMaxScenarioTime));
  f.duration = r.number("duration", f.duration, Range::non_negative_up_to(kMaxScenarioTime));
  if (f.kind != Kind::pose_outlier && f.kind != Kind::knock)
    f.finger = static_cast<int>(r.integer("finger", f.finger, 0, fingers - 1));
  if (f.kind == Kind::force_spike)
    f.magnitude = r.number("magnitude", f.magnitude, Range::closed(-1000.0, 1000.0));
  if (f.kind == Kind::pose_outlier)  // m
    f.vector = vec3(r.numbers("vector", {0, 0, 0}, 3, Range::closed(-1.0, 1.0)));
  if (f.kind == Kind::knock)  // N
    f.vector = vec3(r.numbers("vector", {0, 0, 0}, 3, Range::closed(-1000.0, 1000.0)));
  if (r.has("expect")) expect = read_fault_expectation(r.object("expect"));
  r.finish();
  return f;
}

/// Where a field named by HandPlant::validate / ReactiveController::validate lives in
/// the file.
inline std::string plant_field_path(const std::string& f) {
  if (f.rfind("contact.", 0) == 0) return "plant." + f.substr(8);
  if (f.rfind("sensing.", 0) == 0 || f == "time_step" || f == "gravity" ||
      f == "joint_velocity_lag")
    return "plant." + f;
  if (f == "shape.radius") return "object.radius";
  if (f == "shape.half_length") return "object.length";
  if (f == "shape.half_extents") return "object.size";
  if (f == "mass") return "object.mass";
  if (f.rfind("pose", 0) == 0) return "object.pose_offset";
  return "hand (" + f + ")";
}

inline std::string controller_field_path(const std::string& f) {
  if (f.rfind("ik.", 0) == 0) return "controller.ik";
  return "controller." + f;
}

inline double stage_time(const plant::StageSpec& s) {
  if (s.kind != plant::StageKind::manipulate) return s.duration;
  double t = s.settle;
  for (const auto& seg : s.segments) t += seg.duration;
  return t;
}

}  // namespace scenario_detail

/// Upper bounds on the work of a run of `spec` by plant::ScenarioRunner, known before it
/// starts (reached unless a grasp completes before its timeout or the run stops early).
/// Doubles: a tiny time step may give counts beyond any integer type.
struct RunSize {
  double simulated_time = 0.0;  ///< s, all stages
  double control_ticks = 0.0;   ///< controller updates = rows of a trace
  double plant_steps = 0.0;     ///< internal integration steps of the plant
};

/// As the runner counts: round(stage time / control_period) ticks per stage, each
/// advancing the plant by control_period / time_step steps.
inline RunSize run_size(const plant::ScenarioSpec& spec) {
  RunSize r;
  const double dt = spec.controller.control_period;
  for (const plant::StageSpec& st : spec.stages) {
    const double t = scenario_detail::stage_time(st);
    r.simulated_time += t;
    r.control_ticks += std::round(t / dt);
  }
  r.plant_steps = std::round(r.control_ticks * dt / spec.plant.time_step);
  return r;
}

/// Builds a ScenarioFile from parsed JSON; throws JsonError (see the file comment).
inline ScenarioFile parse_scenario(const Json& j) {
  ScenarioFile out;
  ObjectReader r(j, "");
  plant::ScenarioSpec& s = out.spec;
  s.name = r.required_string("name");
  if (s.name.empty() || s.name.size() > 200)
    throw JsonError("name", "must have 1 to 200 characters");
  out.description = r.string("description", "");
  out.hand_preset =
      r.choice("hand", "shadow_like",
               {"shadow_like", "three_finger", "allegro_like", "shadow_like_coupled"});
  if (out.hand_preset == "three_finger")
    s.hand = plant::three_finger_hand();
  else if (out.hand_preset == "allegro_like")
    s.hand = plant::allegro_like_hand();
  else if (out.hand_preset == "shadow_like_coupled")
    s.hand = plant::shadow_like_coupled_hand();
  else
    s.hand = plant::shadow_like_hand();
  ObjectReader plant_reader = r.object("plant");
  out.engine = plant_reader.choice("engine", "analytic", {"analytic", "mujoco"});
  const bool mujoco = out.engine == "mujoco";
  if (mujoco) {
    if (out.hand_preset != "three_finger" && out.hand_preset != "shadow_like")
      throw JsonError("hand",
                      "plant.engine \"mujoco\" has the three_finger and shadow_like "
                      "hands (models/), got \"" +
                          out.hand_preset + "\"");
    out.mujoco = scenario_detail::read_mujoco_plant(plant_reader, out.hand_preset);
    if (r.has("object"))
      out.mujoco.object_mass = scenario_detail::read_mujoco_object_mass(r.object("object"));
    s.object.pose = s.hand.object_pose;
  } else {
    if (!r.has("object")) throw JsonError("object", "required key is missing");
    s.object = scenario_detail::read_object(r.object("object"), s.hand);
    s.plant = scenario_detail::read_plant(plant_reader);
  }
  s.controller = scenario_detail::read_controller(r.object("controller"), out.gravity_from_plant);
  if (out.gravity_from_plant) {
    if (mujoco)
      out.mujoco.gravity_from_model = true;
    else
      s.controller.force_layer.gravity_direction = s.plant.gravity;
  }
  {
    ObjectReader t = r.object("tolerances");
    plant::MetricsTolerances& m = s.tolerances;
    m.drop_distance = t.number("drop_distance", m.drop_distance, Range::positive_up_to(1.0));
    m.settle_position_tolerance = t.number("settle_position_tolerance", m.settle_position_tolerance,
                                           Range::positive_up_to(1.0));
    m.settle_orientation_tolerance =
        t.number("settle_orientation_tolerance", m.settle_orientation_tolerance,
                 Range::positive_up_to(scenario_detail::kPi));
    t.finish();
  }
  const Json& stages = r.array("stages", true);
  if (stages.empty()) throw JsonError("stages", "needs at least one stage");
  if (stages.size() > 100) throw JsonError("stages", "at most 100 stages");
  std::vector<std::string> names;
  double total = 0.0;
  for (std::size_t i = 0; i < stages.size(); ++i) {
    const std::string p = index_path("stages", i);
    plant::StageSpec st = scenario_detail::read_stage(ObjectReader(stages[i], p), i);
    for (const std::string& n : names)
      if (n == st.name) throw JsonError(p + ".name", "duplicate stage name \"" + st.name + "\"");
    if (i == 0 && st.kind != plant::StageKind::grasp)
      throw JsonError(
          p + ".kind",
          "the first stage must be a grasp (hold and manipulate need a grasped object)");
    const double t = scenario_detail::stage_time(st);
    if (t < s.controller.control_period) throw JsonError(p, "lasts less than one control period");
    total += t;
    names.push_back(st.name);
    s.stages.push_back(st);
  }
  if (total > scenario_detail::kMaxScenarioTime)
    throw JsonError("stages", "total duration " + Range::format_number(total) + " s exceeds " +
                                  Range::format_number(scenario_detail::kMaxScenarioTime) + " s");
  const Json& faults = r.array("faults", false);
  if (faults.size() > 100) throw JsonError("faults", "at most 100 faults");
  for (std::size_t i = 0; i < faults.size(); ++i) {
    out.fault_expect.emplace_back();
    s.faults.push_back(scenario_detail::read_fault(ObjectReader(faults[i], index_path("faults", i)),
                                                   names, static_cast<int>(s.hand.fingers.size()),
                                                   out.fault_expect.back()));
  }
  if (const Json* e = r.raw("expect")) out.expect = parse_expectations(*e, "expect", names);
  r.finish();

  // Cross-field checks of the plant and the controller, reported by key.
  Validation v;
  if (!mujoco) {  // (MuJoCo's model is checked when it is loaded, before the run)
    if (s.controller.control_period < s.plant.time_step)
      throw JsonError("controller.control_period", "must be >= plant.time_step");
    v = plant::HandPlant::validate(s.hand.fingers, s.object, s.plant);
    if (!v.ok()) throw JsonError(scenario_detail::plant_field_path(v.field), v.reason);
  }
  v = plant::HandController::validate(plant::controller_config_for(s.hand, s.controller));
  if (!v.ok()) throw JsonError(scenario_detail::controller_field_path(v.field), v.reason);
  return out;
}

/// Human-readable violations of the faults' "expect" bounds by the run's fault reports
/// (same order as the file's "faults"); empty when all hold.
inline std::vector<std::string> check_fault_expectations(
    const std::vector<FaultExpectation>& expect, const std::vector<plant::FaultReport>& reports) {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < expect.size() && i < reports.size(); ++i) {
    const FaultExpectation& e = expect[i];
    const plant::FaultReport& r = reports[i];
    const std::string who = "fault " + std::to_string(i) + " (" + plant::to_string(r.kind) + ")";
    const auto check_ticks = [&](const char* what, long ticks,
                                 const std::optional<long long>& bound) {
      if (!bound) return;
      if (ticks < 0)
        out.push_back(who + ": " + what + " never happened (bound " + std::to_string(*bound) +
                      " ticks)");
      else if (ticks > *bound)
        out.push_back(who + ": " + what + " after " + std::to_string(ticks) + " ticks exceeds " +
                      std::to_string(*bound));
    };
    check_ticks("detection", r.detection_ticks, e.max_detection_ticks);
    check_ticks("reacquisition", r.reacquire_ticks, e.max_reacquire_ticks);
    if (e.max_force_integral && !(r.max_force_integral <= *e.max_force_integral))
      out.push_back(who + ": max |force integral| " + detail::fmt(r.max_force_integral) +
                    " N s exceeds " + detail::fmt(*e.max_force_integral) + " N s");
  }
  return out;
}

/// Reads, parses and validates a scenario file; JsonError messages start with the
/// file name.
inline ScenarioFile load_scenario(const std::string& file) {
  try {
    return parse_scenario(load_json_file(file));
  } catch (const JsonError& e) {
    if (e.path() == file) throw;
    throw JsonError(file, e.what());
  }
}

}  // namespace inhand::examples
