// Floating-point traps: the per-tick paths raise neither FE_INVALID (0/0, inf - inf,
// sqrt of a negative, an ordered comparison with NaN) nor FE_DIVBYZERO on valid input.
//
// Each test enables the traps with feenableexcept(FE_INVALID | FE_DIVBYZERO) (glibc),
// so an offending operation raises SIGFPE and kills the test executable: ctest then
// reports the test as failed, with the signal. The paths run under the traps:
//   - forward_kinematics, point_jacobian and ContactIk::solve / pseudo_inverse on every
//     test finger, at random postures and at the fully stretched (singular) one;
//   - PiController and HybridServo with saturating limits; ForcePlanner; the trajectory;
//   - ReactiveController::update in a closed loop on the analytic plant: the paper's
//     cylinder rotation (sim/scenario.hpp) shortened to about 1 s of manipulation
//     after the grasp and hold stages, with the plant's own code under the traps too.
// The canaries are death tests proving the mechanism: a division by zero and an
// inf - inf under the traps must die of SIGFPE. all_finite() is documented not to
// raise FE_INVALID for quiet NaN; that is checked under the traps as well.
// Not run under valgrind, whose CPU emulation ignores the trap mask.
#include <fenv.h>
#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdlib>
#include <limits>

#include "common/test_support.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/scenario.hpp"

namespace {

/// Enables the FE_INVALID and FE_DIVBYZERO traps for its lifetime.
class TrapGuard {
 public:
  TrapGuard() {
    feclearexcept(FE_ALL_EXCEPT);
    previous_ = feenableexcept(FE_INVALID | FE_DIVBYZERO);
  }
  ~TrapGuard() {
    fedisableexcept(FE_ALL_EXCEPT);
    if (previous_ > 0) feenableexcept(previous_);
    feclearexcept(FE_ALL_EXCEPT);
  }
  TrapGuard(const TrapGuard&) = delete;
  TrapGuard& operator=(const TrapGuard&) = delete;
  bool armed() const {
    return previous_ != -1 &&
           (fegetexcept() & (FE_INVALID | FE_DIVBYZERO)) == (FE_INVALID | FE_DIVBYZERO);
  }

 private:
  int previous_ = -1;
};

// ---------------------------------------------------------------------------
// Canaries

using FpTrapsDeathTest = ::testing::Test;

TEST_F(FpTrapsDeathTest, DivisionByZeroTraps) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        TrapGuard guard;
        volatile double zero = 0.0;
        volatile double r = 1.0 / zero;
        (void)r;
        std::exit(0);
      },
      ::testing::KilledBySignal(SIGFPE), "");
}

TEST_F(FpTrapsDeathTest, InvalidOperationTraps) {
  GTEST_FLAG_SET(death_test_style, "threadsafe");
  EXPECT_EXIT(
      {
        TrapGuard guard;
        volatile double inf = std::numeric_limits<double>::infinity();
        volatile double r = inf - inf;
        (void)r;
        std::exit(0);
      },
      ::testing::KilledBySignal(SIGFPE), "");
}

TEST(FpTraps, GuardArmsAndDisarms) {
  {
    TrapGuard guard;
    EXPECT_TRUE(guard.armed());
  }
  EXPECT_EQ(fegetexcept() & (FE_INVALID | FE_DIVBYZERO), 0);
}

TEST(FpTraps, AllFiniteOnQuietNaNDoesNotRaise) {
  TrapGuard guard;
  ASSERT_TRUE(guard.armed());
  Eigen::Vector3d v(1.0, std::numeric_limits<double>::quiet_NaN(), 2.0);
  EXPECT_FALSE(inhand::all_finite(v));
  EXPECT_FALSE(inhand::is_finite(v(1)));
  EXPECT_TRUE(inhand::all_finite(Eigen::Vector3d(1, 2, 3)));
  EXPECT_EQ(fetestexcept(FE_INVALID | FE_DIVBYZERO), 0);
}

// ---------------------------------------------------------------------------
// Unit paths

template <typename Chain>
class FpTrapsChains : public ::testing::Test {};
TYPED_TEST_SUITE(FpTrapsChains, inhand_test::AllFingerChains, inhand_test::ChainNames);

TYPED_TEST(FpTrapsChains, KinematicsAndIk) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  using Ik = inhand::ContactIk<S, Dim, Chain::Dof, Chain::MaxDof>;
  const Chain chain = inhand_test::make_finger<Chain>();
  inhand_test::Rng rng = inhand_test::make_rng(0xfe0001);
  inhand::FingerKinematics<Chain> ws(chain);
  typename Chain::Jacobian J = Chain::Jacobian::Zero(Dim, chain.dof());
  Ik ik(chain.dof());
  typename Ik::JointVector qd = Ik::JointVector::Zero(chain.dof());
  typename Ik::PseudoInverse pinv = Ik::PseudoInverse::Zero(chain.dof(), Dim);
  const typename Chain::JointVector limits = chain.velocity_limits();
  const typename Chain::JointVector no_limits =
      Chain::JointVector::Constant(chain.dof(), std::numeric_limits<S>::infinity());
  TrapGuard guard;
  ASSERT_TRUE(guard.armed());
  const int n = inhand_test::scaled(300);
  for (int c = 0; c < n; ++c) {
    // Case 0 is the stretched, singular posture q = 0.
    const typename Chain::JointVector q =
        c == 0 ? typename Chain::JointVector(Chain::JointVector::Zero(chain.dof()))
               : inhand_test::random_joint_angles(chain, rng);
    inhand::forward_kinematics(chain, q, ws);
    const auto p = ws.fingertip.transform_point(inhand_test::random_fingertip_offset(chain, rng));
    inhand::point_jacobian(ws, p, J);
    const inhand::Vector<S, Dim> xd = inhand_test::random_vector<S, Dim>(rng, S(-0.05), S(0.05));
    ik.solve(J, xd, limits, qd);
    ik.solve(J, xd, no_limits, qd);
    ik.solve(J, xd, limits, inhand_test::random_joint_velocities(chain, rng), qd);
    ik.pseudo_inverse(J, pinv);
    ik.solve(J, inhand::Vector<S, Dim>::Zero(), limits, qd);  // zero motion
  }
  EXPECT_TRUE(inhand::all_finite(qd));
}

