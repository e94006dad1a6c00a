// inhand_scenario: runs one scenario file on its plant (the analytic 3-D plant, or MuJoCo
// with "plant": {"engine": "mujoco"} in a build that found MuJoCo) and reports the
// per-stage metrics; or, with --table, tabulates the summaries of earlier runs.
//
//   inhand_scenario <scenario.json> [--out DIR] [--trace FILE.csv] [--summary FILE.json]
//                   [--check] [--quiet] [--max-plant-steps N] [--max-trace-rows N]
//   inhand_scenario --table SUMMARY.json... [--check]
//
// --out DIR writes DIR/trace.csv, DIR/summary.json and the pictures of the scene
// DIR/scene_{grasped,mid,end}.svg (scene_pictures.hpp; DIR is created); --trace and
// --summary name the files explicitly (and override --out for that file). Every output
// path is checked, and every temporary output file (next to its target) created, before
// the simulation starts; the files are renamed onto their targets only when all are
// complete. A malformed scenario file, a failed run, or a run killed by SIGINT, SIGTERM
// or SIGHUP leaves no output behind: no target is changed, the temporary files are
// removed, and so is the --out directory if this run created it. An output replaces
// what its path names, so that must be a regular file or nothing yet: a directory,
// FIFO, device, socket or symbolic link there (or an --out DIR that is not a directory)
// is refused with status 2 before the run, and left as it was.
// The work is bounded before the run, from the file alone (upper bounds: a grasp may
// complete before its timeout): a run of more than --max-plant-steps plant integration
// steps (default 10^9, about 15 minutes at the 0.9 us a step measured for
// paper/cylinder_translate_x at a 1 us step), or a trace of more than --max-trace-rows
// rows, one per control tick (default 250000: 250 s at the default 1 ms control period,
// at most about 220 MB at the 527 to 873 bytes a row of the shipped scenarios'
// traces), is refused with status 2, naming the figure, the bound and the flag; 0 lifts
// a bound.
// Exit status: 0 ok; 1 an expectation was violated (with --table: some summary says
// FAIL) and --check was given; 2 usage error, malformed / invalid scenario file, or an
// output path that is not a regular file; 3 I/O or other run-time error.
#include <sys/stat.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <exception>
#include <filesystem>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "common/expectations.hpp"
#include "common/force_layer_summary.hpp"
#include "common/summary_json.hpp"
#include "common/trace_csv.hpp"
#include "scenario_json.hpp"
#include "scene_pictures.hpp"
#ifdef INHAND_SCENARIO_WITH_MUJOCO
#include "mujoco_adapter.hpp"
#endif

