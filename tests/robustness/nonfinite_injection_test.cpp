// Non-finite injection into every per-tick entry point: one input scalar at a time
// is replaced by quiet NaN, signalling NaN, +inf or -inf, and the documented contract
// of the call is checked exactly.
//
// ReactiveController::update (grasp and manipulation phases, every finger touching
// and every other finger touching, chain and external kinematics, fixed and run-time
// sized hands, planar and spatial, float and double): the input scalars are enumerated
// programmatically (every coefficient of every Eigen member of Input and of each
// FingerInput, plus the time and the normal force). For a field the controller reads
// in that state the tick must return invalid_input with fault.field naming the field
// and fault.finger the finger (-1 for time and object pose), every joint velocity
// exactly 0 and every output finite; the state must be frozen: the next valid tick
// gives bit-identically the output of a twin controller that never saw the bad tick,
// and so do the following ticks (recovery). Fields legitimately ignored in that state
// (contact data of a finger that is not touching, the Jacobian of a chain-kinematics
// finger, the virtual contact point of a touching or chain-kinematics finger) must
// leave the tick exactly as the twin computes it on the clean input: same status,
// bit-identical and finite output, and the same on the following ticks.
// ContactIk::solve / pseudo_inverse, HybridServo::update, PiController::update,
// ForcePlanner::plan, forward_kinematics / point_jacobian and ObjectTrajectory::
// evaluate are checked the same way against their own documented fallbacks.
// Nothing may throw (every entry point is noexcept, also asserted at compile time).
// Absurd finite magnitudes (+-max, 1e300) in any controller input scalar must leave the
// joint velocity command finite, within its limits, and zero when the tick is rejected.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/presets.hpp"
#include "inhand/sim/scenario.hpp"
#include "robustness/robustness_support.hpp"

namespace {

using inhand::ControllerStatus;
using inhand::InputField;
using inhand_rob::Pattern;
using inhand_rob::same_bits;
using inhand_rob::same_bits_scalar;

// ---------------------------------------------------------------------------
// The four poisons

template <typename S>
struct Poison {
  const char* name;
  S value;
};
template <typename S>
std::array<Poison<S>, 4> poisons() {
  return {{{"quiet_NaN", std::numeric_limits<S>::quiet_NaN()},
           {"signaling_NaN", std::numeric_limits<S>::signaling_NaN()},
           {"+inf", std::numeric_limits<S>::infinity()},
           {"-inf", -std::numeric_limits<S>::infinity()}}};
}

/// Prints at most this many failure descriptions per test (a broken contract would
/// otherwise flood the log with thousands of lines).
constexpr int kMaxReported = 12;

struct FailureLog {
  int count = 0;
  void fail(const std::string& what) {
    if (++count <= kMaxReported) ADD_FAILURE() << what;
  }
  ~FailureLog() {
    if (count > kMaxReported)
      ADD_FAILURE() << (count - kMaxReported) << " further failures not shown";
  }
};

// ---------------------------------------------------------------------------
// Enumerating the controller's input scalars

/// When the controller reads a field (see check_input and the phase code).
enum class Read { always, if_touching, if_external, if_external_not_touching };

struct Slot {
  InputField field = InputField::none;
  int finger = -1;
  std::string name;
  Read read = Read::always;
};

template <typename M, typename F>
void each_coeff(M& m, const std::string& name, F&& f) {
  for (Eigen::Index c = 0; c < m.cols(); ++c)
    for (Eigen::Index r = 0; r < m.rows(); ++r)
      f(name + "(" + std::to_string(r) + "," + std::to_string(c) + ")", m(r, c));
}

/// Calls visit(slot, scalar&) for every scalar of the input, in a fixed order.
template <typename Ctrl, typename Visit>
void for_each_input_scalar(typename Ctrl::Input& in, Visit&& visit) {
  visit(Slot{InputField::time, -1, "time", Read::always}, in.time);
  each_coeff(in.object_pose.position, "object_pose.position", [&](const std::string& n, auto& x) {
    visit(Slot{InputField::object_pose, -1, n, Read::always}, x);
  });
  each_coeff(in.object_pose.rotation, "object_pose.rotation", [&](const std::string& n, auto& x) {
    visit(Slot{InputField::object_pose, -1, n, Read::always}, x);
  });
  for (int i = 0; i < static_cast<int>(in.fingers.size()); ++i) {
    auto& f = in.fingers[static_cast<std::size_t>(i)];
    const std::string p = "fingers[" + std::to_string(i) + "].";
    each_coeff(f.joint_positions, p + "joint_positions", [&](const std::string& n, auto& x) {
      visit(Slot{InputField::joint_positions, i, n, Read::always}, x);
    });
    each_coeff(f.contact.contact_point, p + "contact.contact_point",
               [&](const std::string& n, auto& x) {
                 visit(Slot{InputField::contact_point, i, n, Read::if_touching}, x);
               });
    each_coeff(f.contact.normal, p + "contact.normal", [&](const std::string& n, auto& x) {
      visit(Slot{InputField::contact_normal, i, n, Read::if_touching}, x);
    });
    visit(Slot{InputField::normal_force, i, p + "contact.normal_force", Read::if_touching},
          f.contact.normal_force);
    each_coeff(f.jacobian, p + "jacobian", [&](const std::string& n, auto& x) {
      visit(Slot{InputField::jacobian, i, n, Read::if_external}, x);
    });
    each_coeff(
        f.virtual_contact_point, p + "virtual_contact_point", [&](const std::string& n, auto& x) {
          visit(Slot{InputField::virtual_contact_point, i, n, Read::if_external_not_touching}, x);
        });
  }
}

template <typename Ctrl>
std::vector<Slot> input_slots(typename Ctrl::Input in) {
  std::vector<Slot> slots;
  for_each_input_scalar<Ctrl>(in, [&](const Slot& s, auto&) { slots.push_back(s); });
  return slots;
}

/// Sets scalar number `index` (in for_each_input_scalar order) to `value`.
template <typename Ctrl>
void inject(typename Ctrl::Input& in, std::size_t index, typename Ctrl::Scalar value) {
  std::size_t k = 0;
  for_each_input_scalar<Ctrl>(in, [&](const Slot&, auto& x) {
    if (k++ == index) x = value;
  });
}

template <typename Ctrl>
bool is_read(const Slot& s, const inhand_rob::Rig<Ctrl>& rig, const Pattern& touching) {
  if (s.finger < 0) return true;
  const bool t = touching[static_cast<std::size_t>(s.finger)];
  const bool ext = rig.external(s.finger);
  switch (s.read) {
    case Read::always:
      return true;
    case Read::if_touching:
      return t;
    case Read::if_external:
      return ext;
    case Read::if_external_not_touching:
      return ext && !t;
  }
  return true;
}

// ---------------------------------------------------------------------------
// Rigs under test

struct FixedThreeFinger {
  using Ctrl = inhand::ReactiveController<double, 3, 3, 3>;
  static inhand_rob::Rig<Ctrl> make() {
    auto rig = inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand(), {1});
    rig.config.max_joint_acceleration = 200.0;  // the rate limiter's memory must freeze too
    return rig;
  }
};
struct DynamicShadow {
  using Ctrl = inhand::plant::HandController;  // run-time finger count and DOF
  static inhand_rob::Rig<Ctrl> make() {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::shadow_like_hand(), {3});
  }
};
struct PlanarTwoFinger {
  using Ctrl = inhand::ReactiveController<double, 2, 2, 3>;
  static inhand_rob::Rig<Ctrl> make() { return inhand_rob::planar_rig<Ctrl>(2, {0}); }
};
struct FloatThreeFinger {
  using Ctrl = inhand::ReactiveController<float, 3, 3, 3>;
  static inhand_rob::Rig<Ctrl> make() {
    auto rig = inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand(), {2});
    rig.config.max_joint_acceleration = 500.0f;
    return rig;
  }
};

