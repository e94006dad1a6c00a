// Finger chains from a parsed urdfdom model: the walk from each tip link up to its root
// link, fixed joints folded into the frames, revolute and continuous joints turned into
// JointDescriptions, mimic joints into JointCouplings. urdf.hpp documents the rules.
//
// Units: metres, radians, rad/s. Frames: the root link frame is the chain's world frame.
#pragma once

#include <urdf_model/model.h>

#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "inhand/kinematics/chain_model.hpp"
#include "inhand/urdf/spec.hpp"

namespace inhand::urdf {
namespace detail {

inline Pose<double, 3> to_pose(const ::urdf::Pose& p) {
  Pose<double, 3> out;
  out.position = Vector<double, 3>(p.position.x, p.position.y, p.position.z);
  const Eigen::Quaterniond q(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z);
  const double n = q.norm();
  out.rotation = (n > 0 && std::isfinite(n))
                     ? Rotation<double, 3>(q.normalized().toRotationMatrix())
                     : Rotation<double, 3>::Constant(std::nan(""));
  return out;
}

inline const char* joint_type_name(int type) {
  switch (type) {
    case ::urdf::Joint::REVOLUTE:
      return "revolute";
    case ::urdf::Joint::CONTINUOUS:
      return "continuous";
    case ::urdf::Joint::PRISMATIC:
      return "prismatic";
    case ::urdf::Joint::FLOATING:
      return "floating";
    case ::urdf::Joint::PLANAR:
      return "planar";
    case ::urdf::Joint::FIXED:
      return "fixed";
    default:
      return "of unknown type";
  }
}

/// The fingertip sphere of the tip link: its first collision <sphere> (radius, origin
/// xyz in the tip link frame), or the spec's. Returns false if that sphere is not finite.
inline bool fingertip_sphere(const ::urdf::Link& tip, const FingerSpec& spec, double& radius,
                             Vector<double, 3>& centre) {
  radius = spec.fingertip_radius;
  centre = spec.contact_offset;
  std::vector<::urdf::CollisionSharedPtr> collisions = tip.collision_array;
  if (collisions.empty() && tip.collision) collisions.push_back(tip.collision);
  for (const auto& c : collisions) {
    if (!c || !c->geometry || c->geometry->type != ::urdf::Geometry::SPHERE) continue;
    radius = static_cast<const ::urdf::Sphere&>(*c->geometry).radius;
    centre = to_pose(c->origin).position;
    break;
  }
  return std::isfinite(radius) && radius >= 0 && centre.allFinite();
}

/// The joints from root_link down to tip_link, root first; empty with `error` set if
/// a link is missing or the tip is not below the root.
inline std::vector<::urdf::JointConstSharedPtr> joint_path(const ::urdf::ModelInterface& model,
                                                           const FingerSpec& spec,
                                                           std::string& error) {
  std::vector<::urdf::JointConstSharedPtr> path;
  if (!model.getLink(spec.root_link)) {
    error = "root link '" + spec.root_link + "' not found";
    return path;
  }
  ::urdf::LinkConstSharedPtr link = model.getLink(spec.tip_link);
  if (!link) {
    error = "tip link '" + spec.tip_link + "' not found";
    return path;
  }
  while (link->name != spec.root_link) {
    // A tree of L links has paths of at most L - 1 joints; a longer walk is a cycle
    // (urdfdom does not refuse every one of them: a fuzzed file had one).
    if (path.size() >= model.links_.size()) {
      error = "the links above tip link '" + spec.tip_link + "' form a cycle (through link '" +
              link->name + "')";
      path.clear();
      return path;
    }
    const ::urdf::JointConstSharedPtr joint = link->parent_joint;
    if (!joint) {
      error = "tip link '" + spec.tip_link + "' is not below root link '" + spec.root_link +
              "' (its ancestors end at link '" + link->name + "')";
      path.clear();
      return path;
    }
    path.push_back(joint);
    link = model.getLink(joint->parent_link_name);
    if (!link) {
      error = "link '" + joint->parent_link_name + "' (parent of joint '" + joint->name +
              "') not found";
      path.clear();
      return path;
    }
  }
  if (path.empty()) error = "tip link '" + spec.tip_link + "' is the root link";
  return {path.rbegin(), path.rend()};
}

/// One finger's chain (in double), its movable joints' names; false with `error` set.
inline bool read_finger(const ::urdf::ModelInterface& model, const FingerSpec& spec,
                        const ReadOptions& options, FingerChain<double, 3, Dynamic>& chain,
                        std::vector<std::string>& names, std::string& error) {
  const std::vector<::urdf::JointConstSharedPtr> path = joint_path(model, spec, error);
  if (path.empty()) return false;
  using Joint = FingerChain<double, 3, Dynamic>::Joint;
  std::vector<Joint> joints;
  std::vector<const ::urdf::Joint*> movable;
  Pose<double, 3> pending{};  // fixed transforms since the last movable joint (or the root)
  for (const auto& j : path) {
    const Pose<double, 3> origin = to_pose(j->parent_to_joint_origin_transform);
    if (!origin.is_finite()) {
      error = "joint '" + j->name + "': <origin> is not finite";
      return false;
    }
    if (j->type == ::urdf::Joint::FIXED) {
      pending = pending * origin;
      continue;
    }
    if (j->type != ::urdf::Joint::REVOLUTE && j->type != ::urdf::Joint::CONTINUOUS) {
      error = "joint '" + j->name + "' is " + joint_type_name(j->type) +
              ": only revolute, continuous and fixed joints are supported";
      return false;
    }
    Joint d;
    if (joints.empty()) {
      chain.base = pending;
      d.parent_to_joint = origin;
    } else {
      d.parent_to_joint = pending * origin;
    }
    pending = Pose<double, 3>{};
    const Vector<double, 3> axis(j->axis.x, j->axis.y, j->axis.z);
    const double norm = axis.norm();
    if (!std::isfinite(norm) || norm < 1e-9) {
      error = "joint '" + j->name + "': <axis> must be a finite non-zero vector";
      return false;
    }
    d.axis = axis / norm;
    const double vel = j->limits ? j->limits->velocity : 0.0;
    d.max_velocity = vel > 0 ? vel : options.default_velocity;
    if (j->type == ::urdf::Joint::CONTINUOUS) {
      d.lower = -options.continuous_limit;
      d.upper = options.continuous_limit;
    } else {
      d.lower = j->limits ? j->limits->lower : 0.0;
      d.upper = j->limits ? j->limits->upper : 0.0;
      if (!(d.lower <= d.upper)) {
        error = "joint '" + j->name + "': <limit> lower > upper (or not finite)";
        return false;
      }
    }
    joints.push_back(d);
    movable.push_back(j.get());
  }
  if (joints.empty()) {
    error = "no revolute or continuous joint between root link '" + spec.root_link +
            "' and tip link '" + spec.tip_link + "'";
    return false;
  }
  names.clear();
  for (const auto* j : movable) names.push_back(j->name);
  for (std::size_t i = 0; i < movable.size(); ++i) {
    const ::urdf::JointMimicSharedPtr& mimic = movable[i]->mimic;
    if (!mimic) continue;
    std::size_t leader = 0;
    while (leader < names.size() && names[leader] != mimic->joint_name) ++leader;
    if (leader == names.size()) {
      error = "joint '" + names[i] + "' mimics joint '" + mimic->joint_name +
              "', which is not a movable joint of this finger";
      return false;
    }
    joints[i].coupling.leader = static_cast<int>(leader);
    joints[i].coupling.ratio = mimic->multiplier;
    joints[i].coupling.offset = mimic->offset;
  }
  double radius = 0;
  Vector<double, 3> centre;
  if (!fingertip_sphere(*model.getLink(spec.tip_link), spec, radius, centre)) {
    error = "tip link '" + spec.tip_link +
            "': the fingertip sphere needs a finite radius >= 0 and a finite centre";
    return false;
  }
  Pose<double, 3> to_centre{};
  to_centre.position = centre;
  chain.joint_to_tip = pending * to_centre;
  chain.fingertip_radius = radius;
  chain.joints.resize(static_cast<int>(joints.size()));
  for (std::size_t i = 0; i < joints.size(); ++i) chain.joints[static_cast<int>(i)] = joints[i];
  const Validation v = chain.validate();
  if (!v.ok()) {
    error = std::string(v.field) + ": " + v.reason;
    if (v.index >= 0) error = "joint '" + names[static_cast<std::size_t>(v.index)] + "': " + error;
    return false;
  }
  return true;
}

/// The double-precision chain in another chain type (Scalar, MaxDof).
template <typename Chain>
Chain convert_chain(const FingerChain<double, 3, Dynamic>& in) {
  using S = typename Chain::Scalar;
  auto cast_pose = [](const Pose<double, 3>& p) {
    Pose<S, 3> out;
    out.position = p.position.template cast<S>();
    out.rotation = p.rotation.template cast<S>();
    return out;
  };
  Chain out;
  out.base = cast_pose(in.base);
  out.joint_to_tip = cast_pose(in.joint_to_tip);
  out.fingertip_radius = static_cast<S>(in.fingertip_radius);
  out.joints.resize(in.dof());
  for (int i = 0; i < in.dof(); ++i) {
    const auto& j = in.joints[i];
    auto& o = out.joints[i];
    o.parent_to_joint = cast_pose(j.parent_to_joint);
    o.axis = j.axis.template cast<S>();
    o.lower = static_cast<S>(j.lower);
    o.upper = static_cast<S>(j.upper);
    o.max_velocity = static_cast<S>(j.max_velocity);
    o.coupling.leader = j.coupling.leader;
    o.coupling.ratio = static_cast<S>(j.coupling.ratio);
    o.coupling.offset = static_cast<S>(j.coupling.offset);
  }
  return out;
}

}  // namespace detail

/// The fingers of `specs` read from a parsed urdfdom model (see urdf.hpp).
/// Chain: FingerChain<Scalar, 3, Dynamic, MaxDof> (MaxDof: capacity, or Dynamic).
template <typename Chain = FingerChain<double, 3, Dynamic>>
FingersResult<Chain> read_fingers(const ::urdf::ModelInterface& model,
                                  const std::vector<FingerSpec>& specs,
                                  const ReadOptions& options = {}) {
  static_assert(Chain::Dim == 3 && Chain::Dof == Dynamic,
                "read_fingers reads into spatial chains with a run-time joint count");
  FingersResult<Chain> result;
  if (!(options.default_velocity > 0) || !std::isfinite(options.default_velocity) ||
      !(options.continuous_limit > 0) || !std::isfinite(options.continuous_limit)) {
    result.error = "ReadOptions: default_velocity and continuous_limit must be finite and > 0";
    return result;
  }
  for (const FingerSpec& spec : specs) {
    FingerChain<double, 3, Dynamic> chain;
    std::vector<std::string> names;
    std::string error;
    bool ok = detail::read_finger(model, spec, options, chain, names, error);
    if (ok && Chain::MaxDof != Dynamic && chain.dof() > Chain::MaxDof) {
      error = "tip link '" + spec.tip_link + "': " + std::to_string(chain.dof()) +
              " movable joints, more than the chain's capacity MaxDof = " +
              std::to_string(Chain::MaxDof);
      ok = false;
    }
    if (!ok) {
      result.fingers.clear();
      result.joint_names.clear();
      result.error = "finger '" + spec.name + "': " + error;
      return result;
    }
    result.fingers.push_back(detail::convert_chain<Chain>(chain));
    result.joint_names.push_back(std::move(names));
  }
  return result;
}

}  // namespace inhand::urdf
