// The controller's configuration, its per-tick Input and Output (ReactiveController
// exposes these as its nested types Config, Input, Output, ...).
//
// Frames and units: world frame, SI (m, rad, s, N). Contact normals are the object's
// OUTWARD unit normals (towards the fingertip); normal forces are magnitudes >= 0 [N].
// Twists are (linear velocity of the object reference point; angular velocity). Joint
// vectors have the finger's DOF (FingerChain::dof()). Sizes: FingerArray is a
// std::array for a fixed finger count, a std::vector sized once by make_input() /
// make_output() for a run-time one; update() never resizes.
#pragma once

#include <array>
#include <cstddef>
#include <limits>
#include <type_traits>
#include <vector>

#include "inhand/controller/controller_status.hpp"
#include "inhand/controller/force_layer_params.hpp"
#include "inhand/controller/force_planner.hpp"
#include "inhand/controller/grasp.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/pose_feedback.hpp"
#include "inhand/controller/sensor_gates.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace inhand {

/// Where a finger's contact Jacobian comes from.
enum class KinematicsSource : unsigned char {
  chain,     ///< computed from FingerConfig::chain (forward kinematics + point Jacobian)
  external,  ///< supplied each tick in FingerInput::jacobian by the user's kinematics
};

namespace detail {
template <typename T, int N>
using FingerArray = std::conditional_t<N == Dynamic, std::vector<T>,
                                       std::array<T, static_cast<std::size_t>(N > 0 ? N : 1)>>;
}  // namespace detail

/// The controller's value types for NumFingers fingers of Dim-dimensional space, finger
/// DOF as in FingerChain (exact Dof, or Dynamic with MaxDof capacity).
template <typename Scalar, int Dim, int NumFingers, int Dof, int MaxDof = Dof>
struct ControllerTypes {
  using ScalarType = Scalar;
  static constexpr int kDim = Dim;
  static constexpr int kNumFingers = NumFingers;
  static constexpr int kDof = Dof;
  static constexpr int kMaxDof = MaxDof;
  using Chain = FingerChain<Scalar, Dim, Dof, MaxDof>;
  using JointVector = typename Chain::JointVector;
  using Jacobian = typename Chain::Jacobian;
  using Vec = Vector<Scalar, Dim>;
  using TwistT = Twist<Scalar, Dim>;
  using PoseT = Pose<Scalar, Dim>;
  /// (force N; torque N m about the object's reference point), world frame.
  using Wrench = Eigen::Matrix<Scalar, SpatialDim<Dim>::kTwist, 1>;

  struct FingerConfig {
    /// The finger's kinematics. With KinematicsSource::external only the joint count,
    /// the joints' limits (max_velocity; lower/upper when ik.joint_limits) and their
    /// couplings are used; the Jacobian given is then that of all joints.
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
    /// N, <= 0 and >= -max_measured_force: the lowest plausible reading of a touching
    /// finger's normal force. A tactile sensor's zero drifts: with an offset of -0.1 N a
    /// contact carrying less than 0.1 N reads below zero, and such a reading is taken as
    /// measured (the force layer's loops and load estimate see the offset as they see
    /// any bias; force_layer.md). A lower reading is invalid input (fault normal_force):
    /// a contact pulling at the finger by more than the nominal grip is no offset but
    /// a broken sensor.
    Scalar min_measured_force = Scalar(-1);
    /// m, > 0 (+inf disables): chain kinematics only. A touching finger's contact is
    /// implausible when the contact point lies farther than this from the fingertip
    /// sphere's surface, | |c - p| - r | > contact_tolerance (c the sphere centre from
    /// forward kinematics, r its radius, p the contact point), or when the normal points
    /// into the fingertip, n . (c - p) < 0 (n, the object's outward normal, points from
    /// the object towards the fingertip, so n . (c - p) = r for a true contact). Such a
    /// contact is still used (soft pads, calibration offsets), but flagged: the finger's
    /// FingerOutput::implausible_contact and the warning implausible_contact.
    Scalar contact_tolerance = Scalar(0.01);
    /// Joint limits (ik.joint_limits) as a constraint on the object twist
    /// (workspace_limits.hpp). The warning workspace_limited is raised either way when the
    /// commanded twist asks a touching contact to move, along its normal, where a joint
    /// held at its position limit cannot follow. true: the twist is also cut there, so the
    /// object stops at the edge of the hand's workspace instead of being carried on by the
    /// other fingers (which deforms the grasp). false (default): the twist is cut only on
    /// a tick whose force layer reports the grasp at risk (ForceLayerStatus
    /// beyond_capacity or slipping), for at_risk_hold after the last such tick, and, once
    /// cut, for as long as the twist goes on asking beyond the edge; otherwise it is left
    /// alone, and the held finger rolls or slides on the object if it can. While cut, the
    /// pose loop does not integrate the error along the cut (workspace_limits.hpp).
    bool keep_twist_in_reach = false;
    /// s the cut made while the grasp is at risk stays on after the last tick at risk
    /// (>= 0; 0: no hold). Once made, the cut also stays on while the twist goes on asking
    /// beyond the edge; the hold bridges the ticks where it stops asking for a tick or two
    /// (a held joint's bound reached and left tick by tick) while the two flags flicker at
    /// their thresholds (gaps of 1-6 ticks). Short against the pose loop's time constant
    /// (1/8 s).
    Scalar at_risk_hold = Scalar(0.05);
    /// start_manipulation() refuses a trajectory whose start pose is farther than this
    /// from the measured object pose (m, and rad of the rotation between them); > 0.
    Scalar start_position_tolerance = Scalar(0.01);
    Scalar start_orientation_tolerance = Scalar(0.2);
    /// Checks the whole configuration; names the first invalid field (its full path).
    Validation validate() const noexcept {
      const Config& c = *this;
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
      if (!is_finite(c.min_measured_force) || !(c.min_measured_force <= Scalar(0)) ||
          !(c.min_measured_force >= -c.max_measured_force))
        return Validation::invalid("min_measured_force", "must be <= 0 and >= -max_measured_force");
      if (!(c.contact_tolerance > Scalar(0)) || c.contact_tolerance != c.contact_tolerance)
        return Validation::invalid("contact_tolerance", "must be > 0 (+inf disables)");
      if (!is_finite(c.at_risk_hold) || !(c.at_risk_hold >= Scalar(0)))
        return Validation::invalid("at_risk_hold", "must be finite and >= 0");
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
  };

  /// Tactile contact of one finger (world frame).
  struct TactileContact {
    bool touching = false;
    Vec contact_point = Vec::Zero();  ///< m
    /// Object's outward unit normal: its length must be within 1e-3 of 1 (else invalid
    /// input, fault contact_normal); the controller normalises it.
    Vec normal = Vec::UnitX();
    /// N, >= 0 for a true contact force; readings in [Config::min_measured_force,
    /// Config::max_measured_force] are accepted (a sensor's offset may read below 0)
    Scalar normal_force = Scalar(0);
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
};

}  // namespace inhand
