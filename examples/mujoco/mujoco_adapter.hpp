// A MuJoCo world (a hand and a free object, compiled from MJCF: models/) behind the
// generic scenario runner's plant interface (inhand/sim/plant_interface.hpp). The
// controller reads only what a real hand has:
//   joint angles  : the hinges' qpos (exact);
//   object pose   : the object's free joint qpos (position, quaternion w x y z; exact);
//   tactile       : per fingertip geom, its contacts with the object's geoms in
//                   mjData::contact: the point (contact.pos, midway between the two
//                   surfaces), the normal and the normal force (mj_contactForce, first
//                   component, >= 0). MuJoCo's contact frame normal points from geom1 to
//                   geom2; inhand wants the object's OUTWARD normal, towards the fingertip,
//                   so it is negated when the fingertip is geom1. With several contacts on
//                   one fingertip the forces add and the strongest gives point and normal.
//                   Touching: normal force above `touch_threshold` (N).
// Commands: the hand's servo, as real hands realise a joint-velocity command: the command
// qd [rad/s] is integrated into a position set-point q_ref at every engine step, and
// each joint's MuJoCo velocity actuator (torque kv (ctrl - qdot)) receives
//   ctrl = qd + position_gain (q_ref - q),
// i.e. torque = kv (qd - qdot) + kv position_gain (q_ref - q): a PD servo of stiffness
// kv position_gain (1.5 N m/rad with the model's kv 0.05 and the default 30 /s) and
// damping kv, tracking the integrated command; qd is first limited to the actuator's
// control range (the joint's velocity limit, applied by the firmware), and the torque by
// the actuator's force range. The models do not let MuJoCo clip ctrl to the control range
// (ctrllimited false): ctrl carries the position term too, and clipped at 3 rad/s it capped
// the servo's torque at kv x 3 = 0.15 N m instead of the force range's 1 N m, which held
// the thumb below the grasp's 4 N at release_grip 2. A pure velocity servo (position_gain 0)
// holds no position: in contact its joint yields to the contact force at f / kv, the
// force loop sees a damper rather than a spring, and the grasp chatters (measured in
// tests/mujoco/mujoco_cylinder.cpp). The controller is told this servo
// (controller_config(): ForceLayerParams::servo_stiffness kv position_gain, servo_damping
// kv), so that its force loop is scheduled on the servo in series with the contact and
// kept clear of the servo's feedthrough (include/inhand/controller/joint_servo.hpp).
// Frozen object (the grasp stage, as in the paper): a weld equality of the model between
// the object and the world (MujocoSetup::object_hold), switched on and off through
// mjModel::eq_active. It holds the object at its compile-time pose (qpos0: the only
// pose the runner freezes it at, before the grasp) as a stiff soft constraint (solref
// 2 ms against the contacts' 20 ms), solved with the contacts, so that every force stays
// MuJoCo's (measured: the object moves 13 um while the hand closes on it).
// Putting the free joint back after each step was tried first; it made no difference to
// the contact chatter reported in tests/mujoco/mujoco_cylinder.cpp, and it teleports the
// object under the contact solver, so the weld is kept.
// Each control tick runs period / timestep engine steps (mj_step), then mj_forward so that
// contacts and forces read by the next sense() belong to the state after the tick.
// Truth: touching and normal force as sensed (MuJoCo is exact); slip is not measured
// (slip_distance 0); link_contacts counts ticks on which a non-fingertip hand geom
// touched the object. Units SI (m, rad, N, s), MuJoCo's world frame.
#pragma once

#include <mujoco/mujoco.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "inhand/sim/hand_plant_scenario.hpp"
#include "inhand/sim/plant_interface.hpp"
#include "inhand/sim/presets.hpp"
#include "mujoco_chains.hpp"
#include "mujoco_model.hpp"

