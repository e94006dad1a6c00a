// Properties of DampedLeastSquares (math/damped_least_squares.hpp) over every matrix
// shape a finger Jacobian takes: planar 2x2 and 2x3, spatial 3x2 (least squares),
// 3x3, 3x4, 3x5, in float and double, with fixed, run-time bounded and run-time
// unbounded column counts.
//
// Error bounds: the solver works on the Gram matrix (J J^T or J^T J), whose condition
// number is kappa^2, so every residual is judged against C * eps * kappa^2 with the
// constant C stated next to each test.
//
// Each property is a plain function of a DlsProbe (the solver behind an interface in
// double), compiled once and run by one typed test per shape; per shape, only the
// solver's calls and the conversions to and from the shape's types are compiled (GCC 12
// -O3, the file compiled alone: 171 s for the 18 shapes, 55 s with one shape, 62 s
// with two).
#include "inhand/math/damped_least_squares.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <type_traits>
#include <vector>

#include "controller/controller_fixtures.hpp"

namespace {

using namespace inhand_ctl_test;

template <typename Sh>
class DlsShapeTest : public ::testing::Test {};

using Shapes =
    ::testing::Types<Shape<double, 2, 2>, Shape<double, 2, 3>, Shape<double, 3, 2>,
                     Shape<double, 3, 3>, Shape<double, 3, 4>, Shape<double, 3, 5>,
                     Shape<float, 2, 2>, Shape<float, 2, 3>, Shape<float, 3, 2>, Shape<float, 3, 3>,
                     Shape<float, 3, 4>, Shape<float, 3, 5>,
                     Shape<double, 3, Eigen::Dynamic, Eigen::Dynamic, 4>,
                     Shape<float, 3, Eigen::Dynamic, Eigen::Dynamic, 2>,
                     Shape<double, 3, Eigen::Dynamic, 5, 5>, Shape<float, 3, Eigen::Dynamic, 5, 5>,
                     Shape<double, 2, Eigen::Dynamic, 5, 3>, Shape<float, 3, Eigen::Dynamic, 5, 2>>;
TYPED_TEST_SUITE(DlsShapeTest, Shapes, TypeNames);

/// The pieces of a DampingSchedule the properties set, in double; the probe rounds each
/// to the solver's scalar. Absent: the schedule's defaults.
struct Schedule {
  double singular_threshold;
  double max_damping;
};
using OptSchedule = std::optional<Schedule>;

/// DampedLeastSquares::Result in double.
struct DlsResult {
  double min_singular_value = 0.0;
  double damping = 0.0;
  bool damped = false;
  bool valid = false;
};

/// One shape's solver behind an interface in double. The properties below are plain
/// functions of this interface, compiled once; only Probe<Sh> (the solver's calls and
/// the rounding to its scalar) is compiled per shape. A property sees exactly what a
/// body written against the shape's own types would: the matrix and right-hand side
/// rounded to the scalar, the schedule's fields in the scalar, the result cast to double.
class DlsProbe {
 public:
  virtual ~DlsProbe() = default;
  virtual int rows() const = 0;
  virtual int cols() const = 0;
  virtual bool is_double() const = 0;
  /// Machine epsilon of the solver's scalar.
  virtual double eps() const = 0;
  /// v rounded to the scalar.
  virtual double rounded(double v) const = 0;
  /// The schedule's gain_bound(), computed in the scalar.
  virtual double gain_bound(const Schedule& s) const = 0;
  /// M rounded to the scalar (the matrix J under test), in double; the calls below take
  /// it back exactly.
  virtual MatXd rounded(const MatXd& M) const = 0;
  /// b rounded to the scalar (Sh::cartesian), in double.
  virtual VecXd rhs(const VecXd& b) const = 0;
  /// factorize(J, schedule), J = A in the scalar.
  virtual DlsResult factorize(const MatXd& A, const OptSchedule& s) = 0;
  /// factorize(J, schedule), then the pseudo-inverse it applies, in double.
  virtual MatXd pinv(const MatXd& A, const OptSchedule& s, DlsResult& result) = 0;
  /// factorize(J, schedule), then solve(J, b rounded to the scalar).
  virtual VecXd solve(const MatXd& A, const VecXd& b, const OptSchedule& s, DlsResult& result) = 0;
};

template <typename Sh>
class Probe final : public DlsProbe {
  using S = typename Sh::Scalar;
  using Dls = typename Sh::Dls;

