// Properties of ContactIk (controller/ik.hpp): eq. 3 with damping near singularity,
// least squares for m > n, minimum norm and the null-space term for n > m, joint
// velocity limits, and invalid input. Typed over every Jacobian shape a finger
// produces (2x2, 2x3, 3x2, 3x3, 3x4, 3x5; float and double; fixed, run-time bounded
// and run-time unbounded columns) and over the test fingers of common/test_support.hpp.
//
// Error bounds: the solver works on the Gram matrix, whose condition number is
// kappa^2, so residuals are judged against C * eps * kappa^2 (C stated per test).
#include "inhand/controller/ik.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <type_traits>

#include "controller/controller_fixtures.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace {

using namespace inhand_ctl_test;
using inhand::IkStatus;

template <typename Sh>
class IkShapeTest : public ::testing::Test {};

using Shapes =
    ::testing::Types<Shape<double, 2, 2>, Shape<double, 2, 3>, Shape<double, 3, 2>,
                     Shape<double, 3, 3>, Shape<double, 3, 4>, Shape<double, 3, 5>,
                     Shape<float, 2, 2>, Shape<float, 2, 3>, Shape<float, 3, 2>, Shape<float, 3, 3>,
                     Shape<float, 3, 4>, Shape<float, 3, 5>,
                     Shape<double, 3, Eigen::Dynamic, Eigen::Dynamic, 4>,
                     Shape<float, 3, Eigen::Dynamic, Eigen::Dynamic, 2>,
                     Shape<double, 3, Eigen::Dynamic, 5, 5>, Shape<float, 3, Eigen::Dynamic, 5, 5>,
                     Shape<double, 2, Eigen::Dynamic, 5, 3>, Shape<float, 3, Eigen::Dynamic, 5, 2>>;
TYPED_TEST_SUITE(IkShapeTest, Shapes, TypeNames);

/// theta_dot from ContactIk::solve, in double, with the report.
template <typename Sh>
VecXd ik_solve(typename Sh::Ik& ik, const typename Sh::Jacobian& J, const VecXd& xdot,
               const typename Sh::JointVector& limits,
               inhand::IkReport<typename Sh::Scalar>* report, const VecXd* z = nullptr) {
  typename Sh::JointVector qd = Sh::constant_joints(typename Sh::Scalar(0));
  const typename Sh::CartesianVector x = Sh::cartesian(xdot);
  inhand::IkReport<typename Sh::Scalar> r;
  if (z == nullptr) {
    r = ik.solve(J, x, limits, qd);
  } else {
    r = ik.solve(J, x, limits, Sh::joint_vector(*z), qd);
  }
  if (report != nullptr) *report = r;
  return qd.template cast<double>();
}

template <typename Sh>
MatXd ik_pinv(typename Sh::Ik& ik, const typename Sh::Jacobian& J,
              inhand::IkReport<typename Sh::Scalar>* report) {
  typename Sh::PseudoInverse P(Sh::kCols, Sh::kRows);
  P.setZero();
  const auto r = ik.pseudo_inverse(J, P);
  if (report != nullptr) *report = r;
  return P.template cast<double>();
}

double condition_number(const MatXd& A) { return sigma_max(A) / sigma_min(A); }

// Penrose conditions for ContactIk::pseudo_inverse on random matrices with kappa <= 40
// (sigma in [0.05, 2], above the default threshold: undamped, status ok).
// Bound: 50 eps kappa^2, relative.
TYPED_TEST(IkShapeTest, PseudoInversePenroseIdentities) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(201);
  auto ik = Sh::make_ik();
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const auto J = Sh::jacobian(
        matrix_with_singular_values(m, n, random_singular_values(k, 0.05, 2.0, rng), rng));
    const MatXd A = J.template cast<double>();
    inhand::IkReport<S> rep;
    const MatXd P = ik_pinv<Sh>(ik, J, &rep);
    ASSERT_EQ(rep.status, IkStatus::ok);
    ASSERT_EQ(rep.damping, S(0));
    const double kappa = condition_number(A);
    const double unit = eps<S>() * kappa * kappa;
    const MatXd AP = A * P, PA = P * A;
    const double r[4] = {(AP * A - A).norm() / A.norm(), (PA * P - P).norm() / P.norm(),
                         (AP.transpose() - AP).norm(), (PA.transpose() - PA).norm()};
    const char* names[4] = {"A A+ A = A", "A+ A A+ = A+", "(A A+)^T = A A+", "(A+ A)^T = A+ A"};
    for (int i = 0; i < 4; ++i) {
      worst = std::max(worst, r[i] / unit);
      ASSERT_LE(r[i], 50 * unit) << names[i] << ", sample " << t;
    }
  }
  inhand_test::record("penrose_residual_over_eps_kappa2", worst);
}

