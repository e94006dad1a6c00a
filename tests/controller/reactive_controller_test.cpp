// Tests of ReactiveController (controller/reactive_controller.hpp) in a small
// KINEMATIC closed loop written here: velocity-driven fingers with spherical tips
// around a box whose faces give collinear contact normals. Contact is sensed when a
// fingertip sphere penetrates the box; a linear spring gives the normal force. During
// the grasp the box is frozen; during manipulation it moves exactly with the
// commanded twist (integrated on SE(3)), so every check below is about the
// controller's own sign chain and bookkeeping, not about object dynamics:
//   validate()/configure(), the phases, eq. 2 at the measured contact points, the
//   servo split (eq. 7), J theta_dot = e (eq. 3), the thumb balancing the fingers
//   (section 5), contact loss and recovery, the invalid-input contract (zero output,
//   frozen state), external Jacobians, mixed-DOF hands, determinism and reset().
// Units: m, s, N, rad. Frames: world.
#include "inhand/controller/reactive_controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/grasp_forces.hpp"
#include "common/test_support.hpp"

namespace {

using inhand::ControllerStatus;
using inhand::ControllerWarning;
using inhand::FingerRole;
using inhand::FingerState;
using inhand::GraspTarget;
using inhand::InputField;
using inhand::Pose;
using inhand_test::record;

using V2 = Eigen::Vector2d;
using V3 = Eigen::Vector3d;
using M3 = Eigen::Matrix3d;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kPi = 3.14159265358979323846;

using PlanarCtrl = inhand::ReactiveController<double, 2, 3, 3>;
using PlanarDynCtrl = inhand::ReactiveController<double, 2, inhand::Dynamic, 3>;
using MixedCtrl = inhand::ReactiveController<double, 3, 3, inhand::Dynamic, 5>;

template <typename T, int N>
inhand::detail::FingerArray<T, N> finger_array(int n) {
  inhand::detail::FingerArray<T, N> a{};
  if constexpr (N == inhand::Dynamic) a.resize(static_cast<std::size_t>(n));
  return a;
}

// ---------------------------------------------------------------------------
// The plant: a box and kinematic fingers

template <int Dim>
struct Box {
  Pose<double, Dim> pose{};
  inhand::Vector<double, Dim> half = inhand::Vector<double, Dim>::Constant(0.02);
};

template <int Dim>
struct Sensed {
  bool touching = false;
  inhand::Vector<double, Dim> point = inhand::Vector<double, Dim>::Zero();
  inhand::Vector<double, Dim> normal = inhand::Vector<double, Dim>::UnitX();
  double force = 0.0;
  double penetration = 0.0;
};

/// Sphere (centre `tip`, radius r) against the box: penetration r - distance, the
/// box's outward normal at the closest surface point, force = stiffness * penetration.
template <int Dim>
Sensed<Dim> sense_box(const Box<Dim>& box, const inhand::Vector<double, Dim>& tip, double r,
                      double stiffness) {
  using Vec = inhand::Vector<double, Dim>;
  const Vec local = box.pose.rotation.transpose() * (tip - box.pose.position);
  Vec closest = local.cwiseMax(-box.half).cwiseMin(box.half);
  Vec n_local;
  double dist;
  if ((local - closest).norm() > 0.0) {
    dist = (local - closest).norm();
    n_local = (local - closest) / dist;
  } else {  // centre inside: nearest face
    int axis = 0;
    (box.half - local.cwiseAbs()).minCoeff(&axis);
    const double sgn = local(axis) >= 0 ? 1.0 : -1.0;
    n_local = sgn * Vec::Unit(axis);
    dist = -(box.half(axis) - std::abs(local(axis)));
    closest(axis) = sgn * box.half(axis);
  }
  Sensed<Dim> s;
  s.penetration = r - dist;
  s.touching = s.penetration > 0.0;
  s.normal = box.pose.rotation * n_local;
  s.point = box.pose.transform_point(closest);
  s.force = s.touching ? stiffness * s.penetration : 0.0;
  return s;
}

template <typename Ctrl>
struct Plant {
  using Chain = typename Ctrl::Chain;
  static constexpr int Dim = Ctrl::Dim;
  using Vec = inhand::Vector<double, Dim>;
  using JointVector = typename Ctrl::JointVector;

  std::vector<Chain> chains;
  std::vector<inhand::FingerKinematics<Chain>> ws;
  std::vector<JointVector> q;
  std::vector<Vec> expected_normal;     ///< the grasp targets' normals
  std::vector<Vec> last_normal_object;  ///< last sensed normal, object frame
  std::vector<Sensed<Dim>> sensed;
  Box<Dim> box{};
  double time = 0.0;
  double last_time = 0.0;  ///< time of the last fill()
  double dt = 1e-3;
  double stiffness = 1000.0;  ///< N/m: 1 N at 1 mm
  bool object_moves = true;   ///< during manipulation: integrate the commanded twist

  void add_finger(const Chain& c, const JointVector& q0, const Vec& normal) {
    chains.push_back(c);
    ws.emplace_back(c);
    q.push_back(q0);
    expected_normal.push_back(normal);
    last_normal_object.push_back(normal);
    sensed.emplace_back();
  }
  int size() const { return static_cast<int>(chains.size()); }

