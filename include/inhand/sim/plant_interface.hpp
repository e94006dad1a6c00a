// What the scenario runner (scenario_runner.hpp) needs from a plant: a "plant adapter"
// wraps one simulated hand-and-object world (the analytic plant, hand_plant_scenario.hpp;
// the Box2D world, examples/box2d/planar_adapter.hpp) behind this interface.
// ScenarioRunner<A> checks it with static_assert (PlantAdapterCheck below).
//
//   struct A : PlantTypes<Dim, Controller, Setup, Model> {  // which declares:
//     static constexpr int dim;                  // 3 (spatial) or 2 (planar)
//     using Controller = ReactiveController<double, dim, ...>;
//     using Setup;   // the plant's part of a scenario (hand, object, settings): a base
//                    // of ScenarioSpec<A>, default-constructible
//     using Model;   // the simulated plant itself (TickRecord::plant points at it)
//     static constexpr FaultConventions fault_conventions;  // scenario_spec.hpp
//
//     explicit A(const Setup&);  // builds the plant: fingers in their open posture, the
//                                // object at its initial pose, not frozen; throws
//                                // std::invalid_argument on a bad setup
//     // Set-up
//     Controller::Config controller_config(Controller::Config base) const;
//                                // base with `fingers` filled (chains, roles)
//     Targets grasp_targets() const;  // one GraspTarget per finger, needing no object
//                                     // model (world frame); passed to start_grasp()
//     int finger_count() const;
//     // Sensing, each control tick, in this order
//     void sense();                   // draw this tick's sensor noise (or nothing)
//     Pose measured_object_pose() const;     // object pose as sensed, world frame
//     JointVector joint_positions(int i) const;  // sensed joint angles [rad]
//     Tactile tactile(int i) const;   // .touching, .contact_point (world), .normal
//                                     // (the object's outward unit normal, world),
//                                     // .normal_force [N] (read only when touching)
//     // Acting
//     void set_object_force(const Vector& f);  // external force on the object's centre
//                                              // [N, world], held until changed
//     void command(int i, const V& qd, const TickClock& c);  // joint velocities
//                                     // [rad/s] of finger i, held until the next
//                                     // command; the plant may apply its own command
//                                     // faults from the tick clock
//     void command_towards_open(int i, double gain);  // qd = gain (q_open - q)
//                                                     // (the finger_away fault)
//     void step(double dt);           // advance by one control period [s]
//     void set_frozen(bool);          // frozen: the object held still (grasp stage)
//     // Truth, for the metrics
//     Pose object_pose() const;       // true object pose, world frame
//     plant::FingerTruth truth(int i) const;  // touching, normal_force [N],
//                                             // slip_distance (accumulated); the
//                                             // runner fills desired_force
//     int link_contacts() const;      // non-sensing link contacts (0 if not modelled)
//     const Model& model() const;
//   };
#pragma once

#include <type_traits>
#include <utility>

#include "inhand/sim/metrics.hpp"
#include "inhand/sim/scenario_spec.hpp"

namespace inhand::sim {

/// The type members of an adapter, in one base: struct A : PlantTypes<3, C, S, M> {...}.
template <int Dim, class ControllerT, class SetupT, class ModelT>
struct PlantTypes {
  static constexpr int dim = Dim;
  using Controller = ControllerT;
  using Setup = SetupT;
  using Model = ModelT;
};

/// Where in the run a command is given: the fault hooks of a plant's own read it.
struct TickClock {
  int stage = 0;            ///< index into ScenarioSpec::stages
  double stage_time = 0.0;  ///< s since the stage started, at the start of the tick
  double period = 0.0;      ///< control period [s]
};

namespace detail {
template <class A, class = void>
struct HasSensing : std::false_type {};
template <class A>
struct HasSensing<A, std::void_t<decltype(std::declval<A&>().sense()),
                                 decltype(std::declval<const A&>().measured_object_pose()),
                                 decltype(std::declval<const A&>().joint_positions(0)),
                                 decltype(std::declval<const A&>().tactile(0).touching),
                                 decltype(std::declval<const A&>().finger_count())>>
    : std::true_type {};

template <class A, class = void>
struct HasActing : std::false_type {};
template <class A>
struct HasActing<A, std::void_t<decltype(std::declval<A&>().step(0.0)),
                                decltype(std::declval<A&>().set_frozen(true)),
                                decltype(std::declval<A&>().command_towards_open(0, 0.0)),
                                decltype(std::declval<A&>().set_object_force(
                                    std::declval<const typename FaultSpec<A::dim>::Vector&>()))>>
    : std::true_type {};

template <class A, class = void>
struct HasTruth : std::false_type {};
template <class A>
struct HasTruth<A, std::void_t<decltype(std::declval<const A&>().object_pose()),
                               decltype(std::declval<const A&>().truth(0)),
                               decltype(std::declval<const A&>().link_contacts()),
                               decltype(std::declval<const A&>().model()),
                               decltype(std::declval<const A&>().grasp_targets())>>
    : std::true_type {};
}  // namespace detail

/// Compile-time check of an adapter against the interface above.
template <class A>
struct PlantAdapterCheck {
  static_assert(A::dim == 2 || A::dim == 3, "plant adapter: dim is 2 or 3");
  static_assert(A::Controller::Dim == A::dim, "plant adapter: controller of another dimension");
  static_assert(std::is_default_constructible_v<typename A::Setup>,
                "plant adapter: Setup must be default-constructible");
  static_assert(std::is_constructible_v<A, const typename A::Setup&>,
                "plant adapter: constructible from its Setup");
  static_assert(std::is_same_v<std::decay_t<decltype(A::fault_conventions)>, FaultConventions>,
                "plant adapter: fault_conventions");
  static_assert(detail::HasSensing<A>::value, "plant adapter: sensing members missing");
  static_assert(detail::HasActing<A>::value, "plant adapter: acting members missing");
  static_assert(detail::HasTruth<A>::value, "plant adapter: truth members missing");
  static constexpr bool value = true;
};

}  // namespace inhand::sim
