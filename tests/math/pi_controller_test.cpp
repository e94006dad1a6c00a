// Properties of PiController (math/pi_controller.hpp): the PI law against a hand
// computation, anti-windup by conditional integration (bounded integral, no
// overshoot after the error changes sign), the integral limit, reset, invalid input
// and validate().
#include "inhand/math/pi_controller.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "common/test_support.hpp"

namespace {

using inhand::PiController;
using inhand::PiGains;
using inhand::PiStatus;

template <typename S>
class PiTest : public ::testing::Test {};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(PiTest, Scalars, inhand_test::ScalarNames);

template <typename S>
double tol() {
  return 8.0 * static_cast<double>(std::numeric_limits<S>::epsilon());
}

// kp = 2, ki = 3, by hand:
//  dt 0.1, x = (1, -2):   I = (0.1, -0.2),   u = 2 x + 3 I = (2.3, -4.6)
//  dt 0.1, x = (0.5, 0.5): I = (0.15, -0.15), u = (1.45, 0.55)
//  dt 0.2, x = (-1, 0):   I = (-0.05, -0.15), u = (-2.15, -0.45)
TYPED_TEST(PiTest, ProportionalIntegralMatchesHandComputation) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 2, 1>;
  PiController<S, 2> pi(PiGains<S>{S(2), S(3)});
  V u;
  const struct {
    S dt;
    V x, I, u;
  } steps[] = {
      {S(0.1), V(S(1), S(-2)), V(S(0.1), S(-0.2)), V(S(2.3), S(-4.6))},
      {S(0.1), V(S(0.5), S(0.5)), V(S(0.15), S(-0.15)), V(S(1.45), S(0.55))},
      {S(0.2), V(S(-1), S(0)), V(S(-0.05), S(-0.15)), V(S(-2.15), S(-0.45))},
  };
  for (const auto& s : steps) {
    EXPECT_EQ(pi.update(s.x, s.dt, u), PiStatus::ok);
    for (int i = 0; i < 2; ++i) {
      EXPECT_NEAR(pi.integral()(i), s.I(i), 4 * tol<S>());
      EXPECT_NEAR(u(i), s.u(i), 16 * tol<S>());
    }
  }
  // Pure proportional: u = kp x, the integral still accumulates (ki = 0 ignores it).
  PiController<S, 2> p(PiGains<S>{S(1.5), S(0)});
  EXPECT_EQ(p.update(V(S(2), S(-4)), S(0.5), u), PiStatus::ok);
  EXPECT_NEAR(u(0), 3.0, 4 * tol<S>());
  EXPECT_NEAR(u(1), -6.0, 4 * tol<S>());
}

// Random sequences against a reference in double: u_k = kp x_k + ki sum_j x_j dt_j.
TYPED_TEST(PiTest, RandomSequencesMatchReference) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 3, 1>;
  auto rng = inhand_test::make_rng(301);
  const int count = inhand_test::scaled(1000);
  for (int t = 0; t < count; ++t) {
    const double kp = inhand_test::uniform<double>(rng, 0, 5),
                 ki = inhand_test::uniform<double>(rng, 0, 5);
    PiController<S, 3> pi(PiGains<S>{static_cast<S>(kp), static_cast<S>(ki)});
    Eigen::Vector3d I = Eigen::Vector3d::Zero();
    for (int k = 0; k < 20; ++k) {
      const V x = inhand_test::random_vector<S, 3>(rng, S(-1), S(1));
      const S dt = inhand_test::uniform<S>(rng, S(1e-4), S(1e-2));
      V u;
      ASSERT_EQ(pi.update(x, dt, u), PiStatus::ok);
      I += x.template cast<double>() * static_cast<double>(dt);
      const Eigen::Vector3d ref =
          static_cast<double>(static_cast<S>(kp)) * x.template cast<double>() +
          static_cast<double>(static_cast<S>(ki)) * I;
      ASSERT_LE((u.template cast<double>() - ref).norm(), 64 * tol<S>() * (1 + ref.norm()));
    }
  }
}

