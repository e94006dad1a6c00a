// Definitions for common/controller_instances.hpp: the planar hands.
#include "common/controller_instances.hpp"

namespace inhand {
INHAND_TEST_PHASES(, inhand_test::instances::Planar2x3)
INHAND_TEST_PHASES(, inhand_test::instances::Planar3x3)
INHAND_TEST_PHASES(, inhand_test::instances::PlanarDynamic4)
}  // namespace inhand