// Agreement with Eigen's CompleteOrthogonalDecomposition pseudo-inverse (50 eps kappa^2).
TYPED_TEST(IkShapeTest, PseudoInverseMatchesCompleteOrthogonalDecomposition) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(202);
  auto ik = Sh::make_ik();
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const auto J = Sh::jacobian(
        matrix_with_singular_values(m, n, random_singular_values(k, 0.05, 2.0, rng), rng));
    const MatXd A = J.template cast<double>();
    const MatXd P = ik_pinv<Sh>(ik, J, nullptr);
    const MatXd Pref = reference_pinv(A);
    const double kappa = condition_number(A);
    const double rel = (P - Pref).norm() / Pref.norm() / (eps<S>() * kappa * kappa);
    worst = std::max(worst, rel);
    ASSERT_LE(rel, 50.0) << "sample " << t;
  }
  inhand_test::record("cod_disagreement_over_eps_kappa2", worst);
}

// m = n: J qdot = xdot. m > n: residual orthogonal to range(J). n > m: J qdot = xdot and
// qdot orthogonal to null(J). Without limits the status is ok and limit_scale 1.
TYPED_TEST(IkShapeTest, ExactLeastSquaresOrMinimumNorm) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(203);
  auto ik = Sh::make_ik();
  const auto limits = Sh::no_limits();
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const auto J = Sh::jacobian(
        matrix_with_singular_values(m, n, random_singular_values(k, 0.05, 2.0, rng), rng));
    const MatXd A = J.template cast<double>();
    VecXd xd = gaussian_vector(m, rng);
    // Least squares: a part in range(J) plus a unit normal to it, so the residual is ~1.
    if (m > n) xd = A * gaussian_vector(n, rng) + unit_normal_to_range(A);
    xd = Sh::cartesian(xd).template cast<double>();
    inhand::IkReport<S> rep;
    const VecXd qd = ik_solve<Sh>(ik, J, xd, limits, &rep);
    ASSERT_EQ(rep.status, IkStatus::ok);
    ASSERT_EQ(rep.limit_scale, S(1));
    const double kappa = condition_number(A);
    const double tol = 50 * eps<S>() * kappa * kappa;
    if (m == n) {
      ASSERT_LE((A * qd - xd).norm(), tol * xd.norm()) << "J qdot = xdot, sample " << t;
    } else if (m > n) {
      Eigen::JacobiSVD<MatXd> svd(A, Eigen::ComputeThinU);
      const VecXd r = xd - A * qd;
      ASSERT_GT(r.norm(), 0.5) << "xdot should not lie in range(J)";
      ASSERT_LE((svd.matrixU().transpose() * r).norm(), tol * xd.norm())
          << "normal equations: residual not orthogonal to range(J), sample " << t;
    } else {
      ASSERT_LE((A * qd - xd).norm(), tol * xd.norm()) << "J qdot = xdot, sample " << t;
      ASSERT_LE((null_space_basis(A).transpose() * qd).norm(), tol * qd.norm())
          << "minimum norm: qdot has a null-space component, sample " << t;
    }
  }
}

// At a constructed singular Jacobian (sigma_min exactly 0 or 1e-9) and across the damped
// region (sigma_min = 0.3, 0.6, 0.95 of the threshold, where the gain peaks), with x_dot
// weighted towards the least-controllable direction: |qdot| <= gain_bound() |xdot|, the
// status says damped, and qdot is the damped solution for the reported lambda.
TYPED_TEST(IkShapeTest, SingularJacobianIsDampedAndBounded) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  const double tol = std::is_same<S, double>::value ? 1e-6 : 2e-2;
  Rng rng(204);
  const double schedules[][2] = {{5e-3, 5e-3}, {5e-2, 1e-2}, {1e-2, 2e-2}};
  const double fractions[] = {0.0, 1e-9, 0.3, 0.6, 0.95};
  double worst = 0.0;
  const int count = sweep_count() / 3 + 1;
  for (const auto& sc : schedules) {
    inhand::IkParams<S> params;
    params.damping.singular_threshold = static_cast<S>(sc[0]);
    params.damping.max_damping = static_cast<S>(sc[1]);
    auto ik = Sh::make_ik(params);
    for (int t = 0; t < count; ++t) {
      VecXd s = random_singular_values(k, 0.1, 2.0, rng);
      s(k - 1) = fractions[t % 5] * sc[0];
      const MatXd U = random_orthogonal(m, rng);
      const auto J = Sh::jacobian(compose(U, s, random_orthogonal(n, rng)));
      const VecXd xd =
          Sh::cartesian(gaussian_vector(m, rng) + 3.0 * U.col(k - 1)).template cast<double>();
      inhand::IkReport<S> rep;
      const VecXd qd = ik_solve<Sh>(ik, J, xd, Sh::no_limits(), &rep);
      ASSERT_TRUE(qd.allFinite());
      ASSERT_TRUE(has(rep.status, IkStatus::damped)) << inhand::to_string(rep.status);
      ASSERT_FALSE(has(rep.status, IkStatus::invalid_input));
      ASSERT_GT(rep.damping, S(0));
      const double bound = static_cast<double>(ik.gain_bound()) * xd.norm();
      ASSERT_LE(qd.norm(), bound * (1 + tol)) << "sample " << t;
      const double l2 = static_cast<double>(rep.damping) * static_cast<double>(rep.damping);
      const VecXd ref = reference_damped_solve_l2(J.template cast<double>(), xd, l2);
      ASSERT_LE((qd - ref).norm(), tol * bound) << "sample " << t;
      worst = std::max(worst, qd.norm() / bound);
    }
  }
  inhand_test::record("max_qdot_over_gain_bound_xdot", worst);
}