// Constant input x = 1 with kp = 2, ki = 1, output_limit U = 5 for 100 s: the output
// reaches U when 2 + I = 5, and conditional integration stops the integral there, so
// I <= (U - kp x) / ki + x dt = 3 + dt (plain integration would give 100). The output
// never exceeds U and the status says output_limited. When the error changes sign
// (x = -1) the output leaves saturation at once and follows the windup-free response
// kp x + ki (I_sat + integral of x), I_sat = 3: no excursion beyond it.
TYPED_TEST(PiTest, AntiWindupBoundsIntegralAndLeavesSaturationAtOnce) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 1, 1>;
  const S kp = 2, ki = 1, U = 5, dt = S(1e-3);
  PiController<S, 1> pi(PiGains<S>{kp, ki, std::numeric_limits<S>::infinity(), U});
  const double bound = (5.0 - 2.0) / 1.0 + static_cast<double>(dt);
  V u;
  int saturated_steps = 0;
  double previous_integral = 0.0;
  for (int k = 0; k < 100000; ++k) {
    const PiStatus st = pi.update(V(S(1)), dt, u);
    ASSERT_LE(static_cast<double>(u(0)), 5.0 * (1 + tol<S>()));
    ASSERT_LE(static_cast<double>(pi.integral()(0)), bound) << "step " << k;
    ASSERT_GE(static_cast<double>(pi.integral()(0)), previous_integral) << "integral decreased";
    previous_integral = static_cast<double>(pi.integral()(0));
    if (has(st, PiStatus::output_limited)) ++saturated_steps;
  }
  EXPECT_GT(saturated_steps, 90000);
  // Frozen at the last unsaturated integral: u = kp x + ki I in (U - ki dt, U].
  EXPECT_NEAR(static_cast<double>(u(0)), 5.0, 1.01e-3);
  const double i_sat = static_cast<double>(pi.integral()(0));
  EXPECT_NEAR(i_sat, 3.0, 2e-3) << "integral frozen where saturation began";
  inhand_test::record("integral_after_100s_saturated", i_sat);

  // Error changes sign: the very first step is unsaturated, and the output stays on
  // the windup-free response (which decreases monotonically from kp x + ki I_sat = 1).
  double windup_free_integral = i_sat;
  double worst = 0.0;
  for (int k = 0; k < 5000; ++k) {
    const PiStatus st = pi.update(V(S(-1)), dt, u);
    windup_free_integral -= static_cast<double>(dt);
    const double ref = -2.0 + windup_free_integral;
    if (k == 0) {
      EXPECT_FALSE(has(st, PiStatus::output_limited)) << "still saturated after sign change";
    }
    worst = std::max(worst, std::abs(static_cast<double>(u(0)) - ref));
    ASSERT_NEAR(static_cast<double>(u(0)), std::max(ref, -5.0), 1e-3) << "step " << k;
  }
  inhand_test::record("deviation_from_windup_free_response", worst);
}

// Closed loop on an integrator plant y' = u, unit step of the reference, kp = 2,
// ki = 1, |u| <= U = 0.2. Without saturation the loop (2s+1)/(s+1)^2 gives
// y = 1 - e^-t + t e^-t, overshoot e^-2 = 13.5%: that windup-free response is the
// stated bound. With conditional integration the saturated loop stays below it;
// a plain PI whose output is clipped outside the controller winds up and overshoots
// by more than 3 times as much (the check that the scenario does exercise windup).
TYPED_TEST(PiTest, AntiWindupClosedLoopOvershootBelowWindupFreeResponse) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 1, 1>;
  const S dt = S(1e-3);
  const double linear_overshoot = std::exp(-2.0);
  auto run = [&](S output_limit, double clip) {
    PiController<S, 1> pi(PiGains<S>{S(2), S(1), std::numeric_limits<S>::infinity(), output_limit});
    double y = 0.0, ymax = 0.0;
    V u;
    for (int k = 0; k < 30000; ++k) {
      pi.update(V(static_cast<S>(1.0 - y)), dt, u);
      const double v = std::max(-clip, std::min(clip, static_cast<double>(u(0))));
      y += static_cast<double>(dt) * v;
      ymax = std::max(ymax, y);
    }
    EXPECT_NEAR(y, 1.0, 1e-3) << "the loop settles";
    return ymax - 1.0;
  };
  const double inf = std::numeric_limits<double>::infinity();
  const double anti_windup = run(S(0.2), inf);
  const double windup = run(std::numeric_limits<S>::infinity(), 0.2);
  const double unsaturated = run(std::numeric_limits<S>::infinity(), inf);
  EXPECT_NEAR(unsaturated, linear_overshoot, 2e-3) << "the windup-free reference";
  EXPECT_LE(anti_windup, linear_overshoot);
  EXPECT_GT(windup, 3 * linear_overshoot);
  inhand_test::record("overshoot_anti_windup", anti_windup);
  inhand_test::record("overshoot_clipped_plain_pi", windup);
}

