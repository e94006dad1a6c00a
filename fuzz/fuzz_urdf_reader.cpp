// libFuzzer target: the URDF reader of include/inhand/urdf.hpp (text -> urdfdom ->
// finger chains), with the finger specs of the three shipped hands
// (tests/common/urdf_hand_models.hpp), so that the seeds (models/urdf/*.urdf, which
// scripts/lib/fuzz.sh copies in) are read to the end and mutated from there.
//
// The reader's contract, checked here: nothing is thrown for any input (an exception
// escaping is a finding); a refusal carries a non-empty error; an accepted hand has one
// chain and one joint-name list per spec, each chain valid (FingerChain::validate) with as
// many names as joints. Crashes, sanitizer reports, hangs and memory blow-ups are
// findings too.
#include <cstddef>
#include <cstdint>
#include <string>

#include "common/urdf_hand_models.hpp"
#include "inhand/urdf.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::vector<inhand_test::UrdfHandModel> models = inhand_test::urdf_hand_models();
  const std::string text(reinterpret_cast<const char*>(data), size);
  for (const inhand_test::UrdfHandModel& model : models) {
    const auto hand = inhand::urdf::read_fingers_string(text, model.specs);
    if (!hand.ok()) continue;  // a documented refusal (error names the element)
    if (hand.fingers.size() != model.specs.size() || hand.joint_names.size() != model.specs.size())
      __builtin_trap();
    for (std::size_t i = 0; i < hand.fingers.size(); ++i) {
      if (!hand.fingers[i].validate().ok()) __builtin_trap();
      if (static_cast<int>(hand.joint_names[i].size()) != hand.fingers[i].dof()) __builtin_trap();
    }
  }
  return 0;
}
