// Compiled with one INHAND_CASE defined: each instantiates ReactiveController with an
// impossible template argument and must fail with the matching static_assert message
// (tests.cmake checks the message).
#include "inhand/controller/reactive_controller.hpp"

#if INHAND_CASE == 1
template class inhand::ReactiveController<double, 3, 0, 3>;  // no fingers
#elif INHAND_CASE == 2
template class inhand::ReactiveController<double, 3, -2, 3>;  // negative finger count
#elif INHAND_CASE == 3
template class inhand::ReactiveController<double, 4, 3, 3>;  // Dim 4
#elif INHAND_CASE == 4
template class inhand::ReactiveController<double, 3, 3, 0>;  // Dof 0
#elif INHAND_CASE == 5
template class inhand::ReactiveController<double, 3, 3, 4, 3>;  // MaxDof < Dof
#elif INHAND_CASE == 6
template class inhand::ReactiveController<int, 3, 3, 3>;  // not floating point
#elif INHAND_CASE == 7
template class inhand::ReactiveController<double, 3, 3, inhand::Dynamic, 0>;  // MaxDof 0
#endif

int main() { return 0; }
