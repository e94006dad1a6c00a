// The reactive in-hand manipulation controller: one update() per control tick
// (method.md section 7, paper Fig. 2).
//
//   layer 1  trajectory : desired object pose X_d(t) (controller/trajectory.hpp) and
//                         the commanded object twist
//                           V = V_ff + K_p e + K_i integral(e),  e = pose_error(X_d, X_measured)
//                         (feed-forward plus PI feedback on the MEASURED pose, method.md
//                         s.3; gains per part, position and orientation)
//   layer 2  per finger : desired contact-point velocity v_i = v + w x (p_ci - p_o)
//                         (eq. 2 at the MEASURED contact point p_ci) and the desired
//                         normal force f_i from the force planner (section 5)
//   layer 3  per finger : hybrid servo e = g1(v_i) - g2(f_i - f_i,measured) n_i
//                         (eqs. 4-7) and theta_dot = J_F^+ e (eq. 3)
// Frames and units: world frame, SI. Contact normals n are the object's OUTWARD unit
// normals (towards the fingertip); forces are normal-force magnitudes >= 0 in newtons.
// Twists are (linear velocity of the object reference point ; angular velocity).
//
// Real-time contract: update() is noexcept, allocates nothing (fixed NumFingers and
// fixed or bounded DOF, an Output from make_output()), never prints, and runs in time
// bounded by the hand's size. Invalid input (non-finite or malformed) makes update()
// return ControllerStatus::invalid_input with `output.fault` naming the field and
// finger; the output is then the documented fallback: zero joint velocity in every
// finger slot the Output has (never resized), and no internal state changes
// (integrators, filters, time are frozen), so the next valid tick resumes where the
// last valid one ended. Malformed includes an Input or Output with the wrong number of
// fingers (InputField::finger_count) and an Output whose joint_velocities do not have
// the finger's DOF (InputField::output_joint_velocities): update() never resizes.
// Nothing non-finite leaves update(): the outputs are checked at the end of every tick;
// a non-finite value (an overflow the input checks did not foresee) gives
// ControllerStatus::numerical_fault, Output::numerical_fault naming the stage, the same
// zero fallback and the state of the tick before (update() saves it at the start).
// Time: Input::time is a double whatever Scalar is (a time base that keeps 1 us
// resolution for ~270 years); dt is computed in double and then converted to Scalar.
//
// Phases, driven by the user: configure() -> start_grasp(targets) -> update() ...
// returns `grasped` once every finger presses with the nominal force -> the user
// releases the object and calls start_manipulation(trajectory) -> update() tracks it.
// Mixed-DOF hands: use Dof = inhand::Dynamic with MaxDof the largest finger (e.g. a
// 5-joint thumb and 4-joint fingers: Dof = Dynamic, MaxDof = 5): still no allocation.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <type_traits>
#include <vector>

#include "inhand/controller/force_layer.hpp"
#include "inhand/controller/force_planner.hpp"
#include "inhand/controller/grasp.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/controller/trajectory.hpp"
#include "inhand/kinematics/contact_kinematics.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace inhand {

/// Overall result of one update().
enum class ControllerStatus : unsigned char {
  ok,               ///< manipulating, every finger in contact
  grasping,         ///< grasp phase running
  grasped,          ///< grasp complete: every finger presses with the nominal force
  contact_lost,     ///< manipulating, at least one finger is reacquiring its contact
  idle,             ///< configured, no task started: zero output
  not_configured,   ///< configure() has not succeeded: zero output
  invalid_input,    ///< see ControllerOutput::fault; zero output, state frozen
  numerical_fault,  ///< a non-finite value arose (Output::numerical_fault names where);
                    ///< zero output, state as before the tick
};
inline const char* to_string(ControllerStatus s) noexcept {
  switch (s) {
    case ControllerStatus::ok:
      return "ok";
    case ControllerStatus::grasping:
      return "grasping";
    case ControllerStatus::grasped:
      return "grasped";
    case ControllerStatus::contact_lost:
      return "contact_lost";
    case ControllerStatus::idle:
      return "idle";
    case ControllerStatus::not_configured:
      return "not_configured";
    case ControllerStatus::invalid_input:
      return "invalid_input";
    case ControllerStatus::numerical_fault:
      return "numerical_fault";
  }
  return "unknown";
}

/// Which input field was rejected.
enum class InputField : unsigned char {
  none,
  time,
  object_pose,
  joint_positions,
  contact_point,
  contact_normal,
  normal_force,
  jacobian,
  virtual_contact_point,
  finger_count,             ///< Input::fingers or Output::fingers has the wrong size
  output_joint_velocities,  ///< an Output finger's joint_velocities is not its DOF long
};
inline const char* to_string(InputField f) noexcept {
  switch (f) {
    case InputField::none:
      return "none";
    case InputField::time:
      return "time";
    case InputField::object_pose:
      return "object_pose";
    case InputField::joint_positions:
      return "joint_positions";
    case InputField::contact_point:
      return "contact_point";
    case InputField::contact_normal:
      return "contact_normal";
    case InputField::normal_force:
      return "normal_force";
    case InputField::jacobian:
      return "jacobian";
    case InputField::virtual_contact_point:
      return "virtual_contact_point";
    case InputField::finger_count:
      return "finger_count";
    case InputField::output_joint_velocities:
      return "output_joint_velocities";
  }
  return "unknown";
}

struct InputFault {
  InputField field = InputField::none;
  int finger = -1;  ///< -1 for hand-level fields (time, object pose, finger_count)
};

/// Warnings raised during a valid tick (bit flags, never silent saturation).
enum class ControllerWarning : unsigned {
  none = 0,
  ik_damped = 1u << 0,               ///< some finger's IK was damped near a singularity
  joint_velocity_limited = 1u << 1,  ///< some finger's joint velocities were scaled down
  servo_saturated = 1u << 2,         ///< some servo PI hit its integral/output limit
  force_limited = 1u << 3,           ///< the planner limited a balancing force
  twist_limited = 1u << 4,           ///< the commanded object twist was scaled to its limit
  long_tick = 1u << 5,               ///< dt exceeded max_tick: integration used max_tick
  no_balancing_contact = 1u << 6,    ///< no balancing finger touching: forces unbalanced
  rate_limited = 1u << 7,   ///< some finger's command change was scaled to max_joint_acceleration
  pose_outlier = 1u << 8,   ///< the measured object pose jumped implausibly: previous one held
  force_outlier = 1u << 9,  ///< a measured normal force jumped implausibly: previous one held
  slipping = 1u << 10,      ///< some contact slides along the object (force layer)
  grip_raised = 1u << 11,   ///< the grip is above the nominal pattern (force layer)
  beyond_capacity = 1u << 12,  ///< the load needs more than max_force: the object may be lost
  force_integral_limited = 1u << 13,  ///< some force integrator reached its bound
  pose_integral_limited = 1u << 14,   ///< layer 1's pose-error integral reached its bound
  implausible_contact = 1u << 15,     ///< some contact is far from / behind its fingertip
};
constexpr ControllerWarning operator|(ControllerWarning a, ControllerWarning b) noexcept {
  return static_cast<ControllerWarning>(static_cast<unsigned>(a) | static_cast<unsigned>(b));
}
constexpr bool has(ControllerWarning s, ControllerWarning flag) noexcept {
  return (static_cast<unsigned>(s) & static_cast<unsigned>(flag)) != 0u;
}