template <typename Case>
class ControllerInjection : public ::testing::Test {};
using Cases = ::testing::Types<FixedThreeFinger, DynamicShadow, PlanarTwoFinger, FloatThreeFinger>;
struct CaseNames {
  template <typename C>
  static std::string GetName(int) {
    if (std::is_same<C, FixedThreeFinger>::value) return "fixed_three_finger";
    if (std::is_same<C, DynamicShadow>::value) return "dynamic_shadow";
    if (std::is_same<C, PlanarTwoFinger>::value) return "planar_two_finger";
    return "float_three_finger";
  }
};
TYPED_TEST_SUITE(ControllerInjection, Cases, CaseNames);

enum class Phase { grasp, manipulation };

/// A controller warmed up in `phase` with `pattern`: returns the controller, its last
/// output, and the index of the next tick of the nominal stream.
template <typename Ctrl>
struct Warm {
  Ctrl ctl;
  typename Ctrl::Output out;
  int next_tick = 0;
};

template <typename Ctrl>
Warm<Ctrl> warm_up(const inhand_rob::Rig<Ctrl>& rig, Phase phase, const Pattern& pattern) {
  Warm<Ctrl> w;
  inhand_rob::Rig<Ctrl> r = rig;
  if (phase == Phase::manipulation) r.config.grasp.settle_time = 0;
  EXPECT_TRUE(inhand_rob::start_grasp(w.ctl, r));
  w.out = w.ctl.make_output();
  if (phase == Phase::manipulation) {
    EXPECT_TRUE(
        inhand_rob::complete_grasp_and_manipulate(w.ctl, r, typename Ctrl::Scalar(5e-4), w.out));
  }
  for (int k = 0; k < 6; ++k) {
    const auto in = inhand_rob::nominal_input(r, w.ctl, k, pattern, phase == Phase::grasp);
    const ControllerStatus st = w.ctl.update(in, w.out);
    EXPECT_NE(st, ControllerStatus::invalid_input)
        << "warm-up tick " << k << " fault " << inhand::to_string(w.out.fault.field);
  }
  w.next_tick = 6;
  return w;
}

template <typename Ctrl>
std::string describe(const std::string& rig, Phase phase, const Pattern& pattern, const Slot& s,
                     const char* poison) {
  std::ostringstream o;
  o << rig << (phase == Phase::grasp ? " grasp" : " manipulation") << " touching=";
  for (bool b : pattern) o << (b ? '1' : '0');
  o << " " << s.name << " = " << poison;
  return o.str();
}

