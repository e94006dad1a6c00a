// Definitions for common/controller_instances.hpp: the analytic plant's controller and
// scenario runner, the run-time sized hand, and the three-finger spatial hands.
#include "common/controller_instances.hpp"

namespace inhand {
INHAND_TEST_PHASES(, inhand_test::instances::Hand)
INHAND_TEST_PHASES(, inhand_test::instances::DynamicHand)
INHAND_TEST_PHASES(, inhand_test::instances::Spatial3x3)
INHAND_TEST_PHASES(, inhand_test::instances::Spatial3x3Float)
}  // namespace inhand

template class inhand::sim::ScenarioRunner<inhand::plant::HandPlantAdapter>;
