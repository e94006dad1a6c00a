// The reactive in-hand manipulation controller: one update() per control tick
// (docs/method.md section 7, paper Fig. 2).
//
//   layer 1  trajectory : desired object pose X_d(t) (controller/trajectory.hpp) and
//                         the commanded object twist
//                           V = V_ff + K_p e + K_i integral(e),  e = pose_error(X_d, X_measured)
//                         (feed-forward plus PI feedback on the MEASURED pose,
//                         pose_feedback.hpp; gains per part)
//   layer 2  per finger : desired contact-point velocity v_i = v + w x (p_ci - p_o)
//                         (eq. 2 at the MEASURED contact point p_ci; finger_motion.hpp
//                         gives the point and its Jacobian) and the force layer's
//                         velocity u_i along -n_i (force_planner.hpp, force_layer.hpp)
//   layer 3  per finger : hybrid servo e = g1(v_i) - u_i n_i (eqs. 4-7) and
//                         theta_dot = J_F^+ e (eq. 3) (finger_command.hpp)
// Around them: the input checks (tick_checks.hpp), the sensor gates (sensor_gates.hpp)
// and the grasp phase (grasp.hpp). Types of Config, Input, Output: controller_io.hpp.
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
// Phases: configure() -> start_grasp(targets) -> update() until `grasped` (every finger
// presses with its grasp force, grasp.hpp) -> release the object, start_manipulation().
// Mixed-DOF hands: use Dof = inhand::Dynamic with MaxDof the largest finger (e.g. a
// 5-joint thumb and 4-joint fingers: Dof = Dynamic, MaxDof = 5): still no allocation.
#pragma once

#include <algorithm>
#include <cmath>
#include <type_traits>

#include "inhand/controller/controller_io.hpp"
#include "inhand/controller/controller_phases.hpp"
#include "inhand/controller/controller_state.hpp"
#include "inhand/controller/tick_checks.hpp"
#include "inhand/controller/trajectory.hpp"

namespace inhand {

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
  using Types = ControllerTypes<Scalar, Dim, NumFingers, Dof_, MaxDof_>;
  using Chain = typename Types::Chain;
  using JointVector = typename Types::JointVector;
  using Jacobian = typename Types::Jacobian;
  using Vec = typename Types::Vec;
  using TwistT = typename Types::TwistT;
  using PoseT = typename Types::PoseT;
  using Wrench = typename Types::Wrench;
  using Trajectory = ObjectTrajectory<Scalar, Dim>;
  using Planner = ForcePlanner<Scalar, Dim, NumFingers>;
  using Forces = ForceLayer<Scalar, Dim, NumFingers>;
  using KinematicsSource = inhand::KinematicsSource;
  using FingerConfig = typename Types::FingerConfig;
  using Config = typename Types::Config;
  using TactileContact = typename Types::TactileContact;
  using FingerInput = typename Types::FingerInput;
  using Input = typename Types::Input;
  using FingerOutput = typename Types::FingerOutput;
  using Output = typename Types::Output;
  using Targets = detail::FingerArray<GraspTarget<Scalar, Dim>, NumFingers>;
  using Phase = ControllerPhase;  ///< see the file comment

  /// Checks a configuration without applying it; names the first invalid field.
  static Validation validate(const Config& c) noexcept { return c.validate(); }

  /// Validates and applies a configuration (all or nothing). Allocates only for
  /// run-time sized hands or chains. Leaves the controller idle.
  Validation configure(const Config& c) {
    const Validation v = c.validate();
    if (!v.ok()) return v;
    config_ = c;
    state_.size_for(config_);
    scratch_.size_for(config_);
    configured_ = true;
    reset();
    saved_ = state_;  // sizes the saved copy once (run-time sizes allocate here only)
    return Validation::valid();
  }

  /// Back to idle: integrators, filters, grasp and trajectory progress cleared.
  void reset() noexcept { state_.reset(); }

