// Shared machinery of the per-tick benchmarks: the hands, seeded random inputs, the
// timed-loop runner with allocation counting, and benchmark registration.
//
// Units: SI (metres, radians, seconds, newtons), world frame, as in the library.
// Every benchmark follows one pattern: a fixture object builds everything (chains,
// solvers, controller driven into the manipulation phase, kSamples precomputed inputs)
// before the timed loop; the loop calls only the fixture's tick(), a noinline member
// that performs ONE per-tick call on the next input (inputs are rotated through, so no
// single input stays hot in the branch predictors) and hands the result to
// benchmark::DoNotOptimize. Random inputs come from seeded generators and are
// non-singular: the contact Jacobian's smallest singular value is at least
// kMinSigma, twice the default damping threshold, unless a benchmark asks for
// near-singular inputs on purpose (the damped IK path).
// Names: <area>/<case>/<scalar>/<storage>, storage one of
//   fixed    exact finger count and DOF (all Eigen storage fixed-size)
//   bounded  run-time DOF with a fixed capacity (Dof = Dynamic, MaxDof = 3 planar, 5 spatial)
//   dynamic  run-time finger count and DOF on the heap (NumFingers = Dof = MaxDof = Dynamic)
#pragma once

#include <benchmark/benchmark.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "alloc_counter.hpp"
#include "inhand/inhand.hpp"
#include "inhand/math/jacobi_eigen.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/presets_coupled.hpp"

namespace inhand_bench {

using inhand::Dynamic;
using Rng = std::mt19937_64;

/// Precomputed inputs per fixture (a power of two: the index wraps with a mask).
inline constexpr int kSamples = 256;
/// Control period of every timed tick [s].
inline constexpr double kDt = 1e-3;
/// Smallest singular value of a "non-singular" contact Jacobian [m/rad]: twice the
/// default DampingSchedule::singular_threshold (5e-3), so the undamped path runs.
inline constexpr double kMinSigma = 1e-2;
inline constexpr double kPi = 3.14159265358979323846;

template <typename S>
inline const char* scalar_name() {
  return std::is_same<S, float>::value ? "float" : "double";
}

// ---------------------------------------------------------------------------
// Hands (described once in double, converted to every benchmarked chain type)

template <int Dim>
using RefChain = inhand::FingerChain<double, Dim, Dynamic>;
template <int Dim>
using Vec = inhand::Vector<double, Dim>;

/// A hand in its nominal grasp: per finger the chain, the grasp joint angles and the
/// object's outward normal at the finger's nominal contact (from the object towards
/// the finger).
template <int Dim>
struct HandDef {
  std::string name;
  std::vector<RefChain<Dim>> fingers;
  std::vector<Eigen::VectorXd> grasp_q;
  std::vector<Vec<Dim>> normals;
  int thumb = 0;  ///< the balancing finger (force planner), the others are preset
  inhand::Pose<double, Dim> object{};

