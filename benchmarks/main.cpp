// Entry point of inhand_benchmarks: registers every benchmark area, runs Google
// Benchmark with the command-line flags, then fails (exit status 1) if a rule checked
// at run time was broken: an inhand per-tick call that allocated, or a fixture that
// could not be set up. Timings are never judged here.
//
//   inhand_benchmarks --inhand_count=<name> [--inhand_ticks=N] [--inhand_warmup=W]
// instead sets up the one benchmark <name> (exact), runs W ticks (default 1000), then N
// ticks (default 1000) with callgrind's instrumentation on, for
//   valgrind --tool=callgrind --instr-atstart=no inhand_benchmarks --inhand_count=...
// whose total instruction count divided by N is the instructions per tick
// (scripts/bench prints it beside the times).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "bench_support.hpp"

#if defined(__has_include)
#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define INHAND_BENCH_HAS_CALLGRIND 1
#endif
#endif

namespace inhand_bench {
std::vector<std::string>& rule_violations() {
  static std::vector<std::string> v;
  return v;
}
std::map<std::string, TickCounter>& tick_counters() {
  static std::map<std::string, TickCounter> m;
  return m;
}
void instrumentation(bool on) {
#ifdef INHAND_BENCH_HAS_CALLGRIND
  if (on) {
    CALLGRIND_ZERO_STATS;
    CALLGRIND_START_INSTRUMENTATION;
  } else {
    CALLGRIND_STOP_INSTRUMENTATION;
  }
#else
  (void)on;
#endif
}
}  // namespace inhand_bench

namespace {
/// The value of `--<flag>=value` in argv, or nullptr.
const char* flag_value(int argc, char** argv, const char* flag) {
  const std::size_t n = std::strlen(flag);
  for (int i = 1; i < argc; ++i)
    if (std::strncmp(argv[i], "--", 2) == 0 && std::strncmp(argv[i] + 2, flag, n) == 0 &&
        argv[i][2 + n] == '=')
      return argv[i] + 3 + n;
  return nullptr;
}
/// --inhand_count mode; returns the exit status.
int count_ticks(const char* name, int argc, char** argv) {
  const char* ticks = flag_value(argc, argv, "inhand_ticks");
  const char* warmup = flag_value(argc, argv, "inhand_warmup");
  const long n = ticks != nullptr ? std::atol(ticks) : 1000;
  const long w = warmup != nullptr ? std::atol(warmup) : 1000;
  const auto& counters = inhand_bench::tick_counters();
  const auto it = counters.find(name);
  if (it == counters.end() || n <= 0 || w < 0) {
    std::fprintf(stderr, "--inhand_count: no benchmark '%s' (or bad --inhand_ticks)\n", name);
    return 2;
  }
  if (!it->second(w, n)) return 1;
  std::printf("%s: %ld ticks counted\n", name, n);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  inhand_bench::register_floor_benchmarks();
  inhand_bench::register_kinematics_benchmarks();
  inhand_bench::register_ik_benchmarks();
  inhand_bench::register_servo_planner_benchmarks();
  inhand_bench::register_finger_benchmarks();
  inhand_bench::register_controller_benchmarks();
  inhand_bench::register_kdl_benchmarks();
  if (const char* name = flag_value(argc, argv, "inhand_count"))
    return count_ticks(name, argc, argv);
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