/// IkParams asking for sigma_min on every solve (IkParams::exact_min_singular_value).
template <typename S>
inhand::IkParams<S> exact_sigma_params() {
  inhand::IkParams<S> p;
  p.exact_min_singular_value = true;
  return p;
}

// The reported sigma_min is the true one (JacobiSVD), also for m > n:
// |sigma_rep^2 - sigma_true^2| <= 20 eps sigma_max^2 (the Gram matrix resolves sigma^2).
TYPED_TEST(IkShapeTest, ReportedMinSingularValueMatchesJacobiSvd) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(205);
  auto ik = Sh::make_ik(exact_sigma_params<S>());
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const double smin = std::exp(uniform(rng, std::log(1e-6), 0.0));
    VecXd s = random_singular_values(k, smin, 2.0, rng);
    s(k - 1) = smin;
    const auto J = Sh::jacobian(matrix_with_singular_values(m, n, s, rng));
    const VecXd sv = singular_values(J.template cast<double>());
    inhand::IkReport<S> rep;
    ik_solve<Sh>(ik, J, gaussian_vector(m, rng), Sh::no_limits(), &rep);
    const double rs = static_cast<double>(rep.min_singular_value), ts = sv.minCoeff();
    const double err = std::abs(rs * rs - ts * ts) / (eps<S>() * sv.maxCoeff() * sv.maxCoeff());
    worst = std::max(worst, err);
    ASSERT_LE(err, 20.0) << "reported " << rs << " true " << ts << ", sample " << t;
    ASSERT_EQ(has(rep.status, IkStatus::damped), rs < 5e-3) << "sample " << t;
    ASSERT_TRUE(rep.min_singular_value_exact);
  }
  inhand_test::record("sigma2_error_over_eps_sigmamax2", worst);
}

// The default (exact_min_singular_value false) computes sigma_min only where it sets the
// damping. Over the same sweep (sigma_min from 1e-6 to 1, across the threshold): the
// report is either exact (as above) or, outside the damped region only, the threshold
// with the true sigma_min^2 at least threshold^2 - 20 eps sigma_max^2; the damping and
// the command equal those of an exact solver to rounding.
TYPED_TEST(IkShapeTest, CertifiedSigmaKeepsTheCommandAndBoundsSigma) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(206);
  auto fast = Sh::make_ik();
  auto exact = Sh::make_ik(exact_sigma_params<S>());
  const double threshold = 5e-3, tol = std::is_same<S, double>::value ? 1e-12 : 1e-5;
  int certified = 0, computed = 0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const double smin = std::exp(uniform(rng, std::log(1e-6), 0.0));
    VecXd s = random_singular_values(k, smin, 2.0, rng);
    s(k - 1) = smin;
    const auto J = Sh::jacobian(matrix_with_singular_values(m, n, s, rng));
    const VecXd sv = singular_values(J.template cast<double>());
    const VecXd xd = gaussian_vector(m, rng);
    inhand::IkReport<S> rf, re;
    const VecXd qf = ik_solve<Sh>(fast, J, xd, Sh::no_limits(), &rf);
    const VecXd qe = ik_solve<Sh>(exact, J, xd, Sh::no_limits(), &re);
    const double ts = sv.minCoeff(), floor = 20.0 * eps<S>() * sv.maxCoeff() * sv.maxCoeff();
    if (rf.min_singular_value_exact) {
      ++computed;
      ASSERT_EQ(rf.min_singular_value, re.min_singular_value) << "sample " << t;
    } else {
      ++certified;
      ASSERT_EQ(k, 3) << "only 3-row Gram matrices are certified";
      ASSERT_EQ(static_cast<double>(rf.min_singular_value), static_cast<double>(S(threshold)));
      ASSERT_GE(ts * ts, threshold * threshold - floor) << "sample " << t;
      ASSERT_FALSE(has(rf.status, IkStatus::damped)) << "sample " << t;
    }
    ASSERT_NEAR(static_cast<double>(rf.damping), static_cast<double>(re.damping), 1e-6 * threshold)
        << "sample " << t;
    ASSERT_LE((qf - qe).norm(), tol * (1.0 + qe.norm())) << "sample " << t;
  }
  if (k == 3) {
    EXPECT_GT(certified, count / 4);
  }
  EXPECT_GT(computed, 0);
  inhand_test::record("certified_fraction", static_cast<double>(certified) / count);
}