 public:
  int rows() const override { return Sh::kRows; }
  int cols() const override { return Sh::kCols; }
  bool is_double() const override { return std::is_same<S, double>::value; }
  double eps() const override { return inhand_ctl_test::eps<S>(); }
  double rounded(double v) const override { return static_cast<double>(static_cast<S>(v)); }
  double gain_bound(const Schedule& s) const override {
    return static_cast<double>(schedule(s).gain_bound());
  }
  MatXd rounded(const MatXd& M) const override { return Sh::jacobian(M).template cast<double>(); }
  VecXd rhs(const VecXd& b) const override { return Sh::cartesian(b).template cast<double>(); }
  DlsResult factorize(const MatXd& A, const OptSchedule& s) override {
    return converted(dls_.factorize(Sh::jacobian(A), schedule(s)));
  }
  MatXd pinv(const MatXd& A, const OptSchedule& s, DlsResult& result) override {
    const typename Sh::Jacobian J = Sh::jacobian(A);
    result = converted(dls_.factorize(J, schedule(s)));
    typename Dls::Inverse P(Sh::kCols, Sh::kRows);
    P.setZero();  // (GCC 12 cannot see that pseudo_inverse writes every entry)
    dls_.pseudo_inverse(J, P);
    return P.template cast<double>();
  }
  VecXd solve(const MatXd& A, const VecXd& b, const OptSchedule& s, DlsResult& result) override {
    const typename Sh::Jacobian J = Sh::jacobian(A);
    result = converted(dls_.factorize(J, schedule(s)));
    typename Dls::Solution x(Sh::kCols);
    x.setZero();
    const typename Dls::Rhs r = b.cast<S>();
    dls_.solve(J, r, x);
    return x.template cast<double>();
  }

 private:
  static inhand::DampingSchedule<S> schedule(const OptSchedule& s) {
    inhand::DampingSchedule<S> out;
    if (s) {
      out.singular_threshold = static_cast<S>(s->singular_threshold);
      out.max_damping = static_cast<S>(s->max_damping);
    }
    return out;
  }
  static DlsResult converted(const typename Dls::Result& r) {
    return {static_cast<double>(r.min_singular_value), static_cast<double>(r.damping), r.damped,
            r.valid};
  }

  Dls dls_ = Sh::make_dls();  ///< the solver's workspace, reused as a controller would
};

// The four Penrose conditions on random matrices with kappa <= 40 (sigma in [0.05, 2],
// above the default singular threshold, so undamped). Bound: 50 eps kappa^2 relative.
void penrose_identities(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  Rng rng(101);
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const VecXd s = random_singular_values(k, 0.05, 2.0, rng);
    const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
    DlsResult res;
    const MatXd P = dls.pinv(A, std::nullopt, res);
    ASSERT_TRUE(res.valid);
    ASSERT_FALSE(res.damped);
    const double kappa = sigma_max(A) / sigma_min(A);
    const double unit = dls.eps() * kappa * kappa;
    const MatXd AP = A * P, PA = P * A;
    const double r1 = (AP * A - A).norm() / A.norm();
    const double r2 = (PA * P - P).norm() / P.norm();
    const double r3 = (AP.transpose() - AP).norm();
    const double r4 = (PA.transpose() - PA).norm();
    worst = std::max({worst, r1 / unit, r2 / unit, r3 / unit, r4 / unit});
    ASSERT_LE(r1, 50 * unit) << "A A+ A = A, sample " << t;
    ASSERT_LE(r2, 50 * unit) << "A+ A A+ = A+, sample " << t;
    ASSERT_LE(r3, 50 * unit) << "(A A+)^T = A A+, sample " << t;
    ASSERT_LE(r4, 50 * unit) << "(A+ A)^T = A+ A, sample " << t;
  }
  inhand_test::record("penrose_residual_over_eps_kappa2", worst);
}

