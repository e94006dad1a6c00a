// inhand_campaign: a seeded randomized campaign of manipulation runs in the analytic
// 3-D plant, with objects and tasks the controller knows nothing about.
//
// Each case (seed s) draws, from the documented ranges below, a hand preset, an
// object (shape, size, mass), the friction coefficient, an offset of the object's
// pose from the preset's nominal pose, and a small manipulation task (a reciprocating
// translation along, or rotation about, a random unit axis), then runs
// grasp (object frozen) -> release + hold 1 s -> task -> settle 0.5 s.
// A case succeeds when the grasp completes, the object is not dropped, no contact is
// lost, and the task stage meets the campaign bounds (see kBounds).
// Output: one line per failing case (with its seed) and a summary table; exit code 1
// when the success rate is below --min-success. `--first-seed S --count 1 --trace F.csv`
// writes case S's per-tick trace (the columns of inhand_scenario's trace.csv), to see
// why a seed fails.
#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "common/trace_csv.hpp"
#include "inhand/sim/scenario.hpp"

namespace {

using inhand::Pose;
using inhand::TrajectorySegment;
using inhand::Twist;
namespace ip = inhand::plant;
namespace ex = inhand::examples;

/// Documented ranges of the campaign (units: m, kg, rad).
struct Ranges {
  double cylinder_radius[2] = {0.016, 0.024};
  double cylinder_half_length[2] = {0.040, 0.055};
  double box_half_width[2] = {0.008, 0.012};  // the two short half extents
  double box_half_length[2] = {0.035, 0.050};
  double sphere_radius[2] = {0.026, 0.032};
  double mass[2] = {0.03, 0.10};
  double friction[2] = {0.5, 1.2};
  double position_offset = 0.002;  // per axis, uniform in [-a, a]
  double rotation_offset = 0.05;   // per axis (rotation vector), uniform in [-a, a]
  double translation_amount[2] = {0.002, 0.005};
  double rotation_amount[2] = {0.05, 0.20};
  double task_duration[2] = {2.0, 4.0};
};

/// Bounds a task stage must meet.
struct Bounds {
  double rms_position_error = 1e-3;       // m
  double final_position_error = 5e-4;     // m
  double rms_orientation_error = 0.02;    // rad
  double final_orientation_error = 0.01;  // rad
};
constexpr Bounds kBounds{};

double draw(std::mt19937_64& rng, const double (&r)[2]) {
  return std::uniform_real_distribution<double>(r[0], r[1])(rng);
}
Eigen::Vector3d random_unit(std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Vector3d v(n(rng), n(rng), n(rng));
  return v.normalized();
}

struct Case {
  std::uint64_t seed = 0;
  std::string description;
  ip::ScenarioSpec spec;
};

/// --wide: the ranges widened to the force layer's cases (docs/force_layer.md): mass
/// 0.02-0.4 kg, friction 0.4-1.2, gravity along one of +-X, +-Y, +-Z of the hand,
/// contact stiffness 500 N/m-50 kN/m (log-uniform), joint-velocity lag 0-10 ms and
/// 0 or 1 command of delay, and a force bias of +-10 % of the nominal grip on one
/// finger from release to the end.
struct Wide {
  double mass[2] = {0.02, 0.40};
  double friction[2] = {0.4, 1.2};
  double log10_stiffness[2] = {2.69897, 4.69897};  // 500 N/m .. 50 kN/m
  double lag[2] = {0.0, 0.01};
  double bias = 0.1;  // N, +-
};

Case make_case(std::uint64_t seed, bool wide = false) {
  const Ranges R{};
  const Wide W{};
  std::mt19937_64 rng(seed * 0x9E3779B97F4A7C15ull + 1);
  Case c;
  c.seed = seed;
  ip::ScenarioSpec& s = c.spec;
  const int hand = std::uniform_int_distribution<int>(0, 1)(rng);
  s.hand = hand == 0 ? ip::shadow_like_hand() : ip::three_finger_hand();
  const int shape = std::uniform_int_distribution<int>(0, 2)(rng);
  char buf[256];
  if (shape == 0) {
    s.object.shape =
        ip::ObjectShape::cylinder(draw(rng, R.cylinder_radius), draw(rng, R.cylinder_half_length));
    std::snprintf(buf, sizeof buf, "cylinder r=%.1fmm", 1e3 * s.object.shape.radius);
  } else if (shape == 1) {
    const double w = draw(rng, R.box_half_width), h = draw(rng, R.box_half_width);
    s.object.shape = ip::ObjectShape::box(w, h, draw(rng, R.box_half_length));
    std::snprintf(buf, sizeof buf, "box %.1fx%.1fmm", 2e3 * w, 2e3 * h);
  } else {
    s.object.shape = ip::ObjectShape::sphere(draw(rng, R.sphere_radius));
    std::snprintf(buf, sizeof buf, "sphere r=%.1fmm", 1e3 * s.object.shape.radius);
  }
  s.object.mass = draw(rng, wide ? W.mass : R.mass);
  s.plant.contact.friction = draw(rng, wide ? W.friction : R.friction);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Pose<double, 3> pose = s.hand.object_pose;
  pose.position += R.position_offset * Eigen::Vector3d(u(rng), u(rng), u(rng));
  pose.rotation =
      inhand::so3_exp<double>(R.rotation_offset * Eigen::Vector3d(u(rng), u(rng), u(rng))) *
      pose.rotation;
  s.object.pose = pose;

  ip::StageSpec grasp;
  grasp.name = "grasp";
  grasp.kind = ip::StageKind::grasp;
  grasp.duration = 3.0;
  ip::StageSpec hold;
  hold.name = "hold";
  hold.kind = ip::StageKind::hold;
  hold.release = true;
  hold.duration = 1.0;
  ip::StageSpec task;
  task.name = "task";
  task.kind = ip::StageKind::manipulate;
  task.settle = 0.5;
  Twist<double, 3> d = Twist<double, 3>::Zero();
  const Eigen::Vector3d axis = random_unit(rng);
  const bool rotate = std::uniform_int_distribution<int>(0, 1)(rng) == 1;
  const double sign = std::uniform_int_distribution<int>(0, 1)(rng) == 1 ? 1.0 : -1.0;
  double amount = 0.0;
  if (rotate) {
    amount = sign * draw(rng, R.rotation_amount);
    d.tail<3>() = amount * axis;
  } else {
    amount = sign * draw(rng, R.translation_amount);
    d.head<3>() = amount * axis;
  }
  task.segments.push_back(
      TrajectorySegment<double, 3>::reciprocate(d, draw(rng, R.task_duration), 1));
  s.stages = {grasp, hold, task};
  char wide_desc[160] = "";
  if (wide) {  // drawn after everything above, so the narrow draws are unchanged
    const Eigen::Vector3d dirs[6] = {Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(),
                                     Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY(),
                                     Eigen::Vector3d::UnitZ(), -Eigen::Vector3d::UnitZ()};
    const int g = std::uniform_int_distribution<int>(0, 5)(rng);
    s.plant.gravity = 9.81 * dirs[g];
    s.plant.contact.normal_stiffness = std::pow(10.0, draw(rng, W.log10_stiffness));
    s.plant.joint_velocity_lag = draw(rng, W.lag);
    s.plant.command_delay = std::uniform_int_distribution<int>(0, 1)(rng);
    const int n = static_cast<int>(s.hand.fingers.size());
    ip::FaultSpec bias;  // a held force offset on one finger's reading
    bias.kind = ip::FaultSpec::Kind::force_spike;
    bias.finger = std::uniform_int_distribution<int>(0, n - 1)(rng);
    bias.magnitude = (std::uniform_int_distribution<int>(0, 1)(rng) == 1 ? 1.0 : -1.0) * W.bias;
    for (const ip::StageSpec* st : {&hold, &task}) {
      bias.stage = st->name;
      bias.at = 0.0;
      bias.duration = 1e3;
      s.faults.push_back(bias);
    }
    std::snprintf(wide_desc, sizeof wide_desc,
                  " g=%s%c k=%.0fN/m lag=%.1fms delay=%d bias=%+.1fN@%d", g % 2 == 0 ? "+" : "-",
                  "XYZ"[g / 2], s.plant.contact.normal_stiffness, 1e3 * s.plant.joint_velocity_lag,
                  s.plant.command_delay, bias.magnitude, bias.finger);
  }
  char desc[512];
  std::snprintf(desc, sizeof desc, "%s %s m=%.0fg mu=%.2f %s %+.3f%s about/along (%.2f %.2f %.2f)",
                hand == 0 ? "shadow" : "three", buf, 1e3 * s.object.mass, s.plant.contact.friction,
                rotate ? "rotate" : "move", rotate ? amount : 1e3 * amount, rotate ? "rad" : "mm",
                axis.x(), axis.y(), axis.z());
  c.description = std::string(desc) + wide_desc;
  s.name = "campaign_" + std::to_string(seed);
  return c;
}

struct Outcome {
  bool success = false;
  std::string why;
  double rms_p = 0, fin_p = 0, rms_r = 0, fin_r = 0;
};

/// Runs a case; with `trace`, writes its per-tick trace there (committed at the end).
Outcome evaluate(const Case& c, const std::string& trace = {}) {
  Outcome o;
  ip::ScenarioResult r;
  try {
    if (trace.empty()) {
      r = ip::ScenarioRunner{}.run(c.spec);
    } else {
      ex::TraceCsvWriter<3> writer(trace, c.spec.hand.finger_names, c.spec.object.pose.rotation);
      ex::TraceRow<3> row;
      r = ip::ScenarioRunner{}.run(c.spec, [&](const ip::TickRecord& rec) {
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
      "500 N/m-50 kN/m, lag 0-10 ms, delay 0-1 tick, +-0.1 N bias on one finger");
  bool keep_in_reach = false;
  app.add_flag("--keep-twist-in-reach", keep_in_reach,
               "controller Config::keep_twist_in_reach: cut the object twist where a joint held "
               "at its limit cannot follow");
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
  for (long k = 0; k < count; ++k) {
    const std::uint64_t seed = first + static_cast<std::uint64_t>(k);
    Case c = make_case(seed, wide);
    c.spec.controller.keep_twist_in_reach = keep_in_reach;
    const Outcome o = evaluate(c, trace);
    if (o.success) {
      ++ok;
      worst_rms_p = std::max(worst_rms_p, o.rms_p);
      worst_rms_r = std::max(worst_rms_r, o.rms_r);
      sum_rms_p += o.rms_p;
      sum_rms_r += o.rms_r;
    } else {
      failing.push_back(seed);
    }
    if (verbose || !o.success)
      std::printf("seed %6llu %-4s %-70s rms %.3fmm/%.4frad final %.3fmm/%.4frad %s\n",
                  static_cast<unsigned long long>(seed), o.success ? "ok" : "FAIL",
                  c.description.c_str(), 1e3 * o.rms_p, o.rms_r, 1e3 * o.fin_p, o.fin_r,
                  o.why.c_str());
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
  return rate >= min_success ? 0 : 1;
}
