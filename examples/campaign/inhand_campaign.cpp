// inhand_campaign: a seeded randomized campaign of manipulation runs in the analytic
// 3-D plant, with objects and tasks the controller knows nothing about.
//
// Each case (seed s) draws, from the documented ranges below, a hand preset, an
// object (shape, size, mass), the friction coefficient, an offset of the object's
// pose from the preset's nominal pose, and a small manipulation task (a reciprocating
// translation along, or rotation about, a random unit axis), then runs
// grasp (object frozen) -> release + hold 1 s -> task -> settle 0.5 s. The controller is
// told which way gravity pulls (force_layer.gravity_direction; --gravity-unknown: not).
// A case succeeds when the grasp completes, the object is not dropped, no contact is
// lost, and the task stage meets the campaign bounds (see kBounds).
// Output: one line per failing case (with its seed, and which of the warnings that say
// the object may be lost -- release_grip_capped, beyond_capacity, workspace_limited,
// object_astray -- came first, how long before the first contact opened), a summary table,
// how many failures were so warned and how many successes raised the same warnings; exit
// code 1 when the success rate is below --min-success. Each case's task is also checked
// for reach from the hand's kinematics alone (campaign_reach.hpp): a task whose path some
// touching fingertip cannot follow within its joints' limits is said to be beyond the
// hand's reach (in its line, and counted among failures and successes; the success rate
// counts every case as drawn).
// `--first-seed S --count 1 --trace F.csv`
// writes case S's per-tick trace (the columns of inhand_scenario's trace.csv), to see
// why a seed fails.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "campaign/campaign_cases.hpp"
#include "campaign/campaign_reach.hpp"
#include "common/trace_csv.hpp"
#include "inhand/sim/scenario.hpp"

namespace {

namespace ip = inhand::plant;
namespace ex = inhand::examples;

using inhand::examples::campaign::Case;
using inhand::examples::campaign::kBounds;
using inhand::examples::campaign::make_case;

/// The controller's warnings that say the object may be lost (docs/force_layer.md): the
/// grip at release capped below what release_load asks, the load beyond the grip's cap,
/// the task asking a held joint for more than it can give, the object far from its desired
/// pose for a while.
struct Foretelling {
  inhand::ControllerWarning flag;
  const char* name;
};
constexpr Foretelling kForetelling[] = {
    {inhand::ControllerWarning::release_grip_capped, "release_grip_capped"},
    {inhand::ControllerWarning::beyond_capacity, "beyond_capacity"},
    {inhand::ControllerWarning::workspace_limited, "workspace_limited"},
    {inhand::ControllerWarning::object_astray, "object_astray"},
};
constexpr int kForetold = static_cast<int>(sizeof kForetelling / sizeof kForetelling[0]);

struct Outcome {
  bool success = false;
  std::string why;
  double rms_p = 0, fin_p = 0, rms_r = 0, fin_r = 0;
  /// s: the first tick after the grasp on which a sensed contact opened (NaN: none), and
  /// the first tick that raised each of kForetelling (NaN: never raised).
  double loss_time = std::numeric_limits<double>::quiet_NaN();
  double warned_time[kForetold];
  Outcome() {
    for (double& t : warned_time) t = std::numeric_limits<double>::quiet_NaN();
  }
  /// The task's reach (campaign_reach.hpp), checked at its first tick; finger -1: not run.
  inhand::examples::campaign::ReachMiss reach;
  /// Whether kForetelling[k] was raised on a tick before the first contact opened.
  bool warned_before_loss(int k) const { return warned_time[k] < loss_time; }  // NaN: false
};

/// Watches a run's ticks for Outcome::loss_time and warned_time.
class LossWatch {
 public:
  explicit LossWatch(Outcome& o) : o_(o) {}
  void tick(const ip::TickRecord& rec) {
    for (int k = 0; k < kForetold; ++k)
      if (std::isnan(o_.warned_time[k]) && inhand::has(rec.output->warnings, kForetelling[k].flag))
        o_.warned_time[k] = rec.time;
    if (!std::isnan(o_.loss_time)) return;
    const auto& in = rec.input->fingers;
    touching_.resize(in.size(), 0);
    for (std::size_t i = 0; i < in.size(); ++i) {
      const bool now = in[i].contact.touching;
      if (rec.stage > 0 && touching_[i] && !now) o_.loss_time = rec.time;
      touching_[i] = now ? 1 : 0;
    }
  }

