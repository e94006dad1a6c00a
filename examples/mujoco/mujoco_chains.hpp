// The controller's finger chains read from a compiled MuJoCo model, so that a hand is
// described once, in its MJCF file (models/), and never typed a second time.
//
// Units: metres, radians, rad/s, as in MuJoCo and inhand. Frames: the chain's base is the
// world pose of the palm body (a body with no joint between it and the world); every
// joint frame is the frame of the MuJoCo body the joint belongs to, moved to the joint's
// anchor (jnt_pos); the fingertip frame is the frame of the fingertip geom (a sphere, its
// centre the fingertip centre, its radius size[0]). Signs: an inhand joint angle is the
// MuJoCo qpos of that hinge, turning about jnt_axis by the right-hand rule; MuJoCo turns
// by qpos - qpos0, so a hinge with a nonzero reference (ref) is refused.
//
// What is read: body_pos / body_quat (MuJoCo quaternions are w, x, y, z) along the tree
// from the palm body down to the fingertip geom's body, jnt_pos / jnt_axis / jnt_range of
// each hinge on the way (several hinges in one body are taken in MuJoCo's order), and
// the velocity limit from the ctrlrange of the actuator driving the joint
// (min(|lower|, |upper|)), or `default_max_velocity` where no actuator driving it has a range
// around 0. The range is read whether or not MuJoCo clips ctrl with it (ctrllimited): the
// models' servo sends its position term through ctrl as well, so the hand's firmware
// (mujoco_adapter.hpp) limits the commanded velocity and MuJoCo only the torque.
// Throws std::invalid_argument for a name the model lacks, a joint other than a hinge, a
// joint limit MuJoCo does not enforce, or more joints than the chain holds.
#pragma once

#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <vector>

#include "inhand/kinematics/chain_model.hpp"

