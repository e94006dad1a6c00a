// Entry point of inhand_benchmarks: registers every benchmark area, runs Google
// Benchmark with the command-line flags, then fails (exit status 1) if a rule checked
// at run time was broken: an inhand per-tick call that allocated, or a fixture that
// could not be set up. Timings are never judged here.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>

#include "bench_support.hpp"

namespace inhand_bench {
std::vector<std::string>& rule_violations() {
  static std::vector<std::string> v;
  return v;
}
}  // namespace inhand_bench

int main(int argc, char** argv) {
  inhand_bench::register_floor_benchmarks();
  inhand_bench::register_kinematics_benchmarks();
  inhand_bench::register_ik_benchmarks();
  inhand_bench::register_servo_planner_benchmarks();
  inhand_bench::register_finger_benchmarks();
  inhand_bench::register_controller_benchmarks();
  inhand_bench::register_kdl_benchmarks();
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  // A benchmark function runs several times (iteration-count probing, repetitions):
  // report each broken rule once.
  std::vector<std::string> violations;
  for (const std::string& v : inhand_bench::rule_violations())
    if (std::find(violations.begin(), violations.end(), v) == violations.end())
      violations.push_back(v);
  for (const std::string& v : violations) std::fprintf(stderr, "RULE VIOLATION: %s\n", v.c_str());
  return violations.empty() ? 0 : 1;
}
