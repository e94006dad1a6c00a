// ObjectShape: closed-form surface queries against brute-force surface sampling, and
// mass properties against the textbook formulas and numeric integration.
#include "inhand/sim/shapes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>
#include <vector>

namespace {

using inhand::plant::ObjectShape;
using inhand::plant::SurfaceQuery;
constexpr double kPi = 3.14159265358979323846;

int test_scale() {
  const char* s = std::getenv("INHAND_TEST_SCALE");
  const int v = s ? std::atoi(s) : 1;
  return v > 0 ? v : 1;
}

/// Surface samples on a grid of spacing about h, each with its covering radius bound:
/// every surface point lies within `cover` of some sample.
struct SurfaceSamples {
  std::vector<Eigen::Vector3d> points;
  double cover = 0.0;
};

SurfaceSamples sample_surface(const ObjectShape& s, double h) {
  SurfaceSamples out;
  auto grid = [&](double a0, double a1, int n) {
    std::vector<double> v;
    for (int i = 0; i <= n; ++i) v.push_back(a0 + (a1 - a0) * i / n);
    return v;
  };
  switch (s.kind) {
    case ObjectShape::Kind::sphere: {
      // Latitude-longitude grid: spacing <= h along both directions.
      const int nt = static_cast<int>(std::ceil(kPi * s.radius / h));
      for (double th : grid(0.0, kPi, nt)) {
        const int np =
            std::max(1, static_cast<int>(std::ceil(2 * kPi * s.radius * std::sin(th) / h)));
        for (int k = 0; k < np; ++k) {
          const double ph = 2 * kPi * k / np;
          out.points.emplace_back(s.radius * std::sin(th) * std::cos(ph),
                                  s.radius * std::sin(th) * std::sin(ph), s.radius * std::cos(th));
        }
      }
      out.cover = h;  // chord spacings <= h in both directions
      break;
    }
    case ObjectShape::Kind::box: {
      const Eigen::Vector3d e = s.half_extents;
      for (int axis = 0; axis < 3; ++axis) {
        const int a = (axis + 1) % 3, b = (axis + 2) % 3;
        const int na = static_cast<int>(std::ceil(2 * e(a) / h)),
                  nb = static_cast<int>(std::ceil(2 * e(b) / h));
        for (double side : {-1.0, 1.0})
          for (double u : grid(-e(a), e(a), na))
            for (double v : grid(-e(b), e(b), nb)) {
              Eigen::Vector3d p;
              p(axis) = side * e(axis);
              p(a) = u;
              p(b) = v;
              out.points.push_back(p);
            }
      }
      out.cover = h;  // a cell of side <= h: every point within h / sqrt(2) of a corner
      break;
    }
    case ObjectShape::Kind::cylinder: {
      const double r = s.radius, L = s.half_length;
      const int na = static_cast<int>(std::ceil(2 * kPi * r / h));
      const int nz = static_cast<int>(std::ceil(2 * L / h));
      for (int k = 0; k < na; ++k) {
        const double ph = 2 * kPi * k / na;
        for (double z : grid(-L, L, nz))
          out.points.emplace_back(r * std::cos(ph), r * std::sin(ph), z);
      }
      const int nr = static_cast<int>(std::ceil(r / h));
      for (double side : {-1.0, 1.0})
        for (double rr : grid(0.0, r, nr)) {
          const int np = std::max(1, static_cast<int>(std::ceil(2 * kPi * rr / h)));
          for (int k = 0; k < np; ++k) {
            const double ph = 2 * kPi * k / np;
            out.points.emplace_back(rr * std::cos(ph), rr * std::sin(ph), side * L);
          }
        }
      out.cover = h;
      break;
    }
  }
  return out;
}

/// Independent inside test (strict interior).
bool inside(const ObjectShape& s, const Eigen::Vector3d& p) {
  switch (s.kind) {
    case ObjectShape::Kind::sphere:
      return p.norm() < s.radius;
    case ObjectShape::Kind::box:
      return (p.cwiseAbs().array() < s.half_extents.array()).all();
    case ObjectShape::Kind::cylinder:
      return p.head<2>().norm() < s.radius && std::abs(p.z()) < s.half_length;
  }
  return false;
}

void check_queries(const ObjectShape& shape, std::uint32_t seed) {
  constexpr double kSampleSpacing = 0.5e-3;  // m
  const SurfaceSamples samples = sample_surface(shape, kSampleSpacing);
  const double R = shape.bounding_radius();
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> U(-1.3 * R, 1.3 * R);
  const int n = 1000 * test_scale();
  int n_inside = 0;
  for (int k = 0; k < n; ++k) {
    const Eigen::Vector3d p(U(rng), U(rng), U(rng));
    const SurfaceQuery q = shape.query(p);
    double brute = 1e9;
    for (const auto& x : samples.points) brute = std::min(brute, (x - p).norm());
    const bool in = inside(shape, p);
    n_inside += in;
    // Sign: negative exactly inside.
    EXPECT_EQ(q.distance < 0.0, in) << p.transpose();
    // The closest point is on the surface, at |distance| from p, along the normal:
    // p - closest = distance * normal, with a unit normal.
    EXPECT_NEAR(shape.query(q.closest).distance, 0.0, 1e-15);
    EXPECT_NEAR((p - q.closest).norm(), std::abs(q.distance), 1e-15);
    EXPECT_NEAR(q.normal.norm(), 1.0, 1e-14);
    EXPECT_LT((p - q.closest - q.distance * q.normal).norm(), 1e-15) << p.transpose();
    // No surface sample is closer than the reported distance, and the nearest sample
    // is within the sampling cover of it: the closed form is the true distance.
    EXPECT_GE(brute, std::abs(q.distance) - 1e-15) << p.transpose();
    EXPECT_LE(brute, std::abs(q.distance) + samples.cover) << p.transpose();
    // Outward: stepping along the normal from the closest point leaves the solid.
    const double eps = 1e-7;
    EXPECT_NEAR(shape.signed_distance(q.closest + eps * q.normal), eps, 1e-12) << p.transpose();
    EXPECT_LT(shape.signed_distance(q.closest - eps * q.normal), 0.0) << p.transpose();
    // Convenience accessors agree with query().
    EXPECT_EQ(shape.signed_distance(p), q.distance);
    EXPECT_EQ(shape.closest_point(p), q.closest);
    EXPECT_EQ(shape.outward_normal(p), q.normal);
  }
  // The sweep covered both inside and outside points.
  EXPECT_GT(n_inside, n / 50);
  EXPECT_LT(n_inside, n - n / 50);
}

TEST(Shapes, SphereQueriesMatchBruteForce) { check_queries(ObjectShape::sphere(0.03), 1u); }
TEST(Shapes, BoxQueriesMatchBruteForce) { check_queries(ObjectShape::box(0.01, 0.02, 0.04), 2u); }
TEST(Shapes, CylinderQueriesMatchBruteForce) {
  check_queries(ObjectShape::cylinder(0.02, 0.05), 3u);
}

TEST(Shapes, InsideNormalsPointToTheNearestFace) {
  const ObjectShape box = ObjectShape::box(0.01, 0.02, 0.04);
  // 2 mm below the +y face, far from the others.
  SurfaceQuery q = box.query(Eigen::Vector3d(0.001, 0.018, -0.005));
  EXPECT_DOUBLE_EQ(q.distance, -0.002);
  EXPECT_EQ(q.normal, Eigen::Vector3d(0, 1, 0));
  q = box.query(Eigen::Vector3d(-0.0095, 0.0, 0.0));
  EXPECT_EQ(q.normal, Eigen::Vector3d(-1, 0, 0));
  const ObjectShape cyl = ObjectShape::cylinder(0.02, 0.05);
  q = cyl.query(Eigen::Vector3d(0.0, -0.015, 0.01));  // 5 mm from the side, 40 mm from a cap
  EXPECT_NEAR(q.normal.dot(Eigen::Vector3d(0, -1, 0)), 1.0, 1e-15);
  EXPECT_NEAR(q.distance, -0.005, 1e-15);
  q = cyl.query(Eigen::Vector3d(0.0, 0.001, -0.048));  // 2 mm from the -z cap
  EXPECT_EQ(q.normal, Eigen::Vector3d(0, 0, -1));
  EXPECT_NEAR(q.distance, -0.002, 1e-15);
  const ObjectShape sph = ObjectShape::sphere(0.03);
  q = sph.query(Eigen::Vector3d::Zero());  // degenerate centre: a valid unit normal
  EXPECT_NEAR(q.normal.norm(), 1.0, 1e-15);
  EXPECT_DOUBLE_EQ(q.distance, -0.03);
}

TEST(Shapes, ValidationNamesTheField) {
  EXPECT_TRUE(ObjectShape::box(0.01, 0.02, 0.03).validate().ok());
  EXPECT_FALSE(ObjectShape::sphere(0.0).validate().ok());
  const auto v = ObjectShape::box(0.01, -0.02, 0.03).validate();
  ASSERT_FALSE(v.ok());
  EXPECT_STREQ(v.field, "shape.half_extents");
  EXPECT_EQ(v.index, 1);
  EXPECT_STREQ(ObjectShape::cylinder(0.02, NAN).validate().field, "shape.half_length");
}

// Volume and inertia by midpoint-rule integration on an n^3 grid over the bounding box.
void check_mass_properties(const ObjectShape& s, const Eigen::Vector3d& extent, double mass) {
  const int n = 160;
  const Eigen::Vector3d cell = 2.0 * extent / n;
  const double dv = cell.prod();
  double volume = 0.0;
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // integral of r r^T dV
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const Eigen::Vector3d p =
            -extent + cell.cwiseProduct(Eigen::Vector3d(i + 0.5, j + 0.5, k + 0.5));
        if (s.signed_distance(p) >= 0.0) continue;
        volume += dv;
        second += dv * p * p.transpose();
      }
  const double density = mass / s.volume();
  const Eigen::Matrix3d I_numeric =
      density * (second.trace() * Eigen::Matrix3d::Identity() - second);
  const Eigen::Matrix3d I = s.inertia(mass);
  // Curved boundaries on a 160^3 grid: about 1 % volume error at most.
  EXPECT_NEAR(volume / s.volume(), 1.0, 0.01);
  for (int a = 0; a < 3; ++a) {
    EXPECT_NEAR(I_numeric(a, a) / I(a, a), 1.0, 0.02) << "axis " << a;
    for (int b = 0; b < 3; ++b)
      if (a != b) {
        EXPECT_EQ(I(a, b), 0.0);
        EXPECT_LT(std::abs(I_numeric(a, b)), 1e-3 * I(a, a));
      }
  }
}

