// libFuzzer target: the scenario-file reader of examples/scenario/scenario_json.hpp
// (JSON text -> parse_json_text -> parse_scenario, which also validates the plant and
// controller configuration it builds).
//
// Any input may be rejected: a JsonError (the reader's documented error, naming the
// offending key) is the expected outcome for malformed or out-of-range files and is
// ignored. Everything else is a finding, reported by libFuzzer with the reproducing
// input: a crash, a sanitizer report, a hang or excessive memory, and any other
// exception type escaping the reader (its contract is to throw JsonError only).
// Seed corpus: the shipped scenarios/**/*.json (scripts/fuzz copies them in).
#include <cstddef>
#include <cstdint>
#include <string>

#include "scenario/scenario_json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const inhand::examples::ScenarioFile f =
        inhand::examples::parse_scenario(inhand::examples::parse_json_text(text));
    // A file that was accepted must describe a runnable scenario.
    if (f.spec.stages.empty() || f.spec.name.empty()) __builtin_trap();
  } catch (const inhand::examples::JsonError&) {
    // documented rejection
  }
  return 0;
}