namespace inhand::mujoco_demo {

/// The MuJoCo world's part of a scenario.
struct MujocoSetup {
  std::string model_file = model_path("three_finger_cylinder.xml");
  /// Per finger, the palm body and the fingertip geom, in the preset's finger order.
  std::vector<FingerNames> fingers = {
      {"palm", "left_tip"}, {"palm", "right_tip"}, {"palm", "thumb_tip"}};
  std::string object_body = "object";
  /// The weld equality (to the world) that freezes the object: see the file comment.
  std::string object_hold = "object_hold";
  /// Approach geometry, open configuration and thumb of the hand (not its kinematics,
  /// which are read from the model).
  plant::HandPreset hand = plant::three_finger_hand();
  double touch_threshold = 0.02;  ///< N
  /// The hand's servo (see the file comment): joint-velocity command qd realised as
  /// ctrl = qd + position_gain (q_ref - q), q_ref the integral of qd; 0 leaves a pure
  /// velocity servo (no position hold). [1/s]
  double position_gain = 30.0;
  /// Sliding friction coefficient of the object's and the fingertips' geoms (MuJoCo takes
  /// a contact pair's largest); 0 keeps the model's. [-]
  double friction = 0.0;
  /// Torsional friction coefficient of the object's geoms, switched on with it (condim 4;
  /// the model's condim 3 has none); 0 leaves it off. [m]
  double torsional_friction = 0.0;
  /// Object mass, its inertia scaled with it (the same shape); 0 keeps the model's. [kg]
  double object_mass = 0.0;
  /// Tell the controller which way the model's gravity pulls (opt.gravity, world frame) as
  /// ForceLayerParams::gravity_direction, replacing the caller's; false leaves the caller's.
  bool gravity_from_model = false;
};

class MujocoAdapter : public sim::PlantTypes<3, plant::HandController, MujocoSetup, mjModel> {
 public:
  static constexpr sim::FaultConventions fault_conventions{0.0, false, 0.0};
  using JointVector = MujocoChain::JointVector;

  explicit MujocoAdapter(const Setup& s)
      : setup_(s), model_(load_model(s.model_file)), data_(make_data(model_.get())) {
    const mjModel* m = model_.get();
    if (s.fingers.size() != s.hand.fingers.size())
      throw std::invalid_argument("mujoco: finger names and hand preset differ in count");
    object_ = mj_name2id(m, mjOBJ_BODY, s.object_body.c_str());
    if (object_ < 0 || m->body_jntnum[object_] != 1 ||
        m->jnt_type[m->body_jntadr[object_]] != mjJNT_FREE)
      throw std::invalid_argument("mujoco: " + s.object_body + " is not a body with a free joint");
    object_qpos_ = m->jnt_qposadr[m->body_jntadr[object_]];
    hold_ = mj_name2id(m, mjOBJ_EQUALITY, s.object_hold.c_str());
    if (hold_ < 0 || m->eq_type[hold_] != mjEQ_WELD)
      throw std::invalid_argument("mujoco: no weld equality " + s.object_hold);
    apply_contact_and_mass(s);  // before the fingers' angles: mj_setConst resets qpos
    chains_ = finger_chains(m, s.fingers);
    for (std::size_t i = 0; i < s.fingers.size(); ++i) {
      Finger f;
      f.tip = mj_name2id(m, mjOBJ_GEOM, s.fingers[i].tip_geom.c_str());
      f.qpos = finger_qpos_addresses(m, s.fingers[i]);
      for (int adr : f.qpos) f.actuator.push_back(actuator_of(adr));
      const JointVector& q = s.hand.open_configuration[i];
      for (int j = 0; j < q.size(); ++j) data_->qpos[f.qpos[static_cast<std::size_t>(j)]] = q(j);
      f.q_ref.assign(q.data(), q.data() + q.size());
      f.qd.assign(f.qpos.size(), 0.0);
      fingers_.push_back(f);
    }
    mj_forward(m, data_.get());
  }