 private:
  Outcome& o_;
  std::vector<char> touching_;
};

/// Checks the task's reach (campaign_reach.hpp) on the task stage's first tick, from the
/// plant's joint angles and fingertips there and the pose the task starts from (the
/// desired pose of the stage before's last tick); the touching fingers only.
class ReachWatch {
 public:
  ReachWatch(const Case& c, Outcome& o) : c_(c), o_(o) {}
  void tick(const ip::TickRecord& rec) {
    const int task = static_cast<int>(c_.spec.stages.size()) - 1;
    if (rec.stage < task) {
      start_ = *rec.desired;
      return;
    }
    if (done_ || rec.stage != task) return;
    done_ = true;
    const ip::HandPlant& plant = *rec.plant;
    std::vector<const ip::PlantFinger*> chains;
    std::vector<ip::PlantFinger::JointVector> q;
    std::vector<Eigen::Vector3d> tips;
    for (int i = 0; i < plant.finger_count(); ++i) {
      if (!plant.contact(i).active) continue;
      fingers_.push_back(i);
      chains.push_back(&plant.finger(i));
      q.push_back(plant.joint_positions(i));
      tips.push_back(plant.fingertip_pose(i).position);
    }
    o_.reach = inhand::examples::campaign::task_reach(chains, q, tips, start_,
                                                      c_.spec.stages.back().segments);
    if (o_.reach.finger >= 0) o_.reach.finger = fingers_[static_cast<std::size_t>(o_.reach.finger)];
  }

 private:
  const Case& c_;
  Outcome& o_;
  inhand::Pose<double, 3> start_{};
  bool done_ = false;
  std::vector<int> fingers_;
};

/// m: a task whose reach check misses by more is reported beyond the hand's reach. A tenth
/// of the campaign's RMS position bound: a shorter miss cannot fail a bound by itself; the
/// check's IK meets a reachable target to 1e-6 m (tests/sim/campaign_reach_test.cpp).
constexpr double kReachTolerance = 1e-4;

/// "; beyond reach: <finger> <mm> mm short at <t> s into the task".
std::string beyond_reach(const Case& c, const inhand::examples::campaign::ReachMiss& m) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "; beyond reach: %s %.2f mm short at %.2f s into the task",
                c.spec.hand.finger_names[static_cast<std::size_t>(m.finger)].c_str(),
                1e3 * m.distance, m.at);
  return buf;
}

/// "<flag> <ms> ms before the first contact opened" for the earliest warning raised before
/// that tick, or why there is none.
std::string foretold(const Outcome& o) {
  if (std::isnan(o.loss_time)) return "no contact opened";
  int first = -1;
  for (int k = 0; k < kForetold; ++k)
    if (o.warned_before_loss(k) && (first < 0 || o.warned_time[k] < o.warned_time[first]))
      first = k;
  if (first < 0) return "no warning before the first contact opened";
  char buf[160];
  std::snprintf(buf, sizeof buf, "%s %.0f ms before the first contact opened",
                kForetelling[first].name, 1e3 * (o.loss_time - o.warned_time[first]));
  return buf;
}