template <typename Scalar>
struct PoseFeedback {
  Scalar position_gain = Scalar(8);        ///< 1/s
  Scalar orientation_gain = Scalar(8);     ///< 1/s
  Scalar max_linear_speed = Scalar(0.05);  ///< m/s, bound on the commanded linear velocity
  Scalar max_angular_speed = Scalar(1.0);  ///< rad/s
  /// Integral action on the pose error (1/s^2): removes the steady offset left where
  /// the force servos' integrators balance the proportional pose feedback.
  Scalar position_integral_gain = Scalar(10);
  Scalar orientation_integral_gain = Scalar(10);
  /// Bounds on the integrated pose error (m s and rad s), anti-windup: the norm of
  /// each part is scaled down to its bound (direction kept) and the warning
  /// pose_integral_limited is raised. The defaults let the integral term add at most
  /// position_integral_gain * 2e-3 = 0.02 m/s and orientation_integral_gain * 2e-2 =
  /// 0.2 rad/s, i.e. 40 % and 20 % of the default speed bounds.
  Scalar position_integral_limit = Scalar(2e-3);
  Scalar orientation_integral_limit = Scalar(2e-2);
  Validation validate() const noexcept {
    if (!is_finite(position_integral_gain) || position_integral_gain < Scalar(0))
      return Validation::invalid("pose_feedback.position_integral_gain", "must be finite and >= 0");
    if (!is_finite(orientation_integral_gain) || orientation_integral_gain < Scalar(0))
      return Validation::invalid("pose_feedback.orientation_integral_gain",
                                 "must be finite and >= 0");
    if (!is_finite(position_integral_limit) || !(position_integral_limit > Scalar(0)))
      return Validation::invalid("pose_feedback.position_integral_limit", "must be finite and > 0");
    if (!is_finite(orientation_integral_limit) || !(orientation_integral_limit > Scalar(0)))
      return Validation::invalid("pose_feedback.orientation_integral_limit",
                                 "must be finite and > 0");
    if (!is_finite(position_gain) || position_gain < Scalar(0))
      return Validation::invalid("pose_feedback.position_gain", "must be finite and >= 0");
    if (!is_finite(orientation_gain) || orientation_gain < Scalar(0))
      return Validation::invalid("pose_feedback.orientation_gain", "must be finite and >= 0");
    if (!(max_linear_speed > Scalar(0)))
      return Validation::invalid("pose_feedback.max_linear_speed", "must be > 0");
    if (!(max_angular_speed > Scalar(0)))
      return Validation::invalid("pose_feedback.max_angular_speed", "must be > 0");
    return Validation::valid();
  }
};

/// Plausibility gates on the sensed data (sensor faults: a vision outlier, a force
/// spike). A sample whose change since the last ACCEPTED one exceeds what the bound
/// allows over the elapsed time is rejected: the last accepted value is used instead
/// and the warning pose_outlier / force_outlier is raised. After
/// `max_consecutive_rejections` rejections in a row the sample is accepted anyway, so
/// a real jump (the object was knocked) is followed after that many ticks. Contacts
/// that (re)start touching are always accepted. +infinity (the default) disables a gate.
template <typename Scalar>
struct OutlierGates {
  Scalar max_object_speed = std::numeric_limits<Scalar>::infinity();          ///< m/s
  Scalar max_object_angular_speed = std::numeric_limits<Scalar>::infinity();  ///< rad/s
  Scalar max_force_rate = std::numeric_limits<Scalar>::infinity();            ///< N/s
  int max_consecutive_rejections = 5;
  Validation validate() const noexcept {
    if (!(max_object_speed > Scalar(0)) || max_object_speed != max_object_speed)
      return Validation::invalid("outlier_gates.max_object_speed", "must be > 0 (+inf disables)");
    if (!(max_object_angular_speed > Scalar(0)) ||
        max_object_angular_speed != max_object_angular_speed)
      return Validation::invalid("outlier_gates.max_object_angular_speed",
                                 "must be > 0 (+inf disables)");
    if (!(max_force_rate > Scalar(0)) || max_force_rate != max_force_rate)
      return Validation::invalid("outlier_gates.max_force_rate", "must be > 0 (+inf disables)");
    if (max_consecutive_rejections < 0)
      return Validation::invalid("outlier_gates.max_consecutive_rejections", "must be >= 0");
    return Validation::valid();
  }
};

namespace detail {
template <typename T, int N>
using FingerArray =
    std::conditional_t<N == Dynamic, std::vector<T>, std::array<T, (N > 0 ? N : 1)>>;
}  // namespace detail

/// Controller for NumFingers fingers of Dim-dimensional space; finger DOF as in
/// FingerChain (exact Dof, or Dynamic with MaxDof capacity). NumFingers may be Dynamic
/// (sized by configure(), which then allocates once).
template <typename Scalar_, int Dim_, int NumFingers_, int Dof_, int MaxDof_ = Dof_>
class ReactiveController {
  // Impossible template arguments, refused here with a message rather than deep inside
  // Eigen or at configure().
  static_assert(std::is_floating_point<Scalar_>::value,
                "ReactiveController: Scalar must be float, double or long double");
  static_assert(Dim_ == 2 || Dim_ == 3,
                "ReactiveController: Dim must be 2 (planar) or 3 (spatial)");
  static_assert(NumFingers_ == Dynamic || NumFingers_ >= 1,
                "ReactiveController: NumFingers must be >= 1 or inhand::Dynamic");
  static_assert(Dof_ == Dynamic || Dof_ >= 1,
                "ReactiveController: Dof must be >= 1 or inhand::Dynamic");
  static_assert(MaxDof_ == Dynamic || MaxDof_ >= 1,
                "ReactiveController: MaxDof must be >= 1 or inhand::Dynamic");
  static_assert(Dof_ == Dynamic || MaxDof_ == Dof_,
                "ReactiveController: with a fixed Dof, MaxDof must equal Dof");

 public:
  using Scalar = Scalar_;
  static constexpr int Dim = Dim_;
  static constexpr int NumFingers = NumFingers_;
  using Chain = FingerChain<Scalar, Dim, Dof_, MaxDof_>;
  using JointVector = typename Chain::JointVector;
  using Jacobian = typename Chain::Jacobian;
  using Vec = Vector<Scalar, Dim>;
  using TwistT = Twist<Scalar, Dim>;
  using PoseT = Pose<Scalar, Dim>;
  using Trajectory = ObjectTrajectory<Scalar, Dim>;
  using Planner = ForcePlanner<Scalar, Dim, NumFingers>;
  using Forces = ForceLayer<Scalar, Dim, NumFingers>;
  using Wrench = typename Forces::Wrench;

  /// Where a finger's contact Jacobian comes from.
  enum class KinematicsSource : unsigned char {
    chain,     ///< computed from FingerConfig::chain (forward kinematics + point Jacobian)
    external,  ///< supplied each tick in FingerInput::jacobian by the user's kinematics
  };

  struct FingerConfig {
    /// The finger's kinematics. With KinematicsSource::external only the joint count
    /// and the joints' max_velocity are used.
    Chain chain{};
    KinematicsSource kinematics = KinematicsSource::chain;
    FingerRole role = FingerRole::preset;  ///< force-planner role (the thumb: balancing)
  };

