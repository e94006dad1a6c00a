// Properties of the distance from a point to a finitely generated cone
// (math/cone_residual.hpp), in 2 and 3 dimensions: the residual against a reference solved
// independently (projected gradient in long double), the optimality conditions it must
// meet (r . g_i <= 0 for every ray, r . y = |r|^2), zero for a point inside the cone, the
// point itself when no ray helps, and skipped indices, zero rays and dependent rays. The
// reference converges slowly where rays are nearly dependent, so it bounds the distance
// from above; the optimality conditions bound it from below.
#include "inhand/math/cone_residual.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/test_support.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::scaled;
using inhand_test::uniform;

template <typename S, int D>
struct ConeCase {
  using Scalar = S;
  static constexpr int kDim = D;
};

template <typename C>
class ConeResidualTest : public ::testing::Test {};

using ConeCases = ::testing::Types<ConeCase<double, 2>, ConeCase<double, 3>, ConeCase<float, 3>>;
struct ConeCaseNames {
  template <typename C>
  static std::string GetName(int) {
    return std::string(sizeof(typename C::Scalar) == sizeof(float) ? "float" : "double") +
           std::to_string(C::kDim);
  }
};
TYPED_TEST_SUITE(ConeResidualTest, ConeCases, ConeCaseNames);

/// min_{t >= 0} |y - G t| by cyclic coordinate descent in long double (each t_i set to
/// its exact non-negative minimiser in turn): slow, but independent of the subset method
/// under test.
template <int D>
long double reference_distance(const Eigen::Matrix<long double, D, 1>& y,
                               const std::vector<Eigen::Matrix<long double, D, 1>>& g) {
  std::vector<long double> t(g.size(), 0.0L);
  Eigen::Matrix<long double, D, 1> r = y;
  for (int it = 0; it < 20000; ++it) {
    for (std::size_t k = 0; k < g.size(); ++k) {
      const long double gg = g[k].squaredNorm();
      if (gg == 0.0L) continue;
      const long double nt = std::max(0.0L, t[k] + g[k].dot(r) / gg);
      r -= (nt - t[k]) * g[k];
      t[k] = nt;
    }
  }
  return r.norm();
}

/// Whether every set of at most D rays is far from dependent: its Gram determinant over
/// the product of the squared lengths (1 for orthogonal rays) at least `floor`. Rays
/// within 1e-3 rad of the others' span count as dependent (the file comment of the
/// header); the sweep below stays well clear of that.
template <typename Vec>
bool well_conditioned(const std::vector<Vec>& g, double floor) {
  const std::size_t m = g.size();
  for (std::size_t i = 0; i < m; ++i) {
    for (std::size_t j = i + 1; j < m; ++j) {
      const double c = static_cast<double>(g[i].dot(g[j]));
      const double ii = static_cast<double>(g[i].squaredNorm());
      const double jj = static_cast<double>(g[j].squaredNorm());
      if (ii * jj - c * c < floor * ii * jj) return false;
      if constexpr (Vec::RowsAtCompileTime == 3) {
        for (std::size_t l = j + 1; l < m; ++l) {
          Eigen::Matrix3d G;
          G << g[i].template cast<double>(), g[j].template cast<double>(),
              g[l].template cast<double>();
          const double det = G.determinant();
          if (det * det < floor * ii * jj * static_cast<double>(g[l].squaredNorm())) return false;
        }
      }
    }
  }
  return true;
}

TYPED_TEST(ConeResidualTest, MatchesAReferenceAndMeetsTheOptimalityConditions) {
  using S = typename TypeParam::Scalar;
  constexpr int D = TypeParam::kDim;
  using Vec = Eigen::Matrix<S, D, 1>;
  using VecL = Eigen::Matrix<long double, D, 1>;
  const double eps = static_cast<double>(std::numeric_limits<S>::epsilon());
  auto rng = make_rng(91 + D);
  double worst = 0.0;
  int outside = 0, inside = 0, run = 0;
  for (int k = 0; k < scaled(400); ++k) {
    const int m = static_cast<int>(uniform(rng, 0.0, 5.999));
    std::vector<Vec> rays(static_cast<std::size_t>(m));
    std::vector<VecL> rays_l;
    for (Vec& g : rays) {
      for (int i = 0; i < D; ++i) g(i) = static_cast<S>(uniform(rng, -1.0, 1.0));
      if (uniform(rng, 0.0, 1.0) < 0.1) g *= S(1e-3);  // short rays too
      rays_l.push_back(g.template cast<long double>());
    }
    Vec y;
    for (int i = 0; i < D; ++i) y(i) = static_cast<S>(uniform(rng, -1.0, 1.0));
    if (!well_conditioned(rays, 1e-2)) continue;
    ++run;
    Vec r;
    const S r2 = inhand::detail::cone_residual<S, D>(
        y, m,
        [&](int i, Vec& g) {
          g = rays[static_cast<std::size_t>(i)];
          return true;
        },
        r);
    const double ref =
        static_cast<double>(reference_distance<D>(y.template cast<long double>(), rays_l));
    const double got = std::sqrt(static_cast<double>(r2));
    const double tol = 1e4 * eps;  // the rounding of t, amplified by nearly dependent rays
    EXPECT_NEAR(static_cast<double>(r.norm()), got, tol) << "case " << k;
    // Optimality: r separates y from the cone (r . x <= 0 on it, r . y = |r|^2), so no
    // point of the cone is nearer than |r|; and the reference's point is no nearer.
    for (const Vec& g : rays) EXPECT_LE(static_cast<double>(r.dot(g)), tol) << "case " << k;
    EXPECT_NEAR(static_cast<double>(r.dot(y)), static_cast<double>(r2), tol) << "case " << k;
    EXPECT_LE(got, ref + tol) << "case " << k << ", " << m << " rays";
    worst = std::max(worst, got - ref);
    (got > 1e-3 ? outside : inside) += 1;
  }
  EXPECT_GT(run, scaled(400) / 2);
  EXPECT_GT(outside, scaled(400) / 10);
  EXPECT_GT(inside, scaled(400) / 40);
  inhand_test::record("worst_excess_over_reference", worst);
}