// Limits: the whole vector is scaled by s = min(1, min_i limit_i / |qdot_i|) so it stays
// parallel to the unlimited solution, every |qdot_i| <= limit_i, status `limited`
// exactly when s < 1, and limit_scale = s.
TYPED_TEST(IkShapeTest, VelocityLimitsScaleTheWholeVector) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  const double tol = 8 * eps<S>();
  Rng rng(206);
  auto ik = Sh::make_ik();
  int limited_count = 0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    VecXd s = random_singular_values(k, 0.05, 2.0, rng);
    if (t % 4 == 0) s(k - 1) = 1e-4;  // damped as well
    const auto J = Sh::jacobian(matrix_with_singular_values(m, n, s, rng));
    const VecXd xd = Sh::cartesian(gaussian_vector(m, rng)).template cast<double>();
    inhand::IkReport<S> free_rep, rep;
    const VecXd q0 = ik_solve<Sh>(ik, J, xd, Sh::no_limits(), &free_rep);
    VecXd lim(n);
    double expected_scale = 1.0;
    for (int i = 0; i < n; ++i) {
      lim(i) = static_cast<double>(
          static_cast<S>(std::max(std::abs(q0(i)) * uniform(rng, 0.3, 1.6), 1e-3)));
      if (std::abs(q0(i)) > lim(i))
        expected_scale = std::min(expected_scale, lim(i) / std::abs(q0(i)));
    }
    const VecXd q = ik_solve<Sh>(ik, J, xd, Sh::joint_vector(lim), &rep);
    const double sc = static_cast<double>(rep.limit_scale);
    ASSERT_NEAR(sc, expected_scale, 4 * tol * expected_scale) << "sample " << t;
    ASSERT_EQ(has(rep.status, IkStatus::limited), expected_scale < 1.0) << "sample " << t;
    ASSERT_EQ(has(rep.status, IkStatus::damped), has(free_rep.status, IkStatus::damped));
    for (int i = 0; i < n; ++i) ASSERT_LE(std::abs(q(i)), lim(i) * (1 + tol)) << "joint " << i;
    // Parallel: q = s q0, and the angle between them is zero.
    ASSERT_LE((q - sc * q0).norm(), tol * q0.norm()) << "sample " << t;
    ASSERT_GE(q.dot(q0), (1 - 4 * tol) * q.norm() * q0.norm()) << "sample " << t;
    if (expected_scale < 1.0) ++limited_count;
  }
  EXPECT_GT(limited_count, count / 2) << "the sweep should mostly exercise active limits";
}

// Null-space term (I - J+ J) z: for n > m, J times the added joint velocity is zero and
// it equals the projection computed from the reference pseudo-inverse; for n <= m the
// term is ignored (identical output).
TYPED_TEST(IkShapeTest, NullSpaceTerm) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(207);
  auto ik = Sh::make_ik();
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const auto J = Sh::jacobian(
        matrix_with_singular_values(m, n, random_singular_values(k, 0.05, 2.0, rng), rng));
    const MatXd A = J.template cast<double>();
    const VecXd xd = Sh::cartesian(gaussian_vector(m, rng)).template cast<double>();
    const VecXd z = Sh::joint_vector(gaussian_vector(n, rng)).template cast<double>();
    inhand::IkReport<S> r0, rz;
    const VecXd q0 = ik_solve<Sh>(ik, J, xd, Sh::no_limits(), &r0);
    const VecXd qz = ik_solve<Sh>(ik, J, xd, Sh::no_limits(), &rz, &z);
    ASSERT_EQ(r0.status, rz.status);
    if (n <= m) {
      ASSERT_EQ(0, std::memcmp(q0.data(), qz.data(), sizeof(double) * static_cast<std::size_t>(n)))
          << "the null-space term must be ignored for n <= m";
      continue;
    }
    const double kappa = condition_number(A);
    const double tol = 50 * eps<S>() * kappa * kappa;
    const VecXd d = qz - q0;
    const VecXd expected = z - reference_pinv(A) * (A * z);
    ASSERT_LE((A * d).norm(), tol * A.norm() * z.norm())
        << "J (null-space term) != 0, sample " << t;
    ASSERT_LE((d - expected).norm(), tol * z.norm()) << "sample " << t;
    worst = std::max(worst, (A * d).norm() / (A.norm() * z.norm()));
  }
  if (n > m) inhand_test::record("J_times_nullspace_term_relative", worst);
}