  void sense() {
    for (int i = 0; i < size(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      inhand::forward_kinematics(chains[k], q[k], ws[k]);
      sensed[k] =
          sense_box<Dim>(box, ws[k].fingertip.position, chains[k].fingertip_radius, stiffness);
    }
  }

  /// Builds the controller input for the current state. The Jacobian and virtual
  /// contact point (used by KinematicsSource::external fingers) are those of the
  /// point the chain mode servoes (reactive_controller.hpp, FingerInput): when not
  /// touching, the fingertip point facing the target normal (grasp) or the last
  /// normal carried with the object (manipulation); when touching, the fingertip
  /// centre (grasp: the object is held fixed) or the contact point (manipulation).
  void fill(typename Ctrl::Input& in, bool manipulating) {
    sense();
    last_time = time;
    in.time = time;
    in.object_pose = box.pose;
    for (int i = 0; i < size(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      auto& f = in.fingers[k];
      const Sensed<Dim>& s = sensed[k];
      f.joint_positions = q[k];
      f.contact.touching = s.touching;
      f.contact.contact_point = s.point;
      f.contact.normal = s.normal;
      f.contact.normal_force = s.force;
      Vec p;
      if (s.touching) {
        last_normal_object[k] = box.pose.rotation.transpose() * s.normal;
        p = manipulating ? s.point : ws[k].fingertip.position;
      } else {
        const Vec n =
            manipulating ? Vec(box.pose.rotation * last_normal_object[k]) : expected_normal[k];
        p = inhand::fingertip_surface_point(chains[k], ws[k], n);
      }
      f.virtual_contact_point = p;
      inhand::point_jacobian(ws[k], p, f.jacobian);
    }
  }

  void advance(const typename Ctrl::Output& out, bool manipulating) {
    for (int i = 0; i < size(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      q[k] += dt * out.fingers[k].joint_velocities;
    }
    if (manipulating && object_moves)
      box.pose = inhand::integrate(box.pose, out.commanded_twist, dt);
    time += dt;
  }
};

template <typename Ctrl>
bool manipulating(const Ctrl& c) {
  return c.phase() == Ctrl::Phase::manipulating;
}

/// One closed-loop tick: sense, update, move.
template <typename Ctrl>
ControllerStatus tick(Ctrl& c, Plant<Ctrl>& p, typename Ctrl::Input& in,
                      typename Ctrl::Output& out) {
  p.fill(in, manipulating(c));
  const ControllerStatus st = c.update(in, out);
  p.advance(out, manipulating(c));
  return st;
}

// ---------------------------------------------------------------------------
// Hands

template <typename Chain>
typename Chain::JointVector place_tip(const Chain& chain,
                                      const inhand::Vector<double, Chain::Dim>& target,
                                      typename Chain::JointVector q) {
  inhand::FingerKinematics<Chain> ws(chain);
  for (int it = 0; it < 200; ++it) {
    inhand::forward_kinematics(chain, q, ws);
    const inhand::Vector<double, Chain::Dim> e = target - ws.fingertip.position;
    if (e.norm() < 1e-14) break;
    Eigen::MatrixXd J(Chain::Dim, chain.dof());
    inhand::point_jacobian(ws, ws.fingertip.position, J);
    const Eigen::MatrixXd G =
        J * J.transpose() + 1e-12 * Eigen::MatrixXd::Identity(Chain::Dim, Chain::Dim);
    const Eigen::VectorXd dq = J.transpose() * G.ldlt().solve(Eigen::VectorXd(e));
    for (int j = 0; j < chain.dof(); ++j) q(j) += dq(j);
  }
  inhand::forward_kinematics(chain, q, ws);
  EXPECT_LT((ws.fingertip.position - target).norm(), 1e-10) << "finger placement failed";
  return q;
}

template <typename Chain>
Chain planar_chain(const V2& base, double angle) {
  Chain c;
  c.base.position = base;
  c.base.rotation = inhand::so2_exp(angle);
  const double offsets[] = {0.0, 0.05, 0.04};
  for (int i = 0; i < 3; ++i) {
    c.joints[i].parent_to_joint.position = V2(offsets[i], 0.0);
    c.joints[i].axis = V3::UnitZ();
    c.joints[i].max_velocity = 3.0;
  }
  c.joint_to_tip.position = V2(0.03, 0.0);
  c.fingertip_radius = 0.008;
  return c;
}

/// Spatial finger in its base frame: abduction about y, then flexion about z with
/// links along x (5 cm, 4 cm, 3 cm to the tip centre). The thumb splits the middle
/// link with a roll joint about x (5 joints).
template <typename Chain>
Chain spatial_chain(const V3& base, const M3& rot, bool thumb) {
  Chain c;
  c.joints.resize(thumb ? 5 : 4);
  c.base.position = base;
  c.base.rotation = rot;
  auto set = [&c](int i, const V3& offset, const V3& axis) {
    c.joints[i].parent_to_joint.position = offset;
    c.joints[i].axis = axis;
    c.joints[i].max_velocity = 3.0;
  };
  set(0, V3::Zero(), V3::UnitY());
  set(1, V3::Zero(), V3::UnitZ());
  set(2, V3(0.05, 0, 0), V3::UnitZ());
  if (thumb) {
    set(3, V3(0.02, 0, 0), V3::UnitX());
    set(4, V3(0.02, 0, 0), V3::UnitZ());
  } else {
    set(3, V3(0.04, 0, 0), V3::UnitZ());
  }
  c.joint_to_tip.position = V3(0.03, 0, 0);
  c.fingertip_radius = 0.009;
  return c;
}

template <typename Ctrl>
struct Scene {
  typename Ctrl::Config config{};
  Plant<Ctrl> plant{};
  inhand::detail::FingerArray<GraspTarget<double, Ctrl::Dim>, Ctrl::NumFingers> targets{};
};

/// Planar hand: thumb (finger 0, balancing) on the box's -x face, two fingers on the
/// +x face at y = -/+12 mm; fingertips start 8 mm from the faces. The grasp targets
/// expect the faces `expected_offset` further out than they are (unknown geometry).
template <typename Ctrl>
Scene<Ctrl> planar_scene(
    double expected_offset = 0.0,
    inhand::detail::FingerArray<typename Ctrl::KinematicsSource, 3> sources = {}) {
  Scene<Ctrl> s;
  s.config.fingers = finger_array<typename Ctrl::FingerConfig, Ctrl::NumFingers>(3);
  s.targets = finger_array<GraspTarget<double, 2>, Ctrl::NumFingers>(3);
  s.plant.box.half = V2(0.02, 0.03);
  struct Spec {
    V2 base;
    double angle;
    V2 contact;
    V2 normal;
    V3 guess;
  };
  const Spec specs[] = {
      {V2(-0.11, -0.03), 0.0, V2(-0.02, 0.0), V2(-1, 0), V3(0.5, 0.5, 0.5)},
      {V2(0.11, -0.045), kPi, V2(0.02, -0.012), V2(1, 0), V3(-0.5, -0.5, -0.5)},
      {V2(0.11, -0.015), kPi, V2(0.02, 0.012), V2(1, 0), V3(-0.5, -0.5, -0.5)},
  };
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Spec& sp = specs[i];
    auto chain = planar_chain<typename Ctrl::Chain>(sp.base, sp.angle);
    s.config.fingers[k].chain = chain;
    s.config.fingers[k].role = i == 0 ? FingerRole::balancing : FingerRole::preset;
    s.config.fingers[k].kinematics = sources[k];
    const V2 tip = sp.contact + (chain.fingertip_radius + 0.008) * sp.normal;
    typename Ctrl::JointVector q0(3);
    q0 = sp.guess;
    s.plant.add_finger(chain, place_tip(chain, tip, q0), sp.normal);
    s.targets[k].contact_point = sp.contact + expected_offset * sp.normal;
    s.targets[k].normal = sp.normal;
  }
  // These tests hold the controller to the paper's planner (eq. 8's pattern, unscaled):
  // no raised grip at release (force_layer_test.cpp covers it).
  s.config.force_layer.release_grip = 1.0;
  s.config.force_layer.release_load = 0.0;
  return s;
}

/// The grasp forces of grasp.hpp for a scene (common/grasp_forces.hpp).
template <typename Ctrl>
Eigen::VectorXd grasp_forces(const Scene<Ctrl>& s) {
  const std::vector<double> f = inhand_test::grasp_forces<double, Ctrl::Dim>(s.config, s.targets);
  return Eigen::Map<const Eigen::VectorXd>(f.data(), static_cast<Eigen::Index>(f.size()));
}

/// Spatial mixed-DOF hand: a 5-joint thumb (balancing) on the -x face, two 4-joint
/// fingers on the +x face at z = -/+12 mm.
Scene<MixedCtrl> mixed_scene() {
  Scene<MixedCtrl> s;
  using Chain = MixedCtrl::Chain;
  s.plant.box.half = V3(0.02, 0.03, 0.03);
  const M3 flip = Eigen::AngleAxisd(kPi, V3::UnitZ()).toRotationMatrix();
  struct Spec {
    V3 base;
    M3 rot;
    bool thumb;
    V3 contact;
    V3 normal;
    Eigen::VectorXd guess;
  };
  Eigen::VectorXd gt(5), gf(4);
  gt << 0.0, 0.5, 0.5, 0.0, 0.5;
  gf << 0.0, -0.5, -0.5, -0.5;
  const Spec specs[] = {
      {V3(-0.11, -0.03, 0.0), M3::Identity(), true, V3(-0.02, 0, 0), V3(-1, 0, 0), gt},
      {V3(0.11, -0.03, -0.012), flip, false, V3(0.02, 0, -0.012), V3(1, 0, 0), gf},
      {V3(0.11, -0.03, 0.012), flip, false, V3(0.02, 0, 0.012), V3(1, 0, 0), gf},
  };
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const Spec& sp = specs[i];
    const Chain chain = spatial_chain<Chain>(sp.base, sp.rot, sp.thumb);
    s.config.fingers[k].chain = chain;
    s.config.fingers[k].role = sp.thumb ? FingerRole::balancing : FingerRole::preset;
    const V3 tip = sp.contact + (chain.fingertip_radius + 0.008) * sp.normal;
    MixedCtrl::JointVector q0 = sp.guess;
    s.plant.add_finger(chain, place_tip(chain, tip, q0), sp.normal);
    s.targets[k].contact_point = sp.contact;
    s.targets[k].normal = sp.normal;
  }
  s.config.force_layer.release_grip = 1.0;  // the paper's planner, unscaled (as above)
  s.config.force_layer.release_load = 0.0;
  return s;
}

// ---------------------------------------------------------------------------
// Reference computations

/// Eq. 2 written out: v + omega x (p - o).
template <int Dim>
inhand::Vector<double, Dim> eq2(const inhand::Twist<double, Dim>& V,
                                const inhand::Vector<double, Dim>& p,
                                const inhand::Vector<double, Dim>& o) {
  const inhand::Vector<double, Dim> r = p - o;
  if constexpr (Dim == 2) {
    return V.template head<2>() + V(2) * V2(-r.y(), r.x());
  } else {
    return V.template head<3>() + V.template tail<3>().cross(r);
  }
}

/// Finite-difference Jacobian of the point now at p, rigidly attached to the distal
/// link: independent of point_jacobian.
template <typename Chain>
Eigen::MatrixXd fd_point_jacobian(const Chain& chain, const typename Chain::JointVector& q,
                                  const inhand::Vector<double, Chain::Dim>& p) {
  constexpr int Dim = Chain::Dim;
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  const inhand::Vector<double, Dim> local =
      ws.fingertip.rotation.transpose() * (p - ws.fingertip.position);
  Eigen::MatrixXd J(Dim, chain.dof());
  const double h = 1e-6;
  for (int j = 0; j < chain.dof(); ++j) {
    typename Chain::JointVector qp = q, qm = q;
    qp(j) += h;
    qm(j) -= h;
    inhand::forward_kinematics(chain, qp, ws);
    const inhand::Vector<double, Dim> pp = ws.fingertip.transform_point(local);
    inhand::forward_kinematics(chain, qm, ws);
    const inhand::Vector<double, Dim> pm = ws.fingertip.transform_point(local);
    J.col(j) = (pp - pm) / (2 * h);
  }
  return J;
}

template <typename Ctrl>
bool zero_joint_velocities(const Ctrl& c, const typename Ctrl::Output& out) {
  for (int i = 0; i < c.finger_count(); ++i) {
    const auto& jv = out.fingers[static_cast<std::size_t>(i)].joint_velocities;
    if (jv.size() != c.config().fingers[static_cast<std::size_t>(i)].chain.dof()) return false;
    if (!(jv.array() == 0.0).all()) return false;
  }
  return true;
}

/// Bit-identical outputs; `why` names the first difference.
template <typename Out>
bool same_output(const Out& a, const Out& b, std::string& why) {
  std::ostringstream w;
  if (a.fingers.size() != b.fingers.size()) {
    why = "finger count";
    return false;
  }
  for (std::size_t i = 0; i < a.fingers.size(); ++i) {
    const auto& x = a.fingers[i];
    const auto& y = b.fingers[i];
    w.str("");
    w << "finger " << i << ": ";
    if (x.joint_velocities.size() != y.joint_velocities.size() ||
        !(x.joint_velocities == y.joint_velocities)) {
      why = w.str() + "joint_velocities";
      return false;
    }
    if (x.state != y.state)
      why = w.str() + "state";
    else if (!(x.desired_contact_velocity == y.desired_contact_velocity))
      why = w.str() + "desired_contact_velocity";
    else if (x.desired_normal_force != y.desired_normal_force)
      why = w.str() + "desired_normal_force";
    else if (!(x.servo.motion == y.servo.motion) || !(x.servo.force == y.servo.force) ||
             !(x.servo.total == y.servo.total))
      why = w.str() + "servo";
    else if (x.servo_status != y.servo_status)
      why = w.str() + "servo_status";
    else if (x.ik.status != y.ik.status || x.ik.min_singular_value != y.ik.min_singular_value ||
             x.ik.damping != y.ik.damping || x.ik.limit_scale != y.ik.limit_scale)
      why = w.str() + "ik";
    else
      continue;
    return false;
  }
  if (!(a.desired_object_pose.position == b.desired_object_pose.position) ||
      !(a.desired_object_pose.rotation == b.desired_object_pose.rotation))
    why = "desired_object_pose";
  else if (!(a.feedforward_twist == b.feedforward_twist))
    why = "feedforward_twist";
  else if (!(a.commanded_twist == b.commanded_twist))
    why = "commanded_twist";
  else if (!(a.pose_error == b.pose_error))
    why = "pose_error";
  else if (!(a.force_residual == b.force_residual))
    why = "force_residual";
  else if (a.force_plan_status != b.force_plan_status)
    why = "force_plan_status";
  else if (a.warnings != b.warnings)
    why = "warnings";
  else if (a.fault.field != b.fault.field || a.fault.finger != b.fault.finger)
    why = "fault";
  else if (a.manipulation_time != b.manipulation_time)
    why = "manipulation_time";
  else if (a.segment != b.segment)
    why = "segment";
  else
    return true;
  return false;
}

/// Runs the grasp to completion (at most max_ticks); returns the tick count or -1.
template <typename Ctrl>
int run_grasp(Ctrl& c, Plant<Ctrl>& p, typename Ctrl::Input& in, typename Ctrl::Output& out,
              int max_ticks = 4000) {
  for (int k = 0; k < max_ticks; ++k)
    if (tick(c, p, in, out) == ControllerStatus::grasped) return k + 1;
  return -1;
}

/// The planar manipulation task: hold, 5 mm along +x, -0.1 rad about z, a
/// reciprocation in y and rotation, hold (3.5 s).
inhand::ObjectTrajectory<double, 2> planar_task(const Pose<double, 2>& start) {
  using Seg = inhand::TrajectorySegment<double, 2>;
  inhand::ObjectTrajectory<double, 2> tr;
  tr.reset(start);
  tr.append(Seg::hold_for(0.2));
  tr.append(Seg::move(V2::UnitX(), 0.005, 1.0));
  tr.append(Seg::rotate(inhand::AngularVector<double, 2>(1.0), -0.1, 1.0));
  inhand::Twist<double, 2> d;
  d << 0.0, 0.003, 0.05;
  tr.append(Seg::reciprocate(d, 1.0));
  tr.append(Seg::hold_for(0.3));
  return tr;
}

template <typename Ctrl>
void configure_and_grasp(Ctrl& c, Scene<Ctrl>& s, typename Ctrl::Input& in,
                         typename Ctrl::Output& out) {
  ASSERT_TRUE(c.configure(s.config).ok());
  in = c.make_input();
  out = c.make_output();
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  ASSERT_GT(run_grasp(c, s.plant, in, out), 0) << "grasp did not complete";
}

// ---------------------------------------------------------------------------
// Configuration

TEST(ReactiveControllerConfig, ValidateNamesTheOffendingField) {
  const Scene<PlanarCtrl> scene = planar_scene<PlanarCtrl>();
  ASSERT_TRUE(PlanarCtrl::validate(scene.config).ok());
  struct Case {
    const char* name;
    std::function<void(PlanarCtrl::Config&)> edit;
    const char* field;
    int finger;
    int index;
  };
  const std::vector<Case> cases = {
      {"zero control_period", [](PlanarCtrl::Config& c) { c.control_period = 0.0; },
       "control_period", -1, -1},
      {"NaN control_period", [](PlanarCtrl::Config& c) { c.control_period = kNaN; },
       "control_period", -1, -1},
      {"negative control_period", [](PlanarCtrl::Config& c) { c.control_period = -1e-3; },
       "control_period", -1, -1},
      {"max_tick below period", [](PlanarCtrl::Config& c) { c.max_tick = 1e-4; }, "max_tick", -1,
       -1},
      {"zero joint acceleration bound",
       [](PlanarCtrl::Config& c) { c.max_joint_acceleration = 0.0; }, "max_joint_acceleration", -1,
       -1},
      {"NaN joint acceleration bound",
       [](PlanarCtrl::Config& c) { c.max_joint_acceleration = kNaN; }, "max_joint_acceleration", -1,
       -1},
      {"negative integral gain",
       [](PlanarCtrl::Config& c) { c.pose_feedback.position_integral_gain = -1.0; },
       "pose_feedback.position_integral_gain", -1, -1},
      {"zero integral band",
       [](PlanarCtrl::Config& c) { c.pose_feedback.position_integral_band = 0.0; },
       "pose_feedback.position_integral_band", -1, -1},
      {"NaN orientation integral band",
       [](PlanarCtrl::Config& c) { c.pose_feedback.orientation_integral_band = kNaN; },
       "pose_feedback.orientation_integral_band", -1, -1},
      {"zero astray distance", [](PlanarCtrl::Config& c) { c.pose_feedback.astray_distance = 0.0; },
       "pose_feedback.astray_distance", -1, -1},
      {"NaN astray angle", [](PlanarCtrl::Config& c) { c.pose_feedback.astray_angle = kNaN; },
       "pose_feedback.astray_angle", -1, -1},
      {"infinite astray time",
       [](PlanarCtrl::Config& c) {
         c.pose_feedback.astray_time = std::numeric_limits<double>::infinity();
       },
       "pose_feedback.astray_time", -1, -1},
      {"negative position gain",
       [](PlanarCtrl::Config& c) { c.pose_feedback.position_gain = -1.0; },
       "pose_feedback.position_gain", -1, -1},
      {"NaN orientation gain",
       [](PlanarCtrl::Config& c) { c.pose_feedback.orientation_gain = kNaN; },
       "pose_feedback.orientation_gain", -1, -1},
      {"zero speed bound", [](PlanarCtrl::Config& c) { c.pose_feedback.max_linear_speed = 0.0; },
       "pose_feedback.max_linear_speed", -1, -1},
      {"negative motion kp", [](PlanarCtrl::Config& c) { c.servo.motion.kp = -1.0; },
       "servo.motion.kp", -1, -1},
      {"negative force ki", [](PlanarCtrl::Config& c) { c.servo.force.ki = -0.1; },
       "servo.force.ki", -1, -1},
      {"zero force integral limit",
       [](PlanarCtrl::Config& c) { c.servo.force.integral_limit = 0.0; },
       "servo.force.integral_limit", -1, -1},
      {"NaN motion output limit", [](PlanarCtrl::Config& c) { c.servo.motion.output_limit = kNaN; },
       "servo.motion.output_limit", -1, -1},
      {"zero servo integral velocity",
       [](PlanarCtrl::Config& c) { c.servo.max_integral_velocity = 0.0; },
       "servo.max_integral_velocity", -1, -1},
      {"bad damping threshold",
       [](PlanarCtrl::Config& c) { c.ik.damping.singular_threshold = 0.0; },
       "ik.damping.singular_threshold", -1, -1},
      {"negative max damping", [](PlanarCtrl::Config& c) { c.ik.damping.max_damping = -1.0; },
       "ik.damping.max_damping", -1, -1},
      {"infinite force plausibility bound",
       [](PlanarCtrl::Config& c) { c.max_measured_force = kInf; }, "max_measured_force", -1, -1},
      {"zero contact tolerance", [](PlanarCtrl::Config& c) { c.contact_tolerance = 0.0; },
       "contact_tolerance", -1, -1},
      {"NaN start tolerance", [](PlanarCtrl::Config& c) { c.start_position_tolerance = kNaN; },
       "start_position_tolerance", -1, -1},
      {"negative at-risk hold", [](PlanarCtrl::Config& c) { c.at_risk_hold = -1e-3; },
       "at_risk_hold", -1, -1},
      {"infinite at-risk hold", [](PlanarCtrl::Config& c) { c.at_risk_hold = kInf; },
       "at_risk_hold", -1, -1},
      {"infinite pose integral limit",
       [](PlanarCtrl::Config& c) { c.pose_feedback.position_integral_limit = kInf; },
       "pose_feedback.position_integral_limit", -1, -1},
      {"min force above max",
       [](PlanarCtrl::Config& c) {
         c.force_planner.min_force = 3.0;
         c.force_planner.max_force = 2.0;
       },
       "force_planner.max_force", -1, -1},
      {"creep faster than approach", [](PlanarCtrl::Config& c) { c.grasp.creep_speed = 1.0; },
       "grasp.creep_speed", -1, -1},
      {"no balancing finger", [](PlanarCtrl::Config& c) { c.fingers[0].role = FingerRole::preset; },
       "fingers.role", -1, -1},
      {"finger 2 zero joint speed",
       [](PlanarCtrl::Config& c) { c.fingers[2].chain.joints[1].max_velocity = 0.0; },
       "fingers.chain.joints.max_velocity", 2, 1},
      {"finger 2 tilted planar axis",
       [](PlanarCtrl::Config& c) { c.fingers[2].chain.joints[0].axis = V3::UnitX(); },
       "fingers.chain.joints.axis", 2, 0},
      {"finger 1 NaN base",
       [](PlanarCtrl::Config& c) { c.fingers[1].chain.base.position(0) = kNaN; },
       "fingers.chain.base", 1, -1},
      // Frames that are not rotations (finite, so only the rotation check sees them).
      {"finger 1 base scaled by 2",
       [](PlanarCtrl::Config& c) { c.fingers[1].chain.base.rotation *= 2.0; },
       "fingers.chain.base.rotation", 1, -1},
      {"finger 0 zero parent_to_joint of joint 2",
       [](PlanarCtrl::Config& c) {
         c.fingers[0].chain.joints[2].parent_to_joint.rotation.setZero();
       },
       "fingers.chain.joints.parent_to_joint.rotation", 0, 2},
      {"finger 2 reflected joint_to_tip",
       [](PlanarCtrl::Config& c) { c.fingers[2].chain.joint_to_tip.rotation(1, 1) = -1.0; },
       "fingers.chain.joint_to_tip.rotation", 2, -1},
      {"finger 2 slightly sheared parent_to_joint of joint 1",
       [](PlanarCtrl::Config& c) {
         c.fingers[2].chain.joints[1].parent_to_joint.rotation(0, 1) = 1e-4;
       },
       "fingers.chain.joints.parent_to_joint.rotation", 2, 1},
  };
  for (const Case& c : cases) {
    PlanarCtrl::Config cfg = scene.config;
    c.edit(cfg);
    const inhand::Validation v = PlanarCtrl::validate(cfg);
    ASSERT_FALSE(v.ok()) << c.name;
    EXPECT_EQ(std::string(v.field), c.field) << c.name;
    EXPECT_EQ(v.finger, c.finger) << c.name;
    EXPECT_EQ(v.index, c.index) << c.name;
    EXPECT_NE(v.reason, nullptr) << c.name;
    // configure() refuses it the same way.
    PlanarCtrl ctrl;
    const inhand::Validation w = ctrl.configure(cfg);
    ASSERT_FALSE(w.ok());
    EXPECT_EQ(std::string(w.field), c.field);
    EXPECT_FALSE(ctrl.configured());
  }
  // One finger needs no balancing partner.
  inhand::ReactiveController<double, 2, 1, 3>::Config one;
  one.fingers[0].chain = scene.config.fingers[0].chain;
  EXPECT_TRUE((inhand::ReactiveController<double, 2, 1, 3>::validate(one).ok()));
}

TEST(ReactiveControllerConfig, UpdateBeforeConfigureGivesZeroOutput) {
  PlanarCtrl c;
  EXPECT_FALSE(c.configured());
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  for (auto& f : out.fingers) {
    f.joint_velocities.setConstant(7.0);
    f.desired_normal_force = 3.0;
  }
  out.commanded_twist.setConstant(1.0);
  EXPECT_EQ(c.update(in, out), ControllerStatus::not_configured);
  for (const auto& f : out.fingers) {
    EXPECT_TRUE((f.joint_velocities.array() == 0.0).all());
    EXPECT_EQ(f.desired_normal_force, 0.0);
  }
  EXPECT_TRUE(out.commanded_twist.isZero(0.0));
  EXPECT_FALSE(c.start_grasp(planar_scene<PlanarCtrl>().targets).ok());
  EXPECT_FALSE(c.start_manipulation(inhand::ObjectTrajectory<double, 2>{}).ok());
}

TEST(ReactiveControllerConfig, ConfiguredButIdleGivesZeroOutput) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  EXPECT_EQ(c.phase(), PlanarCtrl::Phase::idle);
  PlanarCtrl::Input in = c.make_input();
  PlanarCtrl::Output out = c.make_output();
  for (int k = 0; k < 5; ++k) {
    EXPECT_EQ(tick(c, s.plant, in, out), ControllerStatus::idle);
    EXPECT_TRUE(zero_joint_velocities(c, out));
  }
  // Manipulation cannot start before the grasp has completed.
  const inhand::Validation v = c.start_manipulation(planar_task(s.plant.box.pose));
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(std::string(v.field), "phase");
  // Targets are checked.
  auto bad = s.targets;
  bad[1].normal.setZero();
  const inhand::Validation w = c.start_grasp(bad);
  ASSERT_FALSE(w.ok());
  EXPECT_EQ(std::string(w.field), "grasp_target.normal");
  EXPECT_EQ(w.finger, 1);
}

TEST(ReactiveControllerConfig, ConfigureIsAllOrNothing) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl a, b;
  ASSERT_TRUE(a.configure(s.config).ok());
  ASSERT_TRUE(b.configure(s.config).ok());
  PlanarCtrl::Input in = a.make_input();
  PlanarCtrl::Output oa = a.make_output(), ob = b.make_output();
  ASSERT_TRUE(a.start_grasp(s.targets).ok());
  ASSERT_TRUE(b.start_grasp(s.targets).ok());
  Plant<PlanarCtrl> p = s.plant;
  for (int k = 0; k < 100; ++k) {
    p.fill(in, false);
    a.update(in, oa);
    b.update(in, ob);
    p.advance(oa, false);
  }
  // An invalid configuration that also changes valid fields is refused as a whole.
  PlanarCtrl::Config bad = s.config;
  bad.control_period = 5e-3;
  bad.grasp.approach_speed = 0.1;
  bad.servo.force.kp = 0.5;
  bad.fingers[1].chain.fingertip_radius = 0.02;
  bad.fingers[2].chain.joints[2].max_velocity = -1.0;
  const inhand::Validation v = a.configure(bad);
  ASSERT_FALSE(v.ok());
  EXPECT_EQ(v.finger, 2);
  EXPECT_TRUE(a.configured());
  EXPECT_EQ(a.config().control_period, s.config.control_period);
  EXPECT_EQ(a.config().grasp.approach_speed, s.config.grasp.approach_speed);
  EXPECT_EQ(a.config().servo.force.kp, s.config.servo.force.kp);
  EXPECT_EQ(a.config().fingers[1].chain.fingertip_radius,
            s.config.fingers[1].chain.fingertip_radius);
  EXPECT_EQ(a.phase(), PlanarCtrl::Phase::grasping);
  // ... and the controller carries on exactly like one that never saw it.
  for (int k = 0; k < 300; ++k) {
    p.fill(in, false);
    const ControllerStatus sa = a.update(in, oa), sb = b.update(in, ob);
    ASSERT_EQ(sa, sb);
    std::string why;
    ASSERT_TRUE(same_output(oa, ob, why)) << "tick " << k << ": " << why;
    p.advance(oa, false);
  }
  // A valid reconfiguration takes effect and returns to idle.
  PlanarCtrl::Config good = s.config;
  good.control_period = 2e-3;
  ASSERT_TRUE(a.configure(good).ok());
  EXPECT_EQ(a.config().control_period, 2e-3);
  EXPECT_EQ(a.phase(), PlanarCtrl::Phase::idle);
}

