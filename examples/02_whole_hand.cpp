// 02_whole_hand: a thumb and two fingers under inhand::ReactiveController grasp a box and
// turn it about x to -0.2 rad and back. The program is docs/tour.md's loop, kept in
// tests/consumer/readme_tour.cpp (a test checks that the two are the same text).
#include "../tests/consumer/readme_tour.cpp"
