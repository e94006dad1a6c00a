// What the planar Box2D demo writes and checks, through the helpers shared with the 3-D
// scenario runner (examples/common): the per-tick trace (common/trace_csv.hpp, Dim = 2,
// columns des_/meas_/act_ x, y, angle and per finger "left"/"right" contact, forces and
// servo parts), the run summary (common/summary_json.hpp) and the expectations
// (common/expectations.hpp). The numbers are in the demo's scaled units (planar_world.hpp:
// u = 1 cm of the real hand, N, rad, s) where the common headers say SI metres; the
// summary's extra "units" entry says so. Fault scenarios add the outlier gates and one
// report per injected fault ("faults") to the summary, and their checks to the verdict.
#pragma once

#include <algorithm>
#include <string>
#include <vector>

#include "common/expectations.hpp"
#include "common/summary_json.hpp"
#include "common/trace_csv.hpp"
#include "planar_scenario.hpp"

namespace inhand::box2d_demo {

/// Finger names in traces and summaries (finger 0 comes from the left).
inline std::vector<std::string> finger_names() { return {"left", "right"}; }

/// The bounds every shipped scenario is held to (and the negative case's "it drops").
struct Bounds {
  double hold_position = 0.02;      ///< x the object's size: final error of the hold
  double hold_orientation = 0.01;   ///< rad
  double hold_settle_time = 1.0;    ///< s: within those for the rest of the hold, after this
  double translation_rms = 0.10;    ///< x the amplitude
  double translation_final = 0.05;  ///< x the amplitude
  double rotation_rms = 0.01;       ///< rad
  double rotation_final = 0.005;    ///< rad
  double amplitude = 0.005 * kLengthScale;  ///< u, translation amplitude (5 mm real)
};

inline examples::Expectations box2d_expectations(const ScenarioSpec& spec, const Bounds& b = {}) {
  examples::Expectations e;
  examples::StageExpectation all;
  all.stage = examples::all_stages_key();
  if (spec.expect_drop) {
    examples::StageExpectation hold;
    hold.stage = "hold";
    hold.must_drop = true;
    e.stages.push_back(hold);
    return e;
  }
  all.must_not_drop = true;
  // A knock may push the object off each finger once (a true contact loss, reacquired);
  // sensing faults may not lose a true contact.
  const auto knocks = std::count_if(spec.faults.begin(), spec.faults.end(), [](const FaultSpec& f) {
    return f.kind == FaultSpec::Kind::knock;
  });
  all.max_contact_losses = static_cast<long long>(kFingers) * knocks;
  e.stages.push_back(all);
  for (const StageSpec& st : spec.stages) {
    examples::StageExpectation s;
    s.stage = st.name;
    if (st.kind == StageKind::grasp) {
      s.must_complete = true;
    } else if (st.kind == StageKind::hold) {
      s.max_final_position_error = b.hold_position * spec.object.size();
      s.max_final_orientation_error = b.hold_orientation;
      s.max_settle_time = b.hold_settle_time;
    } else if (st.name == "rotate") {
      s.max_rms_orientation_error = b.rotation_rms;
      s.max_final_orientation_error = b.rotation_final;
    } else {
      s.max_rms_position_error = b.translation_rms * b.amplitude;
      s.max_final_position_error = b.translation_final * b.amplitude;
    }
    e.stages.push_back(s);
  }
  return e;
}

/// A trace row for one tick: desired pose, pose as sensed (before the tick's step), true
/// pose (after it), and the tactile input / servo output of each finger.
inline void fill_trace_row(const ScenarioSpec& spec, const TickRecord& rec,
                           examples::TraceRow<2>& row) {
  examples::fill_trace_row<2>(rec, spec.stages[static_cast<std::size_t>(rec.stage)].name, row);
}

inline examples::RunSummary run_summary(const ScenarioSpec& spec, const ScenarioResult& r) {
  examples::RunSummary s;
  s.scenario = spec.name;
  s.finger_names = finger_names();
  s.stages = r.stages;
  s.failure = r.failure;
  const examples::Expectations e = box2d_expectations(spec);
  s.expectations_checked = !e.empty();
  s.violations = examples::check_expectations(e, r.stages);
  if (r.link_contacts > 0)
    s.violations.push_back("a finger link (no tactile sensing) touched the object " +
                           std::to_string(r.link_contacts) + " time(s)");
  // Every injected fault must be reported by the controller, and a dropout or a knock
  // followed by the reacquisition of the contact (the bounds on the tick counts are the
  // tests', tests/box2d/planar_scenarios.cpp).
  for (std::size_t i = 0; i < r.faults.size() && i < spec.faults.size(); ++i) {
    const FaultReport& f = r.faults[i];
    const std::string what = std::string("fault ") + to_string(f.kind) + " (" +
                             spec.faults[i].stage + ", finger " + std::to_string(f.finger) + ")";
    if (f.start_time < 0.0)
      s.violations.push_back(what + " was never injected");
    else if (f.detection_ticks < 0)
      s.violations.push_back(what + " was not reported by the controller");
    else if ((f.kind == FaultSpec::Kind::tactile_dropout || f.kind == FaultSpec::Kind::knock) &&
             f.reacquire_ticks < 0)
      s.violations.push_back(what + ": the contact was not reacquired");
  }
  return s;
}

/// The fault reports as JSON (ticks of the 1 ms control period; -1: never).
inline examples::Json faults_json(const ScenarioSpec& spec, const ScenarioResult& r) {
  examples::Json a = examples::Json::array();
  for (std::size_t i = 0; i < r.faults.size() && i < spec.faults.size(); ++i) {
    const FaultSpec& fs = spec.faults[i];
    const FaultReport& f = r.faults[i];
    a.push_back({{"kind", to_string(f.kind)},
                 {"stage", fs.stage},
                 {"at_s", fs.at},
                 {"duration_s", fs.duration},
                 {"finger", f.finger},
                 {"magnitude_N", fs.magnitude},
                 {"vector", {fs.vector.x(), fs.vector.y()}},
                 {"start_time_s", f.start_time},
                 {"detection_ticks", f.detection_ticks},
                 {"reacquire_ticks", f.reacquire_ticks},
                 {"reported_ticks", f.reported_ticks},
                 {"max_force_integral_Ns", f.max_force_integral}});
  }
  return a;
}

/// The summary document: common/summary_json.hpp plus the plant, its units and the
/// object the controller did not know.
inline examples::Json summary_document(const ScenarioSpec& spec, const ScenarioResult& r,
                                       const examples::RunSummary& s) {
  examples::Json j = examples::summary_json(s);
  j["plant"] = "box2d";
  j["units"] = {{"length", "u: Box2D unit = 1 cm of the real hand (x100); not m"},
                {"force", "N"},
                {"angle", "rad"},
                {"time", "s"}};
  j["object"] = {{"shape", to_string(spec.object.shape)},
                 {"size_u", spec.object.size()},
                 {"density", spec.object.density},
                 {"friction", spec.object.friction}};
  j["gravity_u_per_s2"] = spec.world.gravity;
  j["control_period_s"] = spec.controller.control_period;
  j["box2d_substeps"] = spec.world.substeps;
  j["link_contacts"] = r.link_contacts;
  if (!spec.faults.empty()) {
    const auto& g = spec.controller.outlier_gates;
    j["outlier_gates"] = {{"max_object_speed_u_per_s", g.max_object_speed},
                          {"max_object_angular_speed_rad_per_s", g.max_object_angular_speed},
                          {"max_force_rate_N_per_s", g.max_force_rate},
                          {"contact_stiffness_N_per_u", g.contact_stiffness},
                          {"max_rejection_time_s", g.max_rejection_time}};
    j["faults"] = faults_json(spec, r);
  }
  return j;
}

}  // namespace inhand::box2d_demo
