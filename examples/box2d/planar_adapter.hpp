// The Box2D world of planar_world.hpp behind the generic scenario runner's plant
// interface (inhand/sim/plant_interface.hpp): the library's ReactiveController for the
// plane (Dim = 2, two fingers of three joints) drives it through the scenario stages of
// inhand/sim/scenario_spec.hpp. What differs from the analytic plant:
//   sensing    : exact (Box2D's own joint angles, object pose and contacts; no noise);
//   grasp      : each finger aims at the object's measured centre along the hand's
//                approach normal (no object geometry);
//   command    : the world's own command fault, CommandOverride (a finger's joint
//                velocities replaced from some time into one stage, for that stage);
//   faults     : the bookkeeping conventions this demo has always used (FaultConventions
//                below: the window ends 1e-12 s early, a reacquisition counts only
//                after the detection, a fault never active reports start_time -1);
//   truth      : contacts of non-sensing links are counted (ScenarioResult::link_contacts).
// Units: see planar_world.hpp (1 u = 1 cm of the real hand, N, rad, s).
#pragma once

#include <array>
#include <cstddef>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/metrics.hpp"
#include "inhand/sim/plant_interface.hpp"
#include "inhand/sim/scenario_spec.hpp"
#include "planar_world.hpp"

namespace inhand::box2d_demo {

/// The library's controller for this hand: planar, two fingers, three joints each.
using PlanarController = ReactiveController<double, 2, kFingers, kLinks>;

/// Replaces one finger's joint-velocity command from `start` seconds into stage
/// `stage` on, to the end of that stage (a fault injected to show that the metrics
/// can fail).
struct CommandOverride {
  int finger = -1;  ///< -1: none
  int stage = 0;
  double start = 0.0;
  JointVector joint_velocity = JointVector::Zero();  ///< rad/s
};

/// The Box2D world's part of a scenario.
struct PlanarSetup {
  HandSpec hand{};
  ObjectSpec object{};
  WorldParams world{};
  CommandOverride command_override{};
  bool expect_drop = false;  ///< the negative case: it is expected to drop
};

class PlanarAdapter : public sim::PlantTypes<2, PlanarController, PlanarSetup, PlanarWorld> {
 public:
  static constexpr sim::FaultConventions fault_conventions{1e-12, true, -1.0};

  explicit PlanarAdapter(const Setup& s) : setup_(s), world_(s.hand, s.object, s.world) {}

  /// Every finger's chain is the controller's kinematics; finger 0 balances (the thumb).
  Controller::Config controller_config(Controller::Config c) const {
    for (int i = 0; i < kFingers; ++i) {
      auto& f = c.fingers[static_cast<std::size_t>(i)];
      f.chain = finger_chain(setup_.hand, i);
      f.kinematics = Controller::KinematicsSource::chain;
      f.role = i == 0 ? FingerRole::balancing : FingerRole::preset;
    }
    return c;
  }
  std::array<GraspTarget<double, 2>, kFingers> grasp_targets() const {
    const Pose<double, 2> object = world_.object_pose();
    std::array<GraspTarget<double, 2>, kFingers> targets{};
    for (int i = 0; i < kFingers; ++i) {
      targets[static_cast<std::size_t>(i)].contact_point = object.position;
      targets[static_cast<std::size_t>(i)].normal =
          object.rotation * setup_.hand.fingers[static_cast<std::size_t>(i)].approach_normal;
    }
    return targets;
  }
  int finger_count() const noexcept { return kFingers; }

  void sense() noexcept {}  // Box2D's sensing is exact: nothing to draw
  Pose<double, 2> measured_object_pose() const noexcept { return world_.object_pose(); }
  JointVector joint_positions(int i) const noexcept { return world_.joint_angles(i); }
  TactileReading tactile(int i) const noexcept { return world_.tactile(i); }

  void set_object_force(const Vec2& f) noexcept { world_.set_object_force(f); }
  template <class V>
  void command(int i, const V& qd, const sim::TickClock& clock) noexcept {
    const CommandOverride& co = setup_.command_override;
    const bool overridden = co.finger == i && co.stage == clock.stage &&
                            clock.stage_time >= co.start - 0.5 * clock.period;
    world_.set_joint_velocity(i, overridden ? co.joint_velocity : JointVector(qd));
  }
  void command_towards_open(int i, double gain) noexcept {
    const JointVector qd =
        gain * (setup_.hand.fingers[static_cast<std::size_t>(i)].q_open - world_.joint_angles(i));
    world_.set_joint_velocity(i, qd);
  }
  void step(double dt) { world_.step(dt); }
  void set_frozen(bool frozen) { world_.set_object_frozen(frozen); }

  Pose<double, 2> object_pose() const noexcept { return world_.object_pose(); }
  plant::FingerTruth truth(int i) const noexcept {
    const TactileReading r = world_.tactile(i);
    plant::FingerTruth t;
    t.touching = r.touching;
    t.normal_force = r.normal_force;
    t.slip_distance = world_.slip_distance(i);
    return t;
  }
  int link_contacts() const noexcept { return world_.link_contacts(); }
  const PlanarWorld& model() const noexcept { return world_; }

 private:
  const Setup& setup_;
  PlanarWorld world_;
};

}  // namespace inhand::box2d_demo
