// The controller's contract, one typed suite for every kind of hand the library
// promises to serve: fixed sizes, bounded DOF (mixed-DOF hand, no allocation), run-time
// finger count and DOF, float, and planar. Each property is what reactive_controller.hpp
// states; the rigs and the valid input stream come from robustness_support.hpp.
// INHAND_TEST_SCALE multiplies the number of manipulation ticks and random patterns.
#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <string>
#include <type_traits>

#include "robustness/robustness_support.hpp"

namespace {

using inhand::ControllerStatus;
using inhand::Dynamic;

struct FixedDouble {
  using Ctrl = inhand::ReactiveController<double, 3, 3, 3>;
  static inhand_rob::Rig<Ctrl> make() {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand(), {1});
  }
};
struct BoundedMixedDof {  // 4-joint fingers and a 5-joint thumb in fixed storage
  using Ctrl = inhand::ReactiveController<double, 3, 4, Dynamic, 5>;
  static inhand_rob::Rig<Ctrl> make() {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::shadow_like_hand());
  }
};
struct DynamicHand {
  using Ctrl = inhand::ReactiveController<double, 3, Dynamic, Dynamic>;
  static inhand_rob::Rig<Ctrl> make() {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::shadow_like_hand(), {2});
  }
};
struct FixedFloat {
  using Ctrl = inhand::ReactiveController<float, 3, 3, 3>;
  static inhand_rob::Rig<Ctrl> make() {
    return inhand_rob::preset_rig<Ctrl>(inhand::plant::three_finger_hand());
  }
};
struct PlanarDouble {
  using Ctrl = inhand::ReactiveController<double, 2, 3, 3>;
  static inhand_rob::Rig<Ctrl> make() { return inhand_rob::planar_rig<Ctrl>(3, {0}); }
};

template <typename Case>
class ControllerContract : public ::testing::Test {};
using Hands = ::testing::Types<FixedDouble, BoundedMixedDof, DynamicHand, FixedFloat, PlanarDouble>;
struct HandNames {
  template <typename C>
  static std::string GetName(int) {
    if (std::is_same<C, FixedDouble>::value) return "fixed_double";
    if (std::is_same<C, BoundedMixedDof>::value) return "bounded_mixed_dof";
    if (std::is_same<C, DynamicHand>::value) return "dynamic";
    if (std::is_same<C, FixedFloat>::value) return "fixed_float";
    return "planar_double";
  }
};
TYPED_TEST_SUITE(ControllerContract, Hands, HandNames);

template <typename Ctrl>
bool command_is_zero(const typename Ctrl::Output& out) {
  for (const auto& f : out.fingers)
    if (!f.joint_velocities.isZero(0)) return false;
  return true;
}

TYPED_TEST(ControllerContract, UnconfiguredTickIsRefusedWithAZeroCommand) {
  using Ctrl = typename TypeParam::Ctrl;
  const auto rig = TypeParam::make();
  Ctrl reference;
  ASSERT_TRUE(reference.configure(rig.config).ok());
  const auto in =
      inhand_rob::nominal_input(rig, reference, 0, inhand_rob::all_touching(rig.fingers()), true);
  auto out = reference.make_output();
  for (auto& f : out.fingers) f.joint_velocities.setConstant(1);
  Ctrl ctl;
  EXPECT_EQ(ctl.update(in, out), ControllerStatus::not_configured);
  EXPECT_TRUE(command_is_zero<Ctrl>(out));
}

TYPED_TEST(ControllerContract, ValidationNamesTheFullPathAndConfigureIsAllOrNothing) {
  using Ctrl = typename TypeParam::Ctrl;
  using S = typename Ctrl::Scalar;
  const auto rig = TypeParam::make();
  struct Case {
    const char* field;
    int finger;
    void (*mutate)(typename Ctrl::Config&);
  };
  const Case cases[] = {
      {"force_layer.bandwidth", -1,
       [](typename Ctrl::Config& c) { c.force_layer.bandwidth = S(-1); }},
      {"pose_feedback.max_linear_speed", -1,
       [](typename Ctrl::Config& c) { c.pose_feedback.max_linear_speed = S(0); }},
      {"ik.damping.max_damping", -1,
       [](typename Ctrl::Config& c) { c.ik.damping.max_damping = S(-1); }},
      {"outlier_gates.max_force_rate", -1,
       [](typename Ctrl::Config& c) { c.outlier_gates.max_force_rate = S(0); }},
      {"outlier_gates.contact_stiffness", -1,
       [](typename Ctrl::Config& c) { c.outlier_gates.contact_stiffness = S(-1); }},
      {"outlier_gates.contact_stiffness", -1,
       [](typename Ctrl::Config& c) {
         c.outlier_gates.contact_stiffness = std::numeric_limits<S>::infinity();
       }},
      {"outlier_gates.max_rejection_time", -1,
       [](typename Ctrl::Config& c) { c.outlier_gates.max_rejection_time = S(-1e-3); }},
      {"outlier_gates.max_rejection_time", -1,
       [](typename Ctrl::Config& c) {
         c.outlier_gates.max_rejection_time = std::numeric_limits<S>::infinity();
       }},
      {"grasp.settle_time", -1, [](typename Ctrl::Config& c) { c.grasp.settle_time = S(-1); }},
      {"max_measured_force", -1, [](typename Ctrl::Config& c) { c.max_measured_force = S(0); }},
      {"min_measured_force", -1, [](typename Ctrl::Config& c) { c.min_measured_force = S(0.1); }},
      {"min_measured_force", -1,
       [](typename Ctrl::Config& c) { c.min_measured_force = -2 * c.max_measured_force; }},
      {"min_measured_force", -1,
       [](typename Ctrl::Config& c) {
         c.min_measured_force = std::numeric_limits<S>::quiet_NaN();
       }},
      {"joints.max_velocity", 1,
       [](typename Ctrl::Config& c) { c.fingers[1].chain.joints[0].max_velocity = S(0); }},
  };
  for (const Case& k : cases) {
    typename Ctrl::Config bad = rig.config;
    k.mutate(bad);
    const inhand::Validation v = Ctrl::validate(bad);
    ASSERT_FALSE(v.ok()) << k.field;
    EXPECT_NE(std::string(v.field).find(k.field), std::string::npos)
        << v.field << " for " << k.field;
    EXPECT_EQ(v.finger, k.finger) << k.field;
    Ctrl ctl;
    EXPECT_FALSE(ctl.configure(bad).ok());
    EXPECT_FALSE(ctl.configured()) << k.field;
  }
}