namespace {

namespace ex = inhand::examples;
namespace ip = inhand::plant;

constexpr int kExitViolation = 1;
constexpr int kExitBadInput = 2;
constexpr int kExitRuntime = 3;

double max_finger_slip(const ip::StageMetrics& m) {
  double s = 0.0;
  for (const auto& f : m.fingers) s = std::max(s, f.slip_distance);
  return s;
}

std::string time_or_never(double t) {
  if (!std::isfinite(t)) return "never";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", t);
  return buf;
}

/// x in at most `width` characters: fixed with `decimals`, or fewer decimals, or %g.
std::string fit(double x, int width, int decimals) {
  char buf[48];
  if (!std::isfinite(x)) return std::isnan(x) ? "nan" : "inf";
  for (int d = decimals; d >= 0; --d) {
    std::snprintf(buf, sizeof buf, "%.*f", d, x);
    if (static_cast<int>(std::strlen(buf)) <= width) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.*g", std::max(1, width - 5), x);
  return buf;
}

/// One line per stage; lengths in mm, angles in mrad (fits 100 columns).
void print_stage_table(const ex::RunSummary& r) {
  std::printf("%-12s %-10s %6s | %-20s | %-20s | %6s %6s %6s %4s %4s %4s\n", "stage", "kind",
              "t[s]", "position err [mm]", "orient. err [mrad]", "settle", "Ferr%", "slip", "loss",
              "drop", "done");
  std::printf("%-12s %-10s %6s | %6s %6s %6s | %6s %6s %6s | %6s %6s %6s %4s %4s %4s\n", "", "", "",
              "rms", "final", "max", "rms", "final", "max", "[s]", "max", "[mm]", "", "", "");
  for (const auto& m : r.stages) {
    std::printf("%-12.12s %-10s %6s | %6s %6s %6s | %6s %6s %6s | %6s %6s %6s %4d %4s %4s\n",
                m.name.c_str(), ip::to_string(m.kind), fit(m.end_time - m.start_time, 6, 2).c_str(),
                fit(1e3 * m.rms_position_error, 6, 3).c_str(),
                fit(1e3 * m.final_position_error, 6, 3).c_str(),
                fit(1e3 * m.max_position_error, 6, 3).c_str(),
                fit(1e3 * m.rms_orientation_error, 6, 2).c_str(),
                fit(1e3 * m.final_orientation_error, 6, 2).c_str(),
                fit(1e3 * m.max_orientation_error, 6, 2).c_str(),
                time_or_never(m.settle_time).c_str(),
                fit(100.0 * m.max_relative_force_error, 6, 1).c_str(),
                fit(1e3 * max_finger_slip(m), 6, 3).c_str(), m.contact_losses,
                m.dropped ? "yes" : "no", m.completed ? "yes" : "no");
  }
}

/// First stage of a kind, or nullptr.
const ip::StageMetrics* find_stage(const ex::RunSummary& r, ip::StageKind k) {
  for (const auto& m : r.stages)
    if (m.kind == k) return &m;
  return nullptr;
}

/// The paper-style table: one row per run summary.
int print_summary_table(const std::vector<std::string>& files, bool check) {
  std::printf("%-20s %-14s | %-47s |\n", "", "stage 1 (hold)", "stage 2 (manipulate)");
  std::printf("%-20s %7s %6s | %7s %7s | %7s %7s | %5s %6s %4s %4s %s\n", "scenario", "settle",
              "peak", "pos rms", "final", "rot rms", "final", "Ferr", "slip", "loss", "drop",
              "result");
  std::printf("%-20s %7s %6s | %7s %7s | %7s %7s | %5s %6s %4s %4s\n", "", "[s]", "[mm]", "[mm]",
              "[mm]", "[mrad]", "[mrad]", "[%]", "[mm]", "", "");
  int failed = 0;
  for (const std::string& file : files) {
    ex::RunSummary r;
    try {
      r = ex::summary_from_json(ex::load_json_file(file), file);
    } catch (const ex::JsonError& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      return kExitBadInput;
    }
    const ip::StageMetrics* hold = find_stage(r, ip::StageKind::hold);
    const ip::StageMetrics* manip = find_stage(r, ip::StageKind::manipulate);
    // Slip: the largest cumulative slip of one finger after the grasp.
    std::vector<double> slip(r.finger_names.size(), 0.0);
    int losses = 0;
    bool dropped = false;
    for (const auto& m : r.stages) {
      losses += m.contact_losses;
      dropped = dropped || m.dropped;
      if (m.kind == ip::StageKind::grasp) continue;
      for (std::size_t i = 0; i < m.fingers.size() && i < slip.size(); ++i)
        slip[i] += m.fingers[i].slip_distance;
    }
    double max_slip = 0.0;
    for (double s : slip) max_slip = std::max(max_slip, s);
    auto num = [](const ip::StageMetrics* m, double v, int decimals, int width = 7) {
      return m == nullptr ? std::string("-") : fit(v, width, decimals);
    };
    const std::string result =
        !r.expectations_checked ? "(no expect)" : (r.passed() ? "PASS" : "FAIL");
    if (r.expectations_checked && !r.passed()) ++failed;
    std::printf("%-20.20s %7s %6s | %7s %7s | %7s %7s | %5s %6s %4d %4s %s\n", r.scenario.c_str(),
                hold ? time_or_never(hold->settle_time).c_str() : "-",
                num(hold, hold ? 1e3 * hold->max_position_error : 0.0, 3, 6).c_str(),
                num(manip, manip ? 1e3 * manip->rms_position_error : 0.0, 4).c_str(),
                num(manip, manip ? 1e3 * manip->final_position_error : 0.0, 4).c_str(),
                num(manip, manip ? 1e3 * manip->rms_orientation_error : 0.0, 3).c_str(),
                num(manip, manip ? 1e3 * manip->final_orientation_error : 0.0, 3).c_str(),
                num(manip, manip ? 100.0 * manip->max_relative_force_error : 0.0, 1, 5).c_str(),
                fit(1e3 * max_slip, 6, 3).c_str(), losses, dropped ? "yes" : "no", result.c_str());
  }
  std::printf(
      "stage 1 = the first hold stage: settle time and peak position error; stage 2 = the first\n"
      "manipulate stage: errors of the true pose, Ferr = max |f - f_d| / f_d over fingers and "
      "ticks;\n"
      "slip: largest slip of one finger after the grasp; loss: contact losses after the grasp.\n");
  std::printf("%zu runs, %d failed\n", files.size(), failed);
  return failed > 0 && check ? kExitViolation : 0;
}

/// The common summary plus, per stage, the force layer's record (force_layer_summary.hpp)
/// and, when faults were injected, what the controller made of them.
ex::Json summary_document(const ex::RunSummary& summary, const ip::ScenarioResult& result,
                          const ex::ForceLayerSummaryAccumulator<3>& force_layer) {
  ex::Json j = ex::summary_json(summary);
  ex::Json fl = ex::Json::array();
  auto vec = [](const auto& v) {
    ex::Json a = ex::Json::array();
    for (int k = 0; k < v.size(); ++k) a.push_back(v(k));
    return a;
  };
  auto drift = [](double d) { return d < 0.0 ? ex::Json(nullptr) : ex::Json(d); };
  for (const ex::ForceLayerStageSummary<3>& s : force_layer.stages()) {
    fl.push_back({{"stage", s.stage},
                  {"max_grip", s.max_grip},
                  {"final_grip", s.final_grip},
                  {"slip_ticks", s.slip_ticks},
                  {"beyond_capacity_ticks", s.beyond_capacity_ticks},
                  {"first_beyond_capacity", drift(s.first_beyond_capacity)},
                  {"object_astray_ticks", s.object_astray_ticks},
                  {"first_object_astray", drift(s.first_object_astray)},
                  {"first_contact_lost", drift(s.first_contact_lost)},
                  {"max_abs_force_integral", s.max_abs_force_integral},
                  {"final_load", vec(s.final_load)},
                  {"final_pose_integral", vec(s.final_pose_integral)},
                  {"force_integral_drift", drift(s.force_integral_drift)},
                  {"pose_integral_drift", drift(s.pose_integral_drift)}});
  }
  j["force_layer"] = fl;
  if (!result.faults.empty()) {
    ex::Json faults = ex::Json::array();
    for (const ip::FaultReport& f : result.faults) {
      faults.push_back({{"kind", ip::to_string(f.kind)},
                        {"finger", f.finger},
                        {"start_time", f.start_time},
                        {"detection_ticks", f.detection_ticks},
                        {"reacquire_ticks", f.reacquire_ticks},
                        {"max_force_integral", f.max_force_integral}});
    }
    j["faults"] = faults;
  }
  return j;
}

void print_faults(const ip::ScenarioResult& result) {
  for (const ip::FaultReport& f : result.faults) {
    const bool finger_fault =
        f.kind != ip::FaultSpec::Kind::pose_outlier && f.kind != ip::FaultSpec::Kind::knock;
    std::printf("fault %-15s ", ip::to_string(f.kind));
    if (finger_fault) std::printf("finger %d ", f.finger);
    std::printf("at %.3f s: ", f.start_time);
    if (f.detection_ticks >= 0)
      std::printf("reported after %ld tick(s)", f.detection_ticks);
    else
      std::printf("never reported");
    if (f.reacquire_ticks >= 0)
      std::printf(", all fingers in contact %ld tick(s) after it", f.reacquire_ticks);
    std::printf(", max |force integral| %.3g N s\n", f.max_force_integral);
  }
}

struct Options {
  std::vector<std::string> files;
  std::string out_dir, trace, summary;
  bool check = false, quiet = false, table = false;
  long long max_plant_steps = 1000000000;  ///< 0: no bound
  long long max_trace_rows = 250000;       ///< 0: no bound
};

/// A count as an integer, or in %g notation when it is too large to print exactly.
std::string count_text(double n) {
  char buf[48];
  std::snprintf(buf, sizeof buf, n < 1e15 ? "%.0f" : "%.3g", n);
  return buf;
}

/// The work bounds (--max-plant-steps, --max-trace-rows): a message saying what is
/// exceeded, or "" when the run stays within them.
std::string work_bound_violation(const Options& o, const ip::ScenarioSpec& spec,
                                 bool writes_trace) {
  const ex::RunSize size = ex::run_size(spec);
  char buf[512];
  if (o.max_plant_steps > 0 && size.plant_steps > static_cast<double>(o.max_plant_steps)) {
    std::snprintf(buf, sizeof buf,
                  "the run takes up to %s plant steps (%g s simulated at plant.time_step %g s), "
                  "more than the bound of %lld; raise it with --max-plant-steps N (0: no bound)",
                  count_text(size.plant_steps).c_str(), size.simulated_time, spec.plant.time_step,
                  o.max_plant_steps);
    return buf;
  }
  if (writes_trace && o.max_trace_rows > 0 &&
      size.control_ticks > static_cast<double>(o.max_trace_rows)) {
    std::snprintf(buf, sizeof buf,
                  "the trace takes up to %s rows (one per control tick: %g s simulated at "
                  "controller.control_period %g s), more than the bound of %lld; raise it with "
                  "--max-trace-rows N (0: no bound)",
                  count_text(size.control_ticks).c_str(), size.simulated_time,
                  spec.controller.control_period, o.max_trace_rows);
    return buf;
  }
  return "";
}

#ifdef INHAND_SCENARIO_WITH_MUJOCO
namespace md = inhand::mujoco_demo;

/// The MuJoCo run of a scenario file (engine "mujoco"): the file's MujocoPlantFile into
/// the adapter's MujocoSetup, the rest as parsed.
inhand::sim::ScenarioSpec<md::MujocoAdapter> mujoco_spec(const ex::ScenarioFile& sf) {
  inhand::sim::ScenarioSpec<md::MujocoAdapter> s;
  const ex::MujocoPlantFile& p = sf.mujoco;
  s.model_file = p.model.find('/') == std::string::npos ? md::model_path(p.model) : p.model;
  s.hand = sf.spec.hand;
  s.fingers.clear();  // the models' naming (models/*.xml): palm, <finger>_tip
  for (const std::string& name : s.hand.finger_names) s.fingers.push_back({"palm", name + "_tip"});
  s.position_gain = p.position_gain;
  s.friction = p.friction;
  s.torsional_friction = p.torsional_friction;
  s.touch_threshold = p.touch_threshold;
  s.object_mass = p.object_mass;
  s.gravity_from_model = p.gravity_from_model;
  s.name = sf.spec.name;
  s.controller = sf.spec.controller;
  s.stages = sf.spec.stages;
  s.faults = sf.spec.faults;
  s.tolerances = sf.spec.tolerances;
  return s;
}
#endif

/// What the run needs of its plant before it starts: the integration step (for the work
/// bound), and the finger chains and object shape the pictures draw.
struct PlantGeometry {
  double time_step = 0.0;  ///< s
  std::vector<ip::PlantFinger> chains;
  ip::ObjectShape object;
};

#ifdef INHAND_SCENARIO_WITH_MUJOCO
/// The shape the pictures draw for the model's object, from its body's first geom: a
/// cylinder, box or sphere as it is; a capsule as the cylinder that bounds it, an ellipsoid
/// as its bounding box, any other geom (a mesh, say) as its bounding sphere. The controller
/// never sees it: the object is unknown to it whatever its shape.
ip::ObjectShape mujoco_object_shape(const mjModel* m, const std::string& body) {
  const int b = mj_name2id(m, mjOBJ_BODY, body.c_str());
  for (int g = 0; b >= 0 && g < m->ngeom; ++g) {
    if (m->geom_bodyid[g] != b) continue;
    const mjtNum* size = m->geom_size + 3 * g;
    switch (m->geom_type[g]) {
      case mjGEOM_CYLINDER:
        return ip::ObjectShape::cylinder(size[0], size[1]);
      case mjGEOM_BOX:
        return ip::ObjectShape::box(size[0], size[1], size[2]);
      case mjGEOM_SPHERE:
        return ip::ObjectShape::sphere(size[0]);
      case mjGEOM_CAPSULE:
        return ip::ObjectShape::cylinder(size[0], size[1] + size[0]);
      case mjGEOM_ELLIPSOID:
        return ip::ObjectShape::box(size[0], size[1], size[2]);
      default:
        return ip::ObjectShape::sphere(m->geom_rbound[g]);
    }
  }
  throw ex::JsonError("plant.model", "body " + body + " has no geom");
}
#endif

/// The plant's geometry: the analytic plant's from the file; MuJoCo's from its model
/// (loaded here, so that a missing or malformed model is an input error before any output
/// is made; throws ex::JsonError naming plant.model).
PlantGeometry plant_geometry(const ex::ScenarioFile& sf) {
  PlantGeometry g;
  if (sf.engine != "mujoco") {
    g.time_step = sf.spec.plant.time_step;
    g.chains = sf.spec.hand.fingers;
    g.object = sf.spec.object.shape;
    return g;
  }
#ifdef INHAND_SCENARIO_WITH_MUJOCO
  try {
    const inhand::sim::ScenarioSpec<md::MujocoAdapter> spec = mujoco_spec(sf);
    const md::ModelPtr model = md::load_model(spec.model_file);
    g.time_step = model->opt.timestep;
    g.chains = md::finger_chains(model.get(), spec.fingers);
    g.object = mujoco_object_shape(model.get(), spec.object_body);
  } catch (const ex::JsonError&) {
    throw;
  } catch (const std::exception& e) {
    throw ex::JsonError("plant.model", e.what());
  }
  return g;
#else
  throw ex::JsonError("plant.engine",
                      "\"mujoco\": this inhand_scenario was built without MuJoCo (Debian: "
                      "libmujoco-dev; docs/mujoco.md)");
#endif
}

/// Runs the scenario on its plant, calling `observer` with every tick's record.
template <class Observer>
ip::ScenarioResult run_on_plant(const ex::ScenarioFile& sf, const Observer& observer) {
#ifdef INHAND_SCENARIO_WITH_MUJOCO
  if (sf.engine == "mujoco") {
    const inhand::sim::ScenarioSpec<md::MujocoAdapter> spec = mujoco_spec(sf);
    return inhand::sim::ScenarioRunner<md::MujocoAdapter>().run(spec, observer);
  }
#endif
  return ip::ScenarioRunner().run(sf.spec, observer);
}

int run_scenario(const Options& o) {
  ex::ScenarioFile sf;
  ip::ScenarioSpec sized;  // the spec with the engine's time step, for the work bound
  PlantGeometry geometry;
  try {
    sf = ex::load_scenario(o.files.front());  // its messages name the file
    sized = sf.spec;
    try {
      geometry = plant_geometry(sf);
    } catch (const ex::JsonError& e) {
      throw ex::JsonError(o.files.front(), e.what());
    }
    sized.plant.time_step = geometry.time_step;
  } catch (const ex::JsonError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  }
  const ip::ScenarioSpec& spec = sf.spec;

  std::string trace_path = o.trace, summary_path = o.summary;
  std::vector<std::string> scene_paths;  // --out only: the pictures (scene_pictures.hpp)
  if (!o.out_dir.empty()) {
    if (trace_path.empty()) trace_path = o.out_dir + "/trace.csv";
    if (summary_path.empty()) summary_path = o.out_dir + "/summary.json";
    for (const char* instant : {"grasped", "mid", "end"})
      scene_paths.push_back(o.out_dir + "/scene_" + instant + ".svg");
  }
  const std::string too_much = work_bound_violation(o, sized, !trace_path.empty());
  if (!too_much.empty()) {
    std::fprintf(stderr, "error: %s: %s\n", o.files.front().c_str(), too_much.c_str());
    return kExitBadInput;
  }
  // Every output is checked before anything is written or run: the outputs replace
  // what their paths name, which must be regular files or nothing yet.
  try {
    if (!o.out_dir.empty()) {
      struct stat st {};
      if (::stat(o.out_dir.c_str(), &st) == 0 && !S_ISDIR(st.st_mode))
        throw ex::OutputTargetError(o.out_dir + ": is a " + ex::file_type_name(st) +
                                    ", not a directory (--out)");
    }
    for (const std::string* p : {&trace_path, &summary_path})
      if (!p->empty()) ex::check_output_target(*p);
    for (const std::string& p : scene_paths) ex::check_output_target(p);
  } catch (const ex::OutputTargetError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitBadInput;
  }
  // A directory this run creates is removed again if the run fails or is killed (it is
  // empty then: the outputs appear only at the end).
  bool created_out_dir = false;
  auto remove_created_dir = [&]() {
    ex::remove_directory_on_signals(nullptr);
    std::error_code ec;
    if (created_out_dir) std::filesystem::remove(o.out_dir, ec);  // only if empty
  };
  // Every temporary file exists before the run (so an output that cannot be created
  // fails it early), all are complete before any is renamed, and a failure or a
  // termination signal removes them.
  std::unique_ptr<ex::TraceCsvWriter<3>> trace;
  std::unique_ptr<ex::AtomicFile> summary_file;
  std::vector<std::unique_ptr<ex::AtomicFile>> scene_files;
  try {
    if (!o.out_dir.empty()) created_out_dir = std::filesystem::create_directories(o.out_dir);
    if (created_out_dir) ex::remove_directory_on_signals(o.out_dir.c_str());
    if (!trace_path.empty())
      trace = std::make_unique<ex::TraceCsvWriter<3>>(trace_path, spec.hand.finger_names,
                                                      spec.object.pose.rotation);
    if (!summary_path.empty()) summary_file = std::make_unique<ex::AtomicFile>(summary_path);
    for (const std::string& p : scene_paths)
      scene_files.push_back(std::make_unique<ex::AtomicFile>(p));
  } catch (const std::exception& e) {
    trace.reset();
    summary_file.reset();
    scene_files.clear();
    remove_created_dir();
    std::fprintf(stderr, "error: %s\n", e.what());
    return kExitRuntime;
  }
  auto fail = [&](int status, const std::string& message) {
    trace.reset();
    summary_file.reset();
    scene_files.clear();
    remove_created_dir();
    std::fprintf(stderr, "error: %s\n", message.c_str());
    return status;
  };

  ex::RunSummary summary;
  summary.scenario = spec.name;
  summary.finger_names = spec.hand.finger_names;
  summary.expectations_checked = !sf.expect.empty();
  ip::ScenarioResult result;
  ex::ForceLayerSummaryAccumulator<3> force_layer;
  ex::ScenePictures pictures(geometry.chains, spec.hand.finger_names, geometry.object, spec.stages,
                             spec.name);
  const auto wall0 = std::chrono::steady_clock::now();
  try {
    ex::TraceRow<3> row;
    std::vector<double> stage_start(spec.stages.size(), -1.0);
    auto observer = [&](const auto& rec) {
      const std::size_t si = static_cast<std::size_t>(rec.stage);
      if (stage_start[si] < 0.0) stage_start[si] = rec.time;
      force_layer.add(rec.stage, spec.stages[si].name, rec.time - stage_start[si], *rec.output);
      if (trace) {
        ex::fill_trace_row<3>(rec, spec.stages[si].name, row);
        trace->write(row);
      }
      if (!scene_files.empty()) pictures.add(rec);
    };
    result = run_on_plant(sf, observer);
  } catch (const std::invalid_argument& e) {
    return fail(kExitBadInput, o.files.front() + ": invalid scenario: " + e.what());
  } catch (const std::exception& e) {
    return fail(kExitRuntime, e.what());
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  summary.stages = result.stages;
  summary.failure = result.failure;
  std::vector<ex::StageWarningTimes> warning_times;
  for (const ex::ForceLayerStageSummary<3>& s : force_layer.stages())
    warning_times.push_back(
        {s.stage, s.first_beyond_capacity, s.first_contact_lost, s.first_object_astray});
  summary.violations = ex::check_expectations(sf.expect, result.stages, &warning_times);
  for (std::string& v : ex::check_fault_expectations(sf.fault_expect, result.faults))
    summary.violations.push_back(std::move(v));
  try {
    if (summary_file)
      summary_file->write(summary_document(summary, result, force_layer).dump(2) + "\n");
    if (!scene_files.empty()) {
      scene_files[0]->write(pictures.grasped());
      scene_files[1]->write(pictures.mid());
      scene_files[2]->write(pictures.end());
    }
    ex::AtomicFile* scene[3] = {nullptr, nullptr, nullptr};
    for (std::size_t i = 0; i < scene_files.size() && i < 3; ++i) scene[i] = scene_files[i].get();
    ex::commit_together(
        {trace ? &trace->file() : nullptr, summary_file.get(), scene[0], scene[1], scene[2]});
  } catch (const std::exception& e) {
    return fail(kExitRuntime, e.what());
  }
  ex::remove_directory_on_signals(nullptr);

  if (!o.quiet) {
    std::printf("scenario %s (%s hand, %s plant, %zu stages): %.1f s simulated in %.2f s\n",
                spec.name.c_str(), sf.hand_preset.c_str(), sf.engine.c_str(), spec.stages.size(),
                result.stages.empty() ? 0.0 : result.stages.back().end_time, wall);
    if (!sf.description.empty()) std::printf("  %s\n", sf.description.c_str());
    print_stage_table(summary);
    print_faults(result);
    if (!result.failure.empty()) std::printf("run stopped early: %s\n", result.failure.c_str());
    if (!trace_path.empty()) std::printf("trace:   %s\n", trace_path.c_str());
    if (!summary_path.empty()) std::printf("summary: %s\n", summary_path.c_str());
    if (!scene_paths.empty())
      std::printf("scene:   %s/scene_{grasped,mid,end}.svg\n", o.out_dir.c_str());
  }
  const bool violated = !summary.violations.empty();
  std::fflush(stdout);
  if (violated && (o.check || !o.quiet)) {
    std::FILE* to = o.check ? stderr : stdout;
    std::fprintf(to, "%s: %zu expectation(s) violated:\n", spec.name.c_str(),
                 summary.violations.size());
    for (const std::string& v : summary.violations) std::fprintf(to, "  - %s\n", v.c_str());
  }
  if (!o.quiet) {
    if (!summary.expectations_checked)
      std::printf("no expectations given\n");
    else
      std::printf("%s\n", violated ? "FAIL" : "PASS");
  }
  return violated && o.check ? kExitViolation : 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "Runs a scenario file on its plant (inhand's analytic 3-D plant, or MuJoCo) and reports "
      "per-stage metrics."};
  app.add_option("files", o.files,
                 "scenario file (JSON); with --table: run summaries (summary.json) to tabulate")
      ->required();
  app.add_option("--out", o.out_dir,
                 "directory for trace.csv, summary.json and scene_{grasped,mid,end}.svg (created)");
  app.add_option("--trace", o.trace, "per-tick trace CSV file");
  app.add_option("--summary", o.summary, "summary JSON file");
  app.add_flag("--check", o.check, "exit with status 1 when an expectation is violated");
  app.add_flag("--quiet", o.quiet, "print nothing but errors and violations");
  app.add_flag("--table", o.table, "print one table row per summary file instead of running");
  app.add_option("--max-plant-steps", o.max_plant_steps,
                 "refuse (before running) a scenario of more plant integration steps; 0: no "
                 "bound")
      ->check(CLI::Range(0LL, std::numeric_limits<long long>::max()))
      ->capture_default_str();
  app.add_option("--max-trace-rows", o.max_trace_rows,
                 "refuse (before running) a trace of more rows (one per control tick); 0: no "
                 "bound")
      ->check(CLI::Range(0LL, std::numeric_limits<long long>::max()))
      ->capture_default_str();
  app.footer(
      "Outputs appear together, only after a complete run; a failed run, or one killed by\n"
      "SIGINT, SIGTERM or SIGHUP, leaves nothing behind. Each output path must name a\n"
      "regular file or nothing yet: a directory, FIFO, device, socket or symbolic link there\n"
      "is refused (status 2) before the run.\n"
      "A scenario over --max-plant-steps, or a trace over --max-trace-rows (when one is\n"
      "written), is refused (status 2) before the run; 0 lifts the bound.\n"
      "Exit status: 0 ok; 1 an expectation was violated (--table: some summary says FAIL)\n"
      "and --check was given; 2 usage error, malformed or invalid scenario file, or an\n"
      "output path that is not a regular file; 3 I/O or other run-time error.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : kExitBadInput;
  }
  if (o.table) {
    if (!o.out_dir.empty() || !o.trace.empty() || !o.summary.empty()) {
      std::fprintf(stderr, "error: --table takes only summary files (and --check)\n");
      return kExitBadInput;
    }
    return print_summary_table(o.files, o.check);
  }
  if (o.files.size() != 1) {
    std::fprintf(stderr, "error: expected exactly one scenario file, got %zu\n", o.files.size());
    return kExitBadInput;
  }
  ex::remove_temporaries_on_signals();
  return run_scenario(o);
}
