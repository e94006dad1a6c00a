// Controller code several test files share, compiled once. Nearly all of the compile of a
// ReactiveController instantiation is its two phase functions (grasp_phase and
// manipulation_phase, controller/controller_phases.hpp), and nearly all of a plant
// scenario's is ScenarioRunner<HandPlantAdapter>::run (sim/scenario_runner.hpp). This
// header declares them `extern template` for the controller types below, which at least
// two test files each instantiate, and likewise the contact IK's solvers for the chain
// types that the IK's typed suites, the robustness sweeps and those controllers share;
// their one definition is in controller_instances_*.cpp and ik_instances_*.cpp (library
// inhand_test_instances). The tests' precompiled header includes this header, so
// every test linked with that library uses it (the urdf area's, built without that
// header, instantiate what they use themselves, as a user's code does). Build plumbing
// only: nothing here changes what the tests check.
#pragma once

#include "inhand/inhand.hpp"
#include "inhand/sim/hand_plant_scenario.hpp"

namespace inhand_test::instances {

/// The analytic plant's controller (sim/hand_plant_scenario.hpp: HandController).
using Hand = inhand::ControllerTypes<double, 3, inhand::Dynamic, inhand::Dynamic, 6>;
/// Run-time finger count and DOF without a bound.
using DynamicHand =
    inhand::ControllerTypes<double, 3, inhand::Dynamic, inhand::Dynamic, inhand::Dynamic>;
using Spatial3x3 = inhand::ControllerTypes<double, 3, 3, 3, 3>;
using Spatial3x3Float = inhand::ControllerTypes<float, 3, 3, 3, 3>;
using Planar2x3 = inhand::ControllerTypes<double, 2, 2, 3, 3>;
using Planar3x3 = inhand::ControllerTypes<double, 2, 3, 3, 3>;
using PlanarDynamic4 = inhand::ControllerTypes<double, 2, inhand::Dynamic, inhand::Dynamic, 4>;

}  // namespace inhand_test::instances

// The contact IK's solvers (ContactIk::solve_impl and pseudo_inverse, defined out of the
// class for this).
namespace inhand {
extern template class ContactIk<double, 2, 2, 2>;
extern template class ContactIk<double, 2, 3, 3>;
extern template class ContactIk<double, 2, Dynamic, 4>;
extern template class ContactIk<double, 2, Dynamic, 5>;
extern template class ContactIk<double, 3, 2, 2>;
extern template class ContactIk<double, 3, 3, 3>;
extern template class ContactIk<double, 3, 4, 4>;
extern template class ContactIk<double, 3, 5, 5>;
extern template class ContactIk<double, 3, Dynamic, 5>;
extern template class ContactIk<double, 3, Dynamic, 6>;
extern template class ContactIk<double, 3, Dynamic, Dynamic>;
extern template class ContactIk<float, 2, 2, 2>;
extern template class ContactIk<float, 2, 3, 3>;
extern template class ContactIk<float, 3, 2, 2>;
extern template class ContactIk<float, 3, 3, 3>;
extern template class ContactIk<float, 3, 4, 4>;
extern template class ContactIk<float, 3, 5, 5>;
extern template class ContactIk<float, 3, Dynamic, 5>;
extern template class ContactIk<float, 3, Dynamic, Dynamic>;
}  // namespace inhand

// INHAND_TEST_PHASES(prefix, T): the explicit instantiation of both phase functions for
// ControllerTypes T, declared (prefix `extern`) or defined (empty prefix), in namespace
// inhand.
#define INHAND_TEST_PHASES(PREFIX, T)                                                            \
  PREFIX template ControllerStatus grasp_phase<T>(const TickInput<T>&, ControllerState<T>&,      \
                                                  TickScratch<T>&, T::Output&) noexcept;         \
  PREFIX template ControllerStatus manipulation_phase<T>(                                        \
      const TickInput<T>&, const ObjectTrajectory<T::ScalarType, T::kDim>&, ControllerState<T>&, \
      TickScratch<T>&, T::Output&) noexcept;

namespace inhand {
INHAND_TEST_PHASES(extern, inhand_test::instances::Hand)
INHAND_TEST_PHASES(extern, inhand_test::instances::DynamicHand)
INHAND_TEST_PHASES(extern, inhand_test::instances::Spatial3x3)
INHAND_TEST_PHASES(extern, inhand_test::instances::Spatial3x3Float)
INHAND_TEST_PHASES(extern, inhand_test::instances::Planar2x3)
INHAND_TEST_PHASES(extern, inhand_test::instances::Planar3x3)
INHAND_TEST_PHASES(extern, inhand_test::instances::PlanarDynamic4)
}  // namespace inhand

extern template class inhand::sim::ScenarioRunner<inhand::plant::HandPlantAdapter>;
