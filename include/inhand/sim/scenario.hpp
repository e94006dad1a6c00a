// Closed-loop scenarios on the analytic plant: the generic specification and runner
// (scenario_spec.hpp, scenario_runner.hpp) with the plant's adapter
// (hand_plant_scenario.hpp), and the paper's experiments (paper_scenarios.hpp).
#pragma once

#include "inhand/sim/hand_plant_scenario.hpp"
#include "inhand/sim/paper_scenarios.hpp"