  /// The controller's configuration for this hand: the chains read from the model, the
  /// model's gravity if `gravity_from_model`, and, unless the caller set them, the joint
  /// servo as the force layer should see it
  /// (ForceLayerParams::servo_stiffness, servo_damping): damping kv, stiffness
  /// kv position_gain, with kv the largest of the fingers' actuators (the stiffer side for
  /// the gain cap).
  Controller::Config controller_config(Controller::Config base) const {
    base = plant::controller_config_for(setup_.hand, base);
    if (base.force_layer.servo_stiffness == 0.0 && base.force_layer.servo_damping == 0.0) {
      double kv = 0.0;
      for (const Finger& f : fingers_)
        for (int a : f.actuator) kv = std::max(kv, model_->actuator_gainprm[a * mjNGAIN]);
      base.force_layer.servo_damping = kv;
      base.force_layer.servo_stiffness = kv * setup_.position_gain;
    }
    if (setup_.gravity_from_model)
      base.force_layer.gravity_direction =
          Eigen::Vector3d(model_->opt.gravity[0], model_->opt.gravity[1], model_->opt.gravity[2]);
    for (std::size_t i = 0; i < chains_.size(); ++i) base.fingers[i].chain = chains_[i];
    return base;
  }
  std::vector<GraspTarget<double, 3>> grasp_targets() const {
    return plant::model_free_grasp_targets(setup_.hand, object_pose());
  }
  int finger_count() const noexcept { return static_cast<int>(fingers_.size()); }

  void sense() noexcept {}  // exact sensing: nothing to draw
  Pose<double, 3> measured_object_pose() const noexcept { return object_pose(); }
  JointVector joint_positions(int i) const {
    const Finger& f = fingers_[static_cast<std::size_t>(i)];
    JointVector q(static_cast<Eigen::Index>(f.qpos.size()));
    for (std::size_t j = 0; j < f.qpos.size(); ++j)
      q(static_cast<Eigen::Index>(j)) = data_->qpos[f.qpos[j]];
    return q;
  }
  plant::TactileReading tactile(int i) const noexcept {
    const Finger& f = fingers_[static_cast<std::size_t>(i)];
    plant::TactileReading r;
    double strongest = 0.0, total = 0.0;
    for (int c = 0; c < data_->ncon; ++c) {
      const mjContact& con = data_->contact[c];
      const bool tip1 = con.geom1 == f.tip, tip2 = con.geom2 == f.tip;
      if (!(tip1 && on_object(con.geom2)) && !(tip2 && on_object(con.geom1))) continue;
      mjtNum force[6];
      mj_contactForce(model_.get(), data_.get(), c, force);
      total += force[0];
      if (force[0] <= strongest) continue;
      strongest = force[0];
      const double sign = tip1 ? -1.0 : 1.0;  // towards the fingertip
      r.contact_point = Eigen::Vector3d(con.pos[0], con.pos[1], con.pos[2]);
      r.normal = sign * Eigen::Vector3d(con.frame[0], con.frame[1], con.frame[2]);
    }
    if (!(total > setup_.touch_threshold)) return plant::TactileReading{};
    r.touching = true;
    r.normal_force = total;
    return r;
  }

  void set_object_force(const Eigen::Vector3d& f) noexcept {
    for (int k = 0; k < 3; ++k) data_->xfrc_applied[6 * object_ + k] = f(k);
  }
  template <class V>
  void command(int i, const V& qd, const sim::TickClock& /*clock*/) noexcept {
    Finger& f = fingers_[static_cast<std::size_t>(i)];
    const mjtNum* range = model_->actuator_ctrlrange;
    for (std::size_t j = 0; j < f.actuator.size(); ++j) {
      // The firmware's velocity limit: the actuator's control range, where it has one.
      const int a = f.actuator[j];
      const double v = qd(static_cast<Eigen::Index>(j)), lo = range[2 * a], hi = range[2 * a + 1];
      f.qd[j] = lo < hi ? std::clamp(v, lo, hi) : v;
    }
  }
  void command_towards_open(int i, double gain) {
    // finger_away: the servo's set-point follows the finger (no pull back to q_ref).
    Finger& f = fingers_[static_cast<std::size_t>(i)];
    for (std::size_t j = 0; j < f.qpos.size(); ++j) f.q_ref[j] = data_->qpos[f.qpos[j]];
    const JointVector qd =
        gain * (setup_.hand.open_configuration[static_cast<std::size_t>(i)] - joint_positions(i));
    command(i, qd, sim::TickClock{});
  }
  void step(double dt) {
    const mjModel* m = model_.get();
    const long steps = std::max(1L, std::lround(dt / m->opt.timestep));
    const double h = m->opt.timestep;
    for (long k = 0; k < steps; ++k) {
      for (Finger& f : fingers_)
        for (std::size_t j = 0; j < f.actuator.size(); ++j) {
          f.q_ref[j] += h * f.qd[j];
          data_->ctrl[f.actuator[j]] =
              f.qd[j] + setup_.position_gain * (f.q_ref[j] - data_->qpos[f.qpos[j]]);
        }
      mj_step(m, data_.get());
    }
    mj_forward(m, data_.get());
    if (link_touching()) ++link_contact_ticks_;
  }
  void set_frozen(bool frozen) noexcept { model_->eq_active[hold_] = frozen ? 1 : 0; }