// The null-space term is limited together with the rest: every |qdot_i| <= limit_i.
TYPED_TEST(IkShapeTest, NullSpaceTermRespectsLimits) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(208);
  auto ik = Sh::make_ik();
  const int count = sweep_count() / 4;
  for (int t = 0; t < count; ++t) {
    const auto J = Sh::jacobian(
        matrix_with_singular_values(m, n, random_singular_values(k, 0.05, 2.0, rng), rng));
    const VecXd xd = gaussian_vector(m, rng);
    const VecXd z = 10.0 * gaussian_vector(n, rng);
    const VecXd lim = VecXd::Constant(n, 0.5);
    inhand::IkReport<S> rep;
    const VecXd q = ik_solve<Sh>(ik, J, xd, Sh::joint_vector(lim), &rep, &z);
    for (int i = 0; i < n; ++i) ASSERT_LE(std::abs(q(i)), 0.5 * (1 + 8 * eps<S>()));
  }
}

// Non-finite J, xdot or z, and non-positive or NaN limits: zero output, invalid_input.
TYPED_TEST(IkShapeTest, InvalidInputGivesZero) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols, k = m < n ? m : n;
  Rng rng(209);
  auto ik = Sh::make_ik();
  const S nan = std::numeric_limits<S>::quiet_NaN(), inf = std::numeric_limits<S>::infinity();
  const auto J0 = Sh::jacobian(matrix_with_singular_values(m, n, VecXd::Ones(k), rng));
  const typename Sh::CartesianVector x0 = Sh::cartesian(gaussian_vector(m, rng));
  const auto z0 = Sh::joint_vector(gaussian_vector(n, rng));
  const auto lim0 = Sh::constant_joints(S(2));

  auto expect_invalid = [&](const typename Sh::Jacobian& J, const typename Sh::CartesianVector& x,
                            const typename Sh::JointVector& lim, const typename Sh::JointVector* z,
                            const char* what) {
    typename Sh::JointVector qd = Sh::constant_joints(S(7));
    const auto rep = z == nullptr ? ik.solve(J, x, lim, qd) : ik.solve(J, x, lim, *z, qd);
    EXPECT_EQ(rep.status, IkStatus::invalid_input) << what;
    EXPECT_TRUE(qd.isZero(0)) << what << ": " << qd.transpose();
  };
  for (S bad : {nan, inf, -inf}) {
    for (int idx = 0; idx < m * n; ++idx) {
      auto J = J0;
      J(idx % m, idx / m) = bad;
      expect_invalid(J, x0, lim0, nullptr, "non-finite J");
      expect_invalid(J, x0, lim0, &z0, "non-finite J (null-space solve)");
      typename Sh::PseudoInverse P(n, m);
      P.setConstant(S(7));
      EXPECT_EQ(ik.pseudo_inverse(J, P).status, IkStatus::invalid_input);
      EXPECT_TRUE(P.isZero(0));
    }
    for (int i = 0; i < m; ++i) {
      auto x = x0;
      x(i) = bad;
      expect_invalid(J0, x, lim0, nullptr, "non-finite xdot");
      expect_invalid(J0, x, lim0, &z0, "non-finite xdot (null-space solve)");
    }
    for (int i = 0; i < n; ++i) {
      auto z = z0;
      z(i) = bad;
      expect_invalid(J0, x0, lim0, &z, "non-finite z");
    }
  }
  for (S bad_limit : {S(0), S(-1), -inf, nan}) {
    for (int i = 0; i < n; ++i) {
      auto lim = lim0;
      lim(i) = bad_limit;
      expect_invalid(J0, x0, lim, nullptr, "non-positive or NaN limit");
      expect_invalid(J0, x0, lim, &z0, "non-positive or NaN limit (null-space solve)");
    }
  }
  // +inf means "no limit" and is valid.
  typename Sh::JointVector qd = Sh::constant_joints(S(0));
  EXPECT_EQ(ik.solve(J0, x0, Sh::no_limits(), qd).status, IkStatus::ok);
  EXPECT_TRUE(qd.allFinite());
}

TEST(IkStatus, NamesAndFlags) {
  EXPECT_STREQ(inhand::to_string(IkStatus::ok), "ok");
  EXPECT_STREQ(inhand::to_string(IkStatus::damped | IkStatus::limited), "damped_and_limited");
  EXPECT_STREQ(inhand::to_string(IkStatus::invalid_input), "invalid_input");
  EXPECT_TRUE(has(IkStatus::damped_and_limited, IkStatus::damped));
  EXPECT_TRUE(has(IkStatus::damped_and_limited, IkStatus::limited));
  EXPECT_FALSE(has(IkStatus::damped, IkStatus::limited));
}