  int finger_count() const { return static_cast<int>(fingers.size()); }
  int max_dof() const {
    int m = 0;
    for (const auto& f : fingers) m = std::max(m, f.dof());
    return m;
  }
};

/// Copies a reference chain into any chain type (scalar, DOF storage).
template <typename Chain, int Dim>
Chain convert_chain(const RefChain<Dim>& src) {
  using S = typename Chain::Scalar;
  Chain c;
  if (!c.joints.resize(src.dof())) throw std::invalid_argument("chain type cannot hold this DOF");
  c.base = src.base.template cast<S>();
  for (int i = 0; i < src.dof(); ++i) {
    c.joints[i].parent_to_joint = src.joints[i].parent_to_joint.template cast<S>();
    c.joints[i].axis = src.joints[i].axis.template cast<S>();
    c.joints[i].lower = static_cast<S>(src.joints[i].lower);
    c.joints[i].upper = static_cast<S>(src.joints[i].upper);
    c.joints[i].max_velocity = static_cast<S>(src.joints[i].max_velocity);
  }
  c.joint_to_tip = src.joint_to_tip.template cast<S>();
  c.fingertip_radius = static_cast<S>(src.fingertip_radius);
  return c;
}

inline RefChain<3> from_plant(const inhand::plant::PlantFinger& f) {
  RefChain<3> r;
  r.joints.resize(f.dof());
  r.base = f.base;
  for (int i = 0; i < f.dof(); ++i) r.joints[i] = f.joints[i];
  r.joint_to_tip = f.joint_to_tip;
  r.fingertip_radius = f.fingertip_radius;
  return r;
}

inline HandDef<3> from_preset(const inhand::plant::HandPreset& p) {
  HandDef<3> h;
  h.name = p.name;
  for (std::size_t i = 0; i < p.fingers.size(); ++i) {
    h.fingers.push_back(from_plant(p.fingers[i]));
    h.grasp_q.push_back(p.grasp_configuration[i]);
    h.normals.push_back(p.approach_directions[i]);
  }
  h.thumb = p.thumb;
  h.object = p.object_pose;
  return h;
}

/// The plant's Shadow-like hand: first, middle, ring (4 DOF) and a 5-DOF thumb.
inline HandDef<3> shadow4_hand() {
  HandDef<3> h = from_preset(inhand::plant::shadow_like_hand());
  h.name = "shadow4";
  return h;
}

/// shadow4 with each finger's distal joint following its middle one (the Shadow hand's
/// tendon; sim/presets_coupled.hpp): 3 actuated joints per finger, the joint limits on.
inline HandDef<3> shadow4_coupled_hand() {
  HandDef<3> h = from_preset(inhand::plant::shadow_like_coupled_hand());
  h.name = "shadow4_coupled";
  return h;
}

/// Shadow-like with a little finger (4 DOF, 22 mm beside the ring finger): 4 x 4 DOF
/// fingers and the 5-DOF thumb.
inline HandDef<3> shadow5_hand() {
  HandDef<3> h = shadow4_hand();
  RefChain<3> little = h.fingers[2];
  little.base.position.x() -= 0.022;
  const int t = h.thumb;
  h.fingers.insert(h.fingers.begin() + t, little);
  h.grasp_q.insert(h.grasp_q.begin() + t, h.grasp_q[2]);
  h.normals.insert(h.normals.begin() + t, h.normals[2]);
  h.thumb = t + 1;
  h.name = "shadow5";
  return h;
}

/// The Shadow-like thumb without its sideways joint THJ3 (held at 0 in the grasp): a
/// 4-DOF thumb reaching the same fingertip position.
inline std::pair<RefChain<3>, Eigen::VectorXd> four_joint_thumb() {
  const HandDef<3> s = shadow4_hand();
  const RefChain<3>& t5 = s.fingers[static_cast<std::size_t>(s.thumb)];
  RefChain<3> t4;
  t4.joints.resize(4);
  t4.base = t5.base;
  t4.joints[0] = t5.joints[0];
  t4.joints[1] = t5.joints[1];
  t4.joints[2] = t5.joints[3];
  t4.joints[2].parent_to_joint = t5.joints[2].parent_to_joint * t5.joints[3].parent_to_joint;
  t4.joints[3] = t5.joints[4];
  t4.joint_to_tip = t5.joint_to_tip;
  t4.fingertip_radius = t5.fingertip_radius;
  const Eigen::VectorXd& q5 = s.grasp_q[static_cast<std::size_t>(s.thumb)];
  Eigen::VectorXd q4(4);
  q4 << q5(0), q5(1), q5(3), q5(4);
  return {t4, q4};
}

/// n fingers of 4 DOF each: the 4-joint thumb (balancing) opposing n - 1 Shadow-like
/// fingers side by side, 22 mm apart. n = 4 is the Allegro-like 4 x 4 hand.
inline HandDef<3> four_dof_hand(int n) {
  const HandDef<3> s = shadow4_hand();
  HandDef<3> h;
  h.name = "hand" + std::to_string(n) + "x4";
  h.object = s.object;
  for (int k = 0; k + 1 < n; ++k) {
    RefChain<3> f = s.fingers[0];
    f.base.position.x() = 0.022 * (0.5 * (n - 2) - k);
    h.fingers.push_back(f);
    h.grasp_q.push_back(s.grasp_q[0]);
    h.normals.push_back(s.normals[0]);
  }
  const auto thumb = four_joint_thumb();
  h.fingers.push_back(thumb.first);
  h.grasp_q.push_back(thumb.second);
  h.normals.push_back(s.normals[static_cast<std::size_t>(s.thumb)]);
  h.thumb = n - 1;
  return h;
}

inline HandDef<3> allegro4_hand() {
  HandDef<3> h = four_dof_hand(4);
  h.name = "allegro4";
  return h;
}

inline HandDef<3> three_finger_hand() {
  HandDef<3> h = from_preset(inhand::plant::three_finger_hand());
  h.name = "spatial3x3";
  return h;
}

/// Resolved-rate IK (setup only): joint angles putting the fingertip centre at
/// `target`, from `q0`. Throws if it does not converge to 1e-9 m.
template <int Dim>
Eigen::VectorXd solve_fingertip(const RefChain<Dim>& chain, const Vec<Dim>& target,
                                Eigen::VectorXd q) {
  inhand::FingerKinematics<RefChain<Dim>> ws(chain);
  inhand::ContactIk<double, Dim, Dynamic, Dynamic> ik(chain.dof());
  typename RefChain<Dim>::Jacobian J(Dim, chain.dof());
  typename RefChain<Dim>::JointVector dq(chain.dof());
  const typename RefChain<Dim>::JointVector no_limit =
      RefChain<Dim>::JointVector::Constant(chain.dof(), 1e9);
  for (int it = 0; it < 500; ++it) {
    inhand::forward_kinematics(chain, q, ws);
    const Vec<Dim> e = target - ws.fingertip.position;
    if (e.norm() < 1e-9) return q;
    inhand::point_jacobian(ws, ws.fingertip.position, J);
    ik.solve(J, Vec<Dim>(0.5 * e), no_limit, dq);
    q += dq;
  }
  throw std::runtime_error("setup: fingertip IK did not converge");
}

/// Planar hand: two opposing fingers of `dof` (2 or 3) joints squeezing a 20 mm radius
/// disc at the origin along y (finger 0 preset from +y, finger 1 balancing from -y).
inline HandDef<2> planar_hand(int dof) {
  HandDef<2> h;
  h.name = "planar2x" + std::to_string(dof);
  const std::vector<double> links =
      dof == 2 ? std::vector<double>{0.05, 0.04} : std::vector<double>{0.045, 0.035, 0.03};
  for (int side = 0; side < 2; ++side) {
    const double s = side == 0 ? 1.0 : -1.0;  // the second finger is the first turned by pi
    RefChain<2> f;
    f.joints.resize(dof);
    f.base.position = Vec<2>(-0.045 * s, 0.09 * s);
    f.base.rotation = inhand::so2_exp<double>(-0.5 * kPi + (side == 0 ? 0.0 : kPi));
    for (int i = 0; i < dof; ++i) {
      auto& j = f.joints[i];
      j.parent_to_joint.position =
          Vec<2>(i == 0 ? 0.0 : links[static_cast<std::size_t>(i - 1)], 0.0);
      j.axis = Eigen::Vector3d::UnitZ();
      j.lower = -2.5;
      j.upper = 2.5;
      j.max_velocity = 3.0;
    }
    f.joint_to_tip.position = Vec<2>(links.back(), 0.0);
    f.fingertip_radius = 0.01;
    Eigen::VectorXd q0 = Eigen::VectorXd::Constant(dof, 0.6);
    q0(0) = -0.5;
    h.grasp_q.push_back(solve_fingertip<2>(f, Vec<2>(0.0, 0.03 * s), q0));
    h.fingers.push_back(f);
    h.normals.push_back(Vec<2>(0.0, s));
  }
  h.thumb = 1;
  return h;
}

// ---------------------------------------------------------------------------
// Seeded random inputs

inline double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

/// A small random rotation (angle up to max_angle) in the plane or in space.
template <int Dim>
inhand::Rotation<double, Dim> small_rotation(Rng& rng, double max_angle) {
  if constexpr (Dim == 2) {
    return inhand::so2_exp<double>(uniform(rng, -max_angle, max_angle));
  } else {
    std::normal_distribution<double> g(0.0, 1.0);
    Eigen::Vector3d axis(g(rng), g(rng), g(rng));
    axis.normalize();
    return inhand::so3_exp<double>(Eigen::Vector3d(uniform(rng, 0.0, max_angle) * axis));
  }
}

/// One finger's sensed state.
template <int Dim>
struct FingerSample {
  Eigen::VectorXd q;
  Vec<Dim> contact = Vec<Dim>::Zero();   ///< on the fingertip sphere
  Vec<Dim> normal = Vec<Dim>::UnitX();   ///< object's outward normal at the contact
  double force = 1.0;                    ///< measured normal force [N]
  Vec<Dim> velocity = Vec<Dim>::Zero();  ///< a desired contact velocity [m/s]
  double sigma_min = 0.0;                ///< of the contact Jacobian [m/rad]
};

template <int Dim>
double contact_sigma_min(const RefChain<Dim>& chain, const Eigen::VectorXd& q, const Vec<Dim>& p) {
  inhand::FingerKinematics<RefChain<Dim>> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  typename RefChain<Dim>::Jacobian J(Dim, chain.dof());
  inhand::point_jacobian(ws, p, J);
  // Every benchmarked finger has at least Dim joints: the singular values are the
  // square roots of the eigenvalues of the Dim x Dim matrix J J^T.
  const Eigen::Matrix<double, Dim, Dim> G = J * J.transpose();
  if constexpr (Dim == 2) {
    const double mean = 0.5 * (G(0, 0) + G(1, 1)),
                 half = std::hypot(0.5 * (G(0, 0) - G(1, 1)), G(0, 1));
    return std::sqrt(std::max(0.0, G.determinant() / (mean + half)));
  } else {
    inhand::detail::SymmetricEigen<double, Dim> eig;  // math/jacobi_eigen.hpp
    eig.compute(G);
    return std::sqrt(std::max(0.0, eig.values(0)));
  }
}

/// What kind of configurations to draw.
enum class Conditioning { regular, near_singular };

/// A random sensed state of finger `chain` near `q_nominal` (joint offsets up to
/// `spread` rad, inside the joint limits), touching an object whose nominal outward
/// normal is `n_nominal` (tilted by up to 0.1 rad). regular: sigma_min >= kMinSigma;
/// near_singular: flexion almost straight (every joint but the first within 0.02 rad
/// of 0, limits ignored), touching with the tip of the distal link, sigma_min below
/// 0.8 x the damping threshold.
template <int Dim>
FingerSample<Dim> random_finger_sample(Rng& rng, const RefChain<Dim>& chain,
                                       const Eigen::VectorXd& q_nominal, const Vec<Dim>& n_nominal,
                                       Conditioning mode = Conditioning::regular,
                                       double spread = 0.1) {
  inhand::FingerKinematics<RefChain<Dim>> ws(chain);
  for (int attempt = 0; attempt < 10000; ++attempt) {
    FingerSample<Dim> s;
    s.q = q_nominal;
    for (int i = 0; i < chain.dof(); ++i) {
      const auto& j = chain.joints[i];
      if (mode == Conditioning::regular) {
        s.q(i) = std::clamp(q_nominal(i) + uniform(rng, -spread, spread), j.lower + 0.02,
                            j.upper - 0.02);
      } else {
        s.q(i) = i == 0 ? uniform(rng, -0.3, 0.3) : uniform(rng, -0.02, 0.02);
      }
    }
    inhand::forward_kinematics(chain, s.q, ws);
    if (mode == Conditioning::regular) {
      s.normal = small_rotation<Dim>(rng, 0.1) * n_nominal;
    } else {
      // Pushing with the very end of the (almost straight) finger: the contact lies on
      // the distal link's line, where the contact Jacobian loses rank.
      const Vec<Dim> link = ws.fingertip.position - ws.joint_origins.col(chain.dof() - 1);
      s.normal = -link.normalized();
    }
    s.contact = ws.fingertip.position - chain.fingertip_radius * s.normal;
    s.force = uniform(rng, 0.7, 1.3);
    for (int d = 0; d < Dim; ++d) s.velocity(d) = uniform(rng, -0.02, 0.02);
    s.sigma_min = contact_sigma_min<Dim>(chain, s.q, s.contact);
    const bool ok = mode == Conditioning::regular ? s.sigma_min >= kMinSigma : s.sigma_min < 4e-3;
    if (ok) return s;
  }
  throw std::runtime_error("setup: no configuration with the requested conditioning");
}

/// One sensed state of the whole hand: every finger touching.
template <int Dim>
struct HandSample {
  inhand::Pose<double, Dim> object{};
  std::vector<FingerSample<Dim>> fingers;
};

/// kSamples hand states around the nominal grasp: object displaced by up to 2 mm and
/// turned by up to 0.05 rad, each finger as random_finger_sample (regular).
template <int Dim>
std::vector<HandSample<Dim>> random_hand_samples(const HandDef<Dim>& hand, std::uint64_t seed) {
  Rng rng(seed);
  std::vector<HandSample<Dim>> out(kSamples);
  for (auto& s : out) {
    s.object = hand.object;
    for (int d = 0; d < Dim; ++d) s.object.position(d) += uniform(rng, -2e-3, 2e-3);
    s.object.rotation = small_rotation<Dim>(rng, 0.05) * hand.object.rotation;
    for (int i = 0; i < hand.finger_count(); ++i) {
      const auto k = static_cast<std::size_t>(i);
      s.fingers.push_back(
          random_finger_sample<Dim>(rng, hand.fingers[k], hand.grasp_q[k], hand.normals[k]));
    }
  }
  return out;
}

/// kSamples states of one finger of a hand.
template <int Dim>
std::vector<FingerSample<Dim>> random_finger_samples(const HandDef<Dim>& hand, int finger,
                                                     std::uint64_t seed,
                                                     Conditioning mode = Conditioning::regular) {
  Rng rng(seed);
  const auto k = static_cast<std::size_t>(finger);
  std::vector<FingerSample<Dim>> out;
  for (int i = 0; i < kSamples; ++i)
    out.push_back(
        random_finger_sample<Dim>(rng, hand.fingers[k], hand.grasp_q[k], hand.normals[k], mode));
  return out;
}

// ---------------------------------------------------------------------------
// Timed loop, allocation accounting, registration

/// Names of benchmarks that broke a rule checked at run time (an inhand tick that
/// allocated, a fixture that could not be set up); main() fails if any.
std::vector<std::string>& rule_violations();

/// Turns callgrind's instrumentation on or off (main.cpp; nothing outside valgrind).
void instrumentation(bool on);

/// Runs a fixture: Fixture(args...) is the set-up (not timed); the timed loop calls
/// tick() once per iteration. Fixtures that set `kMaintenancePeriod` > 0 get
/// maintain() called every that many ticks with the timer paused (e.g. a controller
/// whose clock must be restarted), and its allocations are not counted. Reports the
/// counter allocs_per_tick; for `allocation_free` benchmarks a non-zero count is a
/// rule violation.
template <typename Fixture, typename... Args>
void run_fixture(benchmark::State& state, const std::string& name, bool allocation_free,
                 Args... args) {
  std::unique_ptr<Fixture> f;
  try {
    f = std::make_unique<Fixture>(args...);
  } catch (const std::exception& e) {
    rule_violations().push_back(name + ": set-up failed: " + e.what());
    state.SkipWithError(e.what());
    return;
  }
  std::uint64_t excluded = 0;
  const std::uint64_t before = allocation_count();
  if constexpr (Fixture::kMaintenancePeriod > 0) {
    long countdown = Fixture::kMaintenancePeriod;
    for (auto _ : state) {
      benchmark::DoNotOptimize(f->tick());
      if (--countdown == 0) {
        countdown = Fixture::kMaintenancePeriod;
        state.PauseTiming();
        const std::uint64_t m0 = allocation_count();
        f->maintain();
        excluded += allocation_count() - m0;
        state.ResumeTiming();
      }
    }
  } else {
    for (auto _ : state) benchmark::DoNotOptimize(f->tick());
  }
  const std::uint64_t allocations = allocation_count() - before - excluded;
  state.counters["allocs_per_tick"] =
      benchmark::Counter(static_cast<double>(allocations), benchmark::Counter::kAvgIterations);
  if (allocation_free && allocations != 0)
    rule_violations().push_back(name + ": heap allocations in the timed loop");
}

/// Maximum over the repetitions (Benchmark's own aggregates are mean, median, stddev, cv).
inline double max_statistic(const std::vector<double>& v) {
  return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end());
}