// Same matrices: agreement with Eigen's CompleteOrthogonalDecomposition pseudo-inverse.
void matches_complete_orthogonal_decomposition(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  Rng rng(102);
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const VecXd s = random_singular_values(k, 0.05, 2.0, rng);
    const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
    DlsResult res;
    const MatXd P = dls.pinv(A, std::nullopt, res);
    const MatXd Pref = reference_pinv(A);
    const double kappa = sigma_max(A) / sigma_min(A);
    const double rel = (P - Pref).norm() / Pref.norm() / (dls.eps() * kappa * kappa);
    worst = std::max(worst, rel);
    ASSERT_LE(rel, 50.0) << "sample " << t;
  }
  inhand_test::record("cod_disagreement_over_eps_kappa2", worst);
}

// m = n: J x = b exactly. m > n: the residual is orthogonal to range(J) (normal
// equations). n > m: J x = b and x is orthogonal to null(J) (minimum norm).
void exact_least_squares_or_minimum_norm(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  Rng rng(103);
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const VecXd s = random_singular_values(k, 0.05, 2.0, rng);
    const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
    VecXd b = gaussian_vector(m, rng);
    // Least squares: a part in range(J) plus a unit normal to it, so the residual is ~1.
    if (m > n) b = A * gaussian_vector(n, rng) + unit_normal_to_range(A);
    b = dls.rhs(b);
    DlsResult res;
    const VecXd x = dls.solve(A, b, std::nullopt, res);
    const double kappa = sigma_max(A) / sigma_min(A);
    const double tol = 50 * dls.eps() * kappa * kappa;
    if (m <= n) {
      ASSERT_LE((A * x - b).norm(), tol * b.norm()) << "J x = b, sample " << t;
    }
    if (m > n) {
      Eigen::JacobiSVD<MatXd> svd(A, Eigen::ComputeThinU);
      const VecXd r = b - A * x;
      ASSERT_GT(r.norm(), 0.5) << "b should not lie in range(J)";
      ASSERT_LE((svd.matrixU().transpose() * r).norm(), tol * b.norm())
          << "residual not orthogonal to range(J), sample " << t;
    }
    if (n > m) {
      const MatXd N = null_space_basis(A);
      ASSERT_LE((N.transpose() * x).norm(), tol * x.norm())
          << "x has a null-space component, sample " << t;
    }
    ASSERT_LE((x - reference_pinv(A) * b).norm(), tol * b.norm() / sigma_min(A)) << "sample " << t;
  }
}

// With sigma_min fixed below the threshold, the damped pseudo-inverse converges to the
// true one as max_damping -> 0. In exact arithmetic the spectral-norm relative error is
// lambda^2 / (sigma_min^2 + lambda^2), lambda^2 = max_damping^2 (1 - (sigma_min/eps)^2):
// the measured error must follow that curve to within a floor of 20 eps kappa^2.
void damped_tends_to_pseudo_inverse(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  const bool is_double = dls.is_double();
  // Float keeps kappa^2 eps small by using a larger sigma_min.
  const double smin = is_double ? 1e-3 : 3e-2;
  const double threshold = is_double ? 5e-3 : 1e-1;
  const std::vector<double> ratios =
      is_double ? std::vector<double>{1, 0.3, 0.1, 3e-2, 1e-2, 3e-3, 1e-3, 1e-4, 1e-5}
                : std::vector<double>{1, 0.3, 0.1, 3e-2, 1e-2, 1e-3};
  Rng rng(104);
  double worst_dev = 0.0, worst_final = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    VecXd s = random_singular_values(k, 0.5, 1.5, rng);
    s(k - 1) = smin;
    const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
    const MatXd Pref = reference_pinv(A);
    const double sig = sigma_min(A);
    const double kappa = sigma_max(A) / sig;
    const double floor = 20 * dls.eps() * kappa * kappa;
    double previous = std::numeric_limits<double>::infinity();
    for (double ratio : ratios) {
      const Schedule sched{threshold, ratio * smin};
      DlsResult res;
      const MatXd P = dls.pinv(A, sched, res);
      ASSERT_TRUE(res.damped);
      const double l = dls.rounded(sched.max_damping);
      const double l2 = l * l * (1 - (sig / threshold) * (sig / threshold));
      const double expected = l2 / (sig * sig + l2);
      const double err = spectral_norm(P - Pref) / spectral_norm(Pref);
      worst_dev = std::max(worst_dev, std::abs(err - expected) / floor);
      ASSERT_NEAR(err, expected, floor) << "max_damping " << l << ", sample " << t;
      ASSERT_LE(err, previous + floor) << "error grew as damping decreased, sample " << t;
      previous = err;
    }
    worst_final = std::max(worst_final, previous);
    ASSERT_LE(previous, floor) << "no convergence at the smallest damping, sample " << t;
  }
  inhand_test::record("deviation_from_theory_in_floors", worst_dev);
  inhand_test::record("final_relative_error", worst_final);
}