// ---------------------------------------------------------------------------
// Grasp

TEST(ReactiveControllerGrasp, SceneIsWellConditioned) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  s.plant.sense();
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_FALSE(s.plant.sensed[k].touching);
    EXPECT_NEAR(-s.plant.sensed[k].penetration, 0.008, 1e-9);  // 8 mm gap
    const Eigen::MatrixXd J =
        fd_point_jacobian(s.plant.chains[k], s.plant.q[k], s.plant.sensed[k].point);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
    EXPECT_GT(svd.singularValues().minCoeff(), 0.02) << "finger " << i;
  }
  Scene<MixedCtrl> m = mixed_scene();
  m.plant.sense();
  for (int i = 0; i < 3; ++i) {
    const auto k = static_cast<std::size_t>(i);
    EXPECT_NEAR(-m.plant.sensed[k].penetration, 0.008, 1e-9);
    const Eigen::MatrixXd J =
        fd_point_jacobian(m.plant.chains[k], m.plant.q[k], m.plant.sensed[k].point);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(J);
    EXPECT_GT(svd.singularValues().minCoeff(), 0.01) << "finger " << i;
  }
}

TEST(ReactiveControllerGrasp, FingersApproachTouchAndReachTheNominalForce) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  PlanarCtrl::Input in = c.make_input();
  PlanarCtrl::Output out = c.make_output();
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  const auto& g = s.config.grasp;
  // The thumb balances the two fingers: 1 N, 1 N and (2 + rho) / (1 + rho) for it.
  const Eigen::VectorXd f_grasp = grasp_forces(s);
  const double rho = s.config.force_planner.regularisation;
  ASSERT_NEAR(f_grasp(0), (2.0 + rho) / (1.0 + rho), 1e-12);
  ASSERT_EQ(f_grasp(1), 1.0);
  ASSERT_EQ(f_grasp(2), 1.0);
  std::vector<double> prev_dist(3, kInf);
  std::vector<bool> touched(3, false), checked_first_press(3, false), pressing_still(3, false);
  double worst_v = 0.0, worst_ik = 0.0, worst_tangential = 0.0;
  int ticks = -1;
  for (int k = 0; k < 4000 && ticks < 0; ++k) {
    s.plant.fill(in, false);
    const ControllerStatus st = c.update(in, out);
    if (st == ControllerStatus::grasped)
      ticks = k + 1;
    else
      ASSERT_EQ(st, ControllerStatus::grasping);
    for (int i = 0; i < 3; ++i) {
      const auto j = static_cast<std::size_t>(i);
      const auto& fo = out.fingers[j];
      const auto& sensed = s.plant.sensed[j];
      if (!sensed.touching) {
        ASSERT_EQ(fo.state, FingerState::approaching);
        EXPECT_EQ(fo.desired_normal_force, 0.0);
        EXPECT_TRUE(fo.servo.force.isZero(0.0));
        // The approach law of grasp.hpp at the fingertip point facing the target.
        const V2 p_v = s.plant.ws[j].fingertip.position -
                       s.plant.chains[j].fingertip_radius * s.targets[j].normal;
        const V2 v =
            inhand::approach_velocity(g, p_v, s.targets[j].contact_point, s.targets[j].normal);
        worst_v = std::max(worst_v, (fo.desired_contact_velocity - v).norm());
        // Before the first touch, the gap to the object only closes.
        if (!touched[j]) {
          EXPECT_LT(-sensed.penetration, prev_dist[j]) << "finger " << i << " tick " << k;
          prev_dist[j] = -sensed.penetration;
        }
      } else {
        touched[j] = true;
        ASSERT_EQ(fo.state, FingerState::pressing);
        // It slides to its target with slide_force_fraction of its grasp force; once
        // placed it presses with the full grasp force and no longer slides, for good.
        const double slide = g.slide_force_fraction * f_grasp(i);
        if (std::abs(fo.desired_normal_force - f_grasp(i)) < 1e-12) pressing_still[j] = true;
        if (pressing_still[j]) {
          EXPECT_NEAR(fo.desired_normal_force, f_grasp(i), 1e-12)
              << "finger " << i << " tick " << k;
          EXPECT_TRUE(fo.desired_contact_velocity.isZero(0.0)) << "finger " << i;
        } else {
          EXPECT_NEAR(fo.desired_normal_force, slide, 1e-12) << "finger " << i << " tick " << k;
        }
        // While pressing the motion part is tangential: motion along the normal
        // comes from the force servo alone.
        worst_tangential =
            std::max(worst_tangential, std::abs(fo.desired_contact_velocity.dot(sensed.normal)));
        if (!checked_first_press[j]) {
          // First touch: the force is below its grasp force, so the force part pushes
          // INTO the object, along -n (servo.hpp's sign convention).
          checked_first_press[j] = true;
          EXPECT_LT(sensed.force, fo.desired_normal_force);
          EXPECT_LT(fo.servo.force.dot(sensed.normal), 0.0) << "finger " << i;
        }
      }
      // Eq. 3: the joint velocities realise the servo command at the servoed point:
      // the fingertip centre while pressing on the fixed object, else the virtual point.
      if (fo.ik.status == inhand::IkStatus::ok) {
        const V2 p = sensed.touching ? s.plant.ws[j].fingertip.position
                                     : V2(s.plant.ws[j].fingertip.position -
                                          s.plant.chains[j].fingertip_radius * s.targets[j].normal);
        const Eigen::MatrixXd J = fd_point_jacobian(s.plant.chains[j], s.plant.q[j], p);
        worst_ik = std::max(worst_ik, (J * fo.joint_velocities - fo.servo.total).norm() /
                                          (1e-9 + fo.servo.total.norm()));
      }
    }
    s.plant.advance(out, false);
  }
  ASSERT_GT(ticks, 0) << "grasp did not complete in 4 s";
  EXPECT_LT(worst_v, 1e-15);
  EXPECT_LT(worst_ik, 1e-6);
  EXPECT_LT(worst_tangential, 1e-15);
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(pressing_still[static_cast<std::size_t>(i)]) << i;
  // Every finger presses with its grasp force within the tolerance.
  s.plant.sense();
  for (int i = 0; i < 3; ++i) {
    EXPECT_TRUE(s.plant.sensed[static_cast<std::size_t>(i)].touching);
    EXPECT_NEAR(in.fingers[static_cast<std::size_t>(i)].contact.normal_force, f_grasp(i),
                g.force_tolerance * f_grasp(i))
        << "finger " << i;
  }
  // The box was frozen.
  EXPECT_TRUE(s.plant.box.pose.position.isZero(0.0));
  // After the grasp the controller keeps holding and keeps reporting grasped.
  for (int k = 0; k < 50; ++k) EXPECT_EQ(tick(c, s.plant, in, out), ControllerStatus::grasped);
  record("grasp_time_s", ticks * s.plant.dt);
  record("ik_relative_residual", worst_ik);
}

