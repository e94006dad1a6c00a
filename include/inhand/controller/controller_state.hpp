// What the controller remembers from one tick to the next (ControllerState), and the
// preallocated per-tick workspace (TickScratch) that carries values between the steps
// of one tick without allocating. The state is copied before every tick and put back
// if the tick produces a non-finite value (reactive_controller.hpp), so it holds only
// what a tick reads from an earlier one; the scratch (forward kinematics, the IK and
// its workspace) is rewritten every tick before it is read, except what configure()
// derives from the chains once (chain plans, the hand's lanes, layer 3's limits and
// couplings). Units as in controller_io.hpp.
#pragma once

#include "inhand/controller/controller_io.hpp"
#include "inhand/controller/finger_command.hpp"
#include "inhand/controller/force_layer.hpp"
#include "inhand/controller/force_planner.hpp"
#include "inhand/controller/grasp.hpp"
#include "inhand/controller/hand_kinematics.hpp"
#include "inhand/controller/pose_feedback.hpp"
#include "inhand/controller/sensor_gates.hpp"
#include "inhand/math/whole_copy.hpp"

namespace inhand {

/// Controller phase: configure() -> idle; start_grasp() -> grasping; the grasp completes
/// -> grasped; start_manipulation() -> manipulating.
enum class ControllerPhase : unsigned char { idle, grasping, grasped, manipulating };

/// One finger's memory.
template <typename Types>
struct FingerMemory {
  using Scalar = typename Types::ScalarType;
  using Vec = typename Types::Vec;
  /// Layer 3's servo integrators and last command.
  FingerServoMemory<Scalar, Types::kDim, Types::kDof, Types::kMaxDof> layer3{};
  /// The Jacobian of the point servoed on the last tick: this tick's measured step
  /// of the fingertip is J (q - q_prev).
  detail::WholeCopy<typename Types::Jacobian> jacobian{};
  detail::WholeCopy<typename Types::JointVector>
      q_prev{};  ///< rad, joint positions of the last tick
  bool has_q_prev = false;
  GraspTarget<Scalar, Types::kDim> target{};
  Scalar grasp_pattern = Scalar(0);  ///< N, q_g of grasp.hpp, set by start_grasp
  Scalar grasp_force = Scalar(0);    ///< N, f_g of grasp.hpp, set by start_grasp
  FingerState state = FingerState::idle;
  bool touched = false;  ///< touched the object since start_grasp
  SettleWindow<Scalar, Types::kDim> settle{};
  ForceGate<Scalar> force_gate{};
  Vec last_contact_object = Vec::Zero();  ///< m, last contact point, object frame
  Vec last_normal_object = Vec::UnitX();  ///< last outward normal, object frame
  /// Gates this tick's normal-force reading of finger input `f` (ForceGate), crediting
  /// the fingertip's measured step into the object over the last tick, -n . J (q - q_prev)
  /// through the last tick's Jacobian, times g.contact_stiffness. Returns true when the
  /// reading was rejected. Reads the last tick's Jacobian and joint positions, before
  /// the force layer moves them on.
  bool gate_force(const OutlierGates<Scalar>& g, const typename Types::FingerInput& f,
                  Scalar dt) noexcept {
    const typename Types::TactileContact& c = f.contact;
    Scalar into = Scalar(0);  // m
    if (c.touching && has_q_prev && g.max_force_rate < std::numeric_limits<Scalar>::infinity()) {
      const Vec n = c.normal.normalized();
      for (Eigen::Index j = 0; j < jacobian.cols(); ++j)
        into -= n.dot(jacobian.col(j)) * (f.joint_positions(j) - q_prev(j));
    }
    return force_gate.update(g, c.touching, c.normal_force, g.contact_stiffness * into, dt);
  }
  /// Keeps contact c (world frame) in the object frame of `object`.
  void remember_contact(const typename Types::TactileContact& c,
                        const typename Types::PoseT& object) noexcept {
    last_contact_object = object.rotation.transpose() * (c.contact_point - object.position);
    last_normal_object = object.rotation.transpose() * c.normal;
  }
};

template <typename Types>
struct ControllerState {
  using Scalar = typename Types::ScalarType;
  static constexpr int Dim = Types::kDim;
  detail::FingerArray<FingerMemory<Types>, Types::kNumFingers> fingers{};
  ForcePlanner<Scalar, Dim, Types::kNumFingers> planner{};
  ForceLayer<Scalar, Dim, Types::kNumFingers> forces{};
  ControllerPhase phase = ControllerPhase::idle;
  double last_time = 0.0;  ///< s, the time base (see Input::time)
  bool has_time = false;
  Scalar settled_time = Scalar(0);       ///< s the grasp criterion has held
  Scalar manipulation_time = Scalar(0);  ///< s since start_manipulation
  Scalar risk_hold = Scalar(0);          ///< s the at-risk cut stays on (Config::at_risk_hold)
  Scalar grasp_grip = Scalar(0);         ///< s_g of the grasp (grasp.hpp); 0: none begun
  bool grasp_grip_measured = false;      ///< s_g sized over the measured normals yet
  bool grasp_grip_capped = false;        ///< max_force lowered s_g (release_grip_scale)
  bool grasp_balanced = false;           ///< the balancing shift was taken (balance_grasp)
  int grasp_balancing = -1;              ///< the finger sliding to it, -1: none
  /// The twist was cut on the last tick and still asked beyond the workspace's edge
  /// (workspace_limits.hpp: the cut then stays on).
  bool edge_cut = false;
  PoseLoop<Scalar, Dim> pose_loop{};
  PoseGate<Scalar, Dim> pose_gate{};

