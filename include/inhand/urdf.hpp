// Finger chains read from a URDF description of a hand (target inhand::urdf, which
// links urdfdom; find_package(inhand COMPONENTS urdf)). docs/urdf.md has the details.
//
//   std::vector<inhand::urdf::FingerSpec> specs = {{"index", "palm", "index_tip"}, ...};
//   auto hand = inhand::urdf::read_fingers_file("hand.urdf", specs);
//   if (!hand.ok()) std::cerr << hand.error << "\n";  // names the link or joint
//   // hand.fingers[i]: FingerChain<double, 3, Dynamic>; hand.joint_names[i]
//
// Units: metres, radians, rad/s, as URDF. Frames and conventions:
//  - Each finger runs from its root link (the palm) down the URDF tree to its tip link.
//    The root link frame is the chain's world (hand) frame.
//  - A URDF joint <origin> maps the parent link frame to the joint frame, which is the
//    child link frame; a revolute joint turns the child about <axis> (in the joint frame,
//    normalised here) by q, right-hand rule: the same convention as FingerChain, so
//    JointDescription::parent_to_joint = the joint's <origin>, composed with the fixed
//    joints since the previous movable joint.
//  - Fixed joints are folded into the frames: chain.base = root link frame -> the first
//    movable joint's parent link frame; chain.joint_to_tip = last movable joint's frame ->
//    tip link frame -> fingertip sphere centre (a pure translation: the fingertip frame
//    has the tip link's orientation and the sphere centre as origin).
//  - Fingertip sphere: the tip link's first collision <sphere> (radius, <origin> xyz);
//    without one, FingerSpec::fingertip_radius and contact_offset.
//  - Joint limits: revolute joints take <limit lower upper>; continuous joints take
//    +-ReadOptions::continuous_limit (1000 rad). Velocity limit: <limit velocity>, or
//    ReadOptions::default_velocity (2 rad/s) where that is 0 or absent.
//  - <mimic joint multiplier offset> becomes JointCoupling (leader = the mimicked
//    joint's index in the same finger, ratio = multiplier, offset); the mimicked joint
//    must be a movable joint of the same finger.
// Refused, with an error naming the finger and the element: XML or URDF that urdfdom
// rejects (its messages are passed on), a '%' in an attribute value or text other than a
// mesh filename (urdfdom 3.0 would use it as a printf format: urdf/parse.hpp), missing root or tip
// link, a tip link not below its root link, prismatic, planar or floating joints on the path, no
// movable joint, a zero axis, lower > upper, non-finite numbers, a mimic of a joint outside the
// finger, more joints than the chain's MaxDof, and anything FingerChain::validate() refuses.
// Nothing is thrown for bad input (only std::bad_alloc could escape, from the
// allocation of the result).
#pragma once

#include <string>
#include <vector>

#include "inhand/urdf/parse.hpp"
#include "inhand/urdf/read_fingers.hpp"
#include "inhand/urdf/spec.hpp"

namespace inhand::urdf {

/// The fingers of `specs` read from a URDF document held in a string.
template <typename Chain = FingerChain<double, 3, Dynamic>>
FingersResult<Chain> read_fingers_string(const std::string& xml,
                                         const std::vector<FingerSpec>& specs,
                                         const ReadOptions& options = {}) {
  FingersResult<Chain> result;
  const ::urdf::ModelInterfaceSharedPtr model = detail::parse_model(xml, result.error);
  if (!model) return result;
  result = read_fingers<Chain>(*model, specs, options);
  detail::release_model(*model);
  return result;
}

/// The fingers of `specs` read from a URDF file.
template <typename Chain = FingerChain<double, 3, Dynamic>>
FingersResult<Chain> read_fingers_file(const std::string& path,
                                       const std::vector<FingerSpec>& specs,
                                       const ReadOptions& options = {}) {
  std::string xml;
  FingersResult<Chain> result;
  if (!detail::read_text_file(path, xml, result.error)) return result;
  result = read_fingers_string<Chain>(xml, specs, options);
  if (!result.ok()) result.error = path + ": " + result.error;
  return result;
}

}  // namespace inhand::urdf