  struct Config {
    detail::FingerArray<FingerConfig, NumFingers> fingers{};
    Scalar control_period = Scalar(1e-3);  ///< s, nominal tick (used for the first tick)
    Scalar max_tick = Scalar(0.01);        ///< s, longest dt integrated in one tick
    /// Command continuity bound (rad/s^2): per finger, the change of the joint-velocity
    /// command between two ticks is scaled so that no joint changes by more than
    /// max_joint_acceleration * dt (the direction of the change is kept, the warning
    /// rate_limited is raised). +infinity (the default) disables it. The bound then
    /// holds for every cause of a change: a step in the target, a contact loss, a
    /// grasp-phase transition. It is relative to the last VALID tick's command: the
    /// zero-velocity fallback of an invalid tick does not reset it.
    Scalar max_joint_acceleration = std::numeric_limits<Scalar>::infinity();
    PoseFeedback<Scalar> pose_feedback{};
    ServoGains<Scalar> servo{};
    IkParams<Scalar> ik{};
    ForcePlannerParams<Scalar> force_planner{};
    /// The normal-force loops, the grip and slip detection (force_layer.hpp). The
    /// force part of `servo` is not used by the controller: these loops replace it.
    ForceLayerParams<Scalar> force_layer{};
    GraspParams<Scalar> grasp{};
    OutlierGates<Scalar> outlier_gates{};
    /// N, > 0 and >= force_planner.nominal_force: plausibility bound on a measured
    /// normal force. A larger reading is invalid input (fault normal_force), like a
    /// non-finite one: no finger sensor reads ten kilonewtons, and an unbounded force
    /// would overflow the force layer's arithmetic.
    Scalar max_measured_force = Scalar(1e4);
    /// m, > 0 (+inf disables): chain kinematics only. A touching finger's contact is
    /// implausible when the contact point lies farther than this from the fingertip
    /// sphere's surface, | |c - p| - r | > contact_tolerance (c the sphere centre from
    /// forward kinematics, r its radius, p the contact point), or when the normal points
    /// into the fingertip, n . (c - p) < 0 (n, the object's outward normal, points from
    /// the object towards the fingertip, so n . (c - p) = r for a true contact). Such a
    /// contact is still used (soft pads, calibration offsets), but flagged: the finger's
    /// FingerOutput::implausible_contact and the warning implausible_contact.
    Scalar contact_tolerance = Scalar(0.01);
    /// start_manipulation() refuses a trajectory whose start pose is farther than this
    /// from the measured object pose (m, and rad of the rotation between them); > 0.
    Scalar start_position_tolerance = Scalar(0.01);
    Scalar start_orientation_tolerance = Scalar(0.2);
  };

  /// Tactile contact of one finger (world frame).
  struct TactileContact {
    bool touching = false;
    Vec contact_point = Vec::Zero();  ///< m
    /// Object's outward unit normal: its length must be within 1e-3 of 1 (else invalid
    /// input, fault contact_normal); the controller normalises it.
    Vec normal = Vec::UnitX();
    Scalar normal_force = Scalar(0);  ///< N, in [0, Config::max_measured_force]
  };

  struct FingerInput {
    JointVector joint_positions{};  ///< rad, size = the finger's DOF
    TactileContact contact{};
    /// KinematicsSource::external only: the Dim x DOF Jacobian of the point the
    /// controller servoes, and the virtual contact point (fingertip surface point
    /// facing the object, world frame). That point is, as in the chain mode: when not
    /// touching, the virtual contact point; when touching during the grasp phase
    /// (approaching/pressing, object held fixed), the fingertip sphere centre; when
    /// touching during manipulation, the measured contact point.
    Jacobian jacobian{};
    Vec virtual_contact_point = Vec::Zero();
  };

  struct Input {
    /// s, strictly increasing. A double whatever Scalar is: a float time stamp stops
    /// resolving 1 ms steps after 9 hours. Consecutive stamps must differ by a dt that
    /// is > 0 in Scalar too.
    double time = 0.0;
    PoseT object_pose{};  ///< measured object pose
    detail::FingerArray<FingerInput, NumFingers> fingers{};
  };

  struct FingerOutput {
    JointVector joint_velocities{};  ///< rad/s, the command
    FingerState state = FingerState::idle;
    Vec desired_contact_velocity = Vec::Zero();  ///< eq. 2 (or the approach velocity)
    /// N, the planned force: the grip times the planner's pattern (0 when no force is
    /// servoed). The measured force settles at force_target instead, which differs by
    /// the share of the load this finger carries (force_layer.hpp).
    Scalar desired_normal_force = Scalar(0);
    Scalar force_target = Scalar(0);    ///< N, what the force loop drives the measured force to
    ServoCommand<Scalar, Dim> servo{};  ///< motion / force parts and their sum
    ServoStatus servo_status = ServoStatus::ok;
    IkReport<Scalar> ik{};
    Scalar stiffness_estimate = Scalar(0);  ///< N/m, the force loop's estimate (force_layer.hpp)
    Scalar force_integral = Scalar(0);      ///< N s, the force loop's integrator (internal part)
    bool slipping = false;                  ///< the contact slides along the object
    /// The contact is implausible for the chain kinematics (Config::contact_tolerance).
    bool implausible_contact = false;
  };

  struct Output {
    detail::FingerArray<FingerOutput, NumFingers> fingers{};
    PoseT desired_object_pose{};
    TwistT feedforward_twist = TwistT::Zero();
    TwistT commanded_twist = TwistT::Zero();  ///< feed-forward + feedback, after limits
    TwistT pose_error = TwistT::Zero();       ///< pose_error(desired, measured)
    Vec force_residual = Vec::Zero();         ///< sum f_i n_i of the plan, N
    ForcePlanStatus force_plan_status = ForcePlanStatus::ok;
    /// External wrench (force N; torque N m about the measured object position, world
    /// frame) that the measured normal forces balance: the load estimate (weight, a
    /// push, a sensor bias) along the directions the normals span. Zero while grasping.
    Wrench load_estimate = Wrench::Zero();
    Scalar grip = Scalar(1);  ///< grip scale s >= 1 of the force layer
    ForceLayerStatus force_layer_status = ForceLayerStatus::ok;
    TwistT pose_error_integral = TwistT::Zero();  ///< layer 1's integrator (m s; rad s)
    ControllerWarning warnings = ControllerWarning::none;
    InputFault fault{};
    Scalar manipulation_time = Scalar(0);  ///< s since start_manipulation
    int segment = -1;                      ///< active trajectory segment
    /// s, the time step this tick integrated (after the max_tick bound); 0 when the
    /// tick was rejected.
    Scalar dt = Scalar(0);
    /// With ControllerStatus::numerical_fault: the stage whose output was not finite
    /// ("trajectory", "pose_feedback", "force_layer", "servo", "ik"); else nullptr.
    const char* numerical_fault = nullptr;
  };

  /// Controller phase (see the file comment).
  enum class Phase : unsigned char { idle, grasping, grasped, manipulating };

  ReactiveController() = default;

