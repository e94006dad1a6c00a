// Expectations on the per-stage metrics of a run (inhand/sim/metrics.hpp), read from
// the "expect" object of a scenario file and checked after the run.
//
//   "expect": {
//     "all":        { "must_not_drop": true, "max_contact_losses": 0 },
//     "hold":       { "max_settle_time": 1.0 },
//     "manipulate": { "max_rms_position_error": 5e-4, "max_final_position_error": 2e-4 }
//   }
// Keys of "expect" are stage names; "all" applies to every stage that ran. Bounds are
// inclusive and in SI units (m, rad, s; relative force error dimensionless, 0.5 =
// 50 %). Keys of one stage's object:
//   max_rms_position_error, max_final_position_error, max_peak_position_error   [m]
//   max_rms_orientation_error, max_final_orientation_error,
//   max_peak_orientation_error                                                  [rad]
//   max_settle_time [s] (a stage that never settles has settle time +inf)
//   max_relative_force_error   max over fingers and ticks of |f - f_d| / f_d
//   max_slip [m]               largest slip of one finger during the stage
//   max_contact_losses         contact losses of the stage (counted after the grasp)
//   must_not_drop, must_drop   the object (did not) exceed the drop distance
//   must_complete              the stage completed (a grasp reached `grasped`)
//   min_warning_lead [s]       where the stage lost a contact (a finger the controller
//                              reports reacquiring: contact_lost), ControllerWarning::
//                              beyond_capacity or object_astray (the earlier) was raised at
//                              least this long before the first such tick; where it dropped
//                              the object without one, one was raised in the stage. A stage
//                              that lost nothing passes.
//                              Needs the controller's warning times (StageWarningTimes):
//                              a runner that does not record them reports a violation.
// A stage named in "expect" that did not run (the run stopped early) is a violation.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <string>
#include <vector>

#include "common/json_reader.hpp"
#include "inhand/sim/metrics.hpp"

namespace inhand::examples {

struct StageExpectation {
  std::string stage;  ///< a stage name, or "all"
  std::optional<double> max_rms_position_error, max_final_position_error, max_peak_position_error;
  std::optional<double> max_rms_orientation_error, max_final_orientation_error,
      max_peak_orientation_error;
  std::optional<double> max_settle_time, max_relative_force_error, max_slip, min_warning_lead;
  std::optional<long long> max_contact_losses;
  std::optional<bool> must_not_drop, must_drop, must_complete;
};

/// When the controller first raised ControllerWarning::beyond_capacity, first reported
/// a lost contact and first raised ControllerWarning::object_astray in one stage: s into
/// the stage, -1 for never (force_layer_summary.hpp).
struct StageWarningTimes {
  std::string stage;
  double first_beyond_capacity = -1.0, first_contact_lost = -1.0, first_object_astray = -1.0;
};

struct Expectations {
  std::vector<StageExpectation> stages;
  bool empty() const noexcept { return stages.empty(); }
};

/// The name that makes a block apply to every stage.
inline const char* all_stages_key() noexcept { return "all"; }

/// Parses an "expect" object found at `path`. When `stage_names` is not empty, every
/// key must be one of them or "all". Throws JsonError.
inline Expectations parse_expectations(const Json& j, const std::string& path,
                                       const std::vector<std::string>& stage_names = {}) {
  if (!j.is_object()) throw JsonError(path, "must be an object, got " + json_type_name(j));
  Expectations e;
  ObjectReader top(j, path);
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& name = it.key();
    if (!stage_names.empty() && name != all_stages_key() &&
        std::find(stage_names.begin(), stage_names.end(), name) == stage_names.end()) {
      std::string known;
      for (const std::string& s : stage_names) known += (known.empty() ? "" : ", ") + s;
      throw JsonError(top.key_path(name),
                      "no stage of this name (stages: " + known + ", or \"all\")");
    }
    ObjectReader r = top.object(name);
    StageExpectation s;
    s.stage = name;
    const Range len = Range::non_negative_up_to(10.0);
    const Range ang = Range::non_negative_up_to(10.0);
    s.max_rms_position_error = r.optional_number("max_rms_position_error", len);
    s.max_final_position_error = r.optional_number("max_final_position_error", len);
    s.max_peak_position_error = r.optional_number("max_peak_position_error", len);
    s.max_rms_orientation_error = r.optional_number("max_rms_orientation_error", ang);
    s.max_final_orientation_error = r.optional_number("max_final_orientation_error", ang);
    s.max_peak_orientation_error = r.optional_number("max_peak_orientation_error", ang);
    s.max_settle_time = r.optional_number("max_settle_time", Range::non_negative_up_to(3600.0));
    s.max_relative_force_error =
        r.optional_number("max_relative_force_error", Range::non_negative_up_to(1e3));
    s.max_slip = r.optional_number("max_slip", len);
    s.min_warning_lead = r.optional_number("min_warning_lead", Range::non_negative_up_to(3600.0));
    if (r.has("max_contact_losses"))
      s.max_contact_losses = r.integer("max_contact_losses", 0, 0, 1000000);
    else
      r.raw("max_contact_losses");
    s.must_not_drop = r.optional_boolean("must_not_drop");
    s.must_drop = r.optional_boolean("must_drop");
    s.must_complete = r.optional_boolean("must_complete");
    r.finish();
    if (s.must_drop.value_or(false) && s.must_not_drop.value_or(false))
      throw JsonError(r.path(), "must_drop and must_not_drop are both true");
    e.stages.push_back(s);
  }
  return e;
}