TYPED_TEST(ConeResidualTest, InsideIsZeroAndNoHelpingRayLeavesThePoint) {
  using S = typename TypeParam::Scalar;
  constexpr int D = TypeParam::kDim;
  using Vec = Eigen::Matrix<S, D, 1>;
  const S eps = std::numeric_limits<S>::epsilon();
  auto rng = make_rng(7 + D);
  for (int k = 0; k < scaled(100); ++k) {
    std::vector<Vec> rays(3);
    for (Vec& g : rays)
      for (int i = 0; i < D; ++i) g(i) = uniform<S>(rng, S(-1), S(1));
    if (!well_conditioned(rays, 1e-2)) continue;
    // A positive combination lies in the cone: residual 0 (to rounding).
    const Vec y = S(0.3) * rays[0] + S(1.7) * rays[1] + S(0.2) * rays[2];
    Vec r;
    const auto all = [&](int i, Vec& g) {
      g = rays[static_cast<std::size_t>(i)];
      return true;
    };
    const S in2 = inhand::detail::cone_residual<S, D>(y, 3, all, r);
    EXPECT_LE(std::sqrt(in2), S(1e3) * eps * (S(1) + y.norm())) << k;
    // Every ray pointing away from y: the closest point is the apex, r = y.
    const Vec z = rays[0];
    const auto away = [&](int i, Vec& g) {
      g = -z + (i == 0 ? Vec::Zero() : Vec(S(0.01) * rays[static_cast<std::size_t>(i)]));
      return true;
    };
    const S r2 = inhand::detail::cone_residual<S, D>(z, 3, away, r);
    if (z.dot(-z + S(0.01) * rays[1]) < S(0) && z.dot(-z + S(0.01) * rays[2]) < S(0)) {
      EXPECT_NEAR(r2, z.squaredNorm(), S(1e2) * eps) << k;
      EXPECT_LE((r - z).norm(), S(1e2) * eps) << k;
    }
  }
}

TEST(ConeResidual, SkippedZeroAndDependentRays) {
  using Vec = Eigen::Vector3d;
  const Vec y(1.0, 1.0, 0.0);
  Vec r;
  // No ray at all (every index skipped): r = y.
  const auto none = [](int, Vec&) { return false; };
  EXPECT_DOUBLE_EQ((inhand::detail::cone_residual<double, 3>(y, 4, none, r)), 2.0);
  EXPECT_EQ(r, y);
  // Zero rays and a ray repeated: only e_x helps; the y part remains.
  const std::vector<Vec> rays{Vec::Zero(), Vec::UnitX(), Vec::UnitX() * 2.0, Vec::Zero()};
  const auto given = [&](int i, Vec& g) {
    g = rays[static_cast<std::size_t>(i)];
    return true;
  };
  EXPECT_NEAR((inhand::detail::cone_residual<double, 3>(y, 4, given, r)), 1.0, 1e-15);
  EXPECT_LE((r - Vec::UnitY()).norm(), 1e-15);
  // One index skipped leaves the others: e_y alone reaches y's y part, e_x is skipped.
  const std::vector<Vec> two{Vec::UnitX(), Vec::UnitY()};
  const auto skip_x = [&](int i, Vec& g) {
    g = two[static_cast<std::size_t>(i)];
    return i != 0;
  };
  EXPECT_NEAR((inhand::detail::cone_residual<double, 3>(y, 2, skip_x, r)), 1.0, 1e-15);
  EXPECT_LE((r - Vec::UnitX()).norm(), 1e-15);
}

}  // namespace