  /// Checks a configuration without applying it; names the first invalid field.
  static Validation validate(const Config& c) noexcept {
    const int n = static_cast<int>(c.fingers.size());
    if (n < 1) return Validation::invalid("fingers", "at least one finger");
    if (!is_finite(c.control_period) || !(c.control_period > Scalar(0)))
      return Validation::invalid("control_period", "must be finite and > 0");
    if (!is_finite(c.max_tick) || !(c.max_tick >= c.control_period))
      return Validation::invalid("max_tick", "must be finite and >= control_period");
    if (!(c.max_joint_acceleration > Scalar(0)) ||
        c.max_joint_acceleration != c.max_joint_acceleration)
      return Validation::invalid("max_joint_acceleration", "must be > 0 (+inf disables)");
    Validation v = c.pose_feedback.validate();
    if (!v.ok()) return v;
    if (!(v = c.servo.validate()).ok()) return v;
    if (!(v = c.ik.validate()).ok()) return v;
    if (!(v = c.force_planner.validate()).ok()) return v;
    if (!(v = c.force_layer.validate()).ok()) return v;
    if (!(v = c.grasp.validate()).ok()) return v;
    if (!(v = c.outlier_gates.validate()).ok()) return v;
    if (!is_finite(c.max_measured_force) || !(c.max_measured_force > Scalar(0)) ||
        !(c.max_measured_force >= c.force_planner.nominal_force))
      return Validation::invalid("max_measured_force",
                                 "must be finite, > 0 and >= force_planner.nominal_force");
    if (!(c.contact_tolerance > Scalar(0)) || c.contact_tolerance != c.contact_tolerance)
      return Validation::invalid("contact_tolerance", "must be > 0 (+inf disables)");
    if (!is_finite(c.start_position_tolerance) || !(c.start_position_tolerance > Scalar(0)))
      return Validation::invalid("start_position_tolerance", "must be finite and > 0");
    if (!is_finite(c.start_orientation_tolerance) || !(c.start_orientation_tolerance > Scalar(0)))
      return Validation::invalid("start_orientation_tolerance", "must be finite and > 0");
    bool any_balancing = false;
    for (int i = 0; i < n; ++i) {
      const FingerConfig& f = c.fingers[static_cast<std::size_t>(i)];
      if (!(v = f.chain.validate(true)).ok()) return v.for_finger(i);
      any_balancing = any_balancing || f.role == FingerRole::balancing;
    }
    if (n > 1 && !any_balancing)
      return Validation::invalid("fingers.role", "at least one finger must be balancing");
    return Validation::valid();
  }

  /// Validates and applies a configuration (all or nothing). Allocates only for
  /// run-time sized hands or chains. Leaves the controller idle.
  Validation configure(const Config& c) {
    const Validation v = validate(c);
    if (!v.ok()) return v;
    config_ = c;
    const int n = finger_count();
    if constexpr (NumFingers == Dynamic) slots_.resize(static_cast<std::size_t>(n));
    planner_.resize(n);
    planner_.set_params(c.force_planner);
    forces_.set_params(c.force_layer);
    forces_.resize(n);
    force_result_.velocity.setZero(n);
    force_result_.target.setZero(n);
    force_result_.slipping.setZero(n);
    for (int i = 0; i < n; ++i) {
      const FingerConfig& fc = config_.fingers[static_cast<std::size_t>(i)];
      Slot& s = slots_[static_cast<std::size_t>(i)];
      const int dof = fc.chain.dof();
      s.kinematics.joint_origins.setZero(Dim, dof);
      s.kinematics.joint_axes.setZero(3, dof);
      s.ik.set_dof(dof);
      s.ik.set_params(c.ik);
      s.servo.set_gains(c.servo);
      s.jacobian.setZero(Dim, dof);
      s.qdot.setZero(dof);
      s.q_prev.setZero(dof);
      s.max_velocity = fc.chain.velocity_limits();
      planner_.set_role(i, fc.role);
    }
    touching_ = Planner::Mask::Zero(n);
    normals_ = Planner::Normals::Zero(Dim, n);
    desired_forces_ = Planner::ForceVector::Zero(n);
    contact_points_ = Planner::Normals::Zero(Dim, n);
    measured_forces_ = Planner::ForceVector::Zero(n);
    advance_ = Planner::ForceVector::Zero(n);
    configured_ = true;
    reset();
    save_state();  // sizes the saved copy once (run-time sizes allocate here only)
    return Validation::valid();
  }

  /// Back to idle: integrators, filters, grasp and trajectory progress cleared.
  void reset() noexcept {
    phase_ = Phase::idle;
    has_time_ = false;
    settled_time_ = Scalar(0);
    manipulation_time_ = Scalar(0);
    pose_error_integral_.setZero();
    pose_rejections_ = 0;
    pose_age_ = Scalar(0);
    planner_.reset();
    forces_.reset();
    for (Slot& s : slots_) {
      s.servo.reset();
      s.state = FingerState::idle;
      s.had_contact = false;
      s.qdot.setZero();
      s.has_q_prev = false;
      s.last_motion.setZero();
      s.force_valid = false;
      s.force_rejections = 0;
    }
  }

  int finger_count() const noexcept { return static_cast<int>(config_.fingers.size()); }
  const Config& config() const noexcept { return config_; }
  Phase phase() const noexcept { return phase_; }

  /// An Input / Output sized for the configured hand (allocates only for run-time
  /// finger counts); call once, outside the control loop.
  Input make_input() const {
    Input in;
    if constexpr (NumFingers == Dynamic) in.fingers.resize(config_.fingers.size());
    for (int i = 0; i < finger_count(); ++i) {
      const int dof = config_.fingers[static_cast<std::size_t>(i)].chain.dof();
      in.fingers[static_cast<std::size_t>(i)].joint_positions = JointVector::Zero(dof);
      in.fingers[static_cast<std::size_t>(i)].jacobian = Jacobian::Zero(Dim, dof);
    }
    return in;
  }
  Output make_output() const {
    Output out;
    if constexpr (NumFingers == Dynamic) out.fingers.resize(config_.fingers.size());
    for (int i = 0; i < finger_count(); ++i)
      out.fingers[static_cast<std::size_t>(i)].joint_velocities =
          JointVector::Zero(config_.fingers[static_cast<std::size_t>(i)].chain.dof());
    return out;
  }
  bool configured() const noexcept { return configured_; }

  /// Starts the grasp phase towards one target per finger (see grasp.hpp).
  Validation start_grasp(
      const detail::FingerArray<GraspTarget<Scalar, Dim>, NumFingers>& targets) noexcept {
    if (!configured_) return Validation::invalid("controller", "not configured");
    if (static_cast<int>(targets.size()) != finger_count())
      return Validation::invalid("targets", "one target per finger");
    for (int i = 0; i < finger_count(); ++i) {
      const Validation v = targets[static_cast<std::size_t>(i)].validate();
      if (!v.ok()) return v.for_finger(i);
    }
    for (int i = 0; i < finger_count(); ++i) {
      Slot& s = slots_[static_cast<std::size_t>(i)];
      s.target = targets[static_cast<std::size_t>(i)];
      s.target.normal.normalize();
      s.state = FingerState::approaching;
      s.servo.reset();
      s.align_window_time = Scalar(0);
      s.align_stalled = false;
    }
    settled_time_ = Scalar(0);
    phase_ = Phase::grasping;
    return Validation::valid();
  }

  /// Starts tracking `trajectory` (its start pose is normally the measured pose at
  /// release). Allowed once the grasp has completed, or while already manipulating.
  /// The trajectory must be valid (ObjectTrajectory::validate) and start within
  /// Config::start_position_tolerance / start_orientation_tolerance of the last
  /// measured object pose (after the outlier gate): a default-constructed trajectory
  /// starts at the world origin, and the pose feedback would drive the object there.
  Validation start_manipulation(const Trajectory& trajectory) noexcept {
    if (!configured_) return Validation::invalid("controller", "not configured");
    if (phase_ != Phase::grasped && phase_ != Phase::manipulating)
      return Validation::invalid("phase", "the grasp has not completed");
    const Validation tv = trajectory.validate();
    if (!tv.ok()) return tv;
    const Twist<Scalar, Dim> gap = pose_error(trajectory.start_pose(), object_pose_);
    if (!(gap.template head<Dim>().norm() <= config_.start_position_tolerance))
      return Validation::invalid("trajectory.start_pose.position",
                                 "farther than start_position_tolerance from the measured pose");
    if (!(gap.template tail<SpatialDim<Dim>::kRot>().norm() <= config_.start_orientation_tolerance))
      return Validation::invalid("trajectory.start_pose.rotation",
                                 "farther than start_orientation_tolerance from the measured pose");
    trajectory_ = trajectory;
    manipulation_time_ = Scalar(0);
    if (phase_ != Phase::manipulating) pose_error_integral_.setZero();
    phase_ = Phase::manipulating;
    for (Slot& s : slots_)
      if (s.state == FingerState::pressing) s.state = FingerState::in_contact;
    return Validation::valid();
  }

