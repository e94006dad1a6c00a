// Shared support for the robustness suites (non-finite injection, property sweep,
// floating-point traps): controller rigs built from the plant's hand presets and the
// test fingers, tick inputs near a grasp, and bit-exact comparison of outputs.
//
// A Rig holds everything needed to drive a ReactiveController without a plant: the
// configuration, the chains, one grasp target per finger and a nominal joint posture.
// The targets are derived from the posture itself (the fingertip sphere touching an
// imaginary object whose centre is the mean of the fingertip centres), so every rig,
// planar or spatial, preset or random, gets a consistent geometry.
// Inputs: nominal_input() gives the deterministic tick k of a smooth, VALID input
// stream (object pose, joints and contacts wobbling slightly around the grasp), with a
// per-finger touching pattern. perfect_grasp_input() gives the tick that completes a
// grasp at once when GraspParams::settle_time is 0 (contacts exactly on their targets
// with their grasp forces, ReactiveController::grasp_force), which is how the suites reach the
// manipulation phase.
// Units: m, rad, s, N; world frame.
#pragma once

#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/presets.hpp"

namespace inhand_rob {

/// Bitwise equality of two Eigen objects (same size, same bytes): NaN == NaN of the
/// same payload, +0 != -0. This is what "bit-identical" means in these suites.
template <typename A, typename B>
bool same_bits(const Eigen::MatrixBase<A>& a, const Eigen::MatrixBase<B>& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  const auto ea = a.derived().eval();
  const auto eb = b.derived().eval();
  return std::memcmp(ea.data(), eb.data(),
                     sizeof(typename A::Scalar) * static_cast<std::size_t>(ea.size())) == 0;
}
template <typename S>
bool same_bits_scalar(S a, S b) {
  return std::memcmp(&a, &b, sizeof(S)) == 0;
}

template <typename Ctrl>
struct Rig {
  using Scalar = typename Ctrl::Scalar;
  static constexpr int Dim = Ctrl::Dim;
  using Chain = typename Ctrl::Chain;
  using JointVector = typename Ctrl::JointVector;
  using Vec = inhand::Vector<Scalar, Dim>;
  using Targets = inhand::detail::FingerArray<inhand::GraspTarget<Scalar, Dim>, Ctrl::NumFingers>;

  std::string name;
  typename Ctrl::Config config{};
  Targets targets{};
  std::vector<JointVector> q_nominal;
  inhand::Pose<Scalar, Dim> object{};