TEST(ReactiveControllerGrasp, GraspForcesAreSizedForTheReleaseLoad) {
  // Thumb on -x against two fingers on +x: G = sum n n^T + 0.1 I has 3.1 along x, so a
  // load along x takes |w| / 3.1 from a finger; for 6 N the fingers of 1 N need
  // s = 0.2 + 6 / 3.1 = 2.14 > release_grip 2 (the thumb, 2 N, only 1.07). Without the
  // load: release_grip.
  Scene<MixedCtrl> s = mixed_scene();
  s.config.force_layer.release_grip = 2.0;
  s.config.force_layer.release_load = 6.0;
  s.config.force_planner.max_force = 100.0;
  MixedCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  const Eigen::VectorXd f = grasp_forces(s);  // the replica, sized independently
  for (int i = 0; i < 3; ++i) EXPECT_NEAR(c.grasp_force(i), f(i), 1e-12) << i;
  const double pattern_finger = 1.0;  // the preset fingers' nominal force
  EXPECT_GT(c.grasp_force(1), 2.0 * pattern_finger * 1.05);
  s.config.force_layer.release_load = 0.0;
  ASSERT_TRUE(c.configure(s.config).ok());
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  EXPECT_NEAR(c.grasp_force(1), 2.0 * pattern_finger, 1e-9);
}

TEST(ReactiveControllerGrasp, ACappedReleaseGripIsWarnedOnEveryGraspTick) {
  // The mixed hand's thumb pattern is 2 N: release_grip 2 asks it for 4 N. With max_force
  // 3.5 N the grip is held at 1.75 and every grasp tick says release_grip_capped, before the
  // object is released; with the default 6 N it is never raised. Checked on the grasp run to
  // completion, through the re-sizing over the measured normals.
  for (const double max_force : {3.5, 6.0}) {
    Scene<MixedCtrl> s = mixed_scene();
    s.config.force_layer.release_grip = 2.0;
    s.config.force_layer.release_load = 0.0;
    s.config.force_planner.max_force = max_force;
    MixedCtrl c;
    MixedCtrl::Input in;
    MixedCtrl::Output out;
    ASSERT_TRUE(c.configure(s.config).ok());
    in = c.make_input();
    out = c.make_output();
    ASSERT_TRUE(c.start_grasp(s.targets).ok());
    int ticks = 0, warned = 0;
    for (; ticks < 4000; ++ticks) {
      const ControllerStatus st = tick(c, s.plant, in, out);
      warned += has(out.warnings, ControllerWarning::release_grip_capped) ? 1 : 0;
      if (st == ControllerStatus::grasped) break;
    }
    ASSERT_LT(ticks, 4000) << "max_force " << max_force;
    if (max_force < 4.0) {
      EXPECT_EQ(warned, ticks + 1);
      EXPECT_NEAR(c.grasp_force(0), max_force, 1e-9);
    } else {
      EXPECT_EQ(warned, 0);
      EXPECT_NEAR(c.grasp_force(0), grasp_forces(s)(0), 1e-12);  // 2 q_g, about 4 N
    }
  }
}

TEST(ReactiveControllerGrasp, GraspForcesAreOneScaleOfThePatternWithinMaxForce) {
  // The thumb's pattern is 2 N against two fingers of 1 N. release_grip 3 would ask the
  // thumb for 6 N; with max_force 5 every finger is scaled by 2.5 instead, so the grasp
  // forces stay balanced (a per-finger clip to 5 N would leave 1 N pushing the object).
  Scene<MixedCtrl> s = mixed_scene();
  s.config.force_layer.release_grip = 3.0;
  s.config.force_planner.max_force = 5.0;
  MixedCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  EXPECT_EQ(c.grasp_force(0), 0.0);  // before start_grasp
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  const Eigen::VectorXd f = grasp_forces(s);  // the replica planner, scaled
  Eigen::Vector3d resultant = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(c.grasp_force(i), f(i), 1e-12) << i;
    EXPECT_LE(c.grasp_force(i), 5.0 + 1e-12) << i;
    resultant += c.grasp_force(i) * s.targets[static_cast<std::size_t>(i)].normal.normalized();
  }
  EXPECT_NEAR(c.grasp_force(0), 5.0, 1e-3);
  EXPECT_LT(resultant.norm(), 0.01);
  EXPECT_EQ(c.grasp_force(3), 0.0);  // out of range
  EXPECT_EQ(c.grasp_force(-1), 0.0);
}

TEST(ReactiveControllerGrasp, FindsASurfaceDeeperThanExpected) {
  // The targets expect the faces 3 mm further out than they are: after reaching the
  // expected points the fingers must keep creeping until they touch.
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>(0.003);
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  s.plant.sense();
  const Eigen::VectorXd f_grasp = grasp_forces(s);
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(s.plant.sensed[static_cast<std::size_t>(i)].force, f_grasp(i),
                s.config.grasp.force_tolerance * f_grasp(i));
  // And when the object is larger than expected, contact simply comes earlier.
  Scene<PlanarCtrl> big = planar_scene<PlanarCtrl>(-0.003);
  PlanarCtrl d;
  configure_and_grasp(d, big, in, out);
}

// ---------------------------------------------------------------------------
// Manipulation