TYPED_TEST(ControllerInjection, EveryScalarEveryPoisonEveryPhase) {
  using Ctrl = typename TypeParam::Ctrl;
  using S = typename Ctrl::Scalar;
  const inhand_rob::Rig<Ctrl> rig = TypeParam::make();
  const int n = rig.fingers();
  FailureLog log;
  int injected = 0, rejected = 0, ignored = 0;

  {  // the contract is noexcept
    Ctrl c;
    typename Ctrl::Input in;
    typename Ctrl::Output out;
    static_assert(noexcept(c.update(in, out)), "update() is noexcept");
  }

  for (Phase phase : {Phase::grasp, Phase::manipulation}) {
    for (const Pattern& pattern :
         {inhand_rob::all_touching(n), inhand_rob::alternate_touching(n)}) {
      const Warm<Ctrl> warm = warm_up(rig, phase, pattern);
      const bool grasp_phase = phase == Phase::grasp;
      const auto clean =
          inhand_rob::nominal_input(rig, warm.ctl, warm.next_tick, pattern, grasp_phase);
      const std::vector<Slot> slots = input_slots<Ctrl>(clean);
      for (std::size_t si = 0; si < slots.size(); ++si) {
        const Slot& slot = slots[si];
        const bool read = is_read(slot, rig, pattern);
        for (const auto& poison : poisons<S>()) {
          ++injected;
          const std::string what = describe<Ctrl>(rig.name, phase, pattern, slot, poison.name);
          Ctrl a = warm.ctl;     // sees the poisoned tick
          Ctrl twin = warm.ctl;  // never sees it
          typename Ctrl::Output out_a = warm.out, out_t = warm.out;
          typename Ctrl::Input bad = clean;
          inject<Ctrl>(bad, si, poison.value);
          ControllerStatus st = ControllerStatus::ok;
          EXPECT_NO_THROW(st = a.update(bad, out_a)) << what;
          if (!inhand_rob::output_finite<Ctrl>(out_a)) log.fail(what + ": non-finite output");
          if (read) {
            ++rejected;
            if (st != ControllerStatus::invalid_input)
              log.fail(what + ": status " + inhand::to_string(st) + ", expected invalid_input");
            if (out_a.fault.field != slot.field || out_a.fault.finger != slot.finger)
              log.fail(what + ": fault " + inhand::to_string(out_a.fault.field) + " finger " +
                       std::to_string(out_a.fault.finger) + ", expected " +
                       inhand::to_string(slot.field) + " finger " + std::to_string(slot.finger));
            if (out_a.warnings != inhand::ControllerWarning::none)
              log.fail(what + ": warnings raised");
            for (int i = 0; i < n; ++i) {
              const auto& fo = out_a.fingers[static_cast<std::size_t>(i)];
              const bool zero =
                  fo.joint_velocities.size() == rig.chain(i).dof() &&
                  (fo.joint_velocities.array() == S(0)).all() &&
                  (fo.desired_contact_velocity.array() == S(0)).all() &&
                  fo.desired_normal_force == S(0) && (fo.servo.total.array() == S(0)).all() &&
                  (fo.servo.motion.array() == S(0)).all() && (fo.servo.force.array() == S(0)).all();
              if (!zero) log.fail(what + ": finger " + std::to_string(i) + " fallback is not zero");
              if (fo.state != warm.out.fingers[static_cast<std::size_t>(i)].state)
                log.fail(what + ": finger state changed on an invalid tick");
            }
            if (!(out_a.commanded_twist.array() == S(0)).all() ||
                !(out_a.feedforward_twist.array() == S(0)).all())
              log.fail(what + ": twists not zeroed");
            // Frozen state: the next valid tick equals the twin's (which skipped the bad one).
            const ControllerStatus sa = a.update(clean, out_a);
            const ControllerStatus sb = twin.update(clean, out_t);
            if (sa != sb || sa == ControllerStatus::invalid_input)
              log.fail(what + ": recovery status " + inhand::to_string(sa) + " vs twin " +
                       inhand::to_string(sb));
            if (!inhand_rob::same_output<Ctrl>(out_a, out_t))
              log.fail(what + ": state not frozen (next tick differs)");
          } else {
            ++ignored;
            const ControllerStatus sb = twin.update(clean, out_t);
            if (st != sb)
              log.fail(what + ": ignored field changed the status to " + inhand::to_string(st));
            if (!inhand_rob::same_output<Ctrl>(out_a, out_t))
              log.fail(what + ": ignored field changed the output");
          }
          // Recovery goes on: three more clean ticks, bit-identical to the twin.
          for (int k = 1; k <= 3; ++k) {
            const auto next =
                inhand_rob::nominal_input(rig, warm.ctl, warm.next_tick + k, pattern, grasp_phase);
            const ControllerStatus sa = a.update(next, out_a);
            const ControllerStatus sb = twin.update(next, out_t);
            if (sa != sb || sa == ControllerStatus::invalid_input ||
                !inhand_rob::same_output<Ctrl>(out_a, out_t) ||
                !inhand_rob::output_finite<Ctrl>(out_a)) {
              log.fail(what + ": tick +" + std::to_string(k) +
                       " after the injection differs from the twin");
              break;
            }
          }
        }
      }
    }
  }
  inhand_test::record("injections", injected);
  inhand_test::record("rejected", rejected);
  inhand_test::record("ignored_fields", ignored);
  EXPECT_GT(rejected, 0);
  EXPECT_GT(ignored, 0);
}

