// Planar two-finger manipulation on Box2D with the library's ReactiveController
// (Dim = 2, two fingers, three joints each): grasp with the object frozen, release and
// hold, translate +-0.5 u along x and along y, rotate 0 -> -0.2 rad -> 0.
// Scale: 1 Box2D unit (u) = 1 cm of the real hand; forces in N (planar_world.hpp).
//
//   box2d_planar                      the four shipped scenarios, the negative one and the
//                                     four fault scenarios (box_gravity_<fault>)
//   box2d_planar --scenario box_flat  only the named scenario(s) (--list shows them)
//   box2d_planar --out dir            output directory (default out/box2d)
//
// Writes, per scenario, <out>/<scenario>/trace.csv (the per-tick trace of
// examples/common/trace_csv.hpp; every --decimate'th tick), summary.json (per-stage metrics
// and the expectations, examples/common/summary_json.hpp) and SVG snapshots
// (grasped.svg, mid_<stage>.svg at each manipulation's turning point, dropping.svg if the
// object leaves the grasp, end.svg); prints a
// table (and, for a fault scenario, what the controller made of the fault). Exits 1 when
// an expectation is violated (for the negative scenario, the expectation is that the
// object drops; for a fault scenario, also that the fault is reported and a lost contact
// reacquired), 2 on bad arguments, 3 on an I/O error.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "planar_scenario.hpp"
#include "report.hpp"
#include "svg.hpp"

namespace b2d = inhand::box2d_demo;
namespace ex = inhand::examples;