TEST(ReactiveControllerManipulation, FollowsEq2KeepsContactAndBalancesTheThumb) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  const auto task = planar_task(s.plant.box.pose);
  ASSERT_TRUE(c.start_manipulation(task).ok());
  // A replica planner fed what the controller was given.
  inhand::ForcePlanner<double, 2, 3> replica;
  replica.set_params(s.config.force_planner);
  replica.set_role(0, FingerRole::balancing);
  const double rho = s.config.force_planner.regularisation;
  const int n_ticks = static_cast<int>(std::lround((task.duration() + 0.2) / s.plant.dt));
  double worst_eq2 = 0.0, worst_split = 0.0, worst_ik = 0.0, worst_normal = 0.0;
  double worst_force = 0.0, worst_pose = 0.0, worst_planner = 0.0, worst_twist = 0.0;
  int ik_checked = 0;
  const auto& pf = s.config.pose_feedback;
  inhand::Twist<double, 2> integral = inhand::Twist<double, 2>::Zero();
  for (int k = 0; k < n_ticks; ++k) {
    const double t_prev = s.plant.last_time;
    s.plant.fill(in, true);
    const ControllerStatus st = c.update(in, out);
    ASSERT_EQ(st, ControllerStatus::ok) << "tick " << k;
    // Layer 1: the commanded twist is feed-forward + PI feedback on the MEASURED pose,
    // the error integrated within its band and the integral limited per part
    // (pose_feedback.hpp).
    const double dt = in.time - t_prev;
    const auto smp = task.evaluate(out.manipulation_time);
    EXPECT_EQ(out.segment, smp.segment);
    const inhand::Twist<double, 2> e = inhand::pose_error(smp.pose, in.object_pose);
    EXPECT_LT((out.pose_error - e).norm(), 1e-15);
    inhand::Twist<double, 2> banded = e;
    if (e.head<2>().norm() > pf.position_integral_band)
      banded.head<2>() *= pf.position_integral_band / e.head<2>().norm();
    if (std::abs(e(2)) > pf.orientation_integral_band)
      banded(2) *= pf.orientation_integral_band / std::abs(e(2));
    integral += dt * banded;
    if (integral.head<2>().norm() > pf.position_integral_limit)
      integral.head<2>() *= pf.position_integral_limit / integral.head<2>().norm();
    if (std::abs(integral(2)) > pf.orientation_integral_limit)
      integral(2) *= pf.orientation_integral_limit / std::abs(integral(2));
    inhand::Twist<double, 2> V = smp.twist;
    V.head<2>() += pf.position_gain * e.head<2>() + pf.position_integral_gain * integral.head<2>();
    V(2) += pf.orientation_gain * e(2) + pf.orientation_integral_gain * integral(2);
    worst_twist = std::max(worst_twist, (out.commanded_twist - V).norm());
    EXPECT_FALSE(has(out.warnings, ControllerWarning::twist_limited));
    worst_pose = std::max(worst_pose, e.norm());
    // Layer 2: forces.
    Eigen::Matrix<unsigned char, 3, 1> touching;
    Eigen::Matrix<double, 2, 3> normals;
    for (int i = 0; i < 3; ++i) {
      touching(i) = 1;
      normals.col(i) = in.fingers[static_cast<std::size_t>(i)].contact.normal;
    }
    Eigen::Vector3d f_plan;
    V2 residual;
    replica.plan(touching, normals, k == 0 ? 1e-3 : s.plant.dt, f_plan, residual);
    for (int i = 0; i < 3; ++i) {
      const auto j = static_cast<std::size_t>(i);
      const auto& fo = out.fingers[j];
      const auto& fin = in.fingers[j];
      ASSERT_EQ(fo.state, FingerState::in_contact);
      worst_planner = std::max(worst_planner, std::abs(fo.desired_normal_force - f_plan(i)));
      // Eq. 2 at the measured contact point and the measured object position.
      const V2 v = eq2<2>(out.commanded_twist, fin.contact.contact_point, in.object_pose.position);
      worst_eq2 = std::max(worst_eq2, (fo.desired_contact_velocity - v).norm());
      // Eq. 7: total = motion + force; g1 = 1 passes the velocity; the force part is
      // along the measured normal.
      worst_split =
          std::max(worst_split, (fo.servo.total - (fo.servo.motion + fo.servo.force)).norm());
      worst_split = std::max(worst_split, (fo.servo.motion - fo.desired_contact_velocity).norm());
      const V2 n = fin.contact.normal;
      worst_normal = std::max(worst_normal, (fo.servo.force - fo.servo.force.dot(n) * n).norm());
      // Eq. 3.
      if (fo.ik.status == inhand::IkStatus::ok) {
        const Eigen::MatrixXd J =
            fd_point_jacobian(s.plant.chains[j], s.plant.q[j], fin.contact.contact_point);
        worst_ik = std::max(worst_ik, (J * fo.joint_velocities - fo.servo.total).norm() /
                                          (1e-9 + fo.servo.total.norm()));
        ++ik_checked;
      }
      // Force tracking while the object moves (after the initial hold, in which the
      // force loops settle after the release).
      if (out.manipulation_time > 0.2)
        worst_force =
            std::max(worst_force, std::abs(fin.contact.normal_force - fo.desired_normal_force));
    }
    EXPECT_LT((out.force_residual - residual).norm(), 1e-15);
    s.plant.advance(out, true);
  }
  EXPECT_LT(worst_twist, 1e-12);
  EXPECT_LT(worst_eq2, 1e-15);
  EXPECT_EQ(worst_split, 0.0);
  EXPECT_LT(worst_normal, 1e-15);
  EXPECT_LT(worst_ik, 1e-6);
  EXPECT_GT(ik_checked, n_ticks);
  EXPECT_EQ(worst_planner, 0.0);
  EXPECT_LT(worst_force, 0.5);  // contact kept with bounded force error while moving
  EXPECT_LT(worst_pose, 1e-3);
  // At rest at the end: the thumb balances the two fingers, 2 N up to the
  // regularisation, and the measured forces have settled on the plan.
  EXPECT_NEAR(out.fingers[0].desired_normal_force, (2.0 + rho) / (1.0 + rho), 1e-6);
  EXPECT_EQ(out.fingers[1].desired_normal_force, 1.0);
  EXPECT_EQ(out.fingers[2].desired_normal_force, 1.0);
  EXPECT_LT(out.force_residual.norm(), 2.0 * rho);
  // The force loops settle on their targets. The object here is kinematic (moved by
  // the test, not by the forces), so the rigid part of the forces is not set by its
  // equilibrium: the loops correct only the internal (squeezing) part of the plan.
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(in.fingers[static_cast<std::size_t>(i)].contact.normal_force,
                out.fingers[static_cast<std::size_t>(i)].force_target, 0.05);
  // The object reached the end of the task (kinematic object: tracking is exact up
  // to the per-tick integration).
  const auto end = task.evaluate(task.duration());
  EXPECT_LT((s.plant.box.pose.position - end.pose.position).norm(), 1e-5);
  EXPECT_NEAR(inhand::so2_log<double>(s.plant.box.pose.rotation), -0.1, 1e-4);
  record("max_force_error_N", worst_force);
  record("max_pose_error", worst_pose);
  record("ik_relative_residual", worst_ik);
}