/// A time that does not increase (equal or earlier) is an invalid time, state frozen.
TYPED_TEST(ControllerInjection, NonIncreasingTimeIsRejectedAndFrozen) {
  using Ctrl = typename TypeParam::Ctrl;
  using S = typename Ctrl::Scalar;
  const inhand_rob::Rig<Ctrl> rig = TypeParam::make();
  const Pattern pattern = inhand_rob::alternate_touching(rig.fingers());
  const Warm<Ctrl> warm = warm_up(rig, Phase::grasp, pattern);
  const auto clean = inhand_rob::nominal_input(rig, warm.ctl, warm.next_tick, pattern, true);
  const S last = inhand_rob::nominal_input(rig, warm.ctl, warm.next_tick - 1, pattern, true).time;
  for (S t : {last, S(last - S(1e-3)), S(0), S(-1)}) {
    Ctrl a = warm.ctl, twin = warm.ctl;
    typename Ctrl::Output out_a = warm.out, out_t = warm.out;
    typename Ctrl::Input bad = clean;
    bad.time = t;
    EXPECT_EQ(a.update(bad, out_a), ControllerStatus::invalid_input) << "time " << t;
    EXPECT_EQ(out_a.fault.field, InputField::time);
    EXPECT_EQ(out_a.fault.finger, -1);
    EXPECT_EQ(a.update(clean, out_a), twin.update(clean, out_t));
    EXPECT_TRUE(inhand_rob::same_output<Ctrl>(out_a, out_t)) << "time " << t;
  }
}

/// Absurd but finite magnitudes (+-max, +-1e300 or +-1e30 in float, 1e150) in any one
/// scalar: the tick may be rejected or computed, but the joint velocity command stays
/// finite, within the limits, and exactly zero when the tick is rejected. (Overflow in
/// the IK, e.g. a contact point 1e300 m away, used to produce NaN commands.)
TYPED_TEST(ControllerInjection, AbsurdFiniteMagnitudesKeepTheCommandBounded) {
  using Ctrl = typename TypeParam::Ctrl;
  using S = typename Ctrl::Scalar;
  const inhand_rob::Rig<Ctrl> rig = TypeParam::make();
  const int n = rig.fingers();
  const S big = std::is_same<S, float>::value ? S(1e30) : S(1e300);
  const S huge[] = {std::numeric_limits<S>::max(), -std::numeric_limits<S>::max(), big, -big,
                    std::is_same<S, float>::value ? S(1e15) : S(1e150)};
  FailureLog log;
  int cases = 0;
  for (Phase phase : {Phase::grasp, Phase::manipulation}) {
    for (const Pattern& pattern :
         {inhand_rob::all_touching(n), inhand_rob::alternate_touching(n)}) {
      const Warm<Ctrl> warm = warm_up(rig, phase, pattern);
      const auto clean =
          inhand_rob::nominal_input(rig, warm.ctl, warm.next_tick, pattern, phase == Phase::grasp);
      const std::vector<Slot> slots = input_slots<Ctrl>(clean);
      for (std::size_t si = 0; si < slots.size(); ++si) {
        for (S value : huge) {
          ++cases;
          Ctrl a = warm.ctl;
          typename Ctrl::Output out = warm.out;
          typename Ctrl::Input bad = clean;
          inject<Ctrl>(bad, si, value);
          // Two ticks: the absurd one, then the same again (integrators now wound up).
          for (int rep = 0; rep < 2; ++rep) {
            if (rep == 1) bad.time += S(1e-3);
            const ControllerStatus st = a.update(bad, out);
            const bool zero_ok =
                st != ControllerStatus::invalid_input ||
                std::all_of(out.fingers.begin(), out.fingers.end(), [](const auto& f) {
                  return (f.joint_velocities.array() == S(0)).all();
                });
            bool finite = true;
            for (const auto& f : out.fingers)
              finite = finite && inhand::all_finite(f.joint_velocities);
            if (!finite || !inhand_rob::within_limits(rig, out) || !zero_ok) {
              std::ostringstream o;
              o << describe<Ctrl>(rig.name, phase, pattern, slots[si], "huge") << " (" << value
                << ") tick " << rep << ": command not finite/bounded, status "
                << inhand::to_string(st);
              log.fail(o.str());
              break;
            }
          }
        }
      }
    }
  }
  inhand_test::record("cases", cases);
}

TEST(IkAbsurdMagnitudes, OverflowIsRejectedWithZeroOutput) {
  using Ik = inhand::ContactIk<double, 3, 4>;
  Ik::Jacobian J;
  J << 0.05, -0.02, 0.01, 0.03,  //
      0.01, 0.04, -0.03, 0.02,   //
      -0.02, 0.01, 0.05, -0.01;
  const Ik::JointVector limit = Ik::JointVector::Constant(3.0);
  const Eigen::Vector3d xd(0.01, -0.02, 0.005);
  Ik ik;
  Ik::JointVector q = Ik::JointVector::Zero();
  Ik::PseudoInverse p = Ik::PseudoInverse::Zero();
  const double max = std::numeric_limits<double>::max();
  // An enormous Jacobian overflows the Gram matrix.
  auto rep = ik.solve(J * 1e300, xd, limit, q);
  EXPECT_TRUE(inhand::has(rep.status, inhand::IkStatus::invalid_input));
  EXPECT_TRUE((q.array() == 0.0).all());
  rep = ik.pseudo_inverse(J * 1e300, p);
  EXPECT_TRUE(inhand::has(rep.status, inhand::IkStatus::invalid_input));
  EXPECT_TRUE((p.array() == 0.0).all());
  // An enormous velocity overflows the solution.
  rep = ik.solve(J, Eigen::Vector3d(max, -max, max), limit, q);
  EXPECT_TRUE(inhand::has(rep.status, inhand::IkStatus::invalid_input));
  EXPECT_TRUE((q.array() == 0.0).all());
  // Large but representable: solved and limited.
  rep = ik.solve(J, Eigen::Vector3d(1e300, 0, 0), limit, q);
  EXPECT_TRUE(inhand::has(rep.status, inhand::IkStatus::limited));
  EXPECT_TRUE(inhand::all_finite(q));
  EXPECT_LE(q.cwiseAbs().maxCoeff(), 3.0);
  EXPECT_EQ(q.cwiseAbs().maxCoeff(), 3.0);
}