// Near and at singularity (sigma_min in {0, 1e-12, ..., 4e-3}) for several schedules:
// |x| <= gain_bound |b|, the result says damped, lambda is the schedule's value for the
// reported sigma_min, and x equals the damped solution for that lambda computed by SVD
// in double, to within 1e-6 (double) / 2e-2 (float) of gain_bound |b|.
void singular_solution_bounded_and_damped(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  const double tol = dls.is_double() ? 1e-6 : 2e-2;
  const double sigmas[] = {0.0, 1e-12, 1e-8, 1e-5, 1e-3, 4e-3};
  const double schedules[][2] = {{5e-3, 5e-3}, {5e-2, 1e-2}, {1e-2, 5e-3}, {5e-3, 2e-2}};
  Rng rng(105);
  double worst_ratio = 0.0;
  const int count = sweep_count() / 6 + 1;
  for (int t = 0; t < count; ++t) {
    for (double sm : sigmas) {
      VecXd s = random_singular_values(k, 0.2, 2.0, rng);
      s(k - 1) = sm;
      const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
      const VecXd b = dls.rhs(gaussian_vector(m, rng));
      for (const auto& sc : schedules) {
        const Schedule sched{sc[0], sc[1]};
        DlsResult res;
        const VecXd x = dls.solve(A, b, sched, res);
        const double bound = dls.gain_bound(sched) * b.norm();
        ASSERT_TRUE(res.valid);
        ASSERT_TRUE(res.damped) << "sigma_min " << sm;
        ASSERT_TRUE(x.allFinite());
        ASSERT_LE(x.norm(), bound * (1 + tol)) << "sigma_min " << sm << " schedule " << sc[0];
        // lambda follows the schedule for the reported sigma_min, and x is the damped
        // solution for that lambda.
        const double l2 = res.damping * res.damping;
        ASSERT_NEAR(l2, schedule_damping_squared(res.min_singular_value, sc[0], sc[1]),
                    1e-4 * sc[1] * sc[1]);
        const VecXd xref = reference_damped_solve_l2(A, b, l2);
        ASSERT_LE((x - xref).norm(), tol * bound) << "sigma_min " << sm << " schedule " << sc[0];
        worst_ratio = std::max(worst_ratio, x.norm() / bound);
      }
    }
  }
  inhand_test::record("max_x_over_gain_bound_b", worst_ratio);
}