namespace inhand::mujoco_demo {

/// The chain type of MuJoCo hands: up to 6 joints a finger (the scenario runner's).
using MujocoChain = FingerChain<double, 3, Dynamic, 6>;

/// Names of one finger in the model.
struct FingerNames {
  std::string palm_body;  ///< the body the finger's base is fixed to
  std::string tip_geom;   ///< the fingertip sphere geom
};

namespace detail {
inline int id_of(const mjModel* m, mjtObj type, const std::string& name, const char* what) {
  const int id = mj_name2id(m, type, name.c_str());
  if (id < 0) throw std::invalid_argument(std::string("mujoco model has no ") + what + " " + name);
  return id;
}
inline Pose<double, 3> pose_of(const mjtNum* pos, const mjtNum* quat) {
  Pose<double, 3> p;
  p.position = Eigen::Vector3d(pos[0], pos[1], pos[2]);
  p.rotation =
      Eigen::Quaterniond(quat[0], quat[1], quat[2], quat[3]).normalized().toRotationMatrix();
  return p;
}
inline Pose<double, 3> translation(const Eigen::Vector3d& t) {
  Pose<double, 3> p;
  p.position = t;
  return p;
}
inline Pose<double, 3> body_offset(const mjModel* m, int b) {
  return pose_of(m->body_pos + 3 * b, m->body_quat + 4 * b);
}
/// The velocity limit of joint j: its actuator's control range (clipped by MuJoCo or not),
/// or the default.
inline double velocity_limit(const mjModel* m, int j, double default_max_velocity) {
  for (int a = 0; a < m->nu; ++a) {
    if (m->actuator_trntype[a] != mjTRN_JOINT || m->actuator_trnid[2 * a] != j) continue;
    const double lo = m->actuator_ctrlrange[2 * a], hi = m->actuator_ctrlrange[2 * a + 1];
    if (lo < 0.0 && hi > 0.0) return std::min(-lo, hi);
  }
  return default_max_velocity;
}
}  // namespace detail

/// The finger from the palm body to the fingertip geom, as an inhand chain.
inline MujocoChain finger_chain(const mjModel* m, const FingerNames& names,
                                double default_max_velocity = 3.0) {
  using detail::body_offset;
  const int palm = detail::id_of(m, mjOBJ_BODY, names.palm_body, "body");
  const int tip = detail::id_of(m, mjOBJ_GEOM, names.tip_geom, "geom");
  if (m->geom_type[tip] != mjGEOM_SPHERE)
    throw std::invalid_argument("fingertip geom " + names.tip_geom + " is not a sphere");
  std::vector<int> path;  // bodies below the palm down to the tip's body, top first
  for (int b = m->geom_bodyid[tip]; b != palm; b = m->body_parentid[b]) {
    if (b == 0) throw std::invalid_argument(names.tip_geom + " is not below " + names.palm_body);
    path.insert(path.begin(), b);
  }
  MujocoChain chain;
  for (int b = palm; b != 0; b = m->body_parentid[b]) {
    if (m->body_jntnum[b] > 0) throw std::invalid_argument(names.palm_body + " is not fixed");
    chain.base = body_offset(m, b) * chain.base;
  }
  std::vector<MujocoChain::Joint> joints;
  Pose<double, 3> pending{};  // from the last joint's (turned) frame to the current body
  for (int b : path) {
    pending = pending * body_offset(m, b);
    for (int k = 0; k < m->body_jntnum[b]; ++k) {
      const int j = m->body_jntadr[b] + k;
      if (m->jnt_type[j] != mjJNT_HINGE || !m->jnt_limited[j])
        throw std::invalid_argument(names.tip_geom + ": every joint must be a limited hinge");
      if (m->qpos0[m->jnt_qposadr[j]] != 0.0)
        throw std::invalid_argument(names.tip_geom + ": hinge with a nonzero reference angle");
      const Eigen::Vector3d anchor(m->jnt_pos[3 * j], m->jnt_pos[3 * j + 1], m->jnt_pos[3 * j + 2]);
      MujocoChain::Joint joint;
      joint.parent_to_joint = pending * detail::translation(anchor);
      joint.axis =
          Eigen::Vector3d(m->jnt_axis[3 * j], m->jnt_axis[3 * j + 1], m->jnt_axis[3 * j + 2])
              .normalized();
      joint.lower = m->jnt_range[2 * j];
      joint.upper = m->jnt_range[2 * j + 1];
      joint.max_velocity = detail::velocity_limit(m, j, default_max_velocity);
      joints.push_back(joint);
      pending = detail::translation(-anchor);  // MuJoCo turns the body about the anchor
    }
  }
  if (joints.empty() || !chain.joints.resize(static_cast<int>(joints.size())))
    throw std::invalid_argument(names.tip_geom + ": between 1 and 6 joints expected");
  for (int i = 0; i < chain.dof(); ++i) chain.joints[i] = joints[static_cast<std::size_t>(i)];
  chain.joint_to_tip = pending * detail::pose_of(m->geom_pos + 3 * tip, m->geom_quat + 4 * tip);
  chain.fingertip_radius = m->geom_size[3 * tip];
  return chain;
}

/// The chains of several fingers, in the given order.
inline std::vector<MujocoChain> finger_chains(const mjModel* m,
                                              const std::vector<FingerNames>& fingers,
                                              double default_max_velocity = 3.0) {
  std::vector<MujocoChain> out;
  for (const FingerNames& f : fingers) out.push_back(finger_chain(m, f, default_max_velocity));
  return out;
}

/// The qpos addresses of the finger's joints, base to tip (for reading the angles).
inline std::vector<int> finger_qpos_addresses(const mjModel* m, const FingerNames& names) {
  const int palm = detail::id_of(m, mjOBJ_BODY, names.palm_body, "body");
  std::vector<int> adr;
  for (int b = m->geom_bodyid[detail::id_of(m, mjOBJ_GEOM, names.tip_geom, "geom")]; b != palm;
       b = m->body_parentid[b])
    for (int k = m->body_jntnum[b] - 1; k >= 0; --k)
      adr.insert(adr.begin(), m->jnt_qposadr[m->body_jntadr[b] + k]);
  return adr;
}

}  // namespace inhand::mujoco_demo