TEST(ReactiveControllerManipulation, ContactLossIsReportedAndRecovered) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  using Seg = inhand::TrajectorySegment<double, 2>;
  inhand::ObjectTrajectory<double, 2> hold;
  hold.reset(s.plant.box.pose);
  hold.append(Seg::hold_for(10.0));
  ASSERT_TRUE(c.start_manipulation(hold).ok());
  for (int k = 0; k < 300; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
  // The object jumps 4 mm away from the thumb (which presses 2 mm deep at 2 N).
  // The controller remembers the thumb's last contact from the last input.
  const V2 thumb_contact_object =
      in.object_pose.inverse().transform_point(in.fingers[0].contact.contact_point);
  const V2 thumb_normal_object = in.object_pose.rotation.transpose() * in.fingers[0].contact.normal;
  s.plant.box.pose.position.x() += 0.004;
  s.plant.fill(in, true);
  ASSERT_FALSE(in.fingers[0].contact.touching);
  ASSERT_EQ(c.update(in, out), ControllerStatus::contact_lost);
  EXPECT_EQ(out.fingers[0].state, FingerState::reacquiring);
  EXPECT_EQ(out.fingers[1].state, FingerState::in_contact);
  EXPECT_EQ(out.fingers[0].desired_normal_force, 0.0);
  EXPECT_TRUE(out.fingers[0].servo.force.isZero(0.0));
  EXPECT_TRUE(has(out.warnings, ControllerWarning::no_balancing_contact));
  EXPECT_EQ(out.fingers[1].desired_normal_force, 1.0);  // the preset fingers keep 1 N
  {
    // Re-approach along the last normal towards the last contact point carried with
    // the object, plus the object's motion there (eq. 2).
    const V2 n = s.plant.box.pose.rotation * thumb_normal_object;
    EXPECT_LT((n + V2::UnitX()).norm(), 1e-12);
    const V2 p_t = s.plant.box.pose.transform_point(thumb_contact_object);
    const V2 p_v = s.plant.ws[0].fingertip.position - s.plant.chains[0].fingertip_radius * n;
    const V2 v = inhand::approach_velocity(s.config.grasp, p_v, p_t, n) +
                 eq2<2>(out.commanded_twist, p_t, s.plant.box.pose.position);
    EXPECT_LT((out.fingers[0].desired_contact_velocity - v).norm(), 1e-12);
    EXPECT_GT(out.fingers[0].desired_contact_velocity.x() - out.commanded_twist.x(),
              0.0);  // towards the box
  }
  s.plant.advance(out, true);
  // Recovery: the thumb touches again and the forces settle on the plan.
  int lost_ticks = 1, ok_run = 0;
  for (int k = 0; k < 2000 && ok_run < 300; ++k) {
    const ControllerStatus st = tick(c, s.plant, in, out);
    if (st == ControllerStatus::contact_lost) {
      ++lost_ticks;
      ok_run = 0;
      EXPECT_EQ(out.fingers[0].state, FingerState::reacquiring);
    } else {
      ASSERT_EQ(st, ControllerStatus::ok);
      EXPECT_EQ(out.fingers[0].state, FingerState::in_contact);
      ++ok_run;
    }
  }
  EXPECT_EQ(ok_run, 300);
  EXPECT_LT(lost_ticks, 500);
  // Then everything settles back: the pose integral unwinds (slowest closed-loop
  // pole of the kinematic object ~1.5/s with the default PI gains).
  for (int k = 0; k < 4000; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
  for (int i = 0; i < 3; ++i)  // on their targets (kinematic object, see above)
    EXPECT_NEAR(in.fingers[static_cast<std::size_t>(i)].contact.normal_force,
                out.fingers[static_cast<std::size_t>(i)].force_target, 0.05);
  EXPECT_LT(out.pose_error.norm(), 1e-4);  // and the pose is restored
  record("ticks_without_thumb_contact", lost_ticks);
}

// ---------------------------------------------------------------------------
// Invalid input

struct BadInputCase {
  const char* name;
  std::function<void(PlanarCtrl::Input&, double t_prev)> edit;
  InputField field;
  int finger;
};

std::vector<BadInputCase> bad_input_cases() {
  using In = PlanarCtrl::Input;
  return {
      {"NaN time", [](In& in, double) { in.time = kNaN; }, InputField::time, -1},
      {"infinite time", [](In& in, double) { in.time = kInf; }, InputField::time, -1},
      {"repeated time", [](In& in, double t_prev) { in.time = t_prev; }, InputField::time, -1},
      {"NaN object position", [](In& in, double) { in.object_pose.position(1) = kNaN; },
       InputField::object_pose, -1},
      {"NaN object rotation", [](In& in, double) { in.object_pose.rotation(0, 1) = kNaN; },
       InputField::object_pose, -1},
      {"non-orthonormal rotation", [](In& in, double) { in.object_pose.rotation *= 1.01; },
       InputField::object_pose, -1},
      {"NaN joint position", [](In& in, double) { in.fingers[2].joint_positions(1) = kNaN; },
       InputField::joint_positions, 2},
      {"NaN thumb joint", [](In& in, double) { in.fingers[0].joint_positions(0) = kNaN; },
       InputField::joint_positions, 0},
      {"NaN contact point",
       [](In& in, double) {
         in.fingers[2].contact.touching = true;
         in.fingers[2].contact.contact_point(0) = kNaN;
       },
       InputField::contact_point, 2},
      {"NaN normal",
       [](In& in, double) {
         in.fingers[2].contact.touching = true;
         in.fingers[2].contact.normal(1) = kNaN;
       },
       InputField::contact_normal, 2},
      {"zero normal",
       [](In& in, double) {
         in.fingers[2].contact.touching = true;
         in.fingers[2].contact.normal.setZero();
       },
       InputField::contact_normal, 2},
      {"NaN force",
       [](In& in, double) {
         in.fingers[2].contact.touching = true;
         in.fingers[2].contact.normal_force = kNaN;
       },
       InputField::normal_force, 2},
      {"force below min_measured_force",
       [](In& in, double) {
         in.fingers[2].contact.touching = true;
         in.fingers[2].contact.normal_force = -1.5;
       },
       InputField::normal_force, 2},
      {"NaN external Jacobian", [](In& in, double) { in.fingers[2].jacobian(1, 2) = kNaN; },
       InputField::jacobian, 2},
      {"infinite external Jacobian", [](In& in, double) { in.fingers[2].jacobian(0, 0) = kInf; },
       InputField::jacobian, 2},
      {"NaN virtual contact point",
       [](In& in, double) {
         in.fingers[2].contact.touching = false;
         in.fingers[2].virtual_contact_point(0) = kNaN;
       },
       InputField::virtual_contact_point, 2},
  };
}

/// From a snapshot (controller + plant), for every bad-input case: the bad tick gives
/// invalid_input naming the field and finger with zero joint velocities, and the next
/// valid ticks are bit-identical to those of a copy that never saw the bad tick.
void check_bad_inputs(const PlanarCtrl& snapshot, const Plant<PlanarCtrl>& plant,
                      const PlanarCtrl::Output& last_out, const char* phase) {
  for (const BadInputCase& bc : bad_input_cases()) {
    SCOPED_TRACE(std::string(phase) + ": " + bc.name);
    PlanarCtrl a = snapshot, b = snapshot;
    Plant<PlanarCtrl> p = plant;
    PlanarCtrl::Output oa = last_out, ob = last_out;
    PlanarCtrl::Input good = a.make_input();
    const double t_prev = p.last_time;
    const bool manip = manipulating(a);
    p.fill(good, manip);
    PlanarCtrl::Input bad = good;
    bc.edit(bad, t_prev);
    ASSERT_EQ(a.update(bad, oa), ControllerStatus::invalid_input);
    EXPECT_EQ(oa.fault.field, bc.field) << inhand::to_string(oa.fault.field);
    EXPECT_EQ(oa.fault.finger, bc.finger);
    EXPECT_TRUE(zero_joint_velocities(a, oa));
    EXPECT_TRUE(oa.commanded_twist.isZero(0.0));
    EXPECT_EQ(a.phase(), snapshot.phase());
    // Nothing moved during the bad tick (zero command); the next tick is valid.
    p.time += p.dt;
    for (int k = 0; k < 20; ++k) {
      PlanarCtrl::Input next = a.make_input();
      p.fill(next, manipulating(a));
      const ControllerStatus sa = a.update(next, oa), sb = b.update(next, ob);
      ASSERT_EQ(sa, sb);
      ASSERT_NE(sa, ControllerStatus::invalid_input);
      std::string why;
      ASSERT_TRUE(same_output(oa, ob, why)) << "tick " << k << ": " << why;
      p.advance(oa, manipulating(a));
    }
  }
}

TEST(ReactiveControllerInvalidInput, FaultNamesFieldAndFingerZeroOutputAndFrozenState) {
  // Finger 2 takes its Jacobian from the input, so every field is exercised.
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>(
      0.0, {PlanarCtrl::KinematicsSource::chain, PlanarCtrl::KinematicsSource::chain,
            PlanarCtrl::KinematicsSource::external});
  PlanarCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  PlanarCtrl::Input in = c.make_input();
  PlanarCtrl::Output out = c.make_output();
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  // Mid approach.
  for (int k = 0; k < 150; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::grasping);
  check_bad_inputs(c, s.plant, out, "approach");
  // Pressing.
  ASSERT_GT(run_grasp(c, s.plant, in, out), 0);
  check_bad_inputs(c, s.plant, out, "grasped");
  // Mid manipulation.
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 1500; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
  check_bad_inputs(c, s.plant, out, "manipulation");
  // Garbage in the contact fields of a finger that does not touch is ignored.
  PlanarCtrl a = c;
  s.plant.fill(in, true);
  in.fingers[1].contact.touching = false;
  in.fingers[1].contact.contact_point.setConstant(kNaN);
  in.fingers[1].contact.normal.setConstant(kNaN);
  in.fingers[1].contact.normal_force = kNaN;
  EXPECT_EQ(a.update(in, out), ControllerStatus::contact_lost);
  EXPECT_EQ(out.fault.field, InputField::none);
}

// ---------------------------------------------------------------------------
// External kinematics, run-time sizes, determinism

TEST(ReactiveControllerKinematics, ExternalJacobianMatchesChainMode) {
  using KS = PlanarCtrl::KinematicsSource;
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  Scene<PlanarCtrl> se = planar_scene<PlanarCtrl>(0.0, {KS::external, KS::external, KS::external});
  PlanarCtrl a, b;
  ASSERT_TRUE(a.configure(s.config).ok());
  ASSERT_TRUE(b.configure(se.config).ok());
  PlanarCtrl::Input in = a.make_input();
  PlanarCtrl::Output oa = a.make_output(), ob = b.make_output();
  ASSERT_TRUE(a.start_grasp(s.targets).ok());
  ASSERT_TRUE(b.start_grasp(s.targets).ok());
  Plant<PlanarCtrl>& p = s.plant;
  double worst = 0.0;
  int reacquiring_ticks = 0;
  auto step = [&](int k) {
    p.fill(in, manipulating(a));
    const ControllerStatus sa = a.update(in, oa), sb = b.update(in, ob);
    ASSERT_EQ(sa, sb) << "tick " << k;
    for (int i = 0; i < 3; ++i) {
      const auto j = static_cast<std::size_t>(i);
      ASSERT_EQ(oa.fingers[j].state, ob.fingers[j].state);
      worst = std::max(
          worst,
          (oa.fingers[j].joint_velocities - ob.fingers[j].joint_velocities).cwiseAbs().maxCoeff());
      reacquiring_ticks += oa.fingers[j].state == FingerState::reacquiring ? 1 : 0;
    }
    p.advance(oa, manipulating(a));
  };
  int k = 0;
  for (; k < 4000 && a.phase() != PlanarCtrl::Phase::grasped; ++k) step(k);
  ASSERT_EQ(b.phase(), PlanarCtrl::Phase::grasped);
  const auto task = planar_task(p.box.pose);
  ASSERT_TRUE(a.start_manipulation(task).ok());
  ASSERT_TRUE(b.start_manipulation(task).ok());
  for (int m = 0; m < 1500; ++m) step(k++);
  p.box.pose.position.x() += 0.004;  // contact loss: the reacquiring path too
  for (int m = 0; m < 1000; ++m) step(k++);
  EXPECT_GT(reacquiring_ticks, 0);
  EXPECT_EQ(worst, 0.0);
  record("max_joint_velocity_difference", worst);
}

template <typename Ctrl>
std::vector<typename Ctrl::Output> full_run(Ctrl& c, Scene<Ctrl> s, bool configure) {
  std::vector<typename Ctrl::Output> log;
  if (configure) {
    EXPECT_TRUE(c.configure(s.config).ok());
  }
  typename Ctrl::Input in = c.make_input();
  typename Ctrl::Output out = c.make_output();
  EXPECT_TRUE(c.start_grasp(s.targets).ok());
  for (int k = 0; k < 4000 && c.phase() != Ctrl::Phase::grasped; ++k) {
    tick(c, s.plant, in, out);
    log.push_back(out);
  }
  EXPECT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 1200; ++k) {
    tick(c, s.plant, in, out);
    log.push_back(out);
  }
  s.plant.box.pose.position.x() += 0.004;
  for (int k = 0; k < 500; ++k) {
    tick(c, s.plant, in, out);
    log.push_back(out);
  }
  return log;
}

template <typename OutA, typename OutB>
void expect_same_joint_velocities(const std::vector<OutA>& a, const std::vector<OutB>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t k = 0; k < a.size(); ++k)
    for (std::size_t i = 0; i < 3; ++i)
      ASSERT_TRUE(a[k].fingers[i].joint_velocities == b[k].fingers[i].joint_velocities)
          << "tick " << k;
}

TEST(ReactiveControllerDeterminism, SameInputsSameOutputsAndAfterReset) {
  const Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl a, b;
  const auto la = full_run(a, s, true);
  const auto lb = full_run(b, s, true);
  ASSERT_EQ(la.size(), lb.size());
  ASSERT_GT(la.size(), 2000u);
  for (std::size_t k = 0; k < la.size(); ++k) {
    std::string why;
    ASSERT_TRUE(same_output(la[k], lb[k], why)) << "tick " << k << ": " << why;
  }
  // reset(): back to idle with every integrator, filter and clock cleared.
  a.reset();
  EXPECT_EQ(a.phase(), PlanarCtrl::Phase::idle);
  const auto lc = full_run(a, s, false);
  ASSERT_EQ(la.size(), lc.size());
  for (std::size_t k = 0; k < la.size(); ++k) {
    std::string why;
    ASSERT_TRUE(same_output(la[k], lc[k], why)) << "tick " << k << ": " << why;
  }
}

TEST(ReactiveControllerDeterminism, RunTimeFingerCountMatchesFixed) {
  PlanarCtrl a;
  PlanarDynCtrl d;
  const auto la = full_run(a, planar_scene<PlanarCtrl>(), true);
  const auto ld = full_run(d, planar_scene<PlanarDynCtrl>(), true);
  EXPECT_EQ(d.finger_count(), 3);
  expect_same_joint_velocities(la, ld);
}

// ---------------------------------------------------------------------------
// Mixed-DOF spatial hand