// ---------------------------------------------------------------------------
// ContactIk

template <typename S, int Dim, int Dof, int MaxDof, int RunDof>
struct IkCase {
  using Scalar = S;
  using Ik = inhand::ContactIk<S, Dim, Dof, MaxDof>;
  static constexpr int kDim = Dim;
  static constexpr int kRun = RunDof;
  static std::string name() {
    return std::string(std::is_same<S, float>::value ? "float_" : "double_") + std::to_string(Dim) +
           "x" + std::to_string(RunDof) +
           (Dof == inhand::Dynamic ? (MaxDof == inhand::Dynamic ? "_dynamic" : "_bounded") : "");
  }
};
template <typename C>
class IkInjection : public ::testing::Test {};
using IkCases = ::testing::Types<IkCase<double, 3, 4, 4, 4>, IkCase<float, 3, 3, 3, 3>,
                                 IkCase<double, 2, 3, 3, 3>, IkCase<double, 3, 2, 2, 2>,
                                 IkCase<double, 3, inhand::Dynamic, 6, 5>,
                                 IkCase<double, 3, inhand::Dynamic, inhand::Dynamic, 4>>;
struct IkNames {
  template <typename C>
  static std::string GetName(int) {
    return C::name();
  }
};
TYPED_TEST_SUITE(IkInjection, IkCases, IkNames);

TYPED_TEST(IkInjection, SolveRejectsEveryPoisonedScalar) {
  using Ik = typename TypeParam::Ik;
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::kDim;
  const int n = TypeParam::kRun;
  inhand_test::Rng rng = inhand_test::make_rng(0x1c0ffee);
  typename Ik::Jacobian J = Ik::Jacobian::Zero(Dim, n);
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < Dim; ++r) J(r, c) = inhand_test::uniform<S>(rng, S(-0.08), S(0.08));
  typename Ik::CartesianVector xd = Ik::CartesianVector::Zero();
  for (int r = 0; r < Dim; ++r) xd(r) = inhand_test::uniform<S>(rng, S(-0.05), S(0.05));
  typename Ik::JointVector limit = Ik::JointVector::Zero(n), z = Ik::JointVector::Zero(n);
  for (int i = 0; i < n; ++i) {
    limit(i) = inhand_test::uniform<S>(rng, S(0.5), S(3));
    z(i) = inhand_test::uniform<S>(rng, S(-1), S(1));
  }
  FailureLog log;
  int injected = 0;
  static_assert(noexcept(std::declval<Ik&>().solve(J, xd, limit, z)), "solve() is noexcept");

  // Reference results of a never-poisoned solver.
  Ik ref(n);
  typename Ik::JointVector q_ref = Ik::JointVector::Zero(n), q_ref_ns = Ik::JointVector::Zero(n);
  ref.solve(J, xd, limit, q_ref);
  ref.solve(J, xd, limit, z, q_ref_ns);
  ASSERT_TRUE(inhand::all_finite(q_ref));

  // targets: 0 = J, 1 = x_dot, 2 = max_velocity, 3 = null-space velocity
  for (int target = 0; target < 4; ++target) {
    const int count = target == 0 ? Dim * n : (target == 1 ? Dim : n);
    for (int k = 0; k < count; ++k) {
      for (const auto& poison : poisons<S>()) {
        ++injected;
        auto J2 = J;
        auto xd2 = xd;
        auto limit2 = limit;
        auto z2 = z;
        if (target == 0) J2(k % Dim, k / Dim) = poison.value;
        if (target == 1) xd2(k) = poison.value;
        if (target == 2) limit2(k) = poison.value;
        if (target == 3) z2(k) = poison.value;
        const std::string what = std::string("target ") + std::to_string(target) + " coeff " +
                                 std::to_string(k) + " = " + poison.name;
        Ik ik(n);
        typename Ik::JointVector q = Ik::JointVector::Constant(n, S(7));
        inhand::IkReport<S> rep;
        const bool with_z = target == 3;
        EXPECT_NO_THROW(rep = with_z ? ik.solve(J2, xd2, limit2, z2, q)
                                     : ik.solve(J2, xd2, limit2, q));
        // A limit of +inf is documented as "no limit": valid, identical to a huge limit.
        const bool no_limit = target == 2 && poison.value == std::numeric_limits<S>::infinity();
        if (no_limit) {
          auto limit3 = limit;
          limit3(k) = std::numeric_limits<S>::max();
          Ik other(n);
          typename Ik::JointVector q3 = Ik::JointVector::Zero(n);
          other.solve(J, xd, limit3, q3);
          if (inhand::has(rep.status, inhand::IkStatus::invalid_input) || !same_bits(q, q3))
            log.fail(what + ": +inf limit is not treated as no limit");
        } else {
          if (!inhand::has(rep.status, inhand::IkStatus::invalid_input))
            log.fail(what + ": not rejected");
          if (q.size() != n || !(q.array() == S(0)).all())
            log.fail(what + ": fallback is not zero");
        }
        if (!inhand::all_finite(q)) log.fail(what + ": non-finite output");
        // Recovery: the same solver on the clean input matches the reference bit for bit.
        typename Ik::JointVector q2 = Ik::JointVector::Zero(n);
        ik.solve(J, xd, limit, q2);
        if (!same_bits(q2, q_ref)) log.fail(what + ": solve after the poison differs");
        ik.solve(J, xd, limit, z, q2);
        if (!same_bits(q2, q_ref_ns))
          log.fail(what + ": null-space solve after the poison differs");
      }
    }
  }
  inhand_test::record("injections", injected);
}