  int fingers() const { return static_cast<int>(config.fingers.size()); }
  const Chain& chain(int i) const { return config.fingers[static_cast<std::size_t>(i)].chain; }
  bool external(int i) const {
    return config.fingers[static_cast<std::size_t>(i)].kinematics ==
           Ctrl::KinematicsSource::external;
  }
};

template <typename T, int N>
inhand::detail::FingerArray<T, N> finger_array(int n) {
  inhand::detail::FingerArray<T, N> a{};
  if constexpr (N == inhand::Dynamic) a.resize(static_cast<std::size_t>(n));
  return a;
}

/// Copies a double-precision plant finger into any chain type of the same Dim = 3.
template <typename Chain>
Chain convert_chain(const inhand::plant::PlantFinger& f) {
  using S = typename Chain::Scalar;
  Chain c;
  if (!c.joints.resize(f.dof()))
    throw std::invalid_argument("joint count does not fit the chain type");
  c.base.position = f.base.position.cast<S>();
  c.base.rotation = f.base.rotation.cast<S>();
  for (int j = 0; j < f.dof(); ++j) {
    c.joints[j].parent_to_joint.position = f.joints[j].parent_to_joint.position.cast<S>();
    c.joints[j].parent_to_joint.rotation = f.joints[j].parent_to_joint.rotation.cast<S>();
    c.joints[j].axis = f.joints[j].axis.cast<S>();
    c.joints[j].lower = static_cast<S>(f.joints[j].lower);
    c.joints[j].upper = static_cast<S>(f.joints[j].upper);
    c.joints[j].max_velocity = static_cast<S>(f.joints[j].max_velocity);
  }
  c.joint_to_tip.position = f.joint_to_tip.position.cast<S>();
  c.joint_to_tip.rotation = f.joint_to_tip.rotation.cast<S>();
  c.fingertip_radius = static_cast<S>(f.fingertip_radius);
  return c;
}

/// Fingertip sphere centre of a chain at q.
template <typename Chain, typename Q>
inhand::Vector<typename Chain::Scalar, Chain::Dim> tip_centre(const Chain& chain, const Q& q) {
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  return ws.fingertip.position;
}

/// Completes a rig whose config.fingers and q_nominal are set: the object centre is
/// the mean of the fingertip centres, each target normal points from it to the
/// fingertip centre, each target point lies on the fingertip sphere. Tips that
/// coincide with the centre (a one-finger hand) get the normal +x.
template <typename Ctrl>
void derive_targets(Rig<Ctrl>& rig) {
  using Vec = typename Rig<Ctrl>::Vec;
  using S = typename Rig<Ctrl>::Scalar;
  const int n = rig.fingers();
  std::vector<Vec> tips;
  Vec centre = Vec::Zero();
  for (int i = 0; i < n; ++i) {
    tips.push_back(tip_centre(rig.chain(i), rig.q_nominal[static_cast<std::size_t>(i)]));
    centre += tips.back();
  }
  centre /= static_cast<S>(n);
  // A one-finger hand: put the object 3 cm away along the tip's base-relative x.
  if (n == 1) centre = tips[0] - Vec::UnitX() * S(0.03);
  rig.targets = finger_array<inhand::GraspTarget<S, Ctrl::Dim>, Ctrl::NumFingers>(n);
  for (int i = 0; i < n; ++i) {
    Vec d = tips[static_cast<std::size_t>(i)] - centre;
    Vec nrm = d.norm() > S(1e-6) ? Vec(d.normalized()) : Vec(Vec::UnitX());
    auto& t = rig.targets[static_cast<std::size_t>(i)];
    t.normal = nrm;
    t.contact_point = tips[static_cast<std::size_t>(i)] - rig.chain(i).fingertip_radius * nrm;
  }
  rig.object.position = centre;
  rig.object.rotation.setIdentity();
}

/// A rig from one of the plant's presets; `external` lists fingers whose Jacobian is
/// supplied in the input (KinematicsSource::external). The preset's thumb balances.
template <typename Ctrl>
Rig<Ctrl> preset_rig(const inhand::plant::HandPreset& hand, const std::vector<int>& external = {}) {
  static_assert(Ctrl::Dim == 3, "the plant presets are spatial");
  using S = typename Ctrl::Scalar;
  Rig<Ctrl> rig;
  rig.name = hand.name;
  const int n = static_cast<int>(hand.fingers.size());
  rig.config.fingers = finger_array<typename Ctrl::FingerConfig, Ctrl::NumFingers>(n);
  for (int i = 0; i < n; ++i) {
    auto& fc = rig.config.fingers[static_cast<std::size_t>(i)];
    fc.chain = convert_chain<typename Ctrl::Chain>(hand.fingers[static_cast<std::size_t>(i)]);
    fc.role = i == hand.thumb ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
    for (int e : external)
      if (e == i) fc.kinematics = Ctrl::KinematicsSource::external;
    typename Ctrl::JointVector q(fc.chain.dof());
    for (int j = 0; j < fc.chain.dof(); ++j)
      q(j) = static_cast<S>(hand.grasp_configuration[static_cast<std::size_t>(i)](j));
    rig.q_nominal.push_back(q);
  }
  derive_targets(rig);
  return rig;
}

/// A planar rig of `n` copies of the 3-DOF test finger placed around a circle, each
/// curled halfway; the last finger balances.
template <typename Ctrl>
Rig<Ctrl> planar_rig(int n, const std::vector<int>& external = {}) {
  static_assert(Ctrl::Dim == 2, "planar rig");
  using S = typename Ctrl::Scalar;
  Rig<Ctrl> rig;
  rig.name = "planar" + std::to_string(n);
  rig.config.fingers = finger_array<typename Ctrl::FingerConfig, Ctrl::NumFingers>(n);
  for (int i = 0; i < n; ++i) {
    auto spec = inhand_test::finger_spec<S, 2>(3);
    const double a = 2.0 * 3.14159265358979323846 * i / n;
    spec.base.position = inhand::Vector<S, 2>(S(0.09 * std::cos(a)), S(0.09 * std::sin(a)));
    spec.base.rotation = inhand::so2_exp<S>(static_cast<S>(a + 3.14159265358979323846 - 0.6));
    auto& fc = rig.config.fingers[static_cast<std::size_t>(i)];
    fc.chain = inhand_test::to_chain<typename Ctrl::Chain>(spec);
    fc.role = i == n - 1 ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
    for (int e : external)
      if (e == i) fc.kinematics = Ctrl::KinematicsSource::external;
    typename Ctrl::JointVector q(3);
    for (int j = 0; j < 3; ++j)
      q(j) = S(0.5) * (fc.chain.joints[j].lower + fc.chain.joints[j].upper);
    rig.q_nominal.push_back(q);
  }
  derive_targets(rig);
  return rig;
}

/// Per-finger touching pattern of a tick.
using Pattern = std::vector<bool>;

inline Pattern all_touching(int n) { return Pattern(static_cast<std::size_t>(n), true); }
/// Fingers 0, 2, 4, ... touch; 1, 3, ... do not.
inline Pattern alternate_touching(int n) {
  Pattern p(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) p[static_cast<std::size_t>(i)] = (i % 2) == 0;
  return p;
}

/// Fills a finger's external-kinematics fields from its chain: the Jacobian of the
/// point the controller servoes in that state and the virtual contact point.
template <typename Ctrl>
void fill_external(const Rig<Ctrl>& rig, int i, typename Ctrl::FingerInput& f, bool grasp_phase) {
  using Chain = typename Ctrl::Chain;
  const Chain& c = rig.chain(i);
  inhand::FingerKinematics<Chain> ws(c);
  inhand::forward_kinematics(c, f.joint_positions, ws);
  const auto& n = rig.targets[static_cast<std::size_t>(i)].normal;
  f.virtual_contact_point = inhand::fingertip_surface_point(c, ws, n);
  typename Ctrl::Vec p = f.virtual_contact_point;
  if (f.contact.touching) p = grasp_phase ? ws.fingertip.position : f.contact.contact_point;
  f.jacobian.resize(Ctrl::Dim, c.dof());
  inhand::point_jacobian(ws, p, f.jacobian);
}

/// Tick k (k >= 0) of a smooth valid input stream; time = (k + 1) ms.
template <typename Ctrl>
typename Ctrl::Input nominal_input(const Rig<Ctrl>& rig, const Ctrl& ctl, int k,
                                   const Pattern& touching, bool grasp_phase) {
  using S = typename Ctrl::Scalar;
  constexpr int Dim = Ctrl::Dim;
  using Vec = inhand::Vector<S, Dim>;
  typename Ctrl::Input in = ctl.make_input();
  const double kk = static_cast<double>(k);
  in.time = static_cast<S>(1e-3 * (kk + 1.0));
  in.object_pose = rig.object;
  for (int d = 0; d < Dim; ++d)
    in.object_pose.position(d) += static_cast<S>(2e-4 * std::sin(0.3 * kk + d));
  inhand::AngularVector<S, Dim> w;
  for (int d = 0; d < w.size(); ++d) w(d) = static_cast<S>(5e-3 * std::cos(0.2 * kk + d));
  in.object_pose.rotation = inhand::rotation_exp<S>(w) * rig.object.rotation;
  const S f0 = rig.config.force_planner.nominal_force;
  for (int i = 0; i < rig.fingers(); ++i) {
    auto& f = in.fingers[static_cast<std::size_t>(i)];
    const auto& t = rig.targets[static_cast<std::size_t>(i)];
    f.joint_positions = rig.q_nominal[static_cast<std::size_t>(i)];
    for (int j = 0; j < f.joint_positions.size(); ++j)
      f.joint_positions(j) += static_cast<S>(0.01 * std::sin(0.1 * kk + i + 0.5 * j));
    f.contact.touching = touching[static_cast<std::size_t>(i)];
    Vec offset;
    for (int d = 0; d < Dim; ++d) offset(d) = static_cast<S>(3e-4 * std::sin(0.7 * kk + 2 * i + d));
    f.contact.contact_point = t.contact_point + offset;
    Vec nrm = t.normal;
    for (int d = 0; d < Dim; ++d) nrm(d) += static_cast<S>(0.02 * std::cos(0.5 * kk + i + d));
    f.contact.normal = nrm.normalized();
    f.contact.normal_force = f0 * static_cast<S>(1.0 + 0.05 * std::sin(0.4 * kk + i));
    fill_external(rig, i, f, grasp_phase);
  }
  return in;
}

/// The tick that completes a grasp (with settle_time 0): every finger touching exactly
/// at its target, along the target normal, with its grasp force.
template <typename Ctrl>
typename Ctrl::Input perfect_grasp_input(const Rig<Ctrl>& rig, const Ctrl& ctl,
                                         typename Ctrl::Scalar time) {
  typename Ctrl::Input in = nominal_input(rig, ctl, 0, all_touching(rig.fingers()), true);
  in.time = time;
  in.object_pose = rig.object;
  for (int i = 0; i < rig.fingers(); ++i) {
    auto& f = in.fingers[static_cast<std::size_t>(i)];
    const auto& t = rig.targets[static_cast<std::size_t>(i)];
    f.joint_positions = rig.q_nominal[static_cast<std::size_t>(i)];
    f.contact.contact_point = t.contact_point;
    f.contact.normal = t.normal;
    f.contact.normal_force = ctl.grasp_force(i);
    fill_external(rig, i, f, true);
  }
  return in;
}

/// A short trajectory from `start`: reciprocate 5 mm along the first axis together
/// with 0.1 rad about the (first) rotation axis, 1 s per cycle, then hold.
template <typename S, int Dim>
inhand::ObjectTrajectory<S, Dim> test_trajectory(const inhand::Pose<S, Dim>& start) {
  inhand::ObjectTrajectory<S, Dim> traj;
  traj.reset(start);
  inhand::Twist<S, Dim> d = inhand::Twist<S, Dim>::Zero();
  d(0) = S(0.005);
  d(Dim) = S(0.1);
  traj.append(inhand::TrajectorySegment<S, Dim>::reciprocate(d, S(1), 1));
  traj.append(inhand::TrajectorySegment<S, Dim>::hold_for(S(1)));
  return traj;
}

/// Configures `ctl` for the rig and starts its grasp. Returns false on failure.
template <typename Ctrl>
bool start_grasp(Ctrl& ctl, const Rig<Ctrl>& rig) {
  if (!ctl.configure(rig.config).ok()) return false;
  return ctl.start_grasp(rig.targets).ok();
}

/// From a configured controller whose grasp has started (settle_time 0 required):
/// one perfect tick at `time`, then start_manipulation of test_trajectory. Returns
/// false if the controller did not report `grasped`.
template <typename Ctrl>
bool complete_grasp_and_manipulate(Ctrl& ctl, const Rig<Ctrl>& rig, typename Ctrl::Scalar time,
                                   typename Ctrl::Output& out) {
  const typename Ctrl::Input in = perfect_grasp_input(rig, ctl, time);
  if (ctl.update(in, out) != inhand::ControllerStatus::grasped) return false;
  return ctl.start_manipulation(test_trajectory<typename Ctrl::Scalar, Ctrl::Dim>(in.object_pose))
      .ok();
}

/// Every floating-point member of an Output is finite.
template <typename Ctrl>
bool output_finite(const typename Ctrl::Output& out) {
  using inhand::all_finite;
  bool ok = out.desired_object_pose.is_finite() && all_finite(out.feedforward_twist) &&
            all_finite(out.commanded_twist) && all_finite(out.pose_error) &&
            all_finite(out.force_residual) && inhand::is_finite(out.manipulation_time);
  for (const auto& f : out.fingers) {
    ok = ok && all_finite(f.joint_velocities) && all_finite(f.desired_contact_velocity) &&
         inhand::is_finite(f.desired_normal_force) && all_finite(f.servo.motion) &&
         all_finite(f.servo.force) && all_finite(f.servo.total) &&
         inhand::is_finite(f.ik.min_singular_value) && inhand::is_finite(f.ik.damping) &&
         inhand::is_finite(f.ik.limit_scale);
  }
  return ok;
}

/// Bit-identical Outputs: every scalar, status, flag and state.
template <typename Ctrl>
bool same_output(const typename Ctrl::Output& a, const typename Ctrl::Output& b) {
  if (a.fingers.size() != b.fingers.size()) return false;
  bool ok = same_bits(a.desired_object_pose.position, b.desired_object_pose.position) &&
            same_bits(a.desired_object_pose.rotation, b.desired_object_pose.rotation) &&
            same_bits(a.feedforward_twist, b.feedforward_twist) &&
            same_bits(a.commanded_twist, b.commanded_twist) &&
            same_bits(a.pose_error, b.pose_error) &&
            same_bits(a.force_residual, b.force_residual) &&
            a.force_plan_status == b.force_plan_status && a.warnings == b.warnings &&
            a.fault.field == b.fault.field && a.fault.finger == b.fault.finger &&
            same_bits_scalar(a.manipulation_time, b.manipulation_time) && a.segment == b.segment;
  for (std::size_t i = 0; i < a.fingers.size(); ++i) {
    const auto& x = a.fingers[i];
    const auto& y = b.fingers[i];
    ok = ok && same_bits(x.joint_velocities, y.joint_velocities) && x.state == y.state &&
         same_bits(x.desired_contact_velocity, y.desired_contact_velocity) &&
         same_bits_scalar(x.desired_normal_force, y.desired_normal_force) &&
         same_bits(x.servo.motion, y.servo.motion) && same_bits(x.servo.force, y.servo.force) &&
         same_bits(x.servo.total, y.servo.total) && x.servo_status == y.servo_status &&
         x.ik.status == y.ik.status &&
         same_bits_scalar(x.ik.min_singular_value, y.ik.min_singular_value) &&
         same_bits_scalar(x.ik.damping, y.ik.damping) &&
         same_bits_scalar(x.ik.limit_scale, y.ik.limit_scale);
  }
  return ok;
}

/// Largest |qdot_i| / max_velocity_i over the hand (<= 1 when every limit holds).
template <typename Ctrl>
double worst_limit_ratio(const Rig<Ctrl>& rig, const typename Ctrl::Output& out) {
  double worst = 0.0;
  for (int i = 0; i < rig.fingers(); ++i) {
    const auto& qd = out.fingers[static_cast<std::size_t>(i)].joint_velocities;
    for (int j = 0; j < qd.size(); ++j)
      worst = std::max(worst, static_cast<double>(std::abs(qd(j))) /
                                  static_cast<double>(rig.chain(i).joints[j].max_velocity));
  }
  return worst;
}

/// True when every |qdot_i| <= max_velocity_i holds exactly (no tolerance).
template <typename Ctrl>
bool within_limits(const Rig<Ctrl>& rig, const typename Ctrl::Output& out) {
  for (int i = 0; i < rig.fingers(); ++i) {
    const auto& qd = out.fingers[static_cast<std::size_t>(i)].joint_velocities;
    if (qd.size() != rig.chain(i).dof()) return false;
    for (int j = 0; j < qd.size(); ++j)
      if (!(std::abs(qd(j)) <= rig.chain(i).joints[j].max_velocity)) return false;
  }
  return true;
}

}  // namespace inhand_rob