TEST(ReactiveControllerMixedDof, ThumbWithFiveJointsAndFourJointFingers) {
  Scene<MixedCtrl> s = mixed_scene();
  MixedCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  MixedCtrl::Input in = c.make_input();
  MixedCtrl::Output out = c.make_output();
  ASSERT_EQ(in.fingers[0].joint_positions.size(), 5);
  ASSERT_EQ(in.fingers[1].joint_positions.size(), 4);
  ASSERT_EQ(in.fingers[2].jacobian.cols(), 4);
  ASSERT_EQ(out.fingers[0].joint_velocities.size(), 5);
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  const int grasp_ticks = run_grasp(c, s.plant, in, out);
  ASSERT_GT(grasp_ticks, 0);
  s.plant.sense();
  const Eigen::VectorXd f_grasp = grasp_forces(s);  // the thumb 2 N against two of 1 N
  for (int i = 0; i < 3; ++i)
    EXPECT_NEAR(s.plant.sensed[static_cast<std::size_t>(i)].force, f_grasp(i),
                s.config.grasp.force_tolerance * f_grasp(i));

  using Seg = inhand::TrajectorySegment<double, 3>;
  inhand::ObjectTrajectory<double, 3> task;
  task.reset(s.plant.box.pose);
  task.append(Seg::hold_for(0.2));
  task.append(Seg::move(V3::UnitX(), 0.005, 1.0));
  task.append(Seg::rotate(V3::UnitX(), -0.1, 1.0));
  task.append(Seg::rotate(V3::UnitZ(), 0.05, 0.8));
  task.append(Seg::hold_for(0.4));
  ASSERT_TRUE(c.start_manipulation(task).ok());
  const int n_ticks = static_cast<int>(std::lround(task.duration() / s.plant.dt));
  double worst_eq2 = 0.0, worst_ik = 0.0, worst_force = 0.0;
  for (int k = 0; k < n_ticks; ++k) {
    s.plant.fill(in, true);
    ASSERT_EQ(c.update(in, out), ControllerStatus::ok) << "tick " << k;
    for (int i = 0; i < 3; ++i) {
      const auto j = static_cast<std::size_t>(i);
      const auto& fo = out.fingers[j];
      const auto& fin = in.fingers[j];
      ASSERT_EQ(fo.joint_velocities.size(), i == 0 ? 5 : 4);
      worst_eq2 =
          std::max(worst_eq2,
                   (fo.desired_contact_velocity -
                    eq2<3>(out.commanded_twist, fin.contact.contact_point, in.object_pose.position))
                       .norm());
      if (fo.ik.status == inhand::IkStatus::ok) {
        const Eigen::MatrixXd J =
            fd_point_jacobian(s.plant.chains[j], s.plant.q[j], fin.contact.contact_point);
        worst_ik = std::max(worst_ik, (J * fo.joint_velocities - fo.servo.total).norm() /
                                          (1e-9 + fo.servo.total.norm()));
      }
      if (out.manipulation_time > 0.2)
        worst_force =
            std::max(worst_force, std::abs(fin.contact.normal_force - fo.desired_normal_force));
    }
    s.plant.advance(out, true);
  }
  EXPECT_LT(worst_eq2, 1e-15);
  EXPECT_LT(worst_ik, 1e-6);
  EXPECT_LT(worst_force, 0.5);
  const double rho = s.config.force_planner.regularisation;
  EXPECT_NEAR(out.fingers[0].desired_normal_force, (2.0 + rho) / (1.0 + rho), 1e-6);
  const auto end = task.evaluate(task.duration());
  EXPECT_LT((s.plant.box.pose.position - end.pose.position).norm(), 1e-5);
  EXPECT_LT(
      inhand::so3_log<double>(M3(s.plant.box.pose.rotation * end.pose.rotation.transpose())).norm(),
      1e-4);
  const V3 rpy = inhand::euler_from_rotation<double>(s.plant.box.pose.rotation);
  EXPECT_NEAR(rpy(0), -0.1, 1e-3);
  record("grasp_time_s", grasp_ticks * s.plant.dt);
  record("max_force_error_N", worst_force);
}

// ---------------------------------------------------------------------------
// Hardening: malformed Inputs and Outputs, overflow, implausible geometry

/// Every floating-point member of an Output is finite.
template <typename Out>
bool all_outputs_finite(const Out& out) {
  using inhand::all_finite;
  using inhand::is_finite;
  bool ok = out.desired_object_pose.is_finite() && all_finite(out.feedforward_twist) &&
            all_finite(out.commanded_twist) && all_finite(out.pose_error) &&
            all_finite(out.force_residual) && all_finite(out.load_estimate) &&
            all_finite(out.pose_error_integral) && is_finite(out.grip) &&
            is_finite(out.manipulation_time);
  for (const auto& f : out.fingers)
    ok = ok && all_finite(f.joint_velocities) && all_finite(f.desired_contact_velocity) &&
         is_finite(f.desired_normal_force) && is_finite(f.force_target) &&
         all_finite(f.servo.total) && all_finite(f.servo.force) && all_finite(f.servo.motion) &&
         is_finite(f.stiffness_estimate) && is_finite(f.force_integral);
  return ok;
}

/// A planar hand (run-time finger count) that has grasped and is manipulating.
struct DynRun {
  Scene<PlanarDynCtrl> s = planar_scene<PlanarDynCtrl>();
  PlanarDynCtrl c;
  PlanarDynCtrl::Input in;
  PlanarDynCtrl::Output out;
};

TEST(ReactiveControllerHardening, WrongFingerCountZeroesEveryOutputSlotAndNamesTheCount) {
  DynRun r;
  configure_and_grasp(r.c, r.s, r.in, r.out);
  ASSERT_TRUE(r.c.start_manipulation(planar_task(r.s.plant.box.pose)).ok());
  for (int k = 0; k < 50; ++k) ASSERT_EQ(tick(r.c, r.s.plant, r.in, r.out), ControllerStatus::ok);
  bool moving = false;
  for (const auto& f : r.out.fingers) moving = moving || !f.joint_velocities.isZero(0.0);
  ASSERT_TRUE(moving) << "the scene must command motion before the bad tick";

  // An Input with one finger too few: the last valid command must not survive.
  PlanarDynCtrl::Input short_in = r.in;
  short_in.fingers.pop_back();
  short_in.time = r.in.time + 1e-3;
  EXPECT_EQ(r.c.update(short_in, r.out), ControllerStatus::invalid_input);
  EXPECT_EQ(r.out.fault.field, InputField::finger_count);
  EXPECT_EQ(r.out.fault.finger, -1);
  EXPECT_TRUE(zero_joint_velocities(r.c, r.out));
  EXPECT_TRUE(r.out.commanded_twist.isZero(0.0));

  // An Output with one finger too many: every slot it has is zeroed, none resized.
  for (int k = 0; k < 5; ++k) ASSERT_EQ(tick(r.c, r.s.plant, r.in, r.out), ControllerStatus::ok);
  PlanarDynCtrl::Output long_out = r.out;
  long_out.fingers.push_back(long_out.fingers[0]);
  for (auto& f : long_out.fingers) f.joint_velocities.setConstant(0.7);
  r.s.plant.fill(r.in, true);
  EXPECT_EQ(r.c.update(r.in, long_out), ControllerStatus::invalid_input);
  EXPECT_EQ(long_out.fault.field, InputField::finger_count);
  ASSERT_EQ(long_out.fingers.size(), 4u);
  for (const auto& f : long_out.fingers) {
    EXPECT_EQ(f.joint_velocities.size(), 3);
    EXPECT_TRUE(f.joint_velocities.isZero(0.0));
  }
  EXPECT_STREQ(inhand::to_string(InputField::finger_count), "finger_count");
}

TEST(ReactiveControllerHardening, WronglySizedOutputIsRejectedNotResized) {
  Scene<MixedCtrl> s = mixed_scene();
  MixedCtrl c;
  ASSERT_TRUE(c.configure(s.config).ok());
  MixedCtrl::Input in = c.make_input();
  MixedCtrl::Output out = c.make_output();
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  for (int k = 0; k < 10; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::grasping);
  // Finger 1 has 4 joints; an Output not made by make_output() gives it 2.
  MixedCtrl::Output bad = out;
  bad.fingers[1].joint_velocities.setConstant(2, 0.5);
  bad.fingers[0].joint_velocities.setConstant(0.5);
  s.plant.fill(in, false);
  EXPECT_EQ(c.update(in, bad), ControllerStatus::invalid_input);
  EXPECT_EQ(bad.fault.field, InputField::output_joint_velocities);
  EXPECT_EQ(bad.fault.finger, 1);
  EXPECT_EQ(bad.fingers[1].joint_velocities.size(), 2) << "update() must not resize";
  EXPECT_TRUE(bad.fingers[1].joint_velocities.isZero(0.0));
  EXPECT_TRUE(bad.fingers[0].joint_velocities.isZero(0.0));
  // A default-constructed Output (run-time DOF: empty vectors) is refused too.
  MixedCtrl::Output empty;
  EXPECT_EQ(c.update(in, empty), ControllerStatus::invalid_input);
  EXPECT_EQ(empty.fault.field, InputField::output_joint_velocities);
  EXPECT_EQ(empty.fault.finger, 0);
  EXPECT_EQ(empty.fingers[0].joint_velocities.size(), 0);
  // The state was frozen: the proper Output resumes.
  EXPECT_EQ(c.update(in, out), ControllerStatus::grasping);
}

TEST(ReactiveControllerHardening,
     MeasuredForceOutsideItsPlausibleRangeIsInvalidInputAndNothingOverflows) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  s.plant.object_moves = false;
  for (int k = 0; k < 2000; ++k) {
    s.plant.fill(in, true);
    in.fingers[1].contact.normal_force = 1e308;  // finite, absurd
    const ControllerStatus st = c.update(in, out);
    s.plant.advance(out, true);
    ASSERT_EQ(st, ControllerStatus::invalid_input) << "tick " << k;
    ASSERT_EQ(out.fault.field, InputField::normal_force);
    ASSERT_EQ(out.fault.finger, 1);
    ASSERT_TRUE(all_outputs_finite(out)) << "tick " << k;
  }
  // Just above the configured bound is refused, at it is accepted.
  s.plant.fill(in, true);
  in.fingers[1].contact.normal_force = std::nextafter(s.config.max_measured_force, kInf);
  EXPECT_EQ(c.update(in, out), ControllerStatus::invalid_input);
  in.fingers[1].contact.normal_force = s.config.max_measured_force;
  EXPECT_NE(c.update(in, out), ControllerStatus::invalid_input);
  // The same at the lower bound: a reading below zero down to min_measured_force is a
  // sensor's offset, taken as measured; below it, a fault.
  ASSERT_LT(s.config.min_measured_force, 0.0);
  s.plant.advance(out, true);
  for (const double f : {-1e-3, 0.5 * s.config.min_measured_force, s.config.min_measured_force}) {
    s.plant.fill(in, true);
    in.fingers[1].contact.normal_force = f;
    EXPECT_NE(c.update(in, out), ControllerStatus::invalid_input)
        << f << " " << inhand::to_string(out.fault.field);
    s.plant.advance(out, true);
  }
  s.plant.fill(in, true);
  in.fingers[1].contact.normal_force = std::nextafter(s.config.min_measured_force, -kInf);
  EXPECT_EQ(c.update(in, out), ControllerStatus::invalid_input);
  EXPECT_EQ(out.fault.field, InputField::normal_force);
  EXPECT_EQ(out.fault.finger, 1);
}

TEST(ReactiveControllerHardening, NonFiniteIntermediateGivesNumericalFaultZeroOutputAndOldState) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 300; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
  // A measured object 1e308 m away is finite, so it passes the input checks, but the
  // pose error times the gain overflows and the twist bound turns inf into NaN.
  PlanarCtrl twin = c;
  PlanarCtrl::Output twin_out = twin.make_output();
  s.plant.fill(in, true);
  PlanarCtrl::Input far = in;
  far.object_pose.position = V2(-1e308, 0.0);
  EXPECT_EQ(c.update(far, out), ControllerStatus::numerical_fault);
  ASSERT_NE(out.numerical_fault, nullptr);
  EXPECT_STREQ(out.numerical_fault, "pose_feedback");
  EXPECT_TRUE(zero_joint_velocities(c, out));
  EXPECT_TRUE(all_outputs_finite(out));
  EXPECT_STREQ(inhand::to_string(ControllerStatus::numerical_fault), "numerical_fault");
  // The state is that of before the tick: the same next tick gives the same output as
  // a controller that never saw it.
  const ControllerStatus a = c.update(in, out);
  const ControllerStatus b = twin.update(in, twin_out);
  EXPECT_EQ(a, b);
  std::string why;
  EXPECT_TRUE(same_output(out, twin_out, why)) << why;
  EXPECT_EQ(out.numerical_fault, nullptr);
}