// sigma_min swept over a 200-point log grid from 1e-1 to 1e-12 (ratio rho = 1.136
// between neighbours). For max_damping <= threshold the scalar gain
// g(s) = s / (s^2 + lambda(s)^2) satisfies |s g'(s)| <= g(s) <= gain_bound, hence
// |g(s_k) - g(s_k+1)| <= gain_bound ln(rho); the other singular directions (sigma >= 0.6)
// move by far less. Stated bound on the jump of x: (ln rho + 0.01) gain_bound |b|.
// A damping switched on abruptly at the threshold would jump by gain_bound |b| / 2.
// Each point also matches the SVD solution for the reported lambda (as above) and, in
// double, the one for the lambda of the true sigma_min.
void singular_value_sweep_bounded_and_continuous(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  const double tol = dls.is_double() ? 1e-6 : 2e-2;
  constexpr int kPoints = 200;
  const double rho = std::pow(1e11, 1.0 / (kPoints - 1));
  const double schedules[][2] = {{5e-3, 5e-3}, {5e-2, 1e-2}};
  Rng rng(106);
  double worst_jump = 0.0, worst_norm = 0.0;
  const int draws = sweep_count(5);
  for (int t = 0; t < draws; ++t) {
    const MatXd U = random_orthogonal(m, rng), V = random_orthogonal(n, rng);
    const VecXd b = dls.rhs(random_unit_vector(m, rng));
    VecXd s(k);
    for (int i = 0; i < k - 1; ++i) s(i) = 1.0 - 0.4 * i;
    for (const auto& sc : schedules) {
      const Schedule sched{sc[0], sc[1]};
      const double gb = dls.gain_bound(sched) * b.norm();
      const double jump_bound = (std::log(rho) + 0.01) * gb;
      VecXd previous;
      for (int p = 0; p < kPoints; ++p) {
        s(k - 1) = 1e-1 * std::pow(rho, -p);
        const MatXd A = dls.rounded(compose(U, s, V));
        DlsResult res;
        const VecXd x = dls.solve(A, b, sched, res);
        ASSERT_TRUE(x.allFinite());
        ASSERT_LE(x.norm(), gb * (1 + tol)) << "sigma " << s(k - 1);
        const double l2 = res.damping * res.damping;
        ASSERT_LE((x - reference_damped_solve_l2(A, b, l2)).norm(), tol * gb)
            << "sigma " << s(k - 1);
        if (dls.is_double()) {
          // End to end in double, where sigma_min is resolved to ~1e-8 sigma_max: the
          // same as the solution damped for the TRUE sigma_min.
          ASSERT_LE((x - reference_damped_solve(A, b, sc[0], sc[1])).norm(), tol * gb)
              << "sigma " << s(k - 1);
        }
        worst_norm = std::max(worst_norm, x.norm() / gb);
        if (p > 0) {
          const double jump = (x - previous).norm();
          worst_jump = std::max(worst_jump, jump / gb);
          ASSERT_LE(jump, jump_bound + tol * gb) << "jump at sigma " << s(k - 1);
        }
        previous = x;
      }
    }
  }
  inhand_test::record("max_x_over_gain_bound_b", worst_norm);
  inhand_test::record("max_jump_over_gain_bound_b", worst_jump);
  inhand_test::record("stated_jump_bound", std::log(rho) + 0.01);
}

// The reported sigma_min is the true smallest singular value (k-th of min(m, n)),
// also for m > n. Computing it through the Gram matrix costs accuracy in absolute
// terms of sigma^2: |sigma_rep^2 - sigma_true^2| <= 20 eps sigma_max^2.
void min_singular_value_matches_jacobi_svd(DlsProbe& dls) {
  const int m = dls.rows(), n = dls.cols(), k = std::min(m, n);
  Rng rng(107);
  double worst = 0.0;
  const int count = sweep_count();
  for (int t = 0; t < count; ++t) {
    const double smin = std::exp(uniform(rng, std::log(1e-6), 0.0));
    VecXd s = random_singular_values(k, smin, 2.0, rng);
    s(k - 1) = smin;
    const MatXd A = dls.rounded(matrix_with_singular_values(m, n, s, rng));
    const DlsResult res = dls.factorize(A, std::nullopt);
    ASSERT_TRUE(res.valid);
    const VecXd sv = singular_values(A);
    ASSERT_EQ(sv.size(), k);
    const double truth = sv.minCoeff();
    const double rep = res.min_singular_value;
    const double err =
        std::abs(rep * rep - truth * truth) / (dls.eps() * sv.maxCoeff() * sv.maxCoeff());
    worst = std::max(worst, err);
    ASSERT_LE(err, 20.0) << "reported " << rep << " true " << truth << ", sample " << t;
  }
  inhand_test::record("sigma2_error_over_eps_sigmamax2", worst);
}

TYPED_TEST(DlsShapeTest, PenroseIdentities) {
  Probe<TypeParam> dls;
  penrose_identities(dls);
}

TYPED_TEST(DlsShapeTest, MatchesCompleteOrthogonalDecomposition) {
  Probe<TypeParam> dls;
  matches_complete_orthogonal_decomposition(dls);
}

TYPED_TEST(DlsShapeTest, ExactLeastSquaresOrMinimumNorm) {
  Probe<TypeParam> dls;
  exact_least_squares_or_minimum_norm(dls);
}

TYPED_TEST(DlsShapeTest, DampedTendsToPseudoInverse) {
  Probe<TypeParam> dls;
  damped_tends_to_pseudo_inverse(dls);
}

TYPED_TEST(DlsShapeTest, SingularSolutionBoundedAndDamped) {
  Probe<TypeParam> dls;
  singular_solution_bounded_and_damped(dls);
}