  int finger_count() const noexcept { return static_cast<int>(config_.fingers.size()); }
  const Config& config() const noexcept { return config_; }
  Phase phase() const noexcept { return state_.phase; }
  bool configured() const noexcept { return configured_; }
  const Trajectory& trajectory() const noexcept { return trajectory_; }

  /// An Input / Output sized for the configured hand (allocates only for run-time
  /// finger counts); call once, outside the control loop.
  Input make_input() const { return make_sized<Input>(); }
  Output make_output() const { return make_sized<Output>(); }

  /// Starts the grasp phase towards one target per finger (see grasp.hpp).
  Validation start_grasp(const Targets& targets) noexcept {
    if (!configured_) return Validation::invalid("controller", "not configured");
    if (static_cast<int>(targets.size()) != finger_count())
      return Validation::invalid("targets", "one target per finger");
    for (int i = 0; i < finger_count(); ++i) {
      const Validation v = targets[static_cast<std::size_t>(i)].validate();
      if (!v.ok()) return v.for_finger(i);
    }
    begin_grasp<Types>(config_, targets, state_, scratch_);
    state_.settled_time = Scalar(0);
    state_.phase = Phase::grasping;
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
    if (state_.phase != Phase::grasped && state_.phase != Phase::manipulating)
      return Validation::invalid("phase", "the grasp has not completed");
    const Validation tv = trajectory.validate();
    if (!tv.ok()) return tv;
    const TwistT gap = pose_error(trajectory.start_pose(), state_.pose_gate.pose());
    if (!(gap.template head<Dim>().norm() <= config_.start_position_tolerance))
      return Validation::invalid("trajectory.start_pose.position",
                                 "farther than start_position_tolerance from the measured pose");
    if (!(gap.template tail<SpatialDim<Dim>::kRot>().norm() <= config_.start_orientation_tolerance))
      return Validation::invalid("trajectory.start_pose.rotation",
                                 "farther than start_orientation_tolerance from the measured pose");
    trajectory_ = trajectory;
    state_.manipulation_time = Scalar(0);
    if (state_.phase != Phase::manipulating) state_.reset_task_loops();
    state_.phase = Phase::manipulating;
    for (FingerMemory<Types>& s : state_.fingers)
      if (s.state == FingerState::pressing) s.state = FingerState::in_contact;
    return Validation::valid();
  }

  /// One control tick. See the file comment for the contract.
  ControllerStatus update(const Input& in, Output& out) noexcept {
    out.warnings = ControllerWarning::none;
    out.fault = InputFault{};
    out.numerical_fault = nullptr;
    out.dt = Scalar(0);
    if (!configured_) return reject(out, {}, ControllerStatus::not_configured);
    const int n = finger_count();
    if (static_cast<int>(in.fingers.size()) != n || static_cast<int>(out.fingers.size()) != n)
      return reject(out, {InputField::finger_count, -1});  // run-time finger counts only
    for (int i = 0; i < n; ++i)
      if (out.fingers[static_cast<std::size_t>(i)].joint_velocities.size() !=
          config_.fingers[static_cast<std::size_t>(i)].chain.dof())
        return reject(out, {InputField::output_joint_velocities, i});
    const InputFault fault = check_input<Types>(config_, in, state_.has_time, state_.last_time);
    if (fault.field != InputField::none) return reject(out, fault);
    saved_ = state_;
    // dt in double (the time base), then in Scalar.
    double dt_time =
        state_.has_time ? in.time - state_.last_time : static_cast<double>(config_.control_period);
    if (dt_time > static_cast<double>(config_.max_tick)) {
      dt_time = static_cast<double>(config_.max_tick);
      out.warnings |= ControllerWarning::long_tick;
    }
    const Scalar dt = static_cast<Scalar>(dt_time);
    out.dt = dt;
    state_.last_time = in.time;
    // Sensor gates: the object pose and the normal forces this tick uses.
    const typename PoseGate<Scalar, Dim>::Step gated =
        state_.pose_gate.update(config_.outlier_gates, in.object_pose, dt, !state_.has_time);
    if (gated.outlier) out.warnings |= ControllerWarning::pose_outlier;
    for (int i = 0; i < n; ++i)
      if (state_.fingers[static_cast<std::size_t>(i)].gate_force(
              config_.outlier_gates, in.fingers[static_cast<std::size_t>(i)], dt))
        out.warnings |= ControllerWarning::force_outlier;
    state_.has_time = true;

    ControllerStatus status = ControllerStatus::idle;
    const TickInput<Types> tick{config_, in, gated.pose, dt};
    if (state_.phase == Phase::idle) {
      zero_output(out);
    } else if (state_.phase == Phase::manipulating) {
      status = manipulation_phase(tick, trajectory_, state_, scratch_, out);
    } else {
      status = grasp_phase(tick, state_, scratch_, out);
    }
    // Last line of defence: nothing non-finite leaves update().
    const char* stage = non_finite_stage<Types>(out);
    if (stage == nullptr) return status;
    state_ = saved_;
    zero_output(out);
    clear_diagnostics(out);
    out.dt = Scalar(0);
    out.numerical_fault = stage;
    return ControllerStatus::numerical_fault;
  }