/// Every value non_finite_stage() covers, with the stage it must name: a NaN or an
/// infinity in any one of them, the rest of a real tick's output left as it was, is found
/// (the one-pass check of the common case misses none) and named after its stage.
TEST(ReactiveControllerHardening, NonFiniteStageNamesEveryPoisonedOutputValue) {
  using Types = PlanarCtrl::Types;
  using Output = PlanarCtrl::Output;
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  Output clean;
  configure_and_grasp(c, s, in, clean);
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 50; ++k) ASSERT_EQ(tick(c, s.plant, in, clean), ControllerStatus::ok);
  ASSERT_EQ(inhand::non_finite_stage<Types>(clean), nullptr);
  // (stage, every value of one member): the member reached through a pointer into a copy.
  using Values = std::function<std::vector<double*>(Output&)>;
  auto all = [](auto& m) {
    std::vector<double*> v;
    for (Eigen::Index k = 0; k < m.size(); ++k) v.push_back(m.data() + k);
    return v;
  };
  std::vector<std::pair<std::string, Values>> members = {
      {"trajectory", [&](Output& o) { return all(o.desired_object_pose.position); }},
      {"trajectory", [&](Output& o) { return all(o.desired_object_pose.rotation); }},
      {"trajectory", [&](Output& o) { return all(o.feedforward_twist); }},
      {"trajectory", [](Output& o) { return std::vector<double*>{&o.manipulation_time}; }},
      {"pose_feedback", [&](Output& o) { return all(o.pose_error); }},
      {"pose_feedback", [&](Output& o) { return all(o.commanded_twist); }},
      {"pose_feedback", [&](Output& o) { return all(o.pose_error_integral); }},
      {"force_layer", [&](Output& o) { return all(o.force_residual); }},
      {"force_layer", [&](Output& o) { return all(o.load_estimate); }},
      {"force_layer", [](Output& o) { return std::vector<double*>{&o.grip}; }},
  };
  for (std::size_t i = 0; i < clean.fingers.size(); ++i) {
    members.push_back({"force_layer", [i](Output& o) {
                         auto& f = o.fingers[i];
                         return std::vector<double*>{&f.desired_normal_force, &f.force_target,
                                                     &f.stiffness_estimate, &f.force_integral};
                       }});
    members.push_back({"servo", [&, i](Output& o) {
                         auto& f = o.fingers[i];
                         std::vector<double*> v = all(f.desired_contact_velocity);
                         for (auto* m : {&f.servo.motion, &f.servo.force, &f.servo.total})
                           for (double* p : all(*m)) v.push_back(p);
                         return v;
                       }});
    members.push_back({"ik", [&, i](Output& o) {
                         auto& f = o.fingers[i];
                         std::vector<double*> v = all(f.joint_velocities);
                         for (double* p : {&f.ik.min_singular_value, &f.ik.damping,
                                           &f.ik.limit_scale, &f.ik.task_error})
                           v.push_back(p);
                         return v;
                       }});
  }
  int checked = 0;
  for (const auto& [stage, values] : members) {
    Output probe = clean;
    const std::size_t count = values(probe).size();
    ASSERT_GT(count, 0u) << stage;
    for (std::size_t k = 0; k < count; ++k) {
      for (double poison : {std::numeric_limits<double>::quiet_NaN(), kInf, -kInf}) {
        Output o = clean;
        *values(o)[k] = poison;
        const char* named = inhand::non_finite_stage<Types>(o);
        ASSERT_NE(named, nullptr) << stage << " value " << k << " = " << poison;
        EXPECT_EQ(std::string(named), stage) << "value " << k << " = " << poison;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, 100);
}

TEST(ReactiveControllerHardening, ReflectedObjectPoseAndUnnormalisedNormalsAreInvalid) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  configure_and_grasp(c, s, in, out);
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 20; ++k) ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
  s.plant.fill(in, true);
  PlanarCtrl::Input bad = in;
  bad.object_pose.rotation(1, 1) = -1.0;  // orthonormal, det -1: a reflection
  bad.object_pose.rotation(1, 0) = 0.0;
  bad.object_pose.rotation(0, 1) = 0.0;
  bad.object_pose.rotation(0, 0) = 1.0;
  EXPECT_EQ(c.update(bad, out), ControllerStatus::invalid_input);
  EXPECT_EQ(out.fault.field, InputField::object_pose);
  for (const double scale : {0.5, 0.9, 0.998, 1.002, 1.3, 1.5}) {
    bad = in;
    bad.fingers[2].contact.normal *= scale;
    EXPECT_EQ(c.update(bad, out), ControllerStatus::invalid_input) << "length " << scale;
    EXPECT_EQ(out.fault.field, InputField::contact_normal);
    EXPECT_EQ(out.fault.finger, 2);
  }
  bad = in;
  bad.fingers[2].contact.normal *= 1.0005;  // within 1e-3 of unit length
  EXPECT_EQ(c.update(bad, out), ControllerStatus::ok);
}

TEST(ReactiveControllerHardening, ImplausibleContactsAreFlaggedPerFinger) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  ASSERT_TRUE(c.configure(s.config).ok());
  in = c.make_input();
  out = c.make_output();
  ASSERT_TRUE(c.start_grasp(s.targets).ok());
  // The scene's contacts lie on the fingertip spheres: never flagged.
  int grasp_ticks = -1;
  for (int k = 0; k < 4000 && grasp_ticks < 0; ++k) {
    if (tick(c, s.plant, in, out) == ControllerStatus::grasped) grasp_ticks = k;
    ASSERT_FALSE(has(out.warnings, ControllerWarning::implausible_contact)) << "tick " << k;
  }
  ASSERT_GT(grasp_ticks, 0);
  ASSERT_TRUE(c.start_manipulation(planar_task(s.plant.box.pose)).ok());
  for (int k = 0; k < 500; ++k) {
    ASSERT_EQ(tick(c, s.plant, in, out), ControllerStatus::ok);
    ASSERT_FALSE(has(out.warnings, ControllerWarning::implausible_contact)) << "tick " << k;
    for (const auto& f : out.fingers) ASSERT_FALSE(f.implausible_contact);
  }
  // A contact point 1 m from finger 1's fingertip.
  s.plant.fill(in, true);
  PlanarCtrl::Input bad = in;
  bad.fingers[1].contact.contact_point += V2(0.0, 1.0);
  ASSERT_EQ(c.update(bad, out), ControllerStatus::ok);
  EXPECT_TRUE(has(out.warnings, ControllerWarning::implausible_contact));
  EXPECT_FALSE(out.fingers[0].implausible_contact);
  EXPECT_TRUE(out.fingers[1].implausible_contact);
  EXPECT_FALSE(out.fingers[2].implausible_contact);
  // A normal pointing into finger 2's fingertip (unit length, point on the sphere).
  s.plant.time += s.plant.dt;
  s.plant.fill(in, true);
  bad = in;
  bad.fingers[2].contact.normal = -bad.fingers[2].contact.normal;
  ASSERT_EQ(c.update(bad, out), ControllerStatus::ok);
  EXPECT_TRUE(has(out.warnings, ControllerWarning::implausible_contact));
  EXPECT_FALSE(out.fingers[1].implausible_contact);
  EXPECT_TRUE(out.fingers[2].implausible_contact);
  // Back to plausible data: the flags clear.
  s.plant.time += s.plant.dt;
  s.plant.fill(in, true);
  ASSERT_EQ(c.update(in, out), ControllerStatus::ok);
  EXPECT_FALSE(has(out.warnings, ControllerWarning::implausible_contact));
}

TEST(ReactiveControllerHardening, TrajectoryMustStartAtTheMeasuredPose) {
  Scene<PlanarCtrl> s = planar_scene<PlanarCtrl>();
  PlanarCtrl c;
  PlanarCtrl::Input in;
  PlanarCtrl::Output out;
  // The object sits 3 cm from the world origin, where a default trajectory starts.
  s.plant.box.pose.position = V2(0.0, 0.03);
  for (auto& f : s.config.fingers) f.chain.base.position += V2(0.0, 0.03);
  for (auto& ch : s.plant.chains) ch.base.position += V2(0.0, 0.03);
  for (auto& t : s.targets) t.contact_point += V2(0.0, 0.03);
  configure_and_grasp(c, s, in, out);
  inhand::Validation v = c.start_manipulation(inhand::ObjectTrajectory<double, 2>{});
  ASSERT_FALSE(v.ok());
  EXPECT_STREQ(v.field, "trajectory.start_pose.position");
  Pose<double, 2> turned = s.plant.box.pose;
  turned.rotation = inhand::so2_exp(0.3) * turned.rotation;
  v = c.start_manipulation(planar_task(turned));
  ASSERT_FALSE(v.ok());
  EXPECT_STREQ(v.field, "trajectory.start_pose.rotation");
  Pose<double, 2> reflected = s.plant.box.pose;
  reflected.rotation(1, 1) = -1.0;
  inhand::ObjectTrajectory<double, 2> tr;
  tr.reset(reflected);
  v = c.start_manipulation(tr);
  ASSERT_FALSE(v.ok());
  EXPECT_STREQ(v.field, "trajectory.start_pose.rotation");
  // Within the tolerance (5 mm < 1 cm) it starts.
  Pose<double, 2> near = s.plant.box.pose;
  near.position += V2(0.005, 0.0);
  ASSERT_TRUE(c.start_manipulation(planar_task(near)).ok());
  // Held off by 5 mm (the object does not move), the pose integral reaches its bound
  // and says so (growing at the integral band's 2 mm/s: 1 s).
  s.plant.object_moves = false;
  bool limited = false;
  for (int k = 0; k < 2000; ++k) {
    tick(c, s.plant, in, out);
    limited = limited || has(out.warnings, ControllerWarning::pose_integral_limited);
    ASSERT_LE(out.pose_error_integral.head<2>().norm(),
              s.config.pose_feedback.position_integral_limit * (1 + 1e-12));
  }
  EXPECT_TRUE(limited);
}

TEST(ReactiveControllerHardening, FloatControllerKeepsTimeAfterAWeek) {
  using FloatCtrl = inhand::ReactiveController<float, 2, inhand::Dynamic, 3>;
  FloatCtrl::Config cfg;
  cfg.fingers.resize(1);
  const auto chain = planar_chain<PlanarCtrl::Chain>(V2(0, 0), 0.0);
  auto& fc = cfg.fingers[0].chain;
  fc.base.position = chain.base.position.cast<float>();
  for (int j = 0; j < 3; ++j) {
    fc.joints[j].parent_to_joint.position = chain.joints[j].parent_to_joint.position.cast<float>();
    fc.joints[j].max_velocity = 3.0f;
  }
  fc.joint_to_tip.position = chain.joint_to_tip.position.cast<float>();
  FloatCtrl c;
  ASSERT_TRUE(c.configure(cfg).ok());
  FloatCtrl::Input in = c.make_input();
  FloatCtrl::Output out = c.make_output();
  in.fingers[0].joint_positions << 0.3f, 0.2f, 0.1f;
  const double t0 = 604800.0;  // one week of uptime, in seconds
  for (int k = 0; k < 2000; ++k) {
    in.time = t0 + 1e-3 * k;
    ASSERT_EQ(c.update(in, out), ControllerStatus::idle) << "tick " << k;
    if (k > 0) {
      ASSERT_NEAR(static_cast<double>(out.dt), 1e-3, 1e-9) << "tick " << k;
    }
  }
  // A step that vanishes in float is refused as a time fault, not integrated as 0.
  in.time = in.time + 1e-300;
  EXPECT_EQ(c.update(in, out), ControllerStatus::invalid_input);
  EXPECT_EQ(out.fault.field, InputField::time);
}

// Valid template arguments compile (the impossible ones are refused by static_asserts,
// checked by the compile-failure tests of tests/compile_fail).
TEST(ReactiveControllerHardening, ValidTemplateArgumentsInstantiate) {
  inhand::ReactiveController<float, 3, 1, 2> a;
  inhand::ReactiveController<double, 2, inhand::Dynamic, inhand::Dynamic, 4> b;
  inhand::ReactiveController<long double, 3, 5, 4> d;
  EXPECT_FALSE(a.configured());
  EXPECT_FALSE(b.configured());
  EXPECT_FALSE(d.configured());
}

}  // namespace
