// Seeded random property sweep over the per-tick API.
//
// Cases: 10^4 controller ticks per hand family by default, times INHAND_TEST_SCALE
// (scripts/test runs the default; INHAND_TEST_SCALE=100 gives 10^6). Each sequence
// draws a hand (the plant's presets, or 1 to 5 random serial fingers of 1 to 6 joints
// with random axes, offsets, limits and speeds; planar and float variants too), a
// random valid configuration (gains, limits, damping, rate limit, force planner,
// grasp parameters, chain or external kinematics per finger), starts the grasp or the
// manipulation phase, and feeds 5 to 40 random VALID ticks: random time steps (some
// longer than max_tick), object poses within 5 mm / 0.2 rad of nominal, joint angles
// uniform within their limits, random touching flags, contact points within 1 cm of
// their targets, perturbed or random unit normals and forces in [0, 10] N.
// Properties, every tick:
//   - the status is never invalid_input and every output scalar is finite;
//   - |qdot_i| <= max_velocity_i for every joint, exactly (no tolerance);
//   - two controllers fed the same inputs give bit-identical outputs;
//   - after reset() and the same start, the same sequence gives the same outputs again.
// The IK sweep checks, on Jacobians of random fingers at random postures (so near-
// singular ones occur naturally), |qdot| <= gain_bound() |xdot| before limiting (up to
// 1e-9 relative rounding), exact joint limits after limiting with the direction kept,
// and bit-identical results from two solvers.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/scenario.hpp"
#include "robustness/robustness_support.hpp"

