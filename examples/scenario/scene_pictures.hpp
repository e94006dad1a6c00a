// The scenario runner's pictures of the 3-D scene (common/scene_svg.hpp) at three key
// instants of a run, for any plant:
//   grasped : the last tick of the first grasp stage (grasped, or timed out);
//   mid     : the first tick of the first manipulate stage at or after half of its
//             segments' duration (for the paper's out-and-back tasks: the turning point);
//   end     : the last tick of the last stage that ran to its end.
// The fingers are drawn from the chains the controller uses (the analytic plant's preset,
// or the chains read from the MuJoCo model) at the joint angles it read on that tick; the
// contacts as it sensed them; the object at its true and desired poses. An instant the run
// did not reach gives a picture that says so. Units: m, rad, N, s.
#pragma once

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/scene_svg.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/sim/hand_plant_scenario.hpp"
#include "inhand/sim/plant_params.hpp"

namespace inhand::examples {

/// Picture of one tick's scene. `chains[i]` and `names[i]`: finger i's chain and name.
template <class Record>
Scene tick_scene(const Record& rec, const std::vector<plant::PlantFinger>& chains,
                 const std::vector<std::string>& names, const plant::ObjectShape& object,
                 const std::string& title, const std::string& stage_name) {
  Scene s;
  s.object = object;
  s.actual = *rec.actual;
  s.desired = *rec.desired;
  s.title = title;
  char b[240];
  const double angle =
      Eigen::AngleAxisd(rec.desired->rotation.transpose() * rec.actual->rotation).angle();
  std::snprintf(b, sizeof b,
                "t = %.3f s (stage %s, %.3f s in); true pose off the desired one by %.3f mm, "
                "%.2f mrad",
                rec.time, stage_name.c_str(), rec.stage_time,
                1e3 * (rec.actual->position - rec.desired->position).norm(), 1e3 * angle);
  s.subtitle = b;
  for (std::size_t i = 0; i < chains.size() && i < rec.input->fingers.size(); ++i) {
    const plant::PlantFinger& chain = chains[i];
    const auto& in = rec.input->fingers[i];
    FingerKinematics<plant::PlantFinger> ws(chain);
    forward_kinematics(chain, in.joint_positions, ws);
    Scene::Finger f;
    f.name = i < names.size() ? names[i] : "finger " + std::to_string(i);
    for (int j = 0; j < chain.dof(); ++j) f.links.push_back(ws.joint_origins.col(j));
    f.links.push_back(ws.fingertip.position);
    f.tip_radius = chain.fingertip_radius;
    f.touching = in.contact.touching;
    f.contact_point = in.contact.contact_point;
    f.normal = in.contact.normal;
    f.normal_force = in.contact.normal_force;
    s.fingers.push_back(f);
  }
  return s;
}

/// Collects the three pictures during a run (add() on every tick).
class ScenePictures {
 public:
  ScenePictures(std::vector<plant::PlantFinger> chains, std::vector<std::string> names,
                plant::ObjectShape object, std::vector<plant::StageSpec> stages,
                std::string scenario)
      : chains_(std::move(chains)),
        names_(std::move(names)),
        object_(object),
        stages_(std::move(stages)),
        scenario_(std::move(scenario)) {}

  template <class Record>
  void add(const Record& rec) {
    const plant::StageSpec& st = stages_[static_cast<std::size_t>(rec.stage)];
    if (st.kind == plant::StageKind::grasp && grasped_.empty() && rec.stage_end)
      grasped_ = draw(rec, "grasped", st.name);
    if (st.kind == plant::StageKind::manipulate && mid_.empty()) {
      double motion = 0.0;
      for (const auto& seg : st.segments) motion += seg.duration;
      if (rec.stage_time >= 0.5 * motion) mid_ = draw(rec, "mid-motion", st.name);
    }
    if (rec.stage_end) end_ = draw(rec, "end", st.name);
  }
  /// The pictures: grasped, mid, end (a note where the run did not get there).
  std::string grasped() const { return or_note(grasped_, "grasped", "the grasp stage ended"); }
  std::string mid() const { return or_note(mid_, "mid-motion", "half of a manipulate stage"); }
  std::string end() const { return or_note(end_, "end", "the end of a stage"); }

 private:
  template <class Record>
  std::string draw(const Record& rec, const std::string& instant, const std::string& stage) const {
    return scene_svg(tick_scene(rec, chains_, names_, object_, scenario_ + ": " + instant, stage));
  }
  std::string or_note(const std::string& svg, const std::string& instant,
                      const std::string& what) const {
    if (!svg.empty()) return svg;
    SvgWriter w(0.0, 0.0, 0.4, 0.05, 1500.0);
    w.text(Eigen::Vector2d(0.005, 0.03),
           scenario_ + ": no " + instant + " picture: the run did not reach " + what, 14.0);
    return w.str();
  }

  std::vector<plant::PlantFinger> chains_;
  std::vector<std::string> names_;
  plant::ObjectShape object_;
  std::vector<plant::StageSpec> stages_;
  std::string scenario_;
  std::string grasped_, mid_, end_;
};

}  // namespace inhand::examples