// ---------------------------------------------------------------------------
// Real fingers: contact Jacobians from forward kinematics.

template <typename Chain>
Chain test_finger() {
  if constexpr (Chain::Dim == 3 && Chain::Dof == 2) {
    return make_two_joint_spatial_finger<typename Chain::Scalar>();
  } else {
    return inhand_test::make_finger<Chain>();
  }
}

template <typename Chain>
class IkFingerTest : public ::testing::Test {};

using Fingers = ::testing::Types<
    inhand_test::Planar2<float>, inhand_test::Planar2<double>, inhand_test::Planar3<float>,
    inhand_test::Planar3<double>, inhand::FingerChain<float, 3, 2>,
    inhand::FingerChain<double, 3, 2>, inhand_test::Spatial3<float>, inhand_test::Spatial3<double>,
    inhand_test::Spatial4<float>, inhand_test::Spatial4<double>, inhand_test::Spatial5<float>,
    inhand_test::Spatial5<double>, inhand_test::SpatialDynamic<double>,
    inhand_test::SpatialBounded<float>, inhand_test::SpatialBounded<double>>;
TYPED_TEST_SUITE(IkFingerTest, Fingers, inhand_test::ChainNames);

template <typename Chain>
using FingerIk = inhand::ContactIk<typename Chain::Scalar, Chain::Dim, Chain::Dof, Chain::MaxDof>;

/// Contact Jacobian of `chain` at joint angles q for the point at `offset` in the
/// fingertip frame.
template <typename Chain>
typename Chain::Jacobian contact_jacobian(
    const Chain& chain, const typename Chain::JointVector& q,
    const inhand::Vector<typename Chain::Scalar, Chain::Dim>& offset) {
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  typename Chain::Jacobian J(Chain::Dim, chain.dof());
  inhand::point_jacobian(ws, ws.fingertip.transform_point(offset), J);
  return J;
}

// sigma_min reported for real contact Jacobians (fewer than 6 joints, including the
// 3 x 2 least-squares finger) equals the smallest of the min(m, n) singular values:
// |sigma_rep^2 - sigma_true^2| <= 20 eps sigma_max^2.
TYPED_TEST(IkFingerTest, MinSingularValueMatchesJacobiSvd) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  const Chain chain = test_finger<Chain>();
  FingerIk<Chain> ik(chain.dof(), exact_sigma_params<S>());
  Rng rng(210);
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const auto q = inhand_test::random_joint_angles(chain, rng);
    const auto J = contact_jacobian(chain, q, inhand_test::random_fingertip_offset(chain, rng));
    const MatXd A = J.template cast<double>();
    const VecXd sv = singular_values(A);
    ASSERT_EQ(sv.size(), std::min(Chain::Dim, chain.dof()));
    typename Chain::JointVector qd(chain.dof());
    qd.setZero();
    const auto rep =
        ik.solve(J, inhand::Vector<S, Chain::Dim>::UnitX(), chain.velocity_limits(), qd);
    const double rs = static_cast<double>(rep.min_singular_value), ts = sv.minCoeff();
    const double err = std::abs(rs * rs - ts * ts) / (eps<S>() * sv.maxCoeff() * sv.maxCoeff());
    worst = std::max(worst, err);
    ASSERT_LE(err, 20.0) << "reported " << rs << " true " << ts << ", sample " << t;
  }
  inhand_test::record("sigma2_error_over_eps_sigmamax2", worst);
}

// Fully stretched (q = 0, the fingertip centre on the link line) the contact Jacobian is
// singular; the IK damps and |qdot| <= gain_bound |xdot|, for any xdot.
TYPED_TEST(IkFingerTest, StretchedFingerIsDampedAndBounded) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  if constexpr (Chain::Dim == 3 && Chain::Dof == 2) {
    GTEST_SKIP() << "abduction + flexion is not singular when stretched (rank 2 = n)";
  }
  const Chain chain = test_finger<Chain>();
  FingerIk<Chain> ik(chain.dof());
  typename Chain::JointVector q(chain.dof());
  q.setZero();
  const auto J = contact_jacobian(chain, q, inhand::Vector<S, Chain::Dim>::Zero());
  const MatXd A = J.template cast<double>();
  ASSERT_LT(sigma_min(A), 1e3 * eps<S>()) << "the stretched finger should be singular";
  Rng rng(211);
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const VecXd xd = gaussian_vector(Chain::Dim, rng);
    const inhand::Vector<S, Chain::Dim> x = xd.cast<S>();
    typename Chain::JointVector qd(chain.dof());
    qd.setZero();
    typename Chain::JointVector no_limit(chain.dof());
    no_limit.setConstant(std::numeric_limits<S>::infinity());
    const auto rep = ik.solve(J, x, no_limit, qd);
    ASSERT_EQ(rep.status, IkStatus::damped);
    ASSERT_TRUE(qd.allFinite());
    ASSERT_LE(static_cast<double>(qd.norm()),
              static_cast<double>(ik.gain_bound()) * static_cast<double>(x.norm()) * (1 + 1e-3));
  }
}

