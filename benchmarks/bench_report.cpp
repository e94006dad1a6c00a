// inhand_bench_report: turns the JSON written by inhand_benchmarks into a markdown
// report of the key figures (scripts/bench runs it; docs/benchmarks.md shows its table).
//
//   inhand_bench_report <bench.json> <report.md>
//
// Figures (all times are wall-clock nanoseconds per tick, real_time in Benchmark's
// JSON): for every benchmark the mean, median and max over the repetitions (the
// aggregates "mean", "median" and the suite's own "max"; a run without repetitions
// has one value, reported in all three) and the heap allocations per tick (the
// largest over the repetitions). Derived figures:
//   - KDL ratios: kdl/hand/<hand> mean / controller/<hand>/double/<storage> mean, and
//     the per-finger and kinematics-only counterparts;
//   - the latency floor of the 4-joint finger, floor/sincos4 + floor/solve3x4, and the
//     finger's cost relative to it;
//   - a least-squares line through scaling/<n>/double/<storage> (tick time against the
//     finger count n): slope = cost per finger, intercept = per-tick overhead, with R^2.
// Missing benchmarks (e.g. a filtered run) show as "n/a".
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Figures {
  double mean = NAN, median = NAN, max = NAN;
  double allocs = 0.0;
  bool error = false;
  int order = 0;
};

double to_ns(double value, const std::string& unit) {
  if (unit == "us") return value * 1e3;
  if (unit == "ms") return value * 1e6;
  if (unit == "s") return value * 1e9;
  return value;
}

