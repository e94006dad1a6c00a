// Definitions for common/controller_instances.hpp: the contact IK in double.
#include "common/controller_instances.hpp"

namespace inhand {
template class ContactIk<double, 2, 2, 2>;
template class ContactIk<double, 2, 3, 3>;
template class ContactIk<double, 2, Dynamic, 4>;
template class ContactIk<double, 2, Dynamic, 5>;
template class ContactIk<double, 3, 2, 2>;
template class ContactIk<double, 3, 3, 3>;
template class ContactIk<double, 3, 4, 4>;
template class ContactIk<double, 3, 5, 5>;
template class ContactIk<double, 3, Dynamic, 5>;
template class ContactIk<double, 3, Dynamic, 6>;
template class ContactIk<double, 3, Dynamic, Dynamic>;
}  // namespace inhand