  /// Sizes every part for the configuration (allocates only for run-time sizes).
  void size_for(const typename Types::Config& c) {
    const int n = static_cast<int>(c.fingers.size());
    if constexpr (Types::kNumFingers == Dynamic) fingers.resize(static_cast<std::size_t>(n));
    planner.resize(n);
    planner.set_params(c.force_planner);
    forces.set_params(c.force_layer);
    forces.resize(n);
    for (int i = 0; i < n; ++i) {
      const typename Types::FingerConfig& fc = c.fingers[static_cast<std::size_t>(i)];
      FingerMemory<Types>& m = fingers[static_cast<std::size_t>(i)];
      m.layer3.configure(fc.chain.dof(), c.servo);
      m.jacobian.setZero(Dim, fc.chain.dof());
      m.q_prev.setZero(fc.chain.dof());
      planner.set_role(i, fc.role);
    }
  }
  /// The task loops' memory (the pose loop, the at-risk hold, the held cut), cleared when a task
  /// starts from rest.
  void reset_task_loops() noexcept {
    pose_loop.reset();
    risk_hold = Scalar(0);
    edge_cut = false;
  }
  /// Whether the twist is cut for the grasp at risk (the force layer's status `fs` says
  /// beyond_capacity, slipping or over_max_force: a load the grip cannot carry, a contact
  /// sliding, or a contact pressed harder than any target asks): on a tick at risk, and
  /// for `hold` s after the last one (ticks of dt s).
  bool hold_risk(ForceLayerStatus fs, Scalar hold, Scalar dt) noexcept {
    const bool at_risk = has(fs, ForceLayerStatus::beyond_capacity | ForceLayerStatus::slipping |
                                     ForceLayerStatus::over_max_force);
    risk_hold = at_risk ? hold : (risk_hold > dt ? risk_hold - dt : Scalar(0));
    return at_risk || risk_hold > Scalar(0);
  }
  /// A new grasp's grip s_g and whether max_force capped it (start_grasp); the grip's
  /// sizing over the measured normals and the balancing shift not yet taken.
  void begin_grasp_sizing(Scalar grip, bool capped) noexcept {
    grasp_grip = grip;
    grasp_grip_capped = capped;
    grasp_grip_measured = grasp_balanced = false;
    grasp_balancing = -1;
  }
  /// The grasp parameters finger i presses with: position_tolerance a quarter as large
  /// while it slides to the balancing shift's point (balance_grasp).
  GraspParams<Scalar> press_params(const GraspParams<Scalar>& g, int i) const noexcept {
    GraspParams<Scalar> p = g;
    if (i == grasp_balancing) p.position_tolerance *= Scalar(0.25);
    return p;
  }
  /// Back to idle: integrators, filters, grasp and trajectory progress cleared.
  void reset() noexcept {
    phase = ControllerPhase::idle;
    has_time = false;
    settled_time = manipulation_time = Scalar(0);
    reset_task_loops();
    pose_gate.reset();
    planner.reset();
    forces.reset();
    for (FingerMemory<Types>& m : fingers) {
      m.layer3.servo.reset();
      m.layer3.last_command.setZero();
      m.state = FingerState::idle;
      m.has_q_prev = false;
      m.force_gate.reset();
    }
  }
};

/// One finger's per-tick workspace: forward kinematics, its chain's plan, and layer 3
/// (the IK, the joint limits and couplings read from the chain).
template <typename Types>
struct FingerWork {
  FingerKinematics<typename Types::Chain> kinematics{};
  ChainPlan<typename Types::Chain> plan{};  ///< of the finger's chain, built by size_for
  FingerServo<typename Types::ScalarType, Types::kDim, Types::kDof, Types::kMaxDof> layer3{};
};

template <typename Types>
struct TickScratch {
  using Planner = ForcePlanner<typename Types::ScalarType, Types::kDim, Types::kNumFingers>;
  using Forces = ForceLayer<typename Types::ScalarType, Types::kDim, Types::kNumFingers>;
  detail::FingerArray<FingerWork<Types>, Types::kNumFingers> fingers{};
  typename Planner::Mask touching{};
  typename Planner::Normals normals{};         ///< unit outward normals of the touching
  typename Planner::Normals points{};          ///< m, contact points of the touching
  typename Planner::ForceVector pattern{};     ///< N, the planner's pattern q
  typename Planner::ForceVector measured{};    ///< N, gated normal forces
  typename Planner::Normals tip_steps{};       ///< m, fingertip step at the contact this tick
  typename Planner::ForceVector servo_gain{};  ///< 1/m^2, servo_normal_gain() per finger
  typename Forces::Result forces{};
  HandLanes<Types> lanes{};  ///< built by size_for
  /// Sizes and configures every part for the configuration (allocates only for run-time sizes).
  void size_for(const typename Types::Config& c) {
    const int n = static_cast<int>(c.fingers.size());
    if constexpr (Types::kNumFingers == Dynamic) fingers.resize(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      const typename Types::FingerConfig& fc = c.fingers[static_cast<std::size_t>(i)];
      FingerWork<Types>& w = fingers[static_cast<std::size_t>(i)];
      w.kinematics.joint_origins.setZero(Types::kDim, fc.chain.dof());
      w.kinematics.joint_axes.setZero(3, fc.chain.dof());
      w.plan = ChainPlan<typename Types::Chain>(fc.chain);
      w.layer3.configure(fc.chain, c.ik);
    }
    lanes.build(c, [&](int i) -> const ChainPlan<typename Types::Chain>& {
      return fingers[static_cast<std::size_t>(i)].plan;
    });
    touching = Planner::Mask::Zero(n);
    normals = Planner::Normals::Zero(Types::kDim, n);
    points = Planner::Normals::Zero(Types::kDim, n);
    pattern = Planner::ForceVector::Zero(n);
    measured = Planner::ForceVector::Zero(n);
    tip_steps = Planner::Normals::Zero(Types::kDim, n);
    servo_gain = Planner::ForceVector::Zero(n);
    forces.velocity.setZero(n);
    forces.target.setZero(n);
    forces.slipping.setZero(n);
  }
};

namespace detail {
/// On the first grasp tick every finger is placed and touching, s_g is sized again over
/// the measured normals and raised to that if higher: the grasp then presses with
/// f_g = s_g q_g of the contacts it has (grasp.hpp). Uses sc.normals and sc.pattern as
/// its workspace (the grasp phase writes both after it on every tick). Returns
/// release_grip_capped while the last sizing was capped by max_force, else none.
template <typename Types>
ControllerWarning size_grip_on_measured_normals(const typename Types::Config& config,
                                                const typename Types::Input& in,
                                                ControllerState<Types>& st,
                                                TickScratch<Types>& sc) noexcept {
  const ControllerWarning none = ControllerWarning::none;
  const int n = static_cast<int>(st.fingers.size());
  for (int i = 0; i < n && !st.grasp_grip_measured; ++i) {
    const FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    const typename Types::FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
    const bool out = m.state == FingerState::missed;  // left out: pattern 0 (grasp.hpp)
    if (!out && (!f.contact.touching || !m.settle.placed))
      return st.grasp_grip_capped ? ControllerWarning::release_grip_capped : none;
    sc.normals.col(i) =
        out ? typename Types::Vec(Types::Vec::Zero()) : f.contact.normal.normalized();
    sc.pattern(i) = m.grasp_pattern;
  }
  if (!st.grasp_grip_measured) {
    const auto r =
        release_grip_scale(sc.normals.leftCols(n), sc.pattern.head(n), config.force_layer,
                           config.force_planner.min_force, config.force_planner.max_force);
    st.grasp_grip_measured = true;
    st.grasp_grip_capped = r.capped;
    if (r.scale > st.grasp_grip) {
      st.grasp_grip = r.scale;
      for (int i = 0; i < n; ++i) {
        FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
        m.grasp_force = r.scale * m.grasp_pattern;
      }
    }
  }
  return st.grasp_grip_capped ? ControllerWarning::release_grip_capped : none;
}

/// The balancing shift (grasp.hpp, "A squeeze without a couple"): once per grasp, with
/// exactly one balancing finger b, on the first tick every finger touches and is placed,
/// b's target moves by balancing_shift() (grasp_map.hpp) of the grasp pattern over the
/// measured contacts, its target normal becomes the measured one, and if that is farther
/// than a quarter of position_tolerance b slides there (not placed; press_params) before
/// it presses again. Uses sc.points, sc.normals and sc.pattern as its workspace (the grasp
/// phase writes all three after it on every tick).
template <typename Types>
void balance_grasp(const typename Types::Config& config, const typename Types::Input& in,
                   ControllerState<Types>& st, TickScratch<Types>& sc) noexcept {
  using Scalar = typename Types::ScalarType;
  const int n = static_cast<int>(st.fingers.size());
  const int sliding = st.grasp_balancing;
  if (sliding >= 0 && st.fingers[static_cast<std::size_t>(sliding)].settle.placed)
    st.grasp_balancing = -1;
  int b = -1;
  for (int i = 0; i < n && !st.grasp_balanced; ++i) {
    const typename Types::FingerInput& f = in.fingers[static_cast<std::size_t>(i)];
    const FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(i)];
    const bool out = m.state == FingerState::missed;  // left out: pattern 0 (grasp.hpp)
    if (!out && config.fingers[static_cast<std::size_t>(i)].role == FingerRole::balancing) {
      st.grasp_balanced = b >= 0;  // a second balancing finger: no shift for this grasp
      b = i;
    }
    if (!out && (!f.contact.touching || !m.settle.placed)) return;
    sc.points.col(i) = out ? typename Types::Vec(Types::Vec::Zero()) : f.contact.contact_point;
    sc.normals.col(i) =
        out ? typename Types::Vec(Types::Vec::Zero()) : f.contact.normal.normalized();
    sc.pattern(i) = m.grasp_pattern;
  }
  if (st.grasp_balanced || b < 0) return;
  st.grasp_balanced = true;
  const typename Types::Vec d = balancing_shift<Scalar, Types::kDim>(
      sc.points.leftCols(n), sc.normals.leftCols(n), sc.pattern.head(n), b);
  if (!(d.norm() > Scalar(0.25) * config.grasp.position_tolerance)) return;
  FingerMemory<Types>& m = st.fingers[static_cast<std::size_t>(b)];
  m.target.contact_point = sc.points.col(b) + d;
  m.target.normal = sc.normals.col(b);
  m.settle.start();
  m.settle.gravity_side = false;  // aims at the normal measured there (grasp.hpp)
  st.grasp_balancing = b;
}
}  // namespace detail

}  // namespace inhand