namespace {

using inhand::ControllerStatus;
using inhand_test::log_uniform;
using inhand_test::Rng;
using inhand_test::uniform;

constexpr double kPi = 3.14159265358979323846;

template <typename S>
S pick_limit(Rng& rng, S lo, S hi) {  // +inf half of the time
  return uniform<double>(rng, 0, 1) < 0.5 ? std::numeric_limits<S>::infinity()
                                          : log_uniform<S>(rng, lo, hi);
}

/// A random valid serial finger of `dof` joints (planar: axes +-z).
template <typename Chain>
Chain random_chain(Rng& rng, int dof) {
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  Chain c;
  EXPECT_TRUE(c.joints.resize(dof));
  c.base = inhand_test::random_pose<S, Dim>(rng, S(0.08));
  for (int j = 0; j < dof; ++j) {
    auto& jt = c.joints[j];
    if (j > 0) {
      jt.parent_to_joint.position = inhand_test::random_vector<S, Dim>(rng, S(-0.04), S(0.04));
      if (uniform<double>(rng, 0, 1) < 0.5)
        jt.parent_to_joint.rotation = inhand_test::random_rotation_dim<S, Dim>(rng);
    }
    if constexpr (Dim == 3) {
      jt.axis = inhand_test::random_unit_vector<S, 3>(rng);
    } else {
      jt.axis = inhand::Vector<S, 3>(S(0), S(0), uniform<double>(rng, 0, 1) < 0.5 ? S(1) : S(-1));
    }
    jt.lower = uniform<S>(rng, S(-2), S(0.5));
    jt.upper = jt.lower + uniform<S>(rng, S(0.05), S(3));
    jt.max_velocity = log_uniform<S>(rng, S(0.3), S(8));
  }
  c.joint_to_tip.position = inhand_test::random_vector<S, Dim>(rng, S(-0.05), S(0.05));
  c.fingertip_radius = uniform<S>(rng, S(0.004), S(0.015));
  EXPECT_TRUE(c.validate().ok());
  return c;
}

/// Random valid controller parameters (fingers untouched). `settle_zero` makes the
/// perfect grasp tick complete the grasp.
template <typename Ctrl>
void randomise_config(typename Ctrl::Config& c, Rng& rng, bool settle_zero) {
  using S = typename Ctrl::Scalar;
  c.control_period = log_uniform<S>(rng, S(2e-4), S(5e-3));
  c.max_tick = c.control_period * uniform<S>(rng, S(1), S(20));
  c.max_joint_acceleration = pick_limit<S>(rng, S(5), S(1e4));
  auto& pf = c.pose_feedback;
  pf.position_gain = uniform<S>(rng, S(0), S(20));
  pf.orientation_gain = uniform<S>(rng, S(0), S(20));
  pf.position_integral_gain = uniform<S>(rng, S(0), S(20));
  pf.orientation_integral_gain = uniform<S>(rng, S(0), S(20));
  pf.position_integral_limit = log_uniform<S>(rng, S(1e-4), S(1e-2));
  pf.orientation_integral_limit = log_uniform<S>(rng, S(1e-3), S(1e-1));
  pf.position_integral_band = pick_limit<S>(rng, S(1e-5), S(1e-2));
  pf.orientation_integral_band = pick_limit<S>(rng, S(1e-4), S(1e-1));
  pf.max_linear_speed = log_uniform<S>(rng, S(1e-3), S(0.5));
  pf.max_angular_speed = log_uniform<S>(rng, S(0.05), S(5));
  c.servo.motion = {uniform<S>(rng, S(0.2), S(3)), uniform<S>(rng, S(0), S(10)),
                    pick_limit<S>(rng, S(1e-3), S(1)), pick_limit<S>(rng, S(1e-2), S(1))};
  c.servo.force = {uniform<S>(rng, S(0), S(0.1)), uniform<S>(rng, S(0), S(1)),
                   pick_limit<S>(rng, S(1e-2), S(10)), pick_limit<S>(rng, S(1e-3), S(0.5))};
  c.ik.damping.singular_threshold = log_uniform<S>(rng, S(1e-4), S(5e-2));
  c.ik.damping.max_damping =
      uniform<double>(rng, 0, 1) < 0.1 ? S(0) : log_uniform<S>(rng, S(1e-4), S(5e-2));
  auto& fp = c.force_planner;
  fp.nominal_force = uniform<S>(rng, S(0.2), S(3));
  fp.min_force = fp.nominal_force * uniform<S>(rng, S(0), S(1));
  fp.max_force = fp.nominal_force * uniform<S>(rng, S(1), S(5));
  fp.regularisation = log_uniform<S>(rng, S(1e-4), S(1));
  fp.filter_time = uniform<double>(rng, 0, 1) < 0.3 ? S(0) : log_uniform<S>(rng, S(1e-3), S(0.1));
  auto& g = c.grasp;
  g.approach_gain = uniform<S>(rng, S(0.5), S(10));
  g.approach_speed = uniform<S>(rng, S(5e-3), S(0.1));
  g.creep_speed = g.approach_speed * uniform<S>(rng, S(0.05), S(1));
  g.tangential_gain = uniform<S>(rng, S(0), S(10));
  g.alignment_speed = uniform<S>(rng, S(0), S(0.2));
  g.alignment_tolerance = uniform<S>(rng, S(0.01), S(0.3));
  g.position_tolerance = uniform<S>(rng, S(2e-4), S(5e-3));
  g.force_tolerance = uniform<S>(rng, S(0.02), S(0.5));
  g.settle_time = settle_zero ? S(0) : uniform<S>(rng, S(0), S(0.2));
  g.slide_force_fraction = uniform<S>(rng, S(0.05), S(1));
  g.gravity_tilt = uniform<S>(rng, S(0), S(0.5));
  g.flat_curvature = uniform<S>(rng, S(0), S(50));
  // Gravity told in half the cases (the grasp then aims at its side, grasp.hpp).
  if (uniform<double>(rng, 0, 1) < 0.5)
    c.force_layer.gravity_direction = {uniform<S>(rng, S(-10), S(10)),
                                       uniform<S>(rng, S(-10), S(10)),
                                       uniform<S>(rng, S(-10), S(10))};
  for (auto& f : c.fingers)
    f.kinematics = uniform<double>(rng, 0, 1) < 0.3 ? Ctrl::KinematicsSource::external
                                                    : Ctrl::KinematicsSource::chain;
}

/// A random trajectory of 1 to 4 segments from `start`.
template <typename S, int Dim>
inhand::ObjectTrajectory<S, Dim> random_trajectory(Rng& rng, const inhand::Pose<S, Dim>& start) {
  inhand::ObjectTrajectory<S, Dim> t;
  t.reset(start);
  const int n = static_cast<int>(uniform<double>(rng, 1, 4.999));
  for (int i = 0; i < n; ++i) {
    inhand::Twist<S, Dim> d;
    for (int k = 0; k < d.size(); ++k)
      d(k) = k < Dim ? uniform<S>(rng, S(-0.01), S(0.01)) : uniform<S>(rng, S(-0.3), S(0.3));
    const S dur = log_uniform<S>(rng, S(0.005), S(2));
    const int kind = static_cast<int>(uniform<double>(rng, 0, 3.999));
    if (kind == 0) t.append(inhand::TrajectorySegment<S, Dim>::hold_for(dur));
    if (kind == 1)
      t.append(inhand::TrajectorySegment<S, Dim>::move(d.template head<Dim>(),
                                                       d.template head<Dim>().norm(), dur));
    if (kind == 2) {
      inhand::AngularVector<S, Dim> w = d.template tail<inhand::SpatialDim<Dim>::kRot>();
      t.append(inhand::TrajectorySegment<S, Dim>::rotate(w, w.norm(), dur));
    }
    if (kind == 3)
      t.append(inhand::TrajectorySegment<S, Dim>::reciprocate(
          d, dur, 1 + static_cast<int>(uniform<double>(rng, 0, 2.999))));
  }
  return t;
}

/// One random valid tick near the rig's grasp.
template <typename Ctrl>
void random_tick(const inhand_rob::Rig<Ctrl>& rig, Rng& rng, typename Ctrl::Input& in,
                 bool grasp_phase) {
  using S = typename Ctrl::Scalar;
  constexpr int Dim = Ctrl::Dim;
  using Vec = inhand::Vector<S, Dim>;
  in.time += uniform<S>(rng, S(1e-5), S(3) * rig.config.max_tick);
  in.object_pose.position =
      rig.object.position + inhand_test::random_vector<S, Dim>(rng, S(-5e-3), S(5e-3));
  const inhand::AngularVector<S, Dim> w =
      inhand_test::random_vector<S, inhand::SpatialDim<Dim>::kRot>(rng, S(-0.2), S(0.2));
  in.object_pose.rotation = inhand::rotation_exp<S>(w) * rig.object.rotation;
  for (int i = 0; i < rig.fingers(); ++i) {
    auto& f = in.fingers[static_cast<std::size_t>(i)];
    const auto& t = rig.targets[static_cast<std::size_t>(i)];
    f.joint_positions = inhand_test::random_joint_angles(rig.chain(i), rng);
    f.contact.touching = uniform<double>(rng, 0, 1) < 0.6;
    f.contact.contact_point =
        t.contact_point + inhand_test::random_vector<S, Dim>(rng, S(-0.01), S(0.01));
    Vec n = uniform<double>(rng, 0, 1) < 0.1
                ? inhand_test::random_unit_vector<S, Dim>(rng)
                : Vec(t.normal + inhand_test::random_vector<S, Dim>(rng, S(-0.5), S(0.5)));
    if (!(n.norm() > S(1e-3))) n = t.normal;
    f.contact.normal = n.normalized();
    f.contact.normal_force =
        uniform<double>(rng, 0, 1) < 0.05 ? S(0) : uniform<S>(rng, S(0), S(10));
    if (rig.external(i)) {
      inhand_rob::fill_external(rig, i, f, grasp_phase);
      for (int c = 0; c < f.jacobian.cols(); ++c)
        f.jacobian.col(c) += inhand_test::random_vector<S, Dim>(rng, S(-1e-3), S(1e-3));
    }
  }
}

struct SweepStats {
  long ticks = 0;
  long sequences = 0;
  long limited = 0, damped = 0, rate_limited = 0, contact_lost = 0, manipulation = 0;
  double worst_ratio = 0.0;
};

/// Starts `ctl` on the sequence: grasp, or a completed grasp and a trajectory.
template <typename Ctrl>
bool start(Ctrl& ctl, const inhand_rob::Rig<Ctrl>& rig, bool manipulate,
           const inhand::ObjectTrajectory<typename Ctrl::Scalar, Ctrl::Dim>& traj,
           typename Ctrl::Output& out) {
  if (!ctl.start_grasp(rig.targets).ok()) return false;
  if (!manipulate) return true;
  const auto in = inhand_rob::perfect_grasp_input(rig, ctl, typename Ctrl::Scalar(0));
  if (ctl.update(in, out) != ControllerStatus::grasped) return false;
  return ctl.start_manipulation(traj).ok();
}

/// Runs one random sequence on a rig and checks every property; returns false after
/// the first violation (reported with the sequence number for reproduction).
template <typename Ctrl>
bool run_sequence(const inhand_rob::Rig<Ctrl>& rig, Rng& rng, long seq, int ticks,
                  SweepStats& stats) {
  using S = typename Ctrl::Scalar;
  Ctrl a, b;
  if (!a.configure(rig.config).ok() || !b.configure(rig.config).ok()) {
    ADD_FAILURE() << "sequence " << seq
                  << ": random configuration rejected: " << Ctrl::validate(rig.config).field;
    return false;
  }
  const bool manipulate = rig.config.grasp.settle_time == S(0);
  const auto traj = random_trajectory<S, Ctrl::Dim>(rng, rig.object);
  typename Ctrl::Output oa = a.make_output(), ob = b.make_output();
  if (!start(a, rig, manipulate, traj, oa) || !start(b, rig, manipulate, traj, ob)) {
    ADD_FAILURE() << "sequence " << seq << ": could not start";
    return false;
  }
  std::vector<typename Ctrl::Input> inputs;
  std::vector<typename Ctrl::Output> outputs;
  std::vector<ControllerStatus> statuses;
  typename Ctrl::Input in = a.make_input();
  in.time = S(0);
  for (int k = 0; k < ticks; ++k) {
    random_tick(rig, rng, in, !manipulate);
    const ControllerStatus sa = a.update(in, oa);
    const ControllerStatus sb = b.update(in, ob);
    ++stats.ticks;
    if (sa == ControllerStatus::invalid_input) {
      ADD_FAILURE() << "sequence " << seq << " tick " << k << ": valid input rejected, field "
                    << inhand::to_string(oa.fault.field) << " finger " << oa.fault.finger;
      return false;
    }
    if (!inhand_rob::output_finite<Ctrl>(oa)) {
      ADD_FAILURE() << "sequence " << seq << " tick " << k << ": non-finite output";
      return false;
    }
    const double ratio = inhand_rob::worst_limit_ratio(rig, oa);
    stats.worst_ratio = std::max(stats.worst_ratio, ratio);
    if (!inhand_rob::within_limits(rig, oa)) {
      ADD_FAILURE() << "sequence " << seq << " tick " << k
                    << ": joint velocity limit exceeded, |qdot|/limit = " << ratio << " (1 + "
                    << (ratio - 1.0) << ")";
      return false;
    }
    if (sa != sb || !inhand_rob::same_output<Ctrl>(oa, ob)) {
      ADD_FAILURE() << "sequence " << seq << " tick " << k << ": two instances differ";
      return false;
    }
    stats.limited += inhand::has(oa.warnings, inhand::ControllerWarning::joint_velocity_limited);
    stats.damped += inhand::has(oa.warnings, inhand::ControllerWarning::ik_damped);
    stats.rate_limited += inhand::has(oa.warnings, inhand::ControllerWarning::rate_limited);
    stats.contact_lost += sa == ControllerStatus::contact_lost;
    stats.manipulation += manipulate;
    inputs.push_back(in);
    outputs.push_back(oa);
    statuses.push_back(sa);
  }
  // reset(): the same start and inputs give the same outputs again.
  a.reset();
  typename Ctrl::Output oc = a.make_output();
  if (!start(a, rig, manipulate, traj, oc)) {
    ADD_FAILURE() << "sequence " << seq << ": could not restart after reset()";
    return false;
  }
  for (int k = 0; k < ticks; ++k) {
    const ControllerStatus sc = a.update(inputs[static_cast<std::size_t>(k)], oc);
    if (sc != statuses[static_cast<std::size_t>(k)] ||
        !inhand_rob::same_output<Ctrl>(oc, outputs[static_cast<std::size_t>(k)])) {
      ADD_FAILURE() << "sequence " << seq << " tick " << k << ": differs after reset()";
      return false;
    }
  }
  ++stats.sequences;
  return true;
}

template <typename Ctrl, typename MakeRig>
SweepStats sweep(std::uint64_t seed, long total_ticks, MakeRig make_rig) {
  Rng rng = inhand_test::make_rng(seed);
  SweepStats stats;
  long seq = 0;
  while (stats.ticks < total_ticks) {
    inhand_rob::Rig<Ctrl> rig = make_rig(rng);
    const bool manipulate = uniform<double>(rng, 0, 1) < 0.5;
    randomise_config<Ctrl>(rig.config, rng, manipulate);
    const int ticks = static_cast<int>(std::min<long>(
        total_ticks - stats.ticks, static_cast<long>(uniform<double>(rng, 5, 40.999))));
    if (!run_sequence(rig, rng, seq++, ticks, stats)) break;
  }
  return stats;
}

void record(const SweepStats& s, long expected) {
  inhand_test::record("ticks", static_cast<double>(s.ticks));
  inhand_test::record("sequences", static_cast<double>(s.sequences));
  inhand_test::record("ticks_manipulating", static_cast<double>(s.manipulation));
  inhand_test::record("ticks_velocity_limited", static_cast<double>(s.limited));
  inhand_test::record("ticks_damped", static_cast<double>(s.damped));
  inhand_test::record("ticks_rate_limited", static_cast<double>(s.rate_limited));
  inhand_test::record("ticks_contact_lost", static_cast<double>(s.contact_lost));
  inhand_test::record("worst_qdot_over_limit", s.worst_ratio);
  EXPECT_EQ(s.ticks, expected);
  // The sweep must actually reach the interesting branches.
  EXPECT_GT(s.manipulation, 0);
  EXPECT_GT(s.limited, 0);
  EXPECT_GT(s.damped, 0);
  EXPECT_GT(s.rate_limited, 0);
  EXPECT_GT(s.contact_lost, 0);
}

long base_ticks(long n) { return n * inhand_test::scale(); }

TEST(PropertySweep, RandomHandsRunTimeSized) {
  using Ctrl = inhand::plant::HandController;
  const long n = base_ticks(10000);
  const SweepStats s = sweep<Ctrl>(0x5eed0001, n, [](Rng& rng) {
    const double pick = uniform<double>(rng, 0, 1);
    if (pick < 0.15) return inhand_rob::preset_rig<Ctrl>(inhand::plant::shadow_like_hand());
    if (pick < 0.3) return inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand());
    inhand_rob::Rig<Ctrl> rig;
    rig.name = "random";
    const int fingers = static_cast<int>(uniform<double>(rng, 1, 5.999));
    rig.config.fingers.resize(static_cast<std::size_t>(fingers));
    for (int i = 0; i < fingers; ++i) {
      auto& fc = rig.config.fingers[static_cast<std::size_t>(i)];
      fc.chain = random_chain<Ctrl::Chain>(rng, static_cast<int>(uniform<double>(rng, 1, 6.999)));
      fc.role = uniform<double>(rng, 0, 1) < 0.3 ? inhand::FingerRole::balancing
                                                 : inhand::FingerRole::preset;
      rig.q_nominal.push_back(inhand_test::random_joint_angles(fc.chain, rng));
    }
    rig.config.fingers.back().role = inhand::FingerRole::balancing;
    inhand_rob::derive_targets(rig);
    return rig;
  });
  record(s, n);
}