/// Runs a case; with `trace`, writes its per-tick trace there (committed at the end).
Outcome evaluate(const Case& c, const std::string& trace = {}) {
  Outcome o;
  LossWatch watch(o);
  ReachWatch reach(c, o);
  ip::ScenarioResult r;
  try {
    if (trace.empty()) {
      r = ip::ScenarioRunner{}.run(c.spec, [&](const ip::TickRecord& rec) {
        watch.tick(rec);
        reach.tick(rec);
      });
    } else {
      ex::TraceCsvWriter<3> writer(trace, c.spec.hand.finger_names, c.spec.object.pose.rotation);
      ex::TraceRow<3> row;
      r = ip::ScenarioRunner{}.run(c.spec, [&](const ip::TickRecord& rec) {
        watch.tick(rec);
        reach.tick(rec);
        ex::fill_trace_row<3>(rec, c.spec.stages[static_cast<std::size_t>(rec.stage)].name, row);
        writer.write(row);
      });
      ex::commit_together({&writer.file()});
    }
  } catch (const std::exception& e) {
    o.why = std::string("invalid case: ") + e.what();
    return o;
  }
  if (!r.failure.empty()) {
    o.why = r.failure;
    return o;
  }
  const ip::StageMetrics& m = r.stages.back();
  o.rms_p = m.rms_position_error;
  o.fin_p = m.final_position_error;
  o.rms_r = m.rms_orientation_error;
  o.fin_r = m.final_orientation_error;
  if (r.dropped)
    o.why = "dropped";
  else if (r.contact_losses > 0)
    o.why = "contact lost " + std::to_string(r.contact_losses) + "x";
  else if (m.rms_position_error > kBounds.rms_position_error)
    o.why = "rms position error";
  else if (m.final_position_error > kBounds.final_position_error)
    o.why = "final position error";
  else if (m.rms_orientation_error > kBounds.rms_orientation_error)
    o.why = "rms orientation error";
  else if (m.final_orientation_error > kBounds.final_orientation_error)
    o.why = "final orientation error";
  else
    o.success = true;
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Randomized manipulation campaign in the analytic 3-D plant"};
  std::uint64_t first = 0;
  long count = 1000;
  double min_success = 0.99;
  bool verbose = false;
  app.add_option("--first-seed", first, "first seed")->capture_default_str();
  app.add_option("--count", count, "number of cases")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--min-success", min_success, "required success rate in [0,1]")
      ->capture_default_str()
      ->check(CLI::Range(0.0, 1.0));
  app.add_flag("--verbose", verbose, "print every case");
  bool wide = false;
  app.add_flag(
      "--wide", wide,
      "widened ranges: mass 0.02-0.4 kg, friction 0.4-1.2, gravity along +-X/Y/Z, stiffness "
      "500 N/m-50 kN/m (normal and, in the same ratio as the plant default, tangential), lag "
      "0-10 ms, delay 0-1 tick, +-0.1 N bias on one finger");
  bool fixed_shear = false;
  app.add_flag("--fixed-shear-stiffness", fixed_shear,
               "with --wide: the contact's tangential stiffness stays at the plant default "
               "(2 kN/m) whatever the drawn normal stiffness (by default it scales with it); "
               "the wide draw the earlier regression cases were found with");
  bool keep_in_reach = false;
  app.add_flag("--keep-twist-in-reach", keep_in_reach,
               "controller Config::keep_twist_in_reach: cut the object twist where a joint held "
               "at its limit cannot follow");
  double at_risk_hold = inhand::plant::HandController::Config{}.at_risk_hold;
  app.add_option("--at-risk-hold", at_risk_hold,
                 "controller Config::at_risk_hold (s): how long the twist's cut made while the "
                 "grasp is at risk stays on after the last tick at risk")
      ->check(CLI::Range(0.0, 10.0));
  double release_load = inhand::plant::HandController::Config{}.force_layer.release_load;
  app.add_option("--release-load", release_load,
                 "controller Config::force_layer.release_load (N): the load the grip at release "
                 "is sized to take without a contact falling below min_force (0: release_grip "
                 "alone)")
      ->check(CLI::Range(0.0, 1000.0));
  bool gravity_unknown = false;
  app.add_flag("--gravity-unknown", gravity_unknown,
               "controller Config::force_layer.gravity_direction left zero: the hand is not told "
               "which way gravity pulls (by default it is, not the object's weight)");
  double gravity_tilt = inhand::plant::HandController::Config{}.grasp.gravity_tilt;
  app.add_option("--gravity-tilt", gravity_tilt,
                 "controller Config::grasp.gravity_tilt (rad): how far a pressing grasp finger "
                 "aims its normal towards gravity when told which way it pulls (0: at the "
                 "target's normal)")
      ->check(CLI::Range(0.0, 0.7853981633974483));
  std::string trace;
  app.add_option("--trace", trace, "per-tick trace CSV of the one case run (needs --count 1)");
  CLI11_PARSE(app, argc, argv);
  if (!trace.empty() && count != 1) {
    std::fprintf(stderr, "error: --trace needs --count 1\n");
    return 2;
  }

  const auto t0 = std::chrono::steady_clock::now();
  long ok = 0;
  double worst_rms_p = 0, worst_rms_r = 0, sum_rms_p = 0, sum_rms_r = 0;
  std::vector<std::uint64_t> failing;
  long opened = 0, warned = 0;  // failures in which a contact opened; of them, warned before
  long warned_by[kForetold] = {};
  long raised_in_success[kForetold] = {};  // successes that raised the flag at some tick
  long reach_failed = 0, reach_ok = 0;     // cases whose task is beyond reach (kReachTolerance)
  for (long k = 0; k < count; ++k) {
    const std::uint64_t seed = first + static_cast<std::uint64_t>(k);
    Case c = make_case(seed, wide,
                       fixed_shear ? inhand::examples::campaign::Shear::fixed
                                   : inhand::examples::campaign::Shear::scaled);
    c.spec.controller.keep_twist_in_reach = keep_in_reach;
    c.spec.controller.at_risk_hold = at_risk_hold;
    c.spec.controller.force_layer.release_load = release_load;
    if (gravity_unknown) c.spec.controller.force_layer.gravity_direction.setZero();
    c.spec.controller.grasp.gravity_tilt = gravity_tilt;
    const Outcome o = evaluate(c, trace);
    if (o.success) {
      ++ok;
      worst_rms_p = std::max(worst_rms_p, o.rms_p);
      worst_rms_r = std::max(worst_rms_r, o.rms_r);
      sum_rms_p += o.rms_p;
      sum_rms_r += o.rms_r;
      for (int j = 0; j < kForetold; ++j)
        raised_in_success[j] += std::isnan(o.warned_time[j]) ? 0 : 1;
    } else {
      failing.push_back(seed);
      if (!std::isnan(o.loss_time)) {
        ++opened;
        bool any = false;
        for (int j = 0; j < kForetold; ++j)
          if (o.warned_before_loss(j)) {
            ++warned_by[j];
            any = true;
          }
        warned += any ? 1 : 0;
      }
    }
    const bool out_of_reach = o.reach.finger >= 0 && o.reach.distance > kReachTolerance;
    if (out_of_reach) ++(o.success ? reach_ok : reach_failed);
    if (verbose || !o.success)
      std::printf("seed %6llu %-4s %-70s rms %.3fmm/%.4frad final %.3fmm/%.4frad %s%s%s%s\n",
                  static_cast<unsigned long long>(seed), o.success ? "ok" : "FAIL",
                  c.description.c_str(), 1e3 * o.rms_p, o.rms_r, 1e3 * o.fin_p, o.fin_r,
                  o.why.c_str(), o.success ? "" : "; ", o.success ? "" : foretold(o).c_str(),
                  out_of_reach ? beyond_reach(c, o.reach).c_str() : "");
  }
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double rate = static_cast<double>(ok) / static_cast<double>(count);
  std::printf(
      "\n| cases | succeeded | success rate | mean / worst RMS position error (ok cases) | "
      "mean / worst RMS orientation error | wall time |\n|---|---|---|---|---|---|\n");
  std::printf("| %ld | %ld | %.2f %% | %.3f / %.3f mm | %.4f / %.4f rad | %.1f s |\n", count, ok,
              100.0 * rate, ok ? 1e3 * sum_rms_p / static_cast<double>(ok) : 0.0, 1e3 * worst_rms_p,
              ok ? sum_rms_r / static_cast<double>(ok) : 0.0, worst_rms_r, seconds);
  std::printf("failing seeds:");
  for (auto s : failing) std::printf(" %llu", static_cast<unsigned long long>(s));
  std::printf("%s\n", failing.empty() ? " none" : "");
  std::printf("failures in which a contact opened: %ld; warned before it opened: %ld (", opened,
              warned);
  for (int k = 0; k < kForetold; ++k)
    std::printf("%s%s %ld", k ? ", " : "", kForetelling[k].name, warned_by[k]);
  std::printf("); successes that raised them: ");
  for (int k = 0; k < kForetold; ++k)
    std::printf("%s%s %ld", k ? ", " : "", kForetelling[k].name, raised_in_success[k]);
  std::printf("\n");
  std::printf(
      "tasks beyond the hand's reach (a fingertip held more than %.1f mm from the task's "
      "path by its joints' limits, checked at the task's start): %ld of the failures, %ld "
      "of the successes\n",
      1e3 * kReachTolerance, reach_failed, reach_ok);
  return rate >= min_success ? 0 : 1;
}
