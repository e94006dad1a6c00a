// What the planar Box2D demo writes and checks, through the helpers shared with the 3-D
// scenario runner (examples/common): the per-tick trace (common/trace_csv.hpp, Dim = 2,
// columns des_/meas_/act_ x, y, angle and per finger "left"/"right" contact, forces and
// servo parts), the run summary (common/summary_json.hpp) and the expectations
// (common/expectations.hpp). The numbers are in the demo's scaled units (planar_world.hpp:
// u = 1 cm of the real hand, N, rad, s) where the common headers say SI metres; the
// summary's extra "units" entry says so.
#pragma once

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
  all.max_contact_losses = 0;
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
  row.time = rec.time;
  row.stage = rec.stage;
  row.stage_name = spec.stages[static_cast<std::size_t>(rec.stage)].name;
  row.desired = *rec.desired;
  row.measured = rec.input->object_pose;
  row.actual = *rec.actual;
  examples::fill_trace_fingers<2>(*rec.input, *rec.output, row.fingers);
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
  return s;
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
  return j;
}

}  // namespace inhand::box2d_demo
