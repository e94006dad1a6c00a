// Closed-loop scenarios on the analytic plant: the specification (scenario_spec.hpp),
// the runner (scenario_runner.hpp) and the paper's experiments (paper_scenarios.hpp).
#pragma once

#include "inhand/sim/paper_scenarios.hpp"
#include "inhand/sim/scenario_runner.hpp"
#include "inhand/sim/scenario_spec.hpp"