TYPED_TEST(DlsShapeTest, SingularValueSweepBoundedAndContinuous) {
  Probe<TypeParam> dls;
  singular_value_sweep_bounded_and_continuous(dls);
}

TYPED_TEST(DlsShapeTest, MinSingularValueMatchesJacobiSvd) {
  Probe<TypeParam> dls;
  min_singular_value_matches_jacobi_svd(dls);
}

TYPED_TEST(DlsShapeTest, NonFiniteMatrixGivesZero) {
  using Sh = TypeParam;
  using S = typename Sh::Scalar;
  constexpr int m = Sh::kRows, n = Sh::kCols;
  Rng rng(108);
  auto dls = Sh::make_dls();
  const S bad[] = {std::numeric_limits<S>::quiet_NaN(), std::numeric_limits<S>::infinity(),
                   -std::numeric_limits<S>::infinity()};
  for (S v : bad) {
    for (int idx = 0; idx < m * n; ++idx) {
      auto J = Sh::jacobian(matrix_with_singular_values(m, n, VecXd::Ones(m < n ? m : n), rng));
      J(idx % m, idx / m) = v;
      const auto res = dls.factorize(J, inhand::DampingSchedule<S>{});
      EXPECT_FALSE(res.valid);
      typename Sh::Dls::Solution x(n);
      x.setConstant(S(7));
      const typename Sh::Dls::Rhs ones = Sh::Dls::Rhs::Ones();
      dls.solve(J, ones, x);
      EXPECT_TRUE(x.isZero(0)) << x.transpose();
      typename Sh::Dls::Inverse P(n, m);
      P.setConstant(S(7));
      dls.pseudo_inverse(J, P);
      EXPECT_TRUE(P.isZero(0));
    }
  }
}

TEST(DampingSchedule, ValidateNamesTheField) {
  inhand::DampingSchedule<double> s;
  EXPECT_TRUE(s.validate().ok());
  s.singular_threshold = 0.0;
  EXPECT_STREQ(s.validate().field, "singular_threshold");
  s.singular_threshold = std::nan("");
  EXPECT_STREQ(s.validate().field, "singular_threshold");
  s = {};
  s.max_damping = -1e-3;
  EXPECT_STREQ(s.validate().field, "max_damping");
  s.max_damping = std::numeric_limits<double>::infinity();
  EXPECT_STREQ(s.validate().field, "max_damping");
  s.max_damping = 0.0;
  EXPECT_TRUE(s.validate().ok());
}

// lambda^2 is continuous at the threshold (0 there), max_damping^2 at sigma = 0, and
// gain_bound() is the supremum of sigma / (sigma^2 + lambda^2) (checked on a fine grid,
// which must reach it within 1e-4 relative and never exceed it).
TEST(DampingSchedule, GainBoundIsTheSupremum) {
  const double cases[][2] = {{5e-3, 5e-3}, {5e-2, 1e-2}, {1e-2, 5e-3}, {1e-2, 7.2e-3},
                             {5e-3, 2e-2}, {1.0, 0.1},   {0.1, 1e-4}};
  for (const auto& c : cases) {
    inhand::DampingSchedule<double> s;
    s.singular_threshold = c[0];
    s.max_damping = c[1];
    EXPECT_EQ(s.damping_squared(c[0]), 0.0);
    EXPECT_DOUBLE_EQ(s.damping_squared(0.0), c[1] * c[1]);
    EXPECT_NEAR(s.damping_squared(c[0] * (1 - 1e-9)), 0.0, 1e-8 * c[1] * c[1]);
    const double gb = s.gain_bound();
    double sup = 0.0;
    for (int i = 0; i <= 200000; ++i) {
      const double sigma = 3.0 * c[0] * i / 200000.0;
      const double g = sigma / (sigma * sigma + s.damping_squared(sigma));
      EXPECT_LE(g, gb * (1 + 1e-12)) << "sigma " << sigma;
      sup = std::max(sup, g);
    }
    EXPECT_NEAR(sup, gb, 1e-4 * gb) << "threshold " << c[0] << " max_damping " << c[1];
  }
  inhand::DampingSchedule<double> undamped;
  undamped.max_damping = 0.0;
  EXPECT_TRUE(std::isinf(undamped.gain_bound()));
}

}  // namespace