TEST(FpTraps, ServoPiPlannerTrajectory) {
  TrapGuard guard;
  ASSERT_TRUE(guard.armed());
  inhand::ServoGains<double> g;
  g.motion = {1.0, 5.0, 1e-3, 0.02};  // saturate both limits
  g.force = {0.02, 0.2, 0.5, 0.01};
  inhand::HybridServo<double, 3> servo(g);
  inhand::ServoCommand<double, 3> cmd;
  inhand::PiController<double, 3> pi({1.0, 2.0, 1e-3, 1e-2});
  Eigen::Vector3d u;
  inhand::ForcePlanner<double, 3, 4> planner;
  planner.set_role(3, inhand::FingerRole::balancing);
  inhand::ForcePlanner<double, 3, 4>::Mask touching;
  inhand::ForcePlanner<double, 3, 4>::Normals normals;
  inhand::ForcePlanner<double, 3, 4>::ForceVector forces;
  Eigen::Vector3d residual;
  inhand::ObjectTrajectory<double, 3> traj;
  traj.reset(inhand::Pose<double, 3>{});
  traj.append(inhand::TrajectorySegment<double, 3>::move(Eigen::Vector3d(1, 0, 0), 0.005, 0.3));
  traj.append(inhand::TrajectorySegment<double, 3>::rotate(Eigen::Vector3d(0, 1, 0), -0.2, 0.3));
  inhand::Twist<double, 3> d;
  d << 0.005, 0, 0, -0.2, 0, 0;
  traj.append(inhand::TrajectorySegment<double, 3>::reciprocate(d, 0.4, 2));
  traj.append(inhand::TrajectorySegment<double, 3>::hold_for(0.1));
  for (int k = 0; k < 2000; ++k) {
    const double t = 1e-3 * k;
    const Eigen::Vector3d n = Eigen::Vector3d(std::sin(t), 1.0, 0.1 * std::cos(t)).normalized();
    const Eigen::Vector3d v =
        (k % 500 == 0) ? Eigen::Vector3d::Zero() : Eigen::Vector3d(std::sin(3 * t), 0.01, -0.02);
    servo.update(v, 1.0, 1.0 + std::sin(5 * t), n, (k / 100) % 2 == 0, 1e-3, cmd);
    pi.update(v, 1e-3, u);
    touching << (k % 3 != 0), 1, (k % 7 != 0), (k % 400 < 300);
    normals.col(0) = n;
    normals.col(1) = Eigen::Vector3d(0, 1, 0);
    normals.col(2) = Eigen::Vector3d(0.1, 1, 0).normalized();
    normals.col(3) = -n;
    planner.plan(touching, normals, 1e-3, forces, residual);
    const auto s = traj.evaluate(t - 0.1);
    (void)s;
  }
  EXPECT_TRUE(inhand::all_finite(cmd.total) && inhand::all_finite(forces));
  EXPECT_EQ(fetestexcept(FE_DIVBYZERO), 0);
}

// ---------------------------------------------------------------------------
// Closed loop: controller and plant

TEST(FpTraps, ClosedLoopPaperScenario) {
  using namespace inhand::plant;
  ScenarioSpec spec = paper_scenario(PaperObject::cylinder, PaperTask::rotate, 0, 0.6);
  ASSERT_EQ(spec.stages.size(), 3u);
  spec.stages[0].duration = 2.0;  // grasp timeout
  spec.stages[1].duration = 0.2;  // hold
  spec.stages[2].settle = 0.2;    // manipulate: 0.6 s cycle + 0.2 s settle
  long ticks = 0, manipulation_ticks = 0;
  ScenarioResult result;
  {
    TrapGuard guard;
    ASSERT_TRUE(guard.armed());
    result = ScenarioRunner().run(spec, [&](const TickRecord& r) {
      ++ticks;
      if (r.stage == 2) ++manipulation_ticks;
    });
  }
  EXPECT_TRUE(result.failure.empty()) << result.failure;
  ASSERT_EQ(result.stages.size(), 3u);
  EXPECT_FALSE(result.dropped);
  inhand_test::record("ticks", static_cast<double>(ticks));
  inhand_test::record("manipulation_ticks", static_cast<double>(manipulation_ticks));
  EXPECT_GE(manipulation_ticks, 700);
}

}  // namespace