// A 4-joint damped solve (3 x 4): finite, flagged damped, bounded, lambda on the
// schedule for the reported sigma_min, and equal to the damped least-squares solution
// for that lambda computed by SVD in double (1e-6 relative in double, 2e-2 in float,
// of gain_bound |xdot|). Both the real 4-DOF finger close to its
// stretched pose and constructed 3 x 4 matrices with sigma_min below the threshold.
TEST(ContactIkFourJoint, DampedSolveIsFiniteAndCorrect) {
  auto run = [](auto scalar_tag, double tol) {
    using S = decltype(scalar_tag);
    using Chain = inhand_test::Spatial4<S>;
    const Chain chain = inhand_test::make_finger<Chain>();
    inhand::ContactIk<S, 3, 4> ik;
    Rng rng(212);
    const inhand::DampingSchedule<S> sched{};
    const int count = sweep_count();
    int damped = 0;
    for (int t = 0; t < count; ++t) {
      typename Chain::Jacobian J;
      if (t % 2 == 0) {
        typename Chain::JointVector q;
        for (int i = 0; i < 4; ++i) q(i) = static_cast<S>(uniform(rng, -2e-2, 2e-2));
        J = contact_jacobian(chain, q, inhand::Vector<S, 3>::Zero());
      } else {
        VecXd s = random_singular_values(3, 0.05, 0.2, rng);
        s(2) = std::exp(uniform(rng, std::log(1e-7), std::log(4e-3)));
        J = matrix_with_singular_values(3, 4, s, rng).cast<S>();
      }
      const MatXd A = J.template cast<double>();
      const VecXd xd = Eigen::Vector3d(gaussian_vector(3, rng)).cast<S>().template cast<double>();
      Eigen::Matrix<S, 4, 1> qd = Eigen::Matrix<S, 4, 1>::Zero();
      const auto rep =
          ik.solve(J, xd.cast<S>(),
                   Eigen::Matrix<S, 4, 1>::Constant(std::numeric_limits<S>::infinity()), qd);
      const double bound = static_cast<double>(ik.gain_bound()) * xd.norm();
      ASSERT_TRUE(qd.allFinite());
      ASSERT_FALSE(has(rep.status, IkStatus::invalid_input));
      const double smin = sigma_min(A);
      if (smin < 0.99 * 5e-3) {
        ASSERT_TRUE(has(rep.status, IkStatus::damped)) << "sigma " << smin;
      }
      if (smin > 1.01 * 5e-3) {
        ASSERT_FALSE(has(rep.status, IkStatus::damped)) << "sigma " << smin;
      }
      if (!has(rep.status, IkStatus::damped)) continue;
      ++damped;
      ASSERT_LE(static_cast<double>(qd.norm()), bound * (1 + tol));
      const double l2 = static_cast<double>(rep.damping) * static_cast<double>(rep.damping);
      ASSERT_NEAR(l2,
                  schedule_damping_squared(static_cast<double>(rep.min_singular_value),
                                           static_cast<double>(sched.singular_threshold),
                                           static_cast<double>(sched.max_damping)),
                  1e-4 * 25e-6);
      const VecXd ref = reference_damped_solve_l2(A, xd, l2);
      ASSERT_LE((qd.template cast<double>() - ref).norm(), tol * bound) << "sample " << t;
    }
    EXPECT_GT(damped, count * 3 / 4);
  };
  run(double{}, 1e-6);
  run(float{}, 2e-2);
}