namespace detail {
inline std::string fmt(double x) {
  char buf[40];
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}
inline void check_max(std::vector<std::string>& out, const std::string& stage, const char* what,
                      double value, const std::optional<double>& bound, const char* unit) {
  if (bound && !(value <= *bound))
    out.push_back("stage '" + stage + "': " + what + " = " + fmt(value) + unit + " exceeds " +
                  fmt(*bound) + unit);
}
inline void check_stage(std::vector<std::string>& out, const StageExpectation& e,
                        const plant::StageMetrics& m) {
  const std::string& n = m.name;
  check_max(out, n, "rms_position_error", m.rms_position_error, e.max_rms_position_error, " m");
  check_max(out, n, "final_position_error", m.final_position_error, e.max_final_position_error,
            " m");
  check_max(out, n, "max_position_error", m.max_position_error, e.max_peak_position_error, " m");
  check_max(out, n, "rms_orientation_error", m.rms_orientation_error, e.max_rms_orientation_error,
            " rad");
  check_max(out, n, "final_orientation_error", m.final_orientation_error,
            e.max_final_orientation_error, " rad");
  check_max(out, n, "max_orientation_error", m.max_orientation_error, e.max_peak_orientation_error,
            " rad");
  check_max(out, n, "settle_time", m.settle_time, e.max_settle_time, " s");
  check_max(out, n, "max_relative_force_error", m.max_relative_force_error,
            e.max_relative_force_error, "");
  double slip = 0.0;
  for (const auto& f : m.fingers) slip = std::max(slip, f.slip_distance);
  check_max(out, n, "slip", slip, e.max_slip, " m");
  if (e.max_contact_losses && m.contact_losses > *e.max_contact_losses)
    out.push_back("stage '" + n + "': contact_losses = " + std::to_string(m.contact_losses) +
                  " exceeds " + std::to_string(*e.max_contact_losses));
  if (e.must_not_drop.value_or(false) && m.dropped)
    out.push_back("stage '" + n + "': the object was dropped");
  if (e.must_drop.value_or(false) && !m.dropped)
    out.push_back("stage '" + n + "': the object was expected to drop but did not");
  if (e.must_complete.value_or(false) && !m.completed)
    out.push_back("stage '" + n + "': did not complete");
}
/// min_warning_lead (file comment) of stage `m` against its warning times `w` (nullptr:
/// not recorded).
inline void check_warning_lead(std::vector<std::string>& out, const StageExpectation& e,
                               const plant::StageMetrics& m, const StageWarningTimes* w) {
  if (!e.min_warning_lead) return;
  const std::string where = "stage '" + m.name + "': ";
  if (w == nullptr) {
    out.push_back(where + "min_warning_lead: the controller's warning times were not recorded");
    return;
  }
  // The earlier of the two warnings raised (-1: neither), and its name.
  const double capacity = w->first_beyond_capacity, astray = w->first_object_astray;
  const bool by_astray = astray >= 0.0 && (capacity < 0.0 || astray < capacity);
  const double warned = by_astray ? astray : capacity, lost = w->first_contact_lost;
  const std::string name = by_astray ? "object_astray" : "beyond_capacity";
  if (lost >= 0.0) {
    if (warned < 0.0 || warned > lost)
      out.push_back(where + "a contact was lost at " + fmt(lost) +
                    " s with no beyond_capacity or object_astray warning before it");
    else if (!(lost - warned >= *e.min_warning_lead))
      out.push_back(where + name + " raised " + fmt(lost - warned) +
                    " s before the first contact lost, less than " + fmt(*e.min_warning_lead) +
                    " s");
  } else if (m.dropped && warned < 0.0) {
    out.push_back(where +
                  "the object was dropped with no beyond_capacity or object_astray warning");
  }
}
}  // namespace detail

/// Human-readable violations of `e` by the metrics of a run; empty when all hold.
/// `warnings`: the controller's warning times by stage name, for min_warning_lead
/// (nullptr: not recorded, and a stage that asks for a lead is a violation).
inline std::vector<std::string> check_expectations(
    const Expectations& e, const std::vector<plant::StageMetrics>& stages,
    const std::vector<StageWarningTimes>* warnings = nullptr) {
  std::vector<std::string> out;
  const auto check = [&](const StageExpectation& s, const plant::StageMetrics& m) {
    detail::check_stage(out, s, m);
    const StageWarningTimes* w = nullptr;
    if (warnings != nullptr) {
      const auto it = std::find_if(warnings->begin(), warnings->end(),
                                   [&](const StageWarningTimes& t) { return t.stage == m.name; });
      if (it != warnings->end()) w = &*it;
    }
    detail::check_warning_lead(out, s, m, w);
  };
  for (const StageExpectation& s : e.stages) {
    if (s.stage == all_stages_key()) {
      for (const auto& m : stages) check(s, m);
      continue;
    }
    const auto it = std::find_if(stages.begin(), stages.end(),
                                 [&](const plant::StageMetrics& m) { return m.name == s.stage; });
    if (it == stages.end()) {
      out.push_back("stage '" + s.stage + "': did not run");
      continue;
    }
    check(s, *it);
  }
  return out;
}

}  // namespace inhand::examples