namespace {

std::vector<b2d::ScenarioSpec> all_scenarios() {
  std::vector<b2d::ScenarioSpec> s = b2d::shipped_scenarios();
  s.push_back(b2d::dropped_object_scenario());
  for (b2d::ScenarioSpec& f : b2d::fault_scenarios()) s.push_back(std::move(f));
  return s;
}

/// Snapshot instants: the grasp completed, the middle of the first segment of each
/// manipulation stage (the turning point: +0.5 u, -0.2 rad), the first tick the object
/// is farther than the drop distance from its desired pose, the end of the run.
struct Snapshotter {
  const b2d::ScenarioSpec& spec;
  std::string dir;
  bool lost = false;
  void operator()(const b2d::TickRecord& r) {
    const b2d::StageSpec& st = spec.stages[static_cast<std::size_t>(r.stage)];
    const double dt = spec.controller.control_period;
    std::string tag, title;
    if (st.kind == b2d::StageKind::grasp && r.stage_end) {
      tag = "grasped";
      title = spec.name + ": grasped (object frozen)";
    } else if (st.kind == b2d::StageKind::manipulate && !st.segments.empty() &&
               std::abs(r.stage_time - 0.5 * st.segments.front().duration) < 0.5 * dt) {
      tag = "mid_" + st.name;
      title = spec.name + ": " + st.name + ", turning point";
    } else if (!lost &&
               (r.actual->position - r.desired->position).norm() > spec.tolerances.drop_distance) {
      lost = true;
      tag = "dropping";
      title = spec.name + ": the object leaves the grasp";
    } else if (r.stage_end && r.stage + 1 == static_cast<int>(spec.stages.size())) {
      tag = "end";
      title = spec.name + ": end of " + st.name;
    }
    if (!tag.empty()) ex::write_file_atomically(dir + "/" + tag + ".svg", b2d::scene_svg(r, title));
  }
};

void print_summary(const b2d::ScenarioSpec& spec, const b2d::ScenarioResult& r,
                   const ex::RunSummary& s) {
  std::printf("\n%s: %s of size %.2f u, gravity %.0f u/s^2\n", spec.name.c_str(),
              to_string(spec.object.shape), spec.object.size(), spec.world.gravity);
  std::printf("  %-12s %7s %10s %10s %10s %9s %9s %9s %8s %7s\n", "stage", "time[s]", "rms_pos[u]",
              "max_pos[u]", "fin_pos[u]", "rms_rot", "max_rot", "fin_rot", "maxdF[N]", "slip[u]");
  for (const auto& m : r.stages) {
    double slip = 0.0;
    for (const auto& f : m.fingers) slip = std::max(slip, f.slip_distance);
    std::printf("  %-12s %7.3f %10.5f %10.5f %10.5f %9.5f %9.5f %9.5f %8.4f %7.4f\n",
                m.name.c_str(), m.end_time - m.start_time, m.rms_position_error,
                m.max_position_error, m.final_position_error, m.rms_orientation_error,
                m.max_orientation_error, m.final_orientation_error, m.max_force_error, slip);
  }
  std::printf("  dropped %s, contact losses %d, link contacts %d%s\n", r.dropped ? "yes" : "no",
              r.contact_losses, r.link_contacts,
              r.failure.empty() ? "" : ("; stopped: " + r.failure).c_str());
  for (std::size_t i = 0; i < r.faults.size() && i < spec.faults.size(); ++i) {
    const b2d::FaultReport& f = r.faults[i];
    const bool contact =
        f.kind == b2d::FaultSpec::Kind::tactile_dropout || f.kind == b2d::FaultSpec::Kind::knock;
    const bool finger = f.kind == b2d::FaultSpec::Kind::tactile_dropout ||
                        f.kind == b2d::FaultSpec::Kind::force_spike;
    std::printf("  fault %s%s, %s +%.3f s for %.0f ms: detected after %ld tick(s)",
                to_string(f.kind),
                finger ? (" (finger " + std::to_string(f.finger) + ")").c_str() : "",
                spec.faults[i].stage.c_str(), spec.faults[i].at, 1e3 * spec.faults[i].duration,
                f.detection_ticks);
    if (contact) std::printf(", all contacts back %ld tick(s) after it", f.reacquire_ticks);
    std::printf(", max |force integral| %.2g N s\n", f.max_force_integral);
  }
  for (const std::string& v : s.violations) std::printf("  VIOLATED: %s\n", v.c_str());
  std::printf("  %s\n",
              s.passed() ? (spec.expect_drop ? "PASS (dropped, as expected)" : "PASS") : "FAIL");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Planar two-finger manipulation on Box2D with inhand's ReactiveController"};
  std::vector<std::string> names;
  std::string out_dir = "out/box2d";
  int decimate = 1;
  bool list = false, svg = true;
  app.add_option("--scenario", names, "scenario(s) to run (default: all)");
  app.add_option("--out", out_dir, "output directory");
  app.add_option("--decimate", decimate, "write every n-th tick to the CSV trace")
      ->check(CLI::PositiveNumber);
  app.add_flag("--list", list, "list the scenarios and exit");
  app.add_flag("!--no-svg", svg, "do not write SVG snapshots");
  CLI11_PARSE(app, argc, argv);

  std::vector<b2d::ScenarioSpec> scenarios = all_scenarios();
  if (list) {
    for (const auto& s : scenarios) std::cout << s.name << '\n';
    return 0;
  }
  if (!names.empty()) {
    std::vector<b2d::ScenarioSpec> chosen;
    for (const auto& n : names) {
      bool found = false;
      for (const auto& s : scenarios)
        if (s.name == n) {
          chosen.push_back(s);
          found = true;
        }
      if (!found) {
        std::cerr << "unknown scenario '" << n << "' (see --list)\n";
        return 2;
      }
    }
    scenarios = chosen;
  }
  std::filesystem::create_directories(out_dir);
  std::printf(
      "Box2D planar demo: 1 u = 1 cm of the real hand, forces in N; control %g s, outputs in %s/\n",
      b2d::box2d_controller_config().control_period, out_dir.c_str());

  bool all_pass = true;
  try {
    for (const auto& spec : scenarios) {
      const std::string dir = out_dir + "/" + spec.name;
      std::filesystem::create_directories(dir);
      ex::TraceCsvWriter<2> trace(dir + "/trace.csv", b2d::finger_names(),
                                  inhand::so2_exp<double>(spec.object.angle));
      ex::TraceRow<2> row;
      Snapshotter snap{spec, dir};
      long tick = 0;
      const b2d::ScenarioResult r =
          b2d::ScenarioRunner{}.run(spec, [&](const b2d::TickRecord& rec) {
            if (tick++ % decimate == 0 || rec.stage_end) {
              b2d::fill_trace_row(spec, rec, row);
              trace.write(row);
            }
            if (svg) snap(rec);
          });
      const ex::RunSummary summary = b2d::run_summary(spec, r);
      ex::AtomicFile summary_file(dir + "/summary.json");
      summary_file.write(b2d::summary_document(spec, r, summary).dump(2) + "\n");
      trace.commit();
      summary_file.commit();
      print_summary(spec, r, summary);
      all_pass = all_pass && summary.passed();
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 3;
  }
  std::printf("\n%s\n", all_pass ? "all expectations met" : "SOME EXPECTATIONS VIOLATED");
  return all_pass ? 0 : 1;
}