  /// Finger i's grasp force f_g [N] (grasp.hpp): what it presses with once placed; 0 before
  /// start_grasp() (and for an i out of range).
  Scalar grasp_force(int i) const noexcept {
    return i >= 0 && i < finger_count() ? state_.fingers[static_cast<std::size_t>(i)].grasp_force
                                        : Scalar(0);
  }

  /// Largest |integral| of any finger's force loop (N s): for monitoring windup.
  Scalar max_force_integral() const noexcept {
    Scalar m = Scalar(0);
    for (int i = 0; i < state_.forces.size(); ++i)
      m = std::max(m, std::abs(state_.forces.integral()(i)));
    return m;
  }

 private:
  /// An invalid tick: the zero command, the fault named, no state changed.
  ControllerStatus reject(Output& out, InputFault fault,
                          ControllerStatus status = ControllerStatus::invalid_input) noexcept {
    zero_output(out);
    out.fault = fault;
    return status;
  }
  /// The fallback output: zero command, each finger's state as it is.
  void zero_output(Output& out) const noexcept {
    zero_command<Types>(out);
    for (int i = 0; i < static_cast<int>(out.fingers.size()) && i < finger_count(); ++i)
      out.fingers[static_cast<std::size_t>(i)].state =
          state_.fingers[static_cast<std::size_t>(i)].state;
  }
  /// An Input or Output with one slot per finger, each of the finger's DOF.
  template <typename T>
  T make_sized() const {
    T t;
    if constexpr (NumFingers == Dynamic) t.fingers.resize(config_.fingers.size());
    for (int i = 0; i < finger_count(); ++i)
      size_finger(t.fingers[static_cast<std::size_t>(i)],
                  config_.fingers[static_cast<std::size_t>(i)].chain.dof());
    return t;
  }
  static void size_finger(FingerInput& f, int dof) {
    f.joint_positions = JointVector::Zero(dof);
    f.jacobian = Jacobian::Zero(Dim, dof);
  }
  static void size_finger(FingerOutput& f, int dof) { f.joint_velocities = JointVector::Zero(dof); }
  /// After a numerical fault: every diagnostic output from the (restored) state or zero.
  void clear_diagnostics(Output& out) const noexcept {
    out.desired_object_pose = state_.pose_gate.pose();
    out.pose_error.setZero();
    out.pose_error_integral = state_.pose_loop.integral();
    out.force_residual.setZero();
    out.load_estimate.setZero();
    out.grip = Scalar(1);
    out.manipulation_time = state_.manipulation_time;
    for (FingerOutput& fo : out.fingers) fo.stiffness_estimate = fo.force_integral = Scalar(0);
  }

  Config config_{};
  bool configured_ = false;
  ControllerState<Types> state_{};
  ControllerState<Types> saved_{};  ///< state_ before the current tick
  TickScratch<Types> scratch_{};
  Trajectory trajectory_{};
};

}  // namespace inhand
