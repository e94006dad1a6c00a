// Tests of the force planner (controller/force_planner.hpp, docs/method.md section 5): the
// paper's thumb balancing three preset fingers, near-collinear normals, shared
// balancing, limits (always flagged), fingers out of contact, no balancing contact,
// the first-order filter, invalid input, parameter validation, run-time finger count.
#include "inhand/controller/force_planner.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "common/test_support.hpp"

namespace {

using inhand::FingerRole;
using inhand::ForcePlanner;
using inhand::ForcePlannerParams;
using inhand::ForcePlanStatus;
using inhand::has;
using inhand_test::record;
using inhand_test::scaled;

using Planner4 = ForcePlanner<double, 3, 4>;
using V3 = Eigen::Vector3d;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// No filtering, so a single plan() call returns the plan itself.
ForcePlannerParams<double> unfiltered() {
  ForcePlannerParams<double> p;
  p.filter_time = 0.0;
  return p;
}

/// Thumb (finger 0, balancing) pressing on the -y face; fingers 1-3 (preset) on +y.
Planner4 paper_hand(const ForcePlannerParams<double>& p = unfiltered()) {
  Planner4 planner;
  planner.set_params(p);
  planner.set_role(0, FingerRole::balancing);
  return planner;
}

Planner4::Normals collinear_normals() {
  Planner4::Normals n;
  n.col(0) = -V3::UnitY();
  for (int i = 1; i < 4; ++i) n.col(i) = V3::UnitY();
  return n;
}

/// A unit vector at exactly `angle` radians from `n`, in a random direction.
V3 tilt(const V3& n, double angle, inhand_test::Rng& rng) {
  V3 a = inhand_test::random_unit_vector<double, 3>(rng);
  a = (a - a.dot(n) * n).normalized();
  return (std::cos(angle) * n + std::sin(angle) * a).normalized();
}

TEST(ForcePlanner, ThumbBalancesThreePresetFingers) {
  Planner4 planner = paper_hand();
  const Planner4::Mask touching = Planner4::Mask::Ones();
  Planner4::ForceVector f;
  V3 residual;
  const ForcePlanStatus st = planner.plan(touching, collinear_normals(), 1e-3, f, residual);
  EXPECT_EQ(st, ForcePlanStatus::ok);
  const double rho = planner.params().regularisation;
  // Regularised balance, single balancing finger: f = (rho f0 + 3 f0) / (1 + rho).
  EXPECT_NEAR(f(0), (3.0 + rho) / (1.0 + rho), 1e-14);
  EXPECT_NEAR(f(0), 3.0, 2.0 * rho);
  for (int i = 1; i < 4; ++i) EXPECT_EQ(f(i), 1.0);
  // The resultant left by the regularisation: (3 - f) along +y, 2 rho / (1 + rho).
  EXPECT_LE(residual.norm(), 2.0 * rho / (1.0 + rho) + 1e-14);
  EXPECT_NEAR(residual(1), 2.0 * rho / (1.0 + rho), 1e-14);
  // Smaller regularisation, smaller residual.
  ForcePlannerParams<double> p = unfiltered();
  p.regularisation = 1e-9;
  Planner4 tight = paper_hand(p);
  tight.plan(touching, collinear_normals(), 1e-3, f, residual);
  EXPECT_NEAR(f(0), 3.0, 1e-8);
  EXPECT_LT(residual.norm(), 1e-8);
  record("residual_rho_1e-3", 2.0 * rho / (1.0 + rho));
}

TEST(ForcePlanner, NearCollinearNormalsLeaveOnlyTheUnbalanceableResidual) {
  auto rng = inhand_test::make_rng(77);
  const double angle = 5.0 * 3.14159265358979 / 180.0;
  const Planner4::Mask touching = Planner4::Mask::Ones();
  double worst = 0.0, worst_formula = 0.0;
  const int n = scaled(500);
  for (int k = 0; k < n; ++k) {
    Planner4 planner = paper_hand();
    Planner4::Normals normals = collinear_normals();
    for (int i = 0; i < 4; ++i) normals.col(i) = tilt(normals.col(i), angle, rng);
    Planner4::ForceVector f;
    V3 residual;
    ASSERT_EQ(planner.plan(touching, normals, 1e-3, f, residual), ForcePlanStatus::ok);
    const double rho = planner.params().regularisation;
    const V3 nb = normals.col(0);
    const V3 R = normals.col(1) + normals.col(2) + normals.col(3);
    // Closed form: residual = (I - nb nb^T) R + rho (R.nb + f0) / (1 + rho) nb.
    const V3 expected = R - R.dot(nb) * nb + rho * (R.dot(nb) + 1.0) / (1.0 + rho) * nb;
    worst_formula = std::max(worst_formula, (residual - expected).norm());
    // The part along the thumb normal is balanced; what is left is the component of R
    // orthogonal to it: each of the three 1 N normals is at most 10 degrees off -nb.
    EXPECT_LE(residual.norm(), 3.0 * std::sin(2.0 * angle) + 4.0 * rho);
    // Least-squares optimality: no other thumb force does better.
    for (double df : {-0.05, 0.05}) {
      EXPECT_LE(residual.norm(), (R + (f(0) + df) * nb).norm() + 1e-12);
    }
    // The residual equals the sum of the planned forces along the normals.
    EXPECT_LT((residual - (f(0) * nb + R)).norm(), 1e-14);
    worst = std::max(worst, residual.norm());
  }
  EXPECT_LT(worst_formula, 1e-14);
  record("worst_residual_5deg_N", worst);
}

TEST(ForcePlanner, TwoBalancingFingersShare) {
  ForcePlanner<double, 3, 5> planner;
  planner.set_params(unfiltered());
  planner.set_role(0, FingerRole::balancing);
  planner.set_role(4, FingerRole::balancing);
  ForcePlanner<double, 3, 5>::Normals normals;
  normals.col(0) = -V3::UnitY();
  normals.col(4) = -V3::UnitY();
  for (int i = 1; i < 4; ++i) normals.col(i) = V3::UnitY();
  ForcePlanner<double, 3, 5>::ForceVector f;
  V3 residual;
  ASSERT_EQ(planner.plan(ForcePlanner<double, 3, 5>::Mask::Ones(), normals, 1e-3, f, residual),
            ForcePlanStatus::ok);
  const double rho = planner.params().regularisation;
  // Gram [[1,1],[1,1]] + rho I, rhs (3 + rho)(1, 1): equal shares (3 + rho) / (2 + rho).
  EXPECT_NEAR(f(0), (3.0 + rho) / (2.0 + rho), 1e-12);
  EXPECT_NEAR(f(4), f(0), 1e-11);  // Gram condition ~ 2 / rho amplifies rounding
  EXPECT_NEAR(f(0) + f(4), 3.0, 2.0 * rho);
  EXPECT_LE(residual.norm(), rho);
  // Balancing normals tilted to either side: the exact balance f0 n0 + f4 n4 = -R has
  // a unique positive solution, which the regularised plan approaches.
  normals.col(0) = (-V3::UnitY() - 0.2 * V3::UnitX()).normalized();
  normals.col(4) = (-V3::UnitY() + 0.3 * V3::UnitX()).normalized();
  ASSERT_EQ(planner.plan(ForcePlanner<double, 3, 5>::Mask::Ones(), normals, 1e-3, f, residual),
            ForcePlanStatus::ok);
  Eigen::Matrix2d A;
  A << normals(0, 0), normals(0, 4), normals(1, 0), normals(1, 4);
  const Eigen::Vector2d exact = A.inverse() * Eigen::Vector2d(0.0, -3.0);
  EXPECT_GT(exact(0), exact(1));  // the less tilted normal takes more
  EXPECT_NEAR(f(0), exact(0), 0.01);
  EXPECT_NEAR(f(4), exact(1), 0.01);
  EXPECT_LE(residual.norm(), 5e-3);
  // Nb^T residual = -rho (f - f0): the normal equations of the regularised problem.
  EXPECT_NEAR(normals.col(0).dot(residual), -rho * (f(0) - 1.0), 1e-12);
  EXPECT_NEAR(normals.col(4).dot(residual), -rho * (f(4) - 1.0), 1e-12);
}

TEST(ForcePlanner, LimitsAreAppliedAndAlwaysFlagged) {
  ForcePlannerParams<double> p = unfiltered();
  p.max_force = 2.5;
  p.min_force = 0.3;
  // Above max_force: three fingers need 3 N.
  {
    Planner4 planner = paper_hand(p);
    Planner4::ForceVector f;
    V3 residual;
    const ForcePlanStatus st =
        planner.plan(Planner4::Mask::Ones(), collinear_normals(), 1e-3, f, residual);
    EXPECT_TRUE(has(st, ForcePlanStatus::limited));
    EXPECT_EQ(f(0), 2.5);
    EXPECT_NEAR(residual(1), 0.5, 1e-14);  // the unbalanced remainder is reported
  }
  // Below min_force: the preset fingers press on the SAME side as the thumb, so the
  // balance would need a pulling (negative) thumb force.
  {
    Planner4 planner = paper_hand(p);
    Planner4::Normals normals = collinear_normals();
    normals.col(1) = -V3::UnitY();
    normals.col(2) = -V3::UnitY();
    normals.col(3) = V3::UnitY();
    Planner4::ForceVector f;
    V3 residual;
    const ForcePlanStatus st = planner.plan(Planner4::Mask::Ones(), normals, 1e-3, f, residual);
    EXPECT_TRUE(has(st, ForcePlanStatus::limited));
    EXPECT_EQ(f(0), 0.3);
  }
  // Sweep: the flag is set exactly when the unconstrained plan leaves [min, max].
  auto rng = inhand_test::make_rng(4242);
  const int n = scaled(400);
  int flagged = 0;
  for (int k = 0; k < n; ++k) {
    ForcePlannerParams<double> q = unfiltered();
    q.min_force = inhand_test::uniform(rng, 0.0, 1.0);
    q.max_force = inhand_test::uniform(rng, 1.0, 5.0);
    q.nominal_force = inhand_test::uniform(rng, q.min_force, q.max_force);
    Planner4 planner = paper_hand(q);
    Planner4::Normals normals;
    for (int i = 0; i < 4; ++i) normals.col(i) = inhand_test::random_unit_vector<double, 3>(rng);
    Planner4::ForceVector f;
    V3 residual;
    const ForcePlanStatus st = planner.plan(Planner4::Mask::Ones(), normals, 1e-3, f, residual);
    const double rho = q.regularisation;
    const V3 R = q.nominal_force * (normals.col(1) + normals.col(2) + normals.col(3));
    const double free_f = (rho * q.nominal_force - R.dot(normals.col(0))) / (1.0 + rho);
    const bool outside = free_f < q.min_force || free_f > q.max_force;
    EXPECT_EQ(has(st, ForcePlanStatus::limited), outside) << "case " << k;
    EXPECT_GE(f(0), q.min_force);
    EXPECT_LE(f(0), q.max_force);
    if (!outside) {
      EXPECT_NEAR(f(0), free_f, 1e-12);
    }
    flagged += outside ? 1 : 0;
  }
  EXPECT_GT(flagged, 0);
  EXPECT_LT(flagged, n);
}

TEST(ForcePlanner, FingersNotTouchingAreExcluded) {
  Planner4 planner = paper_hand();
  Planner4::Normals normals = collinear_normals();
  normals.col(2).setConstant(kNaN);  // garbage normal of a finger that does not touch
  Planner4::Mask touching = Planner4::Mask::Ones();
  touching(2) = 0;
  Planner4::ForceVector f;
  V3 residual;
  const ForcePlanStatus st = planner.plan(touching, normals, 1e-3, f, residual);
  EXPECT_EQ(st, ForcePlanStatus::ok);
  const double rho = planner.params().regularisation;
  EXPECT_NEAR(f(0), (2.0 + rho) / (1.0 + rho), 1e-14);  // balances two fingers only
  EXPECT_EQ(f(2), 1.0);  // the nominal force it will press with when it touches again
  EXPECT_TRUE(inhand::all_finite(residual));
  EXPECT_LE(residual.norm(), 2.0 * rho);
}

TEST(ForcePlanner, NoBalancingContactIsFlagged) {
  Planner4 planner = paper_hand();
  Planner4::Mask touching = Planner4::Mask::Ones();
  touching(0) = 0;  // the thumb lost contact
  Planner4::ForceVector f;
  V3 residual;
  const ForcePlanStatus st = planner.plan(touching, collinear_normals(), 1e-3, f, residual);
  EXPECT_TRUE(has(st, ForcePlanStatus::no_balancing_contact));
  EXPECT_FALSE(has(st, ForcePlanStatus::invalid_input));
  for (int i = 0; i < 4; ++i) EXPECT_EQ(f(i), 1.0);
  EXPECT_NEAR(residual(1), 3.0, 1e-15);  // the unbalanced resultant is reported
  // A planner without any balancing finger always says so.
  Planner4 all_preset;
  all_preset.set_params(unfiltered());
  EXPECT_TRUE(has(all_preset.plan(Planner4::Mask::Ones(), collinear_normals(), 1e-3, f, residual),
                  ForcePlanStatus::no_balancing_contact));
}

TEST(ForcePlanner, FilterReaches63PercentAfterOneTimeConstant) {
  for (double dt : {1e-3, 5e-3}) {
    ForcePlannerParams<double> p;
    p.filter_time = 0.05;
    p.regularisation = 1e-9;
    Planner4 planner = paper_hand(p);
    Planner4::ForceVector f;
    V3 residual;
    // Primed on the first call: no lag from zero.
    planner.plan(Planner4::Mask::Ones(), collinear_normals(), dt, f, residual);
    EXPECT_NEAR(f(0), 3.0, 1e-8);
    // Step: one preset finger leaves, the target drops to 2 N.
    Planner4::Mask touching = Planner4::Mask::Ones();
    touching(3) = 0;
    const int steps = static_cast<int>(std::lround(p.filter_time / dt));
    double prev = f(0);
    for (int k = 0; k < steps; ++k) {
      planner.plan(touching, collinear_normals(), dt, f, residual);
      EXPECT_LT(f(0), prev);  // monotone
      EXPECT_GT(f(0), 2.0);   // no overshoot
      prev = f(0);
    }
    // Exact discretisation: 1 - e^-1 of the step after tau, whatever dt.
    EXPECT_NEAR((3.0 - f(0)) / 1.0, 1.0 - std::exp(-1.0), 1e-8) << "dt " << dt;
    // The residual reports the filtered (commanded) forces, not the target.
    EXPECT_NEAR(residual(1), 2.0 - f(0), 1e-12);
    // After reset() the filter is primed again from the next plan.
    planner.reset();
    planner.plan(Planner4::Mask::Ones(), collinear_normals(), dt, f, residual);
    EXPECT_NEAR(f(0), 3.0, 1e-8);
  }
}

TEST(ForcePlanner, InvalidInputKeepsTheLastPlanAndTheState) {
  ForcePlannerParams<double> p;
  p.filter_time = 0.02;
  Planner4 a = paper_hand(p), b = paper_hand(p);
  Planner4::ForceVector fa, fb;
  V3 ra, rb;
  Planner4::Mask touching = Planner4::Mask::Ones();
  a.plan(touching, collinear_normals(), 1e-3, fa, ra);
  b.plan(touching, collinear_normals(), 1e-3, fb, rb);
  touching(1) = 0;
  a.plan(touching, collinear_normals(), 1e-3, fa, ra);
  b.plan(touching, collinear_normals(), 1e-3, fb, rb);
  const Planner4::ForceVector last = fa;
  Planner4::Normals bad = collinear_normals();
  bad(1, 2) = kNaN;  // touching finger 2's normal
  for (double dt : {0.0, -1e-3, kNaN, std::numeric_limits<double>::infinity()}) {
    EXPECT_EQ(a.plan(touching, collinear_normals(), dt, fa, ra), ForcePlanStatus::invalid_input);
    EXPECT_TRUE(fa == last);
    EXPECT_TRUE(ra.isZero(0.0));
  }
  EXPECT_EQ(a.plan(touching, bad, 1e-3, fa, ra), ForcePlanStatus::invalid_input);
  EXPECT_TRUE(fa == last);
  // The next valid call continues exactly as if the bad calls never happened.
  EXPECT_EQ(a.plan(touching, collinear_normals(), 1e-3, fa, ra),
            b.plan(touching, collinear_normals(), 1e-3, fb, rb));
  EXPECT_TRUE(fa == fb);
  EXPECT_TRUE(ra == rb);
}

TEST(ForcePlanner, ParamsValidationNamesTheField) {
  struct Case {
    const char* field;
    void (*edit)(ForcePlannerParams<double>&);
  };
  const std::vector<Case> cases = {
      {"force_planner.nominal_force", [](ForcePlannerParams<double>& p) { p.nominal_force = 0; }},
      {"force_planner.nominal_force",
       [](ForcePlannerParams<double>& p) { p.nominal_force = kNaN; }},
      {"force_planner.min_force", [](ForcePlannerParams<double>& p) { p.min_force = -0.1; }},
      {"force_planner.max_force", [](ForcePlannerParams<double>& p) { p.max_force = 0.1; }},
      {"force_planner.nominal_force", [](ForcePlannerParams<double>& p) { p.nominal_force = 7; }},
      {"force_planner.regularisation", [](ForcePlannerParams<double>& p) { p.regularisation = 0; }},
      {"force_planner.filter_time", [](ForcePlannerParams<double>& p) { p.filter_time = -1; }},
      {"force_planner.filter_time", [](ForcePlannerParams<double>& p) { p.filter_time = kNaN; }},
  };
  EXPECT_TRUE(ForcePlannerParams<double>{}.validate().ok());
  for (const Case& c : cases) {
    ForcePlannerParams<double> p;
    c.edit(p);
    const inhand::Validation v = p.validate();
    ASSERT_FALSE(v.ok()) << c.field;
    EXPECT_EQ(std::string(v.field), c.field);
  }
}

TEST(ForcePlanner, RunTimeFingerCountMatchesFixed) {
  ForcePlanner<double, 3, inhand::Dynamic> dyn(4);
  Planner4 fixed = paper_hand(ForcePlannerParams<double>{});
  dyn.set_params(ForcePlannerParams<double>{});
  dyn.set_role(0, FingerRole::balancing);
  EXPECT_EQ(dyn.size(), 4);
  auto rng = inhand_test::make_rng(9);
  for (int k = 0; k < 50; ++k) {
    Planner4::Normals n4 = collinear_normals();
    for (int i = 0; i < 4; ++i) n4.col(i) = tilt(n4.col(i), 0.1, rng);
    Planner4::Mask m4 = Planner4::Mask::Ones();
    m4(1 + k % 3) = static_cast<unsigned char>(k % 2);
    Eigen::MatrixXd nd = n4;
    Eigen::Matrix<unsigned char, Eigen::Dynamic, 1> md = m4;
    Planner4::ForceVector f4;
    Eigen::VectorXd fd(4);
    V3 r4, rd;
    EXPECT_EQ(fixed.plan(m4, n4, 1e-3, f4, r4), dyn.plan(md, nd, 1e-3, fd, rd));
    EXPECT_LT((fd - f4).norm(), 1e-14);
    EXPECT_LT((rd - r4).norm(), 1e-14);
  }
}

TEST(ForcePlanner, PlanarHand) {
  ForcePlanner<double, 2, 3> planner;
  planner.set_params(unfiltered());
  planner.set_role(0, FingerRole::balancing);
  ForcePlanner<double, 2, 3>::Normals n;
  n << -1, 1, 1, 0, 0, 0;  // thumb on the -x face, two fingers on +x
  ForcePlanner<double, 2, 3>::ForceVector f;
  Eigen::Vector2d r;
  EXPECT_EQ(planner.plan(ForcePlanner<double, 2, 3>::Mask::Ones(), n, 1e-3, f, r),
            ForcePlanStatus::ok);
  EXPECT_NEAR(f(0), 2.0, 2e-3);
  EXPECT_LE(r.norm(), 2e-3);
}

}  // namespace