// Integral limit L: whenever I + x dt exceeds L in norm it is scaled onto the sphere of
// radius L along its own direction (status integral_limited), else taken as is.
TYPED_TEST(PiTest, IntegralLimitKeepsDirection) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 3, 1>;
  const S L = S(0.5);
  PiController<S, 3> pi(PiGains<S>{S(1), S(2), L});
  auto rng = inhand_test::make_rng(302);
  int limited = 0;
  const int count = inhand_test::scaled(1000);
  for (int k = 0; k < count; ++k) {
    const V x = inhand_test::random_vector<S, 3>(rng, S(-1), S(1)) + V(S(0.3), S(0), S(0));
    const S dt = S(0.05);
    const Eigen::Vector3d cand =
        pi.integral().template cast<double>() + static_cast<double>(dt) * x.template cast<double>();
    V u;
    const PiStatus st = pi.update(x, dt, u);
    const Eigen::Vector3d I = pi.integral().template cast<double>();
    ASSERT_LE(I.norm(), static_cast<double>(L) * (1 + tol<S>()));
    if (cand.norm() > static_cast<double>(L) * (1 + tol<S>())) {
      ++limited;
      ASSERT_TRUE(has(st, PiStatus::integral_limited));
      ASSERT_LE((I - cand * (static_cast<double>(L) / cand.norm())).norm(), 4 * tol<S>())
          << "step " << k;
    } else if (cand.norm() < static_cast<double>(L) * (1 - tol<S>())) {
      ASSERT_FALSE(has(st, PiStatus::integral_limited));
      ASSERT_LE((I - cand).norm(), 4 * tol<S>());
    }
    const Eigen::Vector3d uref = x.template cast<double>() + 2.0 * I;
    ASSERT_LE((u.template cast<double>() - uref).norm(), 16 * tol<S>());
  }
  EXPECT_GT(limited, count / 2) << "the drift should keep the integral on its limit";
}

// Output limit keeps the direction of kp x + ki I (vector case) and bounds the norm.
TYPED_TEST(PiTest, OutputLimitKeepsDirection) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 3, 1>;
  auto rng = inhand_test::make_rng(303);
  const int count = inhand_test::scaled(1000);
  PiController<S, 3> pi(PiGains<S>{S(3), S(1), std::numeric_limits<S>::infinity(), S(1)});
  for (int k = 0; k < count; ++k) {
    const V x = inhand_test::random_vector<S, 3>(rng, S(-1), S(1));
    const Eigen::Vector3d I_before = pi.integral().template cast<double>();
    V u;
    const PiStatus st = pi.update(x, S(0.01), u);
    const Eigen::Vector3d I = pi.integral().template cast<double>();
    const Eigen::Vector3d raw = 3.0 * x.template cast<double>() + I;
    ASSERT_LE(u.template cast<double>().norm(), 1.0 + 4 * tol<S>());
    if (has(st, PiStatus::output_limited)) {
      ASSERT_GE(u.template cast<double>().dot(raw),
                (1 - 4 * tol<S>()) * u.template cast<double>().norm() * raw.norm());
      // Conditional integration: the integral moved only if that reduced |u|.
      if ((I - I_before).norm() > 0) {
        ASSERT_LE(raw.norm(),
                  (3.0 * x.template cast<double>() + I_before).norm() * (1 + 4 * tol<S>()));
      }
    } else {
      ASSERT_LE((u.template cast<double>() - raw).norm(), 8 * tol<S>());
    }
  }
}