  /// One control tick. See the file comment for the contract.
  ControllerStatus update(const Input& in, Output& out) noexcept {
    out.warnings = ControllerWarning::none;
    out.fault = InputFault{};
    out.numerical_fault = nullptr;
    out.dt = Scalar(0);
    const int n = finger_count();
    if (!configured_) {
      zero_output(out);
      return ControllerStatus::not_configured;
    }
    if (static_cast<int>(in.fingers.size()) != n || static_cast<int>(out.fingers.size()) != n) {
      // Only possible for run-time finger counts; nothing sensible to command.
      zero_output(out);
      out.fault = InputFault{InputField::finger_count, -1};
      return ControllerStatus::invalid_input;
    }
    for (int i = 0; i < n; ++i) {
      if (out.fingers[static_cast<std::size_t>(i)].joint_velocities.size() !=
          config_.fingers[static_cast<std::size_t>(i)].chain.dof()) {
        zero_output(out);
        out.fault = InputFault{InputField::output_joint_velocities, i};
        return ControllerStatus::invalid_input;
      }
    }
    const InputFault fault = check_input(in);
    if (fault.field != InputField::none) {
      zero_output(out);
      out.fault = fault;
      return ControllerStatus::invalid_input;
    }
    save_state();
    // dt in double (the time base), then in Scalar.
    double dt_time = has_time_ ? in.time - last_time_ : static_cast<double>(config_.control_period);
    if (dt_time > static_cast<double>(config_.max_tick)) {
      dt_time = static_cast<double>(config_.max_tick);
      out.warnings = out.warnings | ControllerWarning::long_tick;
    }
    const Scalar dt = static_cast<Scalar>(dt_time);
    out.dt = dt;
    last_time_ = in.time;
    gate_inputs(in, dt, out.warnings);
    has_time_ = true;

    ControllerStatus status = ControllerStatus::idle;
    if (phase_ == Phase::idle) {
      zero_output(out);
    } else if (phase_ == Phase::manipulating) {
      status = manipulate(in, dt, out);
    } else {
      status = grasp(in, dt, out);
    }
    // Last line of defence: nothing non-finite leaves update().
    const char* stage = non_finite_stage(out);
    if (stage != nullptr) {
      restore_state();
      zero_output(out);
      clear_diagnostics(out);
      out.dt = Scalar(0);
      out.numerical_fault = stage;
      return ControllerStatus::numerical_fault;
    }
    return status;
  }

  /// Tick-to-tick bound on the change of a finger's joint-velocity command is not
  /// imposed here; the servo PIs low-pass the command (paper, section IV-B).
  const Trajectory& trajectory() const noexcept { return trajectory_; }

  /// Largest |integral| of any finger's force loop (N s): for monitoring windup.
  Scalar max_force_integral() const noexcept {
    Scalar m = Scalar(0);
    for (int i = 0; i < forces_.size(); ++i) m = std::max(m, std::abs(forces_.integral()(i)));
    return m;
  }

 private:
  struct Slot {
    FingerKinematics<Chain> kinematics{};
    ContactIk<Scalar, Dim, Dof_, MaxDof_> ik{};
    HybridServo<Scalar, Dim> servo{};
    Jacobian jacobian{};
    JointVector qdot{};
    JointVector q_prev{};  ///< joint positions of the last tick (force layer's advance)
    bool has_q_prev = false;
    Vec last_motion = Vec::Zero();  ///< last tick's motion part of the command
    JointVector max_velocity{};
    GraspTarget<Scalar, Dim> target{};
    FingerState state = FingerState::idle;
    bool had_contact = false;
    Scalar force_used = Scalar(0);  ///< measured normal force after the gate, N
    Vec align_window_normal = Vec::Zero();
    Vec align_window_point = Vec::Zero();
    Scalar align_window_time = Scalar(0);
    bool align_stalled = false;
    bool force_valid = false;
    int force_rejections = 0;
    Scalar force_age = Scalar(0);
    Vec last_contact_object = Vec::Zero();  ///< last contact point, object frame
    Vec last_normal_object = Vec::UnitX();  ///< last outward normal, object frame
  };

  InputFault check_input(const Input& in) const noexcept {
    // Strictly increasing, also once the step is converted to Scalar.
    if (!is_finite(in.time) ||
        (has_time_ && !(static_cast<Scalar>(in.time - last_time_) > Scalar(0))))
      return {InputField::time, -1};
    // A measured rotation: orthonormal to 1e-3 (a pose estimate is not re-orthonormalised
    // to machine precision) and det +1 (not a reflection).
    if (!in.object_pose.has_rotation(Scalar(1e-3))) return {InputField::object_pose, -1};
    if (!in.object_pose.is_finite()) return {InputField::object_pose, -1};
    for (int i = 0; i < finger_count(); ++i) {
      const FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
      const FingerConfig& fc = config_.fingers[static_cast<std::size_t>(i)];
      if (f.joint_positions.size() != fc.chain.dof() || !all_finite(f.joint_positions))
        return {InputField::joint_positions, i};
      if (f.contact.touching) {
        if (!all_finite(f.contact.contact_point)) return {InputField::contact_point, i};
        if (!all_finite(f.contact.normal) ||
            !(std::abs(f.contact.normal.norm() - Scalar(1)) <= Scalar(1e-3)))
          return {InputField::contact_normal, i};
        if (!is_finite(f.contact.normal_force) || f.contact.normal_force < Scalar(0) ||
            f.contact.normal_force > config_.max_measured_force)
          return {InputField::normal_force, i};
      }
      if (fc.kinematics == KinematicsSource::external) {
        if (f.jacobian.cols() != fc.chain.dof() || !all_finite(f.jacobian))
          return {InputField::jacobian, i};
        if (!f.contact.touching && !all_finite(f.virtual_contact_point))
          return {InputField::virtual_contact_point, i};
      }
    }
    return {};
  }

  /// The fallback output: every finger slot the Output has is zeroed at its current
  /// size (never resized: no allocation).
  void zero_output(Output& out) const noexcept {
    for (int i = 0; i < static_cast<int>(out.fingers.size()); ++i) {
      FingerOutput& fo = out.fingers[static_cast<std::size_t>(i)];
      fo.joint_velocities.setZero();
      fo.desired_contact_velocity.setZero();
      fo.desired_normal_force = Scalar(0);
      fo.servo = ServoCommand<Scalar, Dim>{};
      fo.ik = IkReport<Scalar>{};
      fo.servo_status = ServoStatus::ok;
      fo.force_target = Scalar(0);
      fo.implausible_contact = false;
      if (i < finger_count()) fo.state = slots_[static_cast<std::size_t>(i)].state;
    }
    out.commanded_twist.setZero();
    out.feedforward_twist.setZero();
  }

