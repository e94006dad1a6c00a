// The paper's 12 experiments (docs/method.md section 9) as ScenarioSpecs: the preset hand
// on the paper's cylinder or slender box, translated 5 mm or rotated 0.2 rad about
// each axis of the reference frame. Units SI (s, m, rad), world frame.
#pragma once

#include <string>

#include "inhand/sim/hand_plant_scenario.hpp"
#include "inhand/sim/presets.hpp"

namespace inhand::plant {

enum class PaperObject { cylinder, slender_box };
enum class PaperTask { translate, rotate };

/// One of the paper's 12 experiments (docs/method.md section 9): object x {translate,
/// rotate} x axis (0 = X, 1 = Y, 2 = Z of the reference frame). Stage 0 grasps at the
/// nominal force with the object frozen, stage 1 releases and holds, stage 2 moves
/// 5 mm along the axis and back, or rotates 0 -> -0.2 rad -> 0 about it.
inline ScenarioSpec paper_scenario(PaperObject object, PaperTask task, int axis,
                                   double cycle_duration = 4.0) {
  ScenarioSpec s;
  s.hand = shadow_like_hand();
  s.object = object == PaperObject::cylinder ? paper_cylinder(s.hand) : paper_slender_box(s.hand);
  static const char* names[] = {"x", "y", "z"};
  s.name = std::string(object == PaperObject::cylinder ? "cylinder" : "box") + "_" +
           (task == PaperTask::translate ? "translate_" : "rotate_") + names[axis];
  StageSpec grasp;
  grasp.name = "grasp";
  grasp.kind = StageSpec::Kind::grasp;
  grasp.duration = 3.0;
  StageSpec hold;
  hold.name = "hold";
  hold.kind = StageSpec::Kind::hold;
  hold.release = true;
  hold.duration = 2.0;
  StageSpec manip;
  manip.name = "manipulate";
  manip.kind = StageSpec::Kind::manipulate;
  manip.settle = 1.0;
  Twist<double, 3> d = Twist<double, 3>::Zero();
  if (task == PaperTask::translate)
    d(axis) = 0.005;
  else
    d(3 + axis) = -0.2;
  manip.segments.push_back(TrajectorySegment<double, 3>::reciprocate(d, cycle_duration, 1));
  s.stages = {grasp, hold, manip};
  return s;
}

}  // namespace inhand::plant