TYPED_TEST(IkInjection, PseudoInverseRejectsEveryPoisonedScalar) {
  using Ik = typename TypeParam::Ik;
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::kDim;
  const int n = TypeParam::kRun;
  inhand_test::Rng rng = inhand_test::make_rng(0x91e);
  typename Ik::Jacobian J = Ik::Jacobian::Zero(Dim, n);
  for (int c = 0; c < n; ++c)
    for (int r = 0; r < Dim; ++r) J(r, c) = inhand_test::uniform<S>(rng, S(-0.08), S(0.08));
  Ik ref(n);
  typename Ik::PseudoInverse p_ref = Ik::PseudoInverse::Zero(n, Dim),
                             p = Ik::PseudoInverse::Zero(n, Dim);
  ref.pseudo_inverse(J, p_ref);
  ASSERT_TRUE(inhand::all_finite(p_ref));
  for (int k = 0; k < Dim * n; ++k) {
    for (const auto& poison : poisons<S>()) {
      auto J2 = J;
      J2(k % Dim, k / Dim) = poison.value;
      Ik ik(n);
      p.setConstant(S(7));
      const auto rep = ik.pseudo_inverse(J2, p);
      EXPECT_TRUE(inhand::has(rep.status, inhand::IkStatus::invalid_input))
          << k << " " << poison.name;
      EXPECT_TRUE((p.array() == S(0)).all()) << k << " " << poison.name;
      ik.pseudo_inverse(J, p);
      EXPECT_TRUE(same_bits(p, p_ref)) << k << " " << poison.name;
    }
  }
}

// ---------------------------------------------------------------------------
// HybridServo and PiController

template <typename S, int Dim>
struct ServoCase {
  using Scalar = S;
  static constexpr int kDim = Dim;
};
template <typename C>
class ServoInjection : public ::testing::Test {};
using ServoCases =
    ::testing::Types<ServoCase<double, 3>, ServoCase<float, 3>, ServoCase<double, 2>>;
TYPED_TEST_SUITE(ServoInjection, ServoCases);

TYPED_TEST(ServoInjection, ServoRejectsEveryReadScalarAndFreezesIntegrators) {
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::kDim;
  using Servo = inhand::HybridServo<S, Dim>;
  using Vec = inhand::Vector<S, Dim>;
  inhand::ServoGains<S> g;
  g.motion = {S(1), S(2), S(0.05), S(0.5)};  // saturating limits exercise every branch
  g.force = {S(0.02), S(0.2), S(1), S(0.1)};
  Servo warm(g);
  inhand::ServoCommand<S, Dim> cmd;
  // Warm-up: non-zero integrators.
  Vec v0 = Vec::Constant(S(0.01)), n0 = Vec::UnitY();
  for (int k = 0; k < 20; ++k)
    warm.update(v0 * S(1 + 0.1 * k), S(1), S(0.7), n0, true, S(1e-3), cmd);
  static_assert(noexcept(warm.update(v0, S(1), S(1), n0, true, S(1e-3), cmd)), "noexcept");
  FailureLog log;
  int injected = 0;
  // Scalars: desired_velocity(0..Dim-1), desired_force, measured_force, normal(0..Dim-1), dt.
  const int count = 2 * Dim + 3;
  for (bool force_active : {true, false}) {
    for (int k = 0; k < count; ++k) {
      for (const auto& poison : poisons<S>()) {
        ++injected;
        Vec v = v0, nrm = n0;
        S fd = S(1), fm = S(0.8), dt = S(1e-3);
        bool read = true;
        if (k < Dim) {
          v(k) = poison.value;
        } else if (k == Dim) {
          fd = poison.value;
          read = force_active;
        } else if (k == Dim + 1) {
          fm = poison.value;
          read = force_active;
        } else if (k < 2 * Dim + 2) {
          nrm(k - Dim - 2) = poison.value;
          read = force_active;
        } else {
          dt = poison.value;
        }
        const std::string what = std::string(force_active ? "active" : "inactive") + " scalar " +
                                 std::to_string(k) + " = " + poison.name;
        Servo a = warm, twin = warm;
        inhand::ServoCommand<S, Dim> ca, ct;
        inhand::ServoStatus st = inhand::ServoStatus::ok;
        EXPECT_NO_THROW(st = a.update(v, fd, fm, nrm, force_active, dt, ca));
        if (!inhand::all_finite(ca.total) || !inhand::all_finite(ca.motion) ||
            !inhand::all_finite(ca.force))
          log.fail(what + ": non-finite command");
        if (read) {
          if (st != inhand::ServoStatus::invalid_input) log.fail(what + ": not rejected");
          if (!(ca.total.array() == S(0)).all() || !(ca.motion.array() == S(0)).all() ||
              !(ca.force.array() == S(0)).all())
            log.fail(what + ": fallback is not zero");
          if (!same_bits(a.motion_pi().integral(), warm.motion_pi().integral()) ||
              !same_bits(a.force_pi().integral(), warm.force_pi().integral()))
            log.fail(what + ": integrator moved");
        } else {
          const auto sb = twin.update(v0, S(1), S(0.8), n0, force_active, S(1e-3), ct);
          if (st != sb || !same_bits(ca.total, ct.total) || !same_bits(ca.force, ct.force))
            log.fail(what + ": ignored scalar changed the result");
        }
        if (read) {  // frozen: the next clean tick equals the twin's, which skipped the bad one
          const auto s1 = a.update(v0, S(1), S(0.8), n0, force_active, S(1e-3), ca);
          const auto s2 = twin.update(v0, S(1), S(0.8), n0, force_active, S(1e-3), ct);
          if (s1 != s2 || !same_bits(ca.total, ct.total)) log.fail(what + ": state not frozen");
        }
        // Recovery: bit-identical to the twin from here on.
        for (int t = 0; t < 3; ++t) {
          const auto s1 = a.update(v0, S(1.1), S(0.9), n0, true, S(1e-3), ca);
          const auto s2 = twin.update(v0, S(1.1), S(0.9), n0, true, S(1e-3), ct);
          if (s1 != s2 || !same_bits(ca.total, ct.total)) {
            log.fail(what + ": recovery differs from the twin");
            break;
          }
        }
      }
    }
  }
  inhand_test::record("injections", injected);
}