  /// After a numerical fault: every diagnostic output set from the (restored) state or
  /// to zero, so that nothing non-finite is left in `out`.
  void clear_diagnostics(Output& out) const noexcept {
    out.desired_object_pose = object_pose_;
    out.pose_error.setZero();
    out.pose_error_integral = pose_error_integral_;
    out.force_residual.setZero();
    out.load_estimate.setZero();
    out.grip = Scalar(1);
    out.manipulation_time = manipulation_time_;
    for (FingerOutput& fo : out.fingers) {
      fo.stiffness_estimate = Scalar(0);
      fo.force_integral = Scalar(0);
    }
  }

  /// The first stage whose output is not finite, or nullptr.
  const char* non_finite_stage(const Output& out) const noexcept {
    if (!out.desired_object_pose.is_finite() || !all_finite(out.feedforward_twist) ||
        !is_finite(out.manipulation_time))
      return "trajectory";
    if (!all_finite(out.pose_error) || !all_finite(out.commanded_twist) ||
        !all_finite(out.pose_error_integral))
      return "pose_feedback";
    if (!all_finite(out.force_residual) || !all_finite(out.load_estimate) || !is_finite(out.grip))
      return "force_layer";
    for (const FingerOutput& fo : out.fingers) {
      if (!is_finite(fo.desired_normal_force) || !is_finite(fo.force_target) ||
          !is_finite(fo.stiffness_estimate) || !is_finite(fo.force_integral))
        return "force_layer";
      if (!all_finite(fo.desired_contact_velocity) || !all_finite(fo.servo.motion) ||
          !all_finite(fo.servo.force) || !all_finite(fo.servo.total))
        return "servo";
      if (!all_finite(fo.joint_velocities) || !is_finite(fo.ik.min_singular_value) ||
          !is_finite(fo.ik.damping) || !is_finite(fo.ik.limit_scale))
        return "ik";
    }
    return nullptr;
  }

  /// The state a tick may change, copied before it (same sizes: no allocation).
  struct SavedState {
    detail::FingerArray<Slot, NumFingers> slots{};
    Planner planner{};
    Forces forces{};
    typename Forces::Result force_result{};
    Phase phase = Phase::idle;
    double last_time = 0.0;
    bool has_time = false;
    Scalar settled_time = Scalar(0);
    Scalar manipulation_time = Scalar(0);
    TwistT pose_error_integral = TwistT::Zero();
    PoseT object_pose{};
    int pose_rejections = 0;
    Scalar pose_age = Scalar(0);
  };
  void save_state() noexcept {
    saved_.slots = slots_;
    saved_.planner = planner_;
    saved_.forces = forces_;
    saved_.force_result = force_result_;
    saved_.phase = phase_;
    saved_.last_time = last_time_;
    saved_.has_time = has_time_;
    saved_.settled_time = settled_time_;
    saved_.manipulation_time = manipulation_time_;
    saved_.pose_error_integral = pose_error_integral_;
    saved_.object_pose = object_pose_;
    saved_.pose_rejections = pose_rejections_;
    saved_.pose_age = pose_age_;
  }
  void restore_state() noexcept {
    slots_ = saved_.slots;
    planner_ = saved_.planner;
    forces_ = saved_.forces;
    force_result_ = saved_.force_result;
    phase_ = saved_.phase;
    last_time_ = saved_.last_time;
    has_time_ = saved_.has_time;
    settled_time_ = saved_.settled_time;
    manipulation_time_ = saved_.manipulation_time;
    pose_error_integral_ = saved_.pose_error_integral;
    object_pose_ = saved_.object_pose;
    pose_rejections_ = saved_.pose_rejections;
    pose_age_ = saved_.pose_age;
  }

  /// Plausibility gates (OutlierGates): sets object_pose_ and each slot's force_used.
  void gate_inputs(const Input& in, Scalar raw_dt, ControllerWarning& w) noexcept {
    const OutlierGates<Scalar>& g = config_.outlier_gates;
    const Scalar elapsed_pose = pose_age_ + raw_dt;
    bool accept = !has_time_;
    if (!accept) {
      const Scalar dp = (in.object_pose.position - object_pose_.position).norm();
      const Scalar dr =
          rotation_log<Scalar>(
              Rotation<Scalar, Dim>(in.object_pose.rotation * object_pose_.rotation.transpose()))
              .norm();
      accept = dp <= g.max_object_speed * elapsed_pose &&
               dr <= g.max_object_angular_speed * elapsed_pose;
      if (!accept && pose_rejections_ >= g.max_consecutive_rejections) accept = true;
    }
    if (accept) {
      object_pose_ = in.object_pose;
      pose_rejections_ = 0;
      pose_age_ = Scalar(0);
    } else {
      ++pose_rejections_;
      pose_age_ = elapsed_pose;
      w = w | ControllerWarning::pose_outlier;
    }
    for (int i = 0; i < finger_count(); ++i) {
      Slot& sl = slots_[static_cast<std::size_t>(i)];
      const TactileContact& c = in.fingers[static_cast<std::size_t>(i)].contact;
      if (!c.touching) {
        sl.force_valid = false;
        continue;
      }
      const Scalar elapsed = sl.force_age + raw_dt;
      bool ok = !sl.force_valid ||
                std::abs(c.normal_force - sl.force_used) <= g.max_force_rate * elapsed ||
                sl.force_rejections >= g.max_consecutive_rejections;
      if (ok) {
        sl.force_used = c.normal_force;
        sl.force_valid = true;
        sl.force_rejections = 0;
        sl.force_age = Scalar(0);
      } else {
        ++sl.force_rejections;
        sl.force_age = elapsed;
        w = w | ControllerWarning::force_outlier;
      }
    }
  }

  /// Kinematics for one finger at the point `p` (contact or virtual contact point).
  void finger_jacobian(int i, const FingerInput& f, const Vec& p) noexcept {
    Slot& s = slots_[static_cast<std::size_t>(i)];
    if (config_.fingers[static_cast<std::size_t>(i)].kinematics == KinematicsSource::external) {
      s.jacobian = f.jacobian;
    } else {
      point_jacobian(s.kinematics, p, s.jacobian);
    }
  }

  /// Fingertip sphere centre (chain kinematics); for external kinematics the user's
  /// Jacobian is used as given.
  Vec fingertip_centre(int i, const FingerInput& f) const noexcept {
    const FingerConfig& fc = config_.fingers[static_cast<std::size_t>(i)];
    if (fc.kinematics == KinematicsSource::external) return f.contact.contact_point;
    return slots_[static_cast<std::size_t>(i)].kinematics.fingertip.position;
  }

  /// Virtual contact point facing an object whose outward normal there is n.
  Vec virtual_point(int i, const FingerInput& f, const Vec& n) const noexcept {
    const FingerConfig& fc = config_.fingers[static_cast<std::size_t>(i)];
    if (fc.kinematics == KinematicsSource::external) return f.virtual_contact_point;
    return fingertip_surface_point(fc.chain, slots_[static_cast<std::size_t>(i)].kinematics, n);
  }

