// Shadow-like hand with coupled distal joints: shadow_like_hand() (presets.hpp) with
// each finger's J1 (joint 3, distal flexion) following its J2 (joint 2, middle
// flexion) at ratio 1, offset 0, as the Shadow hand's tendon and the `mimic` joints of
// models/urdf/shadow_like_hand.urdf; the fingers have 3 actuated joints, the thumb 5.
// The plant keeps followers on their leaders (finger_model.hpp); the controller's IK
// commands them in ratio (controller/finger_command.hpp).
//
// Units: metres, radians, rad/s. Frames and finger roles as shadow_like_hand().
// Configurations (satisfying J1 == J2): the grasp one puts each fingertip centre halfway
// between its nominal contacts on the two paper objects, the open one withdraws it 15 mm
// along the approach direction and 20 mm down (14.7 mm clear of the cylinder, 21.6 mm
// of the box), both found by the
// position IK of tests/sim/presets_test.cpp over the actuated joints (the follower's
// Jacobian column folded into its leader's), from 100 random starts 0.1 rad inside the
// limits, keeping the grasp solution (rounded to 1 mrad) with the best worst-case
// joint-limit margin, Jacobian singular value and link clearance over the object
// offsets that test checks. The thumb is uncoupled and keeps its configurations.
#pragma once

#include "inhand/sim/presets.hpp"

namespace inhand::plant {

/// Shadow-like hand, fingers' J1 = J2: first (0), middle (1), ring (2) on +Y, thumb (3).
inline HandPreset shadow_like_coupled_hand() {
  HandPreset p = shadow_like_hand();
  p.name = "shadow_like_coupled_hand";
  for (int k = 0; k < 3; ++k) {
    auto& coupling = p.fingers[static_cast<std::size_t>(k)].joints[3].coupling;
    coupling.leader = 2;
    coupling.ratio = 1.0;
    coupling.offset = 0.0;
    p.open_configuration[static_cast<std::size_t>(k)] =
        detail::joint_vector({0.0, -0.223, 0.947, 0.947});
    p.grasp_configuration[static_cast<std::size_t>(k)] =
        detail::joint_vector({0.0, 0.083, 1.058, 1.058});
  }
  return p;
}

}  // namespace inhand::plant