TYPED_TEST(ServoInjection, PiRejectsEveryScalarAndFreezesIntegral) {
  using S = typename TypeParam::Scalar;
  constexpr int Dim = TypeParam::kDim;
  using Pi = inhand::PiController<S, Dim>;
  using Vec = typename Pi::Vec;
  Pi warm({S(1.5), S(3), S(0.02), S(1)});
  Vec u = Vec::Zero();
  for (int k = 0; k < 10; ++k) warm.update(Vec::Constant(S(0.1) * S(k)), S(1e-3), u);
  static_assert(noexcept(warm.update(u, S(1), u)), "noexcept");
  for (int k = 0; k <= Dim; ++k) {
    for (const auto& poison : poisons<S>()) {
      Pi a = warm, twin = warm;
      Vec x = Vec::Constant(S(0.3));
      S dt = S(1e-3);
      if (k < Dim)
        x(k) = poison.value;
      else
        dt = poison.value;
      Vec ua = Vec::Constant(S(9)), ut = Vec::Zero();
      EXPECT_EQ(a.update(x, dt, ua), inhand::PiStatus::invalid_input) << k << poison.name;
      EXPECT_TRUE((ua.array() == S(0)).all()) << k << poison.name;
      EXPECT_TRUE(same_bits(a.integral(), warm.integral())) << k << poison.name;
      const Vec xc = Vec::Constant(S(0.3));
      EXPECT_EQ(a.update(xc, S(1e-3), ua), twin.update(xc, S(1e-3), ut));
      EXPECT_TRUE(same_bits(ua, ut)) << k << poison.name;
    }
  }
}

// ---------------------------------------------------------------------------
// ForcePlanner

TEST(PlannerInjection, RejectsTouchingNormalsAndDtIgnoresOthers) {
  using Planner = inhand::ForcePlanner<double, 3, 4>;
  Planner warm;
  inhand::ForcePlannerParams<double> p;
  warm.set_params(p);
  warm.set_role(3, inhand::FingerRole::balancing);
  Planner::Mask touching;
  touching << 1, 0, 1, 1;
  Planner::Normals normals;
  normals.col(0) = Eigen::Vector3d(0.1, 1, 0).normalized();
  normals.col(1) = Eigen::Vector3d(-0.1, 1, 0.05).normalized();
  normals.col(2) = Eigen::Vector3d(0, 1, -0.1).normalized();
  normals.col(3) = Eigen::Vector3d(0.05, -1, 0).normalized();
  Planner::ForceVector desired = Planner::ForceVector::Zero(), last = desired;
  Eigen::Vector3d residual = Eigen::Vector3d::Zero();
  for (int k = 0; k < 5; ++k) warm.plan(touching, normals, 1e-3, last, residual);
  static_assert(noexcept(warm.plan(touching, normals, 1e-3, last, residual)), "noexcept");
  FailureLog log;
  for (int k = 0; k <= normals.size(); ++k) {
    for (const auto& poison : poisons<double>()) {
      Planner a = warm, twin = warm;
      auto nrm = normals;
      double dt = 1e-3;
      bool read = true;
      if (k < normals.size()) {
        nrm(k % 3, k / 3) = poison.value;
        read = touching(k / 3) != 0;
      } else {
        dt = poison.value;
      }
      const std::string what = "scalar " + std::to_string(k) + " = " + poison.name;
      desired.setConstant(9);
      residual.setConstant(9);
      inhand::ForcePlanStatus st = inhand::ForcePlanStatus::ok;
      EXPECT_NO_THROW(st = a.plan(touching, nrm, dt, desired, residual));
      if (!inhand::all_finite(desired) || !inhand::all_finite(residual))
        log.fail(what + ": non-finite output");
      Planner::ForceVector d2 = Planner::ForceVector::Zero();
      Eigen::Vector3d r2 = Eigen::Vector3d::Zero();
      if (read) {
        // Documented fallback: the last plan, zero residual, state untouched.
        if (!inhand::has(st, inhand::ForcePlanStatus::invalid_input))
          log.fail(what + ": not rejected");
        if (!same_bits(desired, last) || !(residual.array() == 0.0).all())
          log.fail(what + ": fallback differs");
        a.plan(touching, normals, 1e-3, desired, residual);
        twin.plan(touching, normals, 1e-3, d2, r2);
      } else {
        twin.plan(touching, normals, 1e-3, d2, r2);
      }
      if (!same_bits(desired, d2) || !same_bits(residual, r2))
        log.fail(what + ": differs from the twin");
    }
  }
}