  /// Copies the touching fingers' contacts (unit normals) and gated forces into the
  /// force layer's input and runs it; `object_free` false during the grasp.
  void run_force_layer(const Input& in, bool object_free, Scalar dt) noexcept {
    for (int i = 0; i < finger_count(); ++i) {
      const TactileContact& c = in.fingers[static_cast<std::size_t>(i)].contact;
      Slot& s = slots_[static_cast<std::size_t>(i)];
      const JointVector& q = in.fingers[static_cast<std::size_t>(i)].joint_positions;
      touching_(i) = c.touching ? 1 : 0;
      advance_(i) = Scalar(0);
      if (c.touching) {
        normals_.col(i) = c.normal.normalized();
        contact_points_.col(i) = c.contact_point;
        measured_forces_(i) = s.force_used;
        // Fingertip displacement since the last tick (last tick's Jacobian) less the
        // displacement the last command gave the object there, along -n.
        if (s.has_q_prev) {
          s.q_prev = q - s.q_prev;  // the joint step (preallocated: no temporary)
          Vec dp;
          dp.noalias() = s.jacobian * s.q_prev;
          advance_(i) = -normals_.col(i).dot(dp - dt * s.last_motion);
        }
      }
      s.q_prev = q;
      s.has_q_prev = true;
    }
    typename Forces::Step step;
    step.touching = &touching_;
    step.points = &contact_points_;
    step.normals = &normals_;
    step.measured = &measured_forces_;
    step.pattern = &desired_forces_;
    step.advance = &advance_;
    step.object_position = object_pose_.position;
    step.object_rotation = object_pose_.rotation;
    step.min_force = config_.force_planner.min_force;
    step.max_force = config_.force_planner.max_force;
    step.object_free = object_free;
    step.dt = dt;
    forces_.update(step, force_result_);
  }

  /// Servo + IK for one finger; fills its output. `force_active`: the finger touches
  /// and the force layer's velocity u (into the object along -n) is added (eq. 7).
  void servo_and_ik(int i, const Vec& v_desired, bool force_active, const FingerInput& f, Scalar dt,
                    FingerOutput& fo, ControllerWarning& w) noexcept {
    Slot& s = slots_[static_cast<std::size_t>(i)];
    fo.desired_contact_velocity = v_desired;
    fo.desired_normal_force = force_active ? force_result_.grip * desired_forces_(i) : Scalar(0);
    fo.force_target = force_active ? force_result_.target(i) : Scalar(0);
    fo.servo_status =
        s.servo.update(v_desired, Scalar(0), Scalar(0), f.contact.normal, false, dt, fo.servo);
    if (force_active) {
      fo.servo.force = -force_result_.velocity(i) * normals_.col(i);
      fo.servo.total = fo.servo.motion + fo.servo.force;
    }
    s.last_motion = fo.servo.motion;
    fo.stiffness_estimate = forces_.stiffness_estimate()(i);
    fo.force_integral = forces_.integral()(i);
    fo.slipping = force_result_.slipping(i) != 0;
    if (fo.servo_status != ServoStatus::ok) w = w | ControllerWarning::servo_saturated;
    fo.ik = s.ik.solve(s.jacobian, fo.servo.total, s.max_velocity, fo.joint_velocities);
    if (has(fo.ik.status, IkStatus::damped)) w = w | ControllerWarning::ik_damped;
    if (has(fo.ik.status, IkStatus::limited)) w = w | ControllerWarning::joint_velocity_limited;
    // Command continuity: scale the change since the last command (direction kept).
    const Scalar max_step = config_.max_joint_acceleration * dt;
    if (max_step < std::numeric_limits<Scalar>::infinity()) {
      const Scalar largest = (fo.joint_velocities - s.qdot).cwiseAbs().maxCoeff();
      if (largest > max_step) {
        fo.joint_velocities = s.qdot + (max_step / largest) * (fo.joint_velocities - s.qdot);
        // A convex combination of two commands within the joint limits: only rounding
        // can leave them; clamp it away (this only shrinks the step).
        fo.joint_velocities =
            fo.joint_velocities.cwiseMin(s.max_velocity).cwiseMax(-s.max_velocity);
        w = w | ControllerWarning::rate_limited;
      }
    }
    s.qdot = fo.joint_velocities;
    fo.state = s.state;
  }

  /// Forward kinematics of the chain fingers, and the plausibility of each touching
  /// chain finger's contact (Config::contact_tolerance).
  void update_kinematics(const Input& in, Output& out, ControllerWarning& w) noexcept {
    for (int i = 0; i < finger_count(); ++i) {
      const FingerConfig& fc = config_.fingers[static_cast<std::size_t>(i)];
      const FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
      Slot& s = slots_[static_cast<std::size_t>(i)];
      bool implausible = false;
      if (fc.kinematics == KinematicsSource::chain) {
        forward_kinematics(fc.chain, f.joint_positions, s.kinematics);
        if (f.contact.touching) {
          const Vec d = s.kinematics.fingertip.position - f.contact.contact_point;
          implausible =
              std::abs(d.norm() - fc.chain.fingertip_radius) > config_.contact_tolerance ||
              f.contact.normal.dot(d) < Scalar(0);
        }
      }
      out.fingers[static_cast<std::size_t>(i)].implausible_contact = implausible;
      if (implausible) w = w | ControllerWarning::implausible_contact;
    }
  }

  void remember_contact(Slot& s, const TactileContact& c, const PoseT& object) noexcept {
    s.had_contact = true;
    s.last_contact_object = object.rotation.transpose() * (c.contact_point - object.position);
    s.last_normal_object = object.rotation.transpose() * c.normal;
  }

  ControllerStatus grasp(const Input& in, Scalar dt, Output& out) noexcept {
    ControllerWarning w = out.warnings;
    update_kinematics(in, out, w);
    const GraspParams<Scalar>& g = config_.grasp;
    const Scalar f0 = config_.force_planner.nominal_force;
    desired_forces_.setConstant(f0);
    run_force_layer(in, false, dt);
    bool all_pressing = true;
    for (int i = 0; i < finger_count(); ++i) {
      Slot& s = slots_[static_cast<std::size_t>(i)];
      const FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
      FingerOutput& fo = out.fingers[static_cast<std::size_t>(i)];
      if (f.contact.touching) {
        if (s.state == FingerState::approaching) s.servo.reset_force();
        s.state = FingerState::pressing;
        remember_contact(s, f.contact, object_pose_);
        // Tangential pull of the recorded contact point towards the target.
        const Vec d = s.target.contact_point - f.contact.contact_point;
        const Vec d_tangential = d - d.dot(f.contact.normal) * f.contact.normal;
        const Scalar cos_angle = f.contact.normal.dot(s.target.normal);
        const Vec misalignment =
            s.target.normal - cos_angle * f.contact.normal;  // |.| = sin(angle)
        const Vec v = g.tangential_gain * d_tangential + g.alignment_speed * misalignment;
        // Grasp phase: the object is held fixed, so the contact LOCATION follows the
        // fingertip sphere centre, not the material point at the contact; servo the
        // centre so that the tangential pull really moves the contact (grasp.hpp).
        finger_jacobian(i, f, fingertip_centre(i, f));
        servo_and_ik(i, v, true, f, dt, fo, w);
        // The contact has settled when it reached its target (position and normal), or
        // when it stalled: over the last settle window the normal turned by less than a
        // quarter of alignment_tolerance and the contact point moved by less than a
        // quarter of position_tolerance (on a sphere, say, an off-centre finger can
        // reach neither its target point nor the expected normal; the two pulls balance).
        if (s.align_window_time <= Scalar(0)) {
          s.align_window_normal = f.contact.normal;
          s.align_window_point = f.contact.contact_point;
        }
        s.align_window_time += dt;
        if (s.align_window_time >= std::max(g.settle_time, dt)) {
          s.align_stalled = (f.contact.normal - s.align_window_normal).norm() <
                                Scalar(0.25) * std::sin(g.alignment_tolerance) &&
                            (f.contact.contact_point - s.align_window_point).norm() <
                                Scalar(0.25) * g.position_tolerance;
          s.align_window_time = Scalar(0);
        }
        const bool reached = cos_angle > Scalar(0) &&
                             misalignment.norm() <= std::sin(g.alignment_tolerance) &&
                             d_tangential.norm() <= g.position_tolerance;
        all_pressing = all_pressing && std::abs(s.force_used - f0) <= g.force_tolerance * f0 &&
                       (reached || s.align_stalled);
      } else {
        if (s.state == FingerState::pressing) s.servo.reset_force();
        s.state = FingerState::approaching;
        const Vec p_v = virtual_point(i, f, s.target.normal);
        const Vec v = approach_velocity(g, p_v, s.target.contact_point, s.target.normal);
        finger_jacobian(i, f, p_v);
        servo_and_ik(i, v, false, f, dt, fo, w);
        all_pressing = false;
      }
    }
    out.warnings = w;
    out.desired_object_pose = object_pose_;
    out.commanded_twist.setZero();
    out.feedforward_twist.setZero();
    out.pose_error.setZero();
    settled_time_ = all_pressing ? settled_time_ + dt : Scalar(0);
    if (settled_time_ >= g.settle_time) phase_ = Phase::grasped;
    return phase_ == Phase::grasped ? ControllerStatus::grasped : ControllerStatus::grasping;
  }

