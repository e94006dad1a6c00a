// What the URDF reader is asked for (FingerSpec, ReadOptions) and what it returns
// (FingersResult). The reading itself is in read_fingers.hpp; urdf.hpp is the entry point.
//
// Units: metres (radii, offsets), radians (limits), rad/s (velocity limits).
// Frames: a finger's root link (the palm) is the world (hand) frame of the chain it is
// read into; the tip link's frame, moved to the fingertip sphere centre, is the chain's
// fingertip frame (docs/urdf.md).
#pragma once

#include <string>
#include <vector>

#include "inhand/kinematics/chain_model.hpp"

namespace inhand::urdf {

/// One finger to read: the links it runs between, and the fingertip used when the tip
/// link has no collision sphere.
struct FingerSpec {
  /// The finger's name, used in error messages only.
  std::string name;
  /// The link the finger hangs from (the palm); its frame is the chain's world frame.
  std::string root_link;
  /// The fingertip link, below root_link in the URDF tree.
  std::string tip_link;
  /// Fingertip sphere radius [m], used when the tip link has no collision <sphere>.
  double fingertip_radius = 0.01;
  /// Fingertip sphere centre in the tip link frame [m], used when the tip link has no
  /// collision <sphere> (with one, the sphere's <origin> xyz is used instead).
  Vector<double, 3> contact_offset = Vector<double, 3>::Zero();
};

/// Choices the URDF format leaves open.
struct ReadOptions {
  /// Velocity limit [rad/s] of a joint whose <limit velocity> is 0 or absent (many
  /// published hand URDFs write 0); > 0.
  double default_velocity = 2.0;
  /// A continuous joint's limits are [-continuous_limit, +continuous_limit] rad: wide
  /// (1000 rad, about 159 turns) so that they never bind, but finite, as FingerChain
  /// requires. Not [-pi, pi]: a continuous joint may cross +-pi, and such limits would
  /// stop it there.
  double continuous_limit = 1000.0;
};

/// The fingers read, in the order of the specs, or the first error.
template <typename Chain>
struct FingersResult {
  /// One chain per FingerSpec (empty on error).
  std::vector<Chain> fingers;
  /// Per finger, the URDF names of its movable joints, base to tip (the chain's joint
  /// order, the order of its joint vectors).
  std::vector<std::vector<std::string>> joint_names;
  /// Empty when the reading succeeded; otherwise what is wrong, naming the finger and
  /// the URDF element (link or joint), e.g. "finger 'index': joint 'j3' is prismatic
  /// ...".
  std::string error;

  bool ok() const noexcept { return error.empty(); }
};

}  // namespace inhand::urdf