std::string fmt(double v, int decimals = 1) {
  if (!std::isfinite(v)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

/// A numeric field, or `fallback` when absent or null (non-finite values were turned
/// into null by read_benchmark_json).
double number(const nlohmann::json& b, const char* key, double fallback) {
  const auto it = b.find(key);
  return it != b.end() && it->is_number() ? it->get<double>() : fallback;
}

/// Google Benchmark writes non-finite statistics as bare NaN / inf (e.g. the
/// coefficient of variation of a counter that is 0 in every repetition), which is not
/// JSON; they are read as null.
nlohmann::json read_benchmark_json(std::istream& in) {
  std::stringstream text;
  text << in.rdbuf();
  static const std::regex non_finite(R"((:\s*)-?(NaN|nan|inf|Infinity)\b)");
  return nlohmann::json::parse(std::regex_replace(text.str(), non_finite, "$1null"));
}

class Report {
 public:
  explicit Report(const nlohmann::json& j) : json_(j) {
    int order = 0;
    for (const auto& b : j.at("benchmarks")) {
      const std::string run = b.value("run_name", b.value("name", std::string()));
      Figures& f = figures_[run];
      if (f.order == 0) {
        f.order = ++order;
        names_.push_back(run);
      }
      if (b.value("error_occurred", false)) {
        f.error = true;
        continue;
      }
      const double t = to_ns(number(b, "real_time", NAN), b.value("time_unit", std::string("ns")));
      const double allocs = number(b, "allocs_per_tick", 0.0);
      if (b.value("run_type", std::string()) == "aggregate") {
        const std::string agg = b.value("aggregate_name", std::string());
        if (agg == "mean") f.mean = t;
        if (agg == "median") f.median = t;
        if (agg == "max") {
          f.max = t;
          f.allocs = std::max(f.allocs, allocs);
        }
      } else {
        // Iterations: kept only when there are no aggregates (no repetitions).
        iterations_[run].push_back(t);
        f.allocs = std::max(f.allocs, allocs);
      }
    }
    for (auto& [run, ts] : iterations_) {
      Figures& f = figures_[run];
      if (!std::isfinite(f.mean) && !ts.empty()) {
        double sum = 0.0, mx = ts[0];
        for (double t : ts) {
          sum += t;
          mx = std::max(mx, t);
        }
        f.mean = sum / static_cast<double>(ts.size());
        f.median = ts[ts.size() / 2];
        f.max = mx;
      }
    }
  }

  const Figures* find(const std::string& name) const {
    const auto it = figures_.find(name);
    return it == figures_.end() ? nullptr : &it->second;
  }
  double mean(const std::string& name) const {
    const Figures* f = find(name);
    return f == nullptr ? NAN : f->mean;
  }

  std::string row(const std::string& name, const std::string& what) const {
    const Figures* f = find(name);
    std::ostringstream s;
    s << "| `" << name << "` | " << what << " | ";
    if (f == nullptr) {
      s << "n/a | n/a | n/a | n/a |";
    } else if (f->error) {
      s << "error | | | |";
    } else {
      s << fmt(f->mean) << " | " << fmt(f->median) << " | " << fmt(f->max) << " | "
        << fmt(f->allocs, 0) << " |";
    }
    return s.str();
  }

  std::string context(const std::string& key) const {
    const auto& c = json_.at("context");
    if (!c.contains(key)) return "n/a";
    const auto& v = c.at(key);
    return v.is_string() ? v.get<std::string>() : v.dump();
  }

  /// Least-squares line through (n, mean of scaling/n/double/storage).
  bool fit(const std::string& storage, double& slope, double& intercept, double& r2,
           int& points) const {
    std::vector<double> x, y;
    for (int n = 1; n <= 16; ++n) {
      const double t = mean("scaling/" + std::to_string(n) + "/double/" + storage);
      if (std::isfinite(t)) {
        x.push_back(n);
        y.push_back(t);
      }
    }
    points = static_cast<int>(x.size());
    if (points < 2) return false;
    double mx = 0, my = 0;
    for (int i = 0; i < points; ++i) {
      mx += x[static_cast<std::size_t>(i)];
      my += y[static_cast<std::size_t>(i)];
    }
    mx /= points;
    my /= points;
    double sxy = 0, sxx = 0, syy = 0;
    for (int i = 0; i < points; ++i) {
      const double dx = x[static_cast<std::size_t>(i)] - mx,
                   dy = y[static_cast<std::size_t>(i)] - my;
      sxy += dx * dy;
      sxx += dx * dx;
      syy += dy * dy;
    }
    slope = sxy / sxx;
    intercept = my - slope * mx;
    r2 = syy > 0 ? (sxy * sxy) / (sxx * syy) : 1.0;
    return true;
  }

  const std::vector<std::string>& names() const { return names_; }

 private:
  const nlohmann::json& json_;
  std::map<std::string, Figures> figures_;
  std::map<std::string, std::vector<double>> iterations_;
  std::vector<std::string> names_;
};

std::string ratio(double a, double b) {
  if (!std::isfinite(a) || !std::isfinite(b) || b <= 0) return "n/a";
  return fmt(a / b, 1) + "x";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: %s <bench.json> <report.md>\n", argv[0]);
    return 2;
  }
  nlohmann::json j;
  try {
    std::ifstream in(argv[1]);
    if (!in) throw std::runtime_error(std::string("cannot open ") + argv[1]);
    j = read_benchmark_json(in);
    if (!j.contains("benchmarks") || !j.contains("context"))
      throw std::runtime_error("not a Google Benchmark JSON file");
  } catch (const std::exception& e) {
    std::fprintf(stderr, "inhand_bench_report: %s\n", e.what());
    return 1;
  }
  const Report r(j);
  std::ostringstream md;

  md << "Machine: " << r.context("cpu_model") << ", " << r.context("num_cpus") << " CPUs at "
     << r.context("mhz_per_cpu")
     << " MHz; load average before the run: " << r.context("load_before")
     << ", after: " << r.context("load_after") << ".\n"
     << "Build: " << r.context("inhand_build") << "; Google Benchmark library built as "
     << r.context("library_build_type") << "; " << r.context("date") << ".\n\n";

  md << "Per-tick wall-clock time in ns over the repetitions (mean, median, max of the "
        "per-repetition means) and heap allocations per tick (largest over the repetitions).\n\n";
  md << "| benchmark | what | mean | median | max | allocs |\n|---|---|---:|---:|---:|---:|\n";
  const std::vector<std::pair<std::string, std::string>> key = {
      {"controller/shadow4/double/bounded", "whole tick, Shadow-like hand (3x4 + 5-DOF thumb)"},
      {"controller/shadow4/double/dynamic", "same, heap-sized controller"},
      {"controller/shadow4/float/bounded", "same, float"},
      {"controller/shadow4_coupled/double/bounded", "same, distal joints coupled"},
      {"controller/shadow5/double/bounded", "whole tick, 4x4 + 5-DOF thumb"},
      {"controller/allegro4/double/fixed", "whole tick, 4 fingers x 4 DOF"},
      {"controller/spatial3x3/double/fixed", "whole tick, 3 fingers x 3 DOF"},
      {"controller/planar2x2/double/fixed", "whole tick, planar 2 fingers x 2 DOF"},
      {"controller/planar2x3/double/fixed", "whole tick, planar 2 fingers x 3 DOF"},
      {"kdl/hand/shadow4", "KDL FK + Jacobian + pinv, 4 fingers of the Shadow-like hand"},
      {"finger/spatial4/double/fixed", "one 4-DOF finger: FK + Jacobian + servo + IK"},
      {"kdl/finger/spatial4", "KDL FK + Jacobian + pinv, one 4-DOF finger"},
      {"kinematics/spatial4/double/fixed", "FK + contact Jacobian, 4 DOF"},
      {"kdl/kinematics/spatial4", "KDL FK + Jacobian + changeRefPoint, 4 DOF"},
      {"ik/3x3/double/fixed", "IK, exact inverse"},
      {"ik/3x4/double/fixed", "IK, pseudo-inverse 3x4"},
      {"ik/3x5/double/fixed", "IK, pseudo-inverse 3x5"},
      {"ik/3x4_damped/double/fixed", "IK, damped (near-singular 3x4)"},
      {"servo/spatial/double/fixed", "hybrid servo, one finger"},
      {"planner/shadow4/double/fixed", "force planner, 4 fingers"},
      {"floor/sincos4/double", "floor: sin + cos of 4 joint angles (inhand::sin_cos)"},
      {"floor/sincos4_libm/double", "the same by std::sin and std::cos"},
      {"floor/solve3x4/double", "floor: bare 3x4 Cholesky solve chain"},
  };
  for (const auto& [name, what] : key) md << r.row(name, what) << "\n";

  md << "\nDerived figures:\n\n";
  const double kdl_hand = r.mean("kdl/hand/shadow4");
  md << "- KDL pipeline / inhand whole-hand tick, Shadow-like hand: "
     << ratio(kdl_hand, r.mean("controller/shadow4/double/bounded")) << " (bounded), "
     << ratio(kdl_hand, r.mean("controller/shadow4/double/dynamic")) << " (dynamic)\n";
  md << "- KDL / inhand, other hands (bounded): allegro4 "
     << ratio(r.mean("kdl/hand/allegro4"), r.mean("controller/allegro4/double/bounded"))
     << ", shadow5 "
     << ratio(r.mean("kdl/hand/shadow5"), r.mean("controller/shadow5/double/bounded"))
     << ", spatial3x3 "
     << ratio(r.mean("kdl/hand/spatial3x3"), r.mean("controller/spatial3x3/double/bounded"))
     << "\n";
  md << "- KDL / inhand per finger (FK + Jacobian + IK; inhand also runs the servo): 3 DOF "
     << ratio(r.mean("kdl/finger/spatial3"), r.mean("finger/spatial3/double/fixed")) << ", 4 DOF "
     << ratio(r.mean("kdl/finger/spatial4"), r.mean("finger/spatial4/double/fixed")) << ", 5 DOF "
     << ratio(r.mean("kdl/finger/spatial5"), r.mean("finger/spatial5/double/fixed")) << "\n";
  md << "- KDL / inhand kinematics only (4 DOF): "
     << ratio(r.mean("kdl/kinematics/spatial4"), r.mean("kinematics/spatial4/double/fixed"))
     << "\n";
  const double sc = r.mean("floor/sincos4/double"), sv = r.mean("floor/solve3x4/double");
  const double floor_sum = sc + sv;
  md << "- Latency floor of a 4-DOF finger: sin/cos " << fmt(sc) << " ns + solve chain " << fmt(sv)
     << " ns = " << fmt(floor_sum) << " ns; finger/spatial4/double/fixed = "
     << ratio(r.mean("finger/spatial4/double/fixed"), floor_sum) << " the floor\n";
  for (const std::string storage : {"fixed", "dynamic"}) {
    double slope = 0, intercept = 0, r2 = 0;
    int points = 0;
    if (r.fit(storage, slope, intercept, r2, points)) {
      md << "- Linear fit of the whole tick against the finger count (4-DOF fingers, double, "
         << storage << ", " << points << " hands): " << fmt(slope) << " ns per finger + "
         << fmt(intercept) << " ns, R^2 = " << fmt(r2, 4) << "\n";
    } else {
      md << "- Linear fit (" << storage << "): n/a\n";
    }
  }
  int inhand_count = 0, allocating = 0;
  std::string offenders;
  for (const std::string& name : r.names()) {
    if (name.rfind("kdl/", 0) == 0) continue;
    ++inhand_count;
    const Figures* f = r.find(name);
    if (f != nullptr && f->allocs > 0) {
      ++allocating;
      offenders += " `" + name + "`";
    }
  }
  md << "- Heap allocations per tick: "
     << (allocating == 0 ? std::string("0") : std::string("NON-ZERO in") + offenders)
     << " across all " << inhand_count << " inhand benchmarks; KDL: kdl/finger/spatial4 "
     << fmt(r.find("kdl/finger/spatial4") ? r.find("kdl/finger/spatial4")->allocs : NAN, 0)
     << ", kdl/hand/shadow4 "
     << fmt(r.find("kdl/hand/shadow4") ? r.find("kdl/hand/shadow4")->allocs : NAN, 0) << "\n";

  md << "\n<details><summary>Every benchmark</summary>\n\n"
     << "| benchmark | mean | median | max | allocs |\n|---|---:|---:|---:|---:|\n";
  for (const std::string& name : r.names()) {
    const Figures* f = r.find(name);
    md << "| `" << name << "` | " << (f->error ? "error" : fmt(f->mean)) << " | " << fmt(f->median)
       << " | " << fmt(f->max) << " | " << fmt(f->allocs, 0) << " |\n";
  }
  md << "\n</details>\n";

  std::ofstream out(argv[2]);
  out << md.str();
  std::cout << md.str();
  return out ? 0 : 1;
}