TEST(PropertySweep, FixedSizeThreeFingerHand) {
  using Ctrl = inhand::ReactiveController<double, 3, 3, 3>;
  const long n = base_ticks(10000);
  const SweepStats s = sweep<Ctrl>(0x5eed0002, n, [](Rng&) {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand());
  });
  record(s, n);
}

TEST(PropertySweep, FloatThreeFingerHand) {
  using Ctrl = inhand::ReactiveController<float, 3, 3, 3>;
  const long n = base_ticks(10000);
  const SweepStats s = sweep<Ctrl>(0x5eed0003, n, [](Rng&) {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand());
  });
  record(s, n);
}

TEST(PropertySweep, RandomPlanarHandsBoundedDof) {
  using Ctrl = inhand::ReactiveController<double, 2, inhand::Dynamic, inhand::Dynamic, 4>;
  const long n = base_ticks(10000);
  const SweepStats s = sweep<Ctrl>(0x5eed0004, n, [](Rng& rng) {
    inhand_rob::Rig<Ctrl> rig;
    rig.name = "random_planar";
    const int fingers = static_cast<int>(uniform<double>(rng, 1, 4.999));
    rig.config.fingers.resize(static_cast<std::size_t>(fingers));
    for (int i = 0; i < fingers; ++i) {
      auto& fc = rig.config.fingers[static_cast<std::size_t>(i)];
      fc.chain = random_chain<Ctrl::Chain>(rng, static_cast<int>(uniform<double>(rng, 1, 4.999)));
      fc.role = i == 0 ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
      rig.q_nominal.push_back(inhand_test::random_joint_angles(fc.chain, rng));
    }
    inhand_rob::derive_targets(rig);
    return rig;
  });
  record(s, n);
}

