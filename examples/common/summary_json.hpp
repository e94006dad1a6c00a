// Summary of a run as JSON: the scenario name, the per-stage metrics
// (inhand/sim/metrics.hpp) and the outcome of the expectations.
//
//   {
//     "scenario": "cylinder_translate_x",
//     "passed": true,               // no expectation violated (true when none given)
//     "expectations_checked": true, // the scenario had an "expect" object
//     "violations": [],             // human-readable, see common/expectations.hpp
//     "failure": "",                // why the run stopped early ("" if it did not)
//     "fingers": ["first", ...],
//     "stages": [ { "name", "kind", "start_time", "end_time",               [s]
//                   "rms_position_error", "max_position_error",
//                   "final_position_error",                                   [m]
//                   "rms_orientation_error", "max_orientation_error",
//                   "final_orientation_error",                                [rad]
//                   "max_force_error", "rms_force_error",                     [N]
//                   "max_relative_force_error",                               [-]
//                   "settle_time",          [s], null when the stage never settled
//                   "final_force_residual", [N]
//                   "contact_losses", "dropped", "completed",
//                   "fingers": [ { "slip_distance" [m], "contact_losses",
//                                  "max_force_error", "rms_force_error" [N],
//                                  "max_relative_force_error",
//                                  "final_desired_force", "final_measured_force" [N] } ] } ]
//   }
// SI units throughout. metrics_from_summary() reads the stages back (for tables).
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/json_reader.hpp"
#include "inhand/sim/metrics.hpp"

namespace inhand::examples {

struct RunSummary {
  std::string scenario;
  std::vector<std::string> finger_names;
  std::vector<plant::StageMetrics> stages;
  bool expectations_checked = false;
  std::vector<std::string> violations;
  std::string failure;
  bool passed() const noexcept { return violations.empty(); }
};

namespace detail {
/// JSON has no infinity: a never-settled stage is written as null.
inline Json finite_or_null(double x) { return std::isfinite(x) ? Json(x) : Json(nullptr); }
inline double number_or_inf(const Json& j) {
  return j.is_null() ? std::numeric_limits<double>::infinity() : j.get<double>();
}
}  // namespace detail

inline Json stage_metrics_json(const plant::StageMetrics& m) {
  Json s;
  s["name"] = m.name;
  s["kind"] = plant::to_string(m.kind);
  s["start_time"] = m.start_time;
  s["end_time"] = m.end_time;
  s["rms_position_error"] = m.rms_position_error;
  s["max_position_error"] = m.max_position_error;
  s["final_position_error"] = m.final_position_error;
  s["rms_orientation_error"] = m.rms_orientation_error;
  s["max_orientation_error"] = m.max_orientation_error;
  s["final_orientation_error"] = m.final_orientation_error;
  s["max_force_error"] = m.max_force_error;
  s["rms_force_error"] = m.rms_force_error;
  s["max_relative_force_error"] = m.max_relative_force_error;
  s["settle_time"] = detail::finite_or_null(m.settle_time);
  s["final_force_residual"] = m.final_force_residual;
  s["contact_losses"] = m.contact_losses;
  s["dropped"] = m.dropped;
  s["completed"] = m.completed;
  Json fingers = Json::array();
  for (const auto& f : m.fingers) {
    Json fj;
    fj["slip_distance"] = f.slip_distance;
    fj["contact_losses"] = f.contact_losses;
    fj["max_force_error"] = f.max_force_error;
    fj["rms_force_error"] = f.rms_force_error;
    fj["max_relative_force_error"] = f.max_relative_force_error;
    fj["final_desired_force"] = f.final_desired_force;
    fj["final_measured_force"] = f.final_measured_force;
    fingers.push_back(fj);
  }
  s["fingers"] = fingers;
  return s;
}

inline Json summary_json(const RunSummary& r) {
  Json j;
  j["scenario"] = r.scenario;
  j["passed"] = r.passed();
  j["expectations_checked"] = r.expectations_checked;
  j["violations"] = r.violations;
  j["failure"] = r.failure;
  j["fingers"] = r.finger_names;
  Json stages = Json::array();
  for (const auto& m : r.stages) stages.push_back(stage_metrics_json(m));
  j["stages"] = stages;
  return j;
}

/// Writes the summary atomically (2-space indented JSON and a final newline).
inline void write_summary(const std::string& path, const RunSummary& r) {
  write_file_atomically(path, summary_json(r).dump(2) + "\n");
}

/// Reads a summary written by write_summary(); throws JsonError on a malformed one.
inline RunSummary summary_from_json(const Json& j, const std::string& path = "") {
  RunSummary r;
  try {
    r.scenario = j.at("scenario").get<std::string>();
    r.expectations_checked = j.at("expectations_checked").get<bool>();
    r.violations = j.at("violations").get<std::vector<std::string>>();
    r.failure = j.at("failure").get<std::string>();
    r.finger_names = j.at("fingers").get<std::vector<std::string>>();
    for (const Json& s : j.at("stages")) {
      plant::StageMetrics m;
      m.name = s.at("name").get<std::string>();
      const std::string kind = s.at("kind").get<std::string>();
      m.kind = kind == "grasp"
                   ? plant::StageKind::grasp
                   : (kind == "manipulate" ? plant::StageKind::manipulate : plant::StageKind::hold);
      m.start_time = s.at("start_time").get<double>();
      m.end_time = s.at("end_time").get<double>();
      m.rms_position_error = s.at("rms_position_error").get<double>();
      m.max_position_error = s.at("max_position_error").get<double>();
      m.final_position_error = s.at("final_position_error").get<double>();
      m.rms_orientation_error = s.at("rms_orientation_error").get<double>();
      m.max_orientation_error = s.at("max_orientation_error").get<double>();
      m.final_orientation_error = s.at("final_orientation_error").get<double>();
      m.max_force_error = s.at("max_force_error").get<double>();
      m.rms_force_error = s.at("rms_force_error").get<double>();
      m.max_relative_force_error = s.at("max_relative_force_error").get<double>();
      m.settle_time = detail::number_or_inf(s.at("settle_time"));
      m.final_force_residual = s.at("final_force_residual").get<double>();
      m.contact_losses = s.at("contact_losses").get<int>();
      m.dropped = s.at("dropped").get<bool>();
      m.completed = s.at("completed").get<bool>();
      for (const Json& f : s.at("fingers")) {
        plant::FingerStageMetrics fm;
        fm.slip_distance = f.at("slip_distance").get<double>();
        fm.contact_losses = f.at("contact_losses").get<int>();
        fm.max_force_error = f.at("max_force_error").get<double>();
        fm.rms_force_error = f.at("rms_force_error").get<double>();
        fm.max_relative_force_error = f.at("max_relative_force_error").get<double>();
        fm.final_desired_force = f.at("final_desired_force").get<double>();
        fm.final_measured_force = f.at("final_measured_force").get<double>();
        m.fingers.push_back(fm);
      }
      r.stages.push_back(m);
    }
  } catch (const Json::exception& e) {
    throw JsonError(path, "not a run summary: " + detail::strip_json_exception_prefix(e.what()));
  }
  return r;
}

}  // namespace inhand::examples
