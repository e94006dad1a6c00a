// Consumer of the installed simulator component (inhand::sim): a preset hand around the
// paper's cylinder, stepped for 10 ms. Returns non-zero unless the plant advanced.
#include <inhand/sim/hand_plant.hpp>
#include <inhand/sim/presets.hpp>

int main() {
  const inhand::plant::HandPreset hand = inhand::plant::shadow_like_hand();
  inhand::plant::HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand));
  return plant.step(0.01) > 0 ? 0 : 1;
}