// A run-time DOF bounded at compile time (ContactIk<S, Dim, Dynamic, MaxDof>) solves over
// fixed-size views for its joint count (controller/ik.hpp, solve_sized): the result must
// be the fixed-DOF solver's. Random 3 x K and 2 x K Jacobians, K = 1..5 (tall, square,
// wide), half of them near-singular (damped), velocity limits that bind in a third of the
// samples, a joint-position box that binds in a quarter (the box re-solve, with the normal
// weighted), the certified and the exact sigma_min. Asserted: the same status, held joints
// and figures, and theta_dot equal to a few units in the last place of its largest entry
// (the same operations; a compiler may contract them differently in the two instances).
// A fixed 3 x 1 solver does not exist (Eigen has no 1 x 3 column-major pseudo-inverse):
// K = 1 is compared with the run-time-unbounded solver, whose code for one column is the
// same.
template <typename S, int Dim, int K, typename Reference = inhand::ContactIk<S, Dim, K, K>>
void expect_bounded_equals_fixed(Rng& rng, int count, double ulps) {
  inhand::IkParams<S> params;
  params.exact_min_singular_value = (count % 2) == 1;
  Reference fixed(K, params);
  inhand::ContactIk<S, Dim, Eigen::Dynamic, 5> bounded(K, params);
  using FixedJ = typename Reference::Jacobian;
  using BoundedJ = typename inhand::ContactIk<S, Dim, Eigen::Dynamic, 5>::Jacobian;
  using FixedV = typename Reference::JointVector;
  using BoundedV = typename inhand::ContactIk<S, Dim, Eigen::Dynamic, 5>::JointVector;
  const double eps = static_cast<double>(std::numeric_limits<S>::epsilon());
  for (int t = 0; t < count; ++t) {
    const int k = std::min(Dim, K);
    VecXd sv = random_singular_values(k, 0.05, 2.0, rng);
    if (t % 2 == 1) sv(k - 1) = std::exp(uniform(rng, std::log(1e-6), std::log(4e-3)));
    const FixedJ Jf = matrix_with_singular_values(Dim, K, sv, rng).cast<S>();
    // Element by element: GCC 12 reports a vectorised copy of a small fixed float matrix
    // into a bounded one as reading past it (-Warray-bounds, a false positive).
    BoundedJ Jb(Dim, K);
    for (int c = 0; c < K; ++c)
      for (int r = 0; r < Dim; ++r) Jb(r, c) = Jf(r, c);
    const Eigen::Matrix<S, Dim, 1> xd = gaussian_vector(Dim, rng).cast<S>();
    FixedV vmax(K), lo(K), hi(K);
    for (int i = 0; i < K; ++i) {
      vmax(i) = static_cast<S>(t % 3 == 0 ? uniform(rng, 0.05, 0.5) : 1e3);
      lo(i) = static_cast<S>(t % 4 == 0 ? -uniform(rng, 0.0, 0.3) : -1e3);
      hi(i) = static_cast<S>(t % 4 == 0 ? uniform(rng, 0.0, 0.3) : 1e3);
    }
    BoundedV vmax_b(K), lo_b(K), hi_b(K);
    for (int i = 0; i < K; ++i) {
      vmax_b(i) = vmax(i);
      lo_b(i) = lo(i);
      hi_b(i) = hi(i);
    }
    const Eigen::Matrix<S, Dim, 1> normal = gaussian_vector(Dim, rng).normalized().cast<S>();
    FixedV qf = FixedV::Zero(K);
    BoundedV qb = BoundedV::Zero(K);
    const auto rf = fixed.solve(Jf, xd, vmax, lo, hi, normal, qf);
    const auto rb = bounded.solve(Jb, xd, vmax_b, lo_b, hi_b, normal, qb);
    ASSERT_EQ(rf.status, rb.status) << "K " << K << " sample " << t;
    ASSERT_EQ(rf.held_joints, rb.held_joints) << "K " << K << " sample " << t;
    ASSERT_EQ(rf.min_singular_value_exact, rb.min_singular_value_exact);
    ASSERT_EQ(qb.size(), K);
    const double scale = std::max(1.0, static_cast<double>(qf.cwiseAbs().maxCoeff()));
    const double tol = ulps * eps * scale;
    ASSERT_LE((qf.template cast<double>() - qb.template cast<double>()).cwiseAbs().maxCoeff(), tol)
        << "K " << K << " sample " << t << " status " << inhand::to_string(rf.status);
    ASSERT_NEAR(static_cast<double>(rf.damping), static_cast<double>(rb.damping),
                ulps * eps * std::max(1.0, static_cast<double>(rf.damping)));
    ASSERT_NEAR(static_cast<double>(rf.limit_scale), static_cast<double>(rb.limit_scale),
                ulps * eps);
  }
}

TEST(ContactIkBoundedStorage, SolvesAsTheFixedSizeSolver) {
  Rng rng(5150);
  const int count = sweep_count(200);
  for (int pass = 0; pass < 2; ++pass) {
    const int c = count + pass;  // an odd count asks for the exact sigma_min
    expect_bounded_equals_fixed<double, 3, 1, inhand::ContactIk<double, 3, Eigen::Dynamic>>(rng, c,
                                                                                            16);
    expect_bounded_equals_fixed<double, 3, 2>(rng, c, 16);
    expect_bounded_equals_fixed<double, 3, 3>(rng, c, 16);
    expect_bounded_equals_fixed<double, 3, 4>(rng, c, 16);
    expect_bounded_equals_fixed<double, 3, 5>(rng, c, 16);
    expect_bounded_equals_fixed<double, 2, 3>(rng, c, 16);
    expect_bounded_equals_fixed<float, 3, 4>(rng, c, 16);
    expect_bounded_equals_fixed<float, 3, 2>(rng, c, 16);
  }
}

}  // namespace
