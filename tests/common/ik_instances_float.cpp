// Definitions for common/controller_instances.hpp: the contact IK in float.
#include "common/controller_instances.hpp"

namespace inhand {
template class ContactIk<float, 2, 2, 2>;
template class ContactIk<float, 2, 3, 3>;
template class ContactIk<float, 3, 2, 2>;
template class ContactIk<float, 3, 3, 3>;
template class ContactIk<float, 3, 4, 4>;
template class ContactIk<float, 3, 5, 5>;
template class ContactIk<float, 3, Dynamic, 5>;
template class ContactIk<float, 3, Dynamic, Dynamic>;
}  // namespace inhand