  ControllerStatus manipulate(const Input& in, Scalar dt, Output& out) noexcept {
    ControllerWarning w = out.warnings;
    update_kinematics(in, out, w);
    manipulation_time_ += dt;
    // Layer 1: desired pose and commanded twist (feed-forward + feedback, method.md s.3).
    const TrajectorySample<Scalar, Dim> sample = trajectory_.evaluate(manipulation_time_);
    out.desired_object_pose = sample.pose;
    out.feedforward_twist = sample.twist;
    out.segment = sample.segment;
    out.manipulation_time = manipulation_time_;
    out.pose_error = pose_error(sample.pose, object_pose_);
    constexpr int R = SpatialDim<Dim>::kRot;
    const PoseFeedback<Scalar>& pf = config_.pose_feedback;
    // Integral of the pose error, each part limited in norm (direction kept).
    pose_error_integral_ += dt * out.pose_error;
    const Scalar ip = pose_error_integral_.template head<Dim>().norm();
    if (ip > pf.position_integral_limit) {
      pose_error_integral_.template head<Dim>() *= pf.position_integral_limit / ip;
      w = w | ControllerWarning::pose_integral_limited;
    }
    const Scalar ir = pose_error_integral_.template tail<R>().norm();
    if (ir > pf.orientation_integral_limit) {
      pose_error_integral_.template tail<R>() *= pf.orientation_integral_limit / ir;
      w = w | ControllerWarning::pose_integral_limited;
    }
    TwistT V = sample.twist;
    V.template head<Dim>() += pf.position_gain * out.pose_error.template head<Dim>() +
                              pf.position_integral_gain * pose_error_integral_.template head<Dim>();
    V.template tail<R>() += pf.orientation_gain * out.pose_error.template tail<R>() +
                            pf.orientation_integral_gain * pose_error_integral_.template tail<R>();
    const Scalar lin = V.template head<Dim>().norm(), ang = V.template tail<R>().norm();
    Scalar scale = Scalar(1);
    if (lin > config_.pose_feedback.max_linear_speed)
      scale = config_.pose_feedback.max_linear_speed / lin;
    if (ang > config_.pose_feedback.max_angular_speed)
      scale = std::min(scale, config_.pose_feedback.max_angular_speed / ang);
    if (scale < Scalar(1)) {
      V *= scale;  // scale the whole twist: the screw axis is kept
      w = w | ControllerWarning::twist_limited;
    }
    out.commanded_twist = V;

    // Layer 2: the planner's force pattern, then the force layer (force_layer.hpp).
    for (int i = 0; i < finger_count(); ++i) {
      const FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
      touching_(i) = f.contact.touching ? 1 : 0;
      if (f.contact.touching) normals_.col(i) = f.contact.normal.normalized();
    }
    out.force_plan_status =
        planner_.plan(touching_, normals_, dt, desired_forces_, out.force_residual);
    if (has(out.force_plan_status, ForcePlanStatus::limited))
      w = w | ControllerWarning::force_limited;
    if (has(out.force_plan_status, ForcePlanStatus::no_balancing_contact))
      w = w | ControllerWarning::no_balancing_contact;
    run_force_layer(in, true, dt);
    out.load_estimate = force_result_.load;
    out.grip = force_result_.grip;
    out.force_layer_status = force_result_.status;
    out.pose_error_integral = pose_error_integral_;
    if (has(force_result_.status, ForceLayerStatus::slipping)) w = w | ControllerWarning::slipping;
    if (has(force_result_.status, ForceLayerStatus::grip_raised))
      w = w | ControllerWarning::grip_raised;
    if (has(force_result_.status, ForceLayerStatus::beyond_capacity))
      w = w | ControllerWarning::beyond_capacity;
    if (has(force_result_.status, ForceLayerStatus::integral_limited))
      w = w | ControllerWarning::force_integral_limited;

    // Layers 2-3 per finger.
    bool lost = false;
    for (int i = 0; i < finger_count(); ++i) {
      Slot& s = slots_[static_cast<std::size_t>(i)];
      const FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
      FingerOutput& fo = out.fingers[static_cast<std::size_t>(i)];
      if (f.contact.touching) {
        if (s.state == FingerState::reacquiring) s.servo.reset_force();
        s.state = FingerState::in_contact;
        remember_contact(s, f.contact, object_pose_);
        const Vec v =
            contact_point_velocity<Scalar, Dim>(V, f.contact.contact_point, object_pose_.position);
        finger_jacobian(i, f, f.contact.contact_point);
        servo_and_ik(i, v, true, f, dt, fo, w);
      } else {
        lost = true;
        if (s.state != FingerState::reacquiring) s.servo.reset_force();
        s.state = FingerState::reacquiring;
        // Aim at the last contact point carried with the measured object, along the
        // last normal; add the object's motion there (eq. 2) so the finger keeps up.
        const Vec n = object_pose_.rotation * s.last_normal_object;
        const Vec p_t = object_pose_.transform_point(s.last_contact_object);
        const Vec p_v = virtual_point(i, f, n);
        const Vec v = approach_velocity(config_.grasp, p_v, p_t, n) +
                      contact_point_velocity<Scalar, Dim>(V, p_t, object_pose_.position);
        finger_jacobian(i, f, p_v);
        servo_and_ik(i, v, false, f, dt, fo, w);
      }
    }
    out.warnings = w;
    return lost ? ControllerStatus::contact_lost : ControllerStatus::ok;
  }

  Config config_{};
  bool configured_ = false;
  Phase phase_ = Phase::idle;
  detail::FingerArray<Slot, NumFingers> slots_{};
  Planner planner_{};
  typename Planner::Mask touching_{};
  typename Planner::Normals normals_{};
  typename Planner::ForceVector desired_forces_{};  ///< the planner's pattern q
  typename Planner::Normals contact_points_{};
  typename Planner::ForceVector measured_forces_{};
  typename Planner::ForceVector advance_{};
  Forces forces_{};
  typename Forces::Result force_result_{};
  Trajectory trajectory_{};
  double last_time_ = 0.0;  ///< s, the time base (see Input::time)
  bool has_time_ = false;
  Scalar settled_time_ = Scalar(0);
  Scalar manipulation_time_ = Scalar(0);
  TwistT pose_error_integral_ = TwistT::Zero();
  PoseT object_pose_{};  ///< measured object pose after the gate
  int pose_rejections_ = 0;
  Scalar pose_age_ = Scalar(0);
  SavedState saved_{};
};

}  // namespace inhand