// ---------------------------------------------------------------------------
// Kinematics: no status to return; non-finite input must come out non-finite (never
// masked into plausible numbers) and leave the workspace reusable.

template <typename Chain>
class KinematicsInjection : public ::testing::Test {};
TYPED_TEST_SUITE(KinematicsInjection, inhand_test::AllFingerChains, inhand_test::ChainNames);

TYPED_TEST(KinematicsInjection, PoisonPropagatesAndWorkspaceRecovers) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  const Chain chain = inhand_test::make_finger<Chain>();
  inhand_test::Rng rng = inhand_test::make_rng(0xf00d);
  const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
  inhand::FingerKinematics<Chain> ref(chain), ws(chain);
  inhand::forward_kinematics(chain, q, ref);
  const inhand::Vector<S, Dim> point =
      ref.fingertip.position + inhand::Vector<S, Dim>::Constant(S(0.004));
  typename Chain::Jacobian J_ref = Chain::Jacobian::Zero(Dim, chain.dof()), J = J_ref;
  inhand::point_jacobian(ref, point, J_ref);
  static_assert(noexcept(inhand::forward_kinematics(chain, q, ws)), "noexcept");
  static_assert(noexcept(inhand::point_jacobian(ws, point, J)), "noexcept");
  for (int j = 0; j < chain.dof(); ++j) {
    for (const auto& poison : poisons<S>()) {
      auto q2 = q;
      q2(j) = poison.value;
      inhand::forward_kinematics(chain, q2, ws);
      EXPECT_FALSE(ws.fingertip.is_finite()) << "q(" << j << ") = " << poison.name << " was masked";
      inhand::forward_kinematics(chain, q, ws);
      EXPECT_TRUE(same_bits(ws.fingertip.position, ref.fingertip.position));
      EXPECT_TRUE(same_bits(ws.fingertip.rotation, ref.fingertip.rotation));
      EXPECT_TRUE(same_bits(ws.joint_origins, ref.joint_origins));
    }
  }
  for (int d = 0; d < Dim; ++d) {
    for (const auto& poison : poisons<S>()) {
      auto p2 = point;
      p2(d) = poison.value;
      inhand::point_jacobian(ref, p2, J);
      EXPECT_FALSE(inhand::all_finite(J))
          << "point(" << d << ") = " << poison.name << " was masked";
      inhand::point_jacobian(ref, point, J);
      EXPECT_TRUE(same_bits(J, J_ref));
    }
  }
}

// ---------------------------------------------------------------------------
// ObjectTrajectory::evaluate: documented to hold the start pose before 0 (NaN
// included) and the final pose with zero twist after the end.

TEST(TrajectoryInjection, NonFiniteTimeHoldsAnEndPose) {
  using Traj = inhand::ObjectTrajectory<double, 3>;
  inhand::Pose<double, 3> start;
  start.position = Eigen::Vector3d(0.01, -0.02, 0.03);
  start.rotation = inhand::rotation_from_euler<double>(Eigen::Vector3d(0.1, -0.2, 0.3));
  Traj traj;
  traj.reset(start);
  traj.append(Traj::Segment::move(Eigen::Vector3d(1, 0, 0), 0.01, 0.5));
  traj.append(Traj::Segment::rotate(Eigen::Vector3d(0, 0, 1), 0.2, 0.5));
  const auto end = traj.evaluate(10.0);
  const auto mid = traj.evaluate(0.3);
  static_assert(noexcept(traj.evaluate(0.0)), "noexcept");
  for (const auto& poison : poisons<double>()) {
    const auto s = traj.evaluate(poison.value);
    EXPECT_TRUE(s.pose.is_finite() && inhand::all_finite(s.twist)) << poison.name;
    EXPECT_TRUE((s.twist.array() == 0.0).all()) << poison.name;
    if (poison.value == std::numeric_limits<double>::infinity()) {
      EXPECT_EQ(s.segment, -1);
      EXPECT_TRUE(same_bits(s.pose.position, end.pose.position) &&
                  same_bits(s.pose.rotation, end.pose.rotation));
    } else {  // NaN and -inf: before the start
      EXPECT_EQ(s.segment, 0) << poison.name;
      EXPECT_TRUE(same_bits(s.pose.position, start.position) &&
                  same_bits(s.pose.rotation, start.rotation))
          << poison.name;
    }
    const auto again = traj.evaluate(0.3);  // const: nothing to recover, but nothing changed
    EXPECT_TRUE(same_bits(again.pose.position, mid.pose.position) &&
                same_bits(again.twist, mid.twist));
  }
}

}  // namespace