/// Instruction counting (scripts/bench, under valgrind's callgrind): per benchmark
/// name, a function that sets the fixture up, runs `warmup` ticks, then `ticks` ticks
/// with callgrind's instrumentation on (CALLGRIND_START/STOP_INSTRUMENTATION: no-ops
/// outside valgrind). Returns false if the set-up failed.
using TickCounter = std::function<bool(long warmup, long ticks)>;
std::map<std::string, TickCounter>& tick_counters();

template <typename Fixture>
void run_counted_ticks(Fixture& f, long warmup, long ticks) {
  for (long k = 0; k < warmup; ++k) benchmark::DoNotOptimize(f.tick());
  instrumentation(true);
  for (long k = 0; k < ticks; ++k) benchmark::DoNotOptimize(f.tick());
  instrumentation(false);
}

/// Registers `Fixture` under `name` with the suite's common settings.
template <typename Fixture, typename... Args>
benchmark::internal::Benchmark* add(const std::string& name, bool allocation_free, Args... args) {
  tick_counters()[name] = [=](long warmup, long ticks) {
    try {
      Fixture f(args...);
      run_counted_ticks(f, warmup, ticks);
      return true;
    } catch (const std::exception& e) {
      std::fprintf(stderr, "%s: set-up failed: %s\n", name.c_str(), e.what());
      return false;
    }
  };
  benchmark::internal::Benchmark* b =
      benchmark::RegisterBenchmark(name.c_str(), [=](benchmark::State& state) {
        run_fixture<Fixture>(state, name, allocation_free, args...);
      });
  b->Unit(benchmark::kNanosecond);
  b->ComputeStatistics("max", max_statistic);
  return b;
}

/// Per-area registration functions (one per benchmarks/*.cpp), called by main().
void register_floor_benchmarks();
void register_kinematics_benchmarks();
void register_ik_benchmarks();
void register_servo_planner_benchmarks();
void register_finger_benchmarks();
void register_controller_benchmarks();
void register_kdl_benchmarks();

}  // namespace inhand_bench
