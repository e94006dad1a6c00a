// The shipped URDF hand models (models/urdf/*.urdf) with the finger specs their header
// comments document, for the tests that read them (tests/urdf, tests/mujoco). Each test
// defines INHAND_MODELS_DIR (the models/ directory). Units: metres.
//
// Finger specs (name, root link, tip link):
//   three_finger_hand.urdf  left/right/thumb: palm -> <name>_distal (sphere 40 mm down
//                           the distal link)
//   shadow_like_hand.urdf   first/middle/ring/thumb: palm -> fftip/mftip/rftip/thtip
//   allegro_like_hand.urdf  index/middle/ring/thumb: palm -> link_3.0_tip/link_7.0_tip/
//                           link_11.0_tip/link_15.0_tip
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "inhand/urdf/spec.hpp"

namespace inhand_test {

struct UrdfHandModel {
  std::string file;  // in models/urdf/
  std::vector<inhand::urdf::FingerSpec> specs;
  std::vector<Eigen::Vector3d> sphere;  // fingertip sphere centre in the tip link frame
};

/// Path of a file in models/urdf/.
inline std::string urdf_model_path(const std::string& file) {
  return std::string(INHAND_MODELS_DIR) + "/urdf/" + file;
}

/// The three shipped hands: three-finger, Shadow-like, Allegro-like (in that order).
inline std::vector<UrdfHandModel> urdf_hand_models() {
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  return {
      {"three_finger_hand.urdf",
       {{"left", "palm", "left_distal"},
        {"right", "palm", "right_distal"},
        {"thumb", "palm", "thumb_distal"}},
       {Eigen::Vector3d(0, 0, -0.04), Eigen::Vector3d(0, 0, -0.04), Eigen::Vector3d(0, 0, -0.04)}},
      {"shadow_like_hand.urdf",
       {{"first", "palm", "fftip"},
        {"middle", "palm", "mftip"},
        {"ring", "palm", "rftip"},
        {"thumb", "palm", "thtip"}},
       {zero, zero, zero, zero}},
      {"allegro_like_hand.urdf",
       {{"index", "palm", "link_3.0_tip"},
        {"middle", "palm", "link_7.0_tip"},
        {"ring", "palm", "link_11.0_tip"},
        {"thumb", "palm", "link_15.0_tip"}},
       {zero, zero, zero, zero}},
  };
}

}  // namespace inhand_test