/// Grasp, then manipulation under random touching patterns: every tick valid, every
/// output finite, every joint within its velocity limit, no numerical fault.
TYPED_TEST(ControllerContract, EveryTickIsFiniteAndWithinTheJointLimits) {
  using Ctrl = typename TypeParam::Ctrl;
  auto rig = TypeParam::make();
  rig.config.grasp.settle_time = 0;
  Ctrl ctl;
  ASSERT_TRUE(inhand_rob::start_grasp(ctl, rig));
  auto out = ctl.make_output();
  const int n = rig.fingers();
  for (int k = 0; k < 20; ++k) {
    const auto in = inhand_rob::nominal_input(rig, ctl, k, inhand_rob::alternate_touching(n), true);
    EXPECT_EQ(ctl.update(in, out), ControllerStatus::grasping);
    ASSERT_TRUE(inhand_rob::output_finite<Ctrl>(out));
    ASSERT_TRUE(inhand_rob::within_limits(rig, out));
  }
  ASSERT_TRUE(
      inhand_rob::complete_grasp_and_manipulate(ctl, rig, typename Ctrl::Scalar(0.0215), out));
  std::mt19937_64 rng(20261201);
  inhand_rob::Pattern pattern = inhand_rob::all_touching(n);
  const int ticks = inhand_test::scaled(2000);
  for (int k = 22; k < 22 + ticks; ++k) {
    if (k % 50 == 0)
      for (int i = 0; i < n; ++i) pattern[static_cast<std::size_t>(i)] = (rng() % 5) != 0;
    const auto in = inhand_rob::nominal_input(rig, ctl, k, pattern, false);
    const ControllerStatus st = ctl.update(in, out);
    ASSERT_TRUE(st == ControllerStatus::ok || st == ControllerStatus::contact_lost)
        << "tick " << k << ": " << inhand::to_string(st);
    ASSERT_TRUE(inhand_rob::output_finite<Ctrl>(out)) << "tick " << k;
    ASSERT_TRUE(inhand_rob::within_limits(rig, out)) << "tick " << k;
    bool all = true;
    for (bool b : pattern) all = all && b;
    EXPECT_EQ(st == ControllerStatus::ok, all) << "tick " << k;
  }
}

/// A rejected tick leaves no trace: a controller that saw it and one that did not give
/// bit-identical outputs on every later tick.
TYPED_TEST(ControllerContract, ARejectedTickChangesNothing) {
  using Ctrl = typename TypeParam::Ctrl;
  auto rig = TypeParam::make();
  rig.config.grasp.settle_time = 0;
  Ctrl a, b;
  ASSERT_TRUE(inhand_rob::start_grasp(a, rig));
  ASSERT_TRUE(inhand_rob::start_grasp(b, rig));
  auto oa = a.make_output(), ob = b.make_output();
  ASSERT_TRUE(inhand_rob::complete_grasp_and_manipulate(a, rig, typename Ctrl::Scalar(5e-4), oa));
  ASSERT_TRUE(inhand_rob::complete_grasp_and_manipulate(b, rig, typename Ctrl::Scalar(5e-4), ob));
  const auto touching = inhand_rob::alternate_touching(rig.fingers());
  for (int k = 0; k < 200; ++k) {
    const auto in = inhand_rob::nominal_input(rig, a, k, touching, false);
    if (k == 100) {
      auto bad = in;
      bad.time = bad.time - 1.0;  // not increasing
      EXPECT_EQ(b.update(bad, ob), ControllerStatus::invalid_input);
      EXPECT_EQ(ob.fault.field, inhand::InputField::time);
      EXPECT_TRUE(command_is_zero<Ctrl>(ob));
    }
    const ControllerStatus sa = a.update(in, oa), sb = b.update(in, ob);
    ASSERT_EQ(sa, sb) << "tick " << k;
    ASSERT_TRUE(inhand_rob::same_output<Ctrl>(oa, ob)) << "tick " << k;
  }
}

TYPED_TEST(ControllerContract, ResetReturnsToIdleWithAZeroCommand) {
  using Ctrl = typename TypeParam::Ctrl;
  const auto rig = TypeParam::make();
  Ctrl ctl;
  ASSERT_TRUE(inhand_rob::start_grasp(ctl, rig));
  auto out = ctl.make_output();
  const auto touching = inhand_rob::all_touching(rig.fingers());
  for (int k = 0; k < 10; ++k)
    ctl.update(inhand_rob::nominal_input(rig, ctl, k, touching, true), out);
  ctl.reset();
  EXPECT_EQ(ctl.phase(), Ctrl::Phase::idle);
  EXPECT_EQ(ctl.update(inhand_rob::nominal_input(rig, ctl, 10, touching, true), out),
            ControllerStatus::idle);
  EXPECT_TRUE(command_is_zero<Ctrl>(out));
  EXPECT_FALSE(ctl.start_manipulation(inhand_rob::test_trajectory(rig.object)).ok());
}

}  // namespace