// ---------------------------------------------------------------------------
// ContactIk on Jacobians of random fingers

TEST(PropertySweep, IkGainBoundLimitsAndDeterminism) {
  using Chain = inhand::FingerChain<double, 3, inhand::Dynamic, 6>;
  using Ik = inhand::ContactIk<double, 3, inhand::Dynamic, 6>;
  Rng rng = inhand_test::make_rng(0x5eed0010);
  const long n = base_ticks(10000);
  double worst_gain = 0.0, worst_dir = 0.0;
  long damped = 0, limited = 0;
  for (long c = 0; c < n; ++c) {
    const int dof = static_cast<int>(uniform<double>(rng, 1, 6.999));
    const Chain chain = random_chain<Chain>(rng, dof);
    inhand::FingerKinematics<Chain> ws(chain);
    inhand::forward_kinematics(chain, inhand_test::random_joint_angles(chain, rng), ws);
    const Eigen::Vector3d p =
        ws.fingertip.position +
        chain.fingertip_radius * inhand_test::random_unit_vector<double, 3>(rng);
    Ik::Jacobian J = Ik::Jacobian::Zero(3, dof);
    inhand::point_jacobian(ws, p, J);
    inhand::IkParams<double> params;
    params.damping.singular_threshold = log_uniform<double>(rng, 1e-4, 5e-2);
    params.damping.max_damping = log_uniform<double>(rng, 1e-5, 5e-2);
    const Eigen::Vector3d xd =
        log_uniform<double>(rng, 1e-6, 1.0) * inhand_test::random_unit_vector<double, 3>(rng);
    Ik a(dof, params), b(dof, params);
    Ik::JointVector free_a = Ik::JointVector::Zero(dof), free_b = free_a, lim_a = free_a,
                    lim_b = free_a;
    const Ik::JointVector inf =
        Ik::JointVector::Constant(dof, std::numeric_limits<double>::infinity());
    const auto ra = a.solve(J, xd, inf, free_a);
    b.solve(J, xd, inf, free_b);
    ASSERT_FALSE(inhand::has(ra.status, inhand::IkStatus::invalid_input)) << "case " << c;
    ASSERT_TRUE(inhand::all_finite(free_a)) << "case " << c;
    ASSERT_TRUE(inhand_rob::same_bits(free_a, free_b)) << "case " << c << ": two solvers differ";
    const double bound = a.gain_bound() * xd.norm();
    worst_gain = std::max(worst_gain, free_a.norm() / bound);
    ASSERT_LE(free_a.norm(), bound * (1.0 + 1e-9)) << "case " << c << ": gain bound violated";
    damped += inhand::has(ra.status, inhand::IkStatus::damped);
    Ik::JointVector limit(dof);
    for (int j = 0; j < dof; ++j)
      limit(j) = chain.joints[j].max_velocity * uniform<double>(rng, 1e-3, 1.0);
    const auto rl = a.solve(J, xd, limit, lim_a);
    b.solve(J, xd, limit, lim_b);
    ASSERT_TRUE(inhand_rob::same_bits(lim_a, lim_b)) << "case " << c;
    for (int j = 0; j < dof; ++j)
      ASSERT_LE(std::abs(lim_a(j)), limit(j)) << "case " << c << " joint " << j;
    if (inhand::has(rl.status, inhand::IkStatus::limited)) {
      ++limited;
      // Direction kept: lim = s * free.
      const double dir_err =
          (lim_a - rl.limit_scale * free_a).norm() / std::max(lim_a.norm(), 1e-300);
      worst_dir = std::max(worst_dir, dir_err);
      ASSERT_LE(dir_err, 1e-12) << "case " << c;
    }
  }
  inhand_test::record("cases", static_cast<double>(n));
  inhand_test::record("worst_gain_over_bound", worst_gain);
  inhand_test::record("damped_cases", static_cast<double>(damped));
  inhand_test::record("limited_cases", static_cast<double>(limited));
  inhand_test::record("worst_direction_error", worst_dir);
  EXPECT_GT(damped, 0);
  EXPECT_GT(limited, 0);
}

}  // namespace