TEST(Shapes, MassPropertiesMatchFormulasAndIntegration) {
  const double m = 0.2;
  // Textbook values.
  EXPECT_DOUBLE_EQ(ObjectShape::sphere(0.03).principal_inertia(m).x(), 0.4 * m * 0.03 * 0.03);
  const Eigen::Vector3d Ib = ObjectShape::box(0.01, 0.02, 0.04).principal_inertia(m);
  EXPECT_NEAR(Ib.x(), m / 12.0 * (0.04 * 0.04 + 0.08 * 0.08), 1e-18);
  EXPECT_NEAR(Ib.z(), m / 12.0 * (0.02 * 0.02 + 0.04 * 0.04), 1e-18);
  const Eigen::Vector3d Ic = ObjectShape::cylinder(0.02, 0.05).principal_inertia(m);
  EXPECT_NEAR(Ic.z(), 0.5 * m * 0.02 * 0.02, 1e-18);
  EXPECT_NEAR(Ic.x(), m / 12.0 * (3 * 0.02 * 0.02 + 0.1 * 0.1), 1e-18);
  EXPECT_NEAR(ObjectShape::box(0.01, 0.02, 0.04).volume(), 0.02 * 0.04 * 0.08, 1e-18);
  EXPECT_NEAR(ObjectShape::cylinder(0.02, 0.05).volume(), kPi * 0.02 * 0.02 * 0.1, 1e-18);
  // Numeric integration.
  check_mass_properties(ObjectShape::sphere(0.03), Eigen::Vector3d::Constant(0.03), m);
  check_mass_properties(ObjectShape::box(0.01, 0.02, 0.04), Eigen::Vector3d(0.01, 0.02, 0.04), m);
  check_mass_properties(ObjectShape::cylinder(0.02, 0.05), Eigen::Vector3d(0.02, 0.02, 0.05), m);
}

}  // namespace