TYPED_TEST(PiTest, ResetZeroesTheIntegral) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 2, 1>;
  PiController<S, 2> pi(PiGains<S>{S(2), S(3)});
  V u;
  for (int k = 0; k < 10; ++k) pi.update(V(S(1), S(-1)), S(0.1), u);
  EXPECT_GT(pi.integral().norm(), S(0.9));
  pi.reset();
  EXPECT_TRUE(pi.integral().isZero(0));
  pi.update(V(S(1), S(2)), S(0.1), u);  // as from a fresh controller: u = 2 x + 3 * 0.1 x
  EXPECT_NEAR(u(0), 2.3, 4 * tol<S>());
  EXPECT_NEAR(u(1), 4.6, 8 * tol<S>());
}

// Non-finite x, dt <= 0 or non-finite dt: u = 0, integral frozen, invalid_input.
TYPED_TEST(PiTest, InvalidInputGivesZeroAndFreezesIntegral) {
  using S = TypeParam;
  using V = Eigen::Matrix<S, 2, 1>;
  const S nan = std::numeric_limits<S>::quiet_NaN(), inf = std::numeric_limits<S>::infinity();
  PiController<S, 2> pi(PiGains<S>{S(2), S(3)});
  V u;
  pi.update(V(S(1), S(-1)), S(0.1), u);
  const V frozen = pi.integral();
  const struct {
    V x;
    S dt;
  } bad[] = {{V(nan, S(0)), S(0.1)}, {V(S(0), inf), S(0.1)},   {V(-inf, S(0)), S(0.1)},
             {V(S(1), S(1)), S(0)},  {V(S(1), S(1)), S(-0.1)}, {V(S(1), S(1)), nan},
             {V(S(1), S(1)), inf}};
  for (const auto& b : bad) {
    u.setConstant(S(7));
    EXPECT_EQ(pi.update(b.x, b.dt, u), PiStatus::invalid_input);
    EXPECT_TRUE(u.isZero(0));
    EXPECT_EQ(pi.integral(), frozen);
  }
  // And it continues from the frozen integral afterwards.
  EXPECT_EQ(pi.update(V(S(0), S(0)), S(0.1), u), PiStatus::ok);
  EXPECT_NEAR(u(0), 3 * frozen(0), 4 * tol<S>());
}

TEST(PiGains, ValidateNamesTheField) {
  const double nan = std::nan(""), inf = std::numeric_limits<double>::infinity();
  EXPECT_TRUE(PiGains<double>{}.validate().ok());
  EXPECT_TRUE((PiGains<double>{1.0, 2.0, 3.0, 4.0}.validate().ok()));
  EXPECT_STREQ((PiGains<double>{-1.0, 0.0}.validate().field), "kp");
  EXPECT_STREQ((PiGains<double>{nan, 0.0}.validate().field), "kp");
  EXPECT_STREQ((PiGains<double>{inf, 0.0}.validate().field), "kp");
  EXPECT_STREQ((PiGains<double>{1.0, -1.0}.validate().field), "ki");
  EXPECT_STREQ((PiGains<double>{1.0, nan}.validate().field), "ki");
  EXPECT_STREQ((PiGains<double>{1.0, 1.0, 0.0}.validate().field), "integral_limit");
  EXPECT_STREQ((PiGains<double>{1.0, 1.0, nan}.validate().field), "integral_limit");
  EXPECT_STREQ((PiGains<double>{1.0, 1.0, inf, -2.0}.validate().field), "output_limit");
  EXPECT_STREQ((PiGains<double>{1.0, 1.0, inf, nan}.validate().field), "output_limit");
  EXPECT_NE((PiGains<double>{-1.0, 0.0}.validate().reason), nullptr);
}

}  // namespace