  Pose<double, 3> object_pose() const noexcept {
    const mjtNum* q = data_->qpos + object_qpos_;
    Pose<double, 3> p;
    p.position = Eigen::Vector3d(q[0], q[1], q[2]);
    p.rotation = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized().toRotationMatrix();
    return p;
  }
  plant::FingerTruth truth(int i) const noexcept {
    const plant::TactileReading r = tactile(i);
    plant::FingerTruth t;
    t.touching = r.touching;
    t.normal_force = r.normal_force;
    return t;
  }
  int link_contacts() const noexcept { return link_contact_ticks_; }
  const mjModel& model() const noexcept { return *model_; }
  const mjData& data() const noexcept { return *data_; }

 private:
  /// MujocoSetup::friction, torsional_friction and object_mass into the model, then its
  /// derived constants recomputed (mj_setConst, which also puts qpos back to qpos0).
  void apply_contact_and_mass(const Setup& s) {
    const std::pair<const char*, double> fields[] = {{"friction", s.friction},
                                                     {"torsional_friction", s.torsional_friction},
                                                     {"object_mass", s.object_mass}};
    for (const auto& [name, value] : fields)
      if (!(std::isfinite(value) && value >= 0.0))
        throw std::invalid_argument(std::string("mujoco: setup.") + name +
                                    ": must be finite and >= 0");
    mjModel* m = model_.get();
    for (int g = 0; g < m->ngeom; ++g) {
      bool tip = false;
      for (const FingerNames& f : s.fingers)
        tip = tip || mj_name2id(m, mjOBJ_GEOM, f.tip_geom.c_str()) == g;
      if (!on_object(g) && !tip) continue;
      if (s.friction > 0.0) m->geom_friction[3 * g] = s.friction;
      if (s.torsional_friction > 0.0 && on_object(g)) {
        m->geom_condim[g] = 4;
        m->geom_friction[3 * g + 1] = s.torsional_friction;
      }
    }
    if (s.object_mass > 0.0) {
      const double scale = s.object_mass / m->body_mass[object_];
      m->body_mass[object_] = s.object_mass;
      for (int k = 0; k < 3; ++k) m->body_inertia[3 * object_ + k] *= scale;
    }
    mj_setConst(m, data_.get());
  }
  struct Finger {
    int tip = -1;
    std::vector<int> qpos, actuator;
    std::vector<double> q_ref, qd;  ///< rad, rad/s: the servo's set-point and command
  };
  int actuator_of(int qpos_adr) const {
    const mjModel* m = model_.get();
    for (int a = 0; a < m->nu; ++a)
      if (m->actuator_trntype[a] == mjTRN_JOINT &&
          m->jnt_qposadr[m->actuator_trnid[2 * a]] == qpos_adr)
        return a;
    throw std::invalid_argument("mujoco: a finger joint has no actuator");
  }
  bool on_object(int geom) const noexcept { return model_->geom_bodyid[geom] == object_; }
  bool link_touching() const noexcept {
    for (int c = 0; c < data_->ncon; ++c) {
      const mjContact& con = data_->contact[c];
      const int other = on_object(con.geom1) ? con.geom2 : on_object(con.geom2) ? con.geom1 : -1;
      if (other < 0 || model_->geom_bodyid[other] == 0) continue;
      bool tip = false;
      for (const Finger& f : fingers_) tip = tip || f.tip == other;
      if (!tip) return true;
    }
    return false;
  }

  const Setup& setup_;
  ModelPtr model_;
  DataPtr data_;
  std::vector<MujocoChain> chains_;
  std::vector<Finger> fingers_;
  int object_ = -1, object_qpos_ = 0;
  int hold_ = -1;
  int link_contact_ticks_ = 0;
};

}  // namespace inhand::mujoco_demo
