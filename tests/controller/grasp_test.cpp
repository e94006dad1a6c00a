// Tests of the grasp-phase primitives (controller/grasp.hpp): approach_velocity's
// saturation and its creep along -n (also past the expected contact point, when the
// object is smaller than expected), the release grip's sizing against the load it must
// take, the balancing finger's shift to where the squeeze has no couple, the pressing
// finger's aim at gravity's side (and its release on a flat face), parameter and target
// validation.
#include "inhand/controller/grasp.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/grasp_map.hpp"

namespace {

using inhand::approach_velocity;
using inhand::GraspParams;
using inhand::GraspTarget;
using inhand_test::record;
using inhand_test::scaled;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

template <int Dim>
void check_saturation_and_creep(std::uint64_t seed) {
  using Vec = inhand::Vector<double, Dim>;
  auto rng = inhand_test::make_rng(seed);
  GraspParams<double> g;
  const int n = scaled(2000);
  int saturated = 0, linear = 0;
  for (int k = 0; k < n; ++k) {
    const Vec nrm = inhand_test::random_unit_vector<double, Dim>(rng);
    const Vec p_t = inhand_test::random_vector<double, Dim>(rng, -0.05, 0.05);
    // Virtual point on the OUTSIDE half-space of the target (where approaches start),
    // from 0.1 mm to 5 cm away.
    Vec dir = inhand_test::random_unit_vector<double, Dim>(rng);
    if (dir.dot(nrm) < 0) dir = -dir;
    const double dist = inhand_test::log_uniform(rng, 1e-4, 0.05);
    const Vec p_v = p_t + dist * dir;
    const Vec v = approach_velocity(g, p_v, p_t, nrm);
    const Vec p_term = v + g.creep_speed * nrm;  // what remains without the creep
    // The P term points at the target and is capped at approach_speed.
    EXPECT_LE(p_term.norm(), g.approach_speed * (1 + 1e-12));
    EXPECT_GT(p_term.dot(p_t - p_v), 0.0);
    EXPECT_LT((p_term.normalized() - (p_t - p_v).normalized()).norm(), 1e-9);
    if (g.approach_gain * dist > g.approach_speed) {
      EXPECT_NEAR(p_term.norm(), g.approach_speed, 1e-12);
      ++saturated;
    } else {
      EXPECT_LT((p_term - g.approach_gain * (p_t - p_v)).norm(), 1e-15);
      ++linear;
    }
    // The overall speed never exceeds approach + creep, and it always moves towards
    // the object (against n) from the outside.
    EXPECT_LE(v.norm(), g.approach_speed + g.creep_speed + 1e-15);
    EXPECT_LT(v.dot(nrm), 0.0);
  }
  EXPECT_GT(saturated, n / 10);
  EXPECT_GT(linear, n / 10);
}

TEST(ApproachVelocity, SaturatesTowardsTheTargetPlanar) { check_saturation_and_creep<2>(11); }
TEST(ApproachVelocity, SaturatesTowardsTheTargetSpatial) { check_saturation_and_creep<3>(12); }

TEST(ApproachVelocity, AtTheTargetCreepsAlongMinusN) {
  GraspParams<double> g;
  const Eigen::Vector3d n = Eigen::Vector3d(1, -2, 0.5).normalized();
  const Eigen::Vector3d p(0.01, 0.02, -0.03);
  const Eigen::Vector3d v = approach_velocity(g, p, p, n);
  EXPECT_LT((v + g.creep_speed * n).norm(), 1e-18);
}

TEST(ApproachVelocity, KeepsCreepingPastTheExpectedContactPoint) {
  // The geometry is unknown: the real surface lies deeper than the expected contact
  // point. The finger must keep creeping along -n until contact is sensed (grasp.hpp),
  // not settle at a fixed offset behind p_t.
  GraspParams<double> g;
  const Eigen::Vector2d n(0.0, 1.0);
  const Eigen::Vector2d p_t(0.004, 0.0);
  const double dt = 1e-3;
  Eigen::Vector2d p(0.0, 0.02);  // 2 cm outside, 4 mm to the side
  double t_reach = -1.0, slowest_inward = 1.0;
  for (int k = 0; k < 3000; ++k) {
    const Eigen::Vector2d v = approach_velocity(g, p, p_t, n);
    if (t_reach < 0 && (p - p_t).dot(n) <= 0.0) t_reach = k * dt;
    if (t_reach >= 0) slowest_inward = std::min(slowest_inward, -v.dot(n));
    p += dt * v;
  }
  ASSERT_GT(t_reach, 0.0);
  // Past the target: at least the creep speed inwards, no pull back out.
  EXPECT_GE(slowest_inward, g.creep_speed * (1 - 1e-12));
  const double depth = -(p - p_t).dot(n);
  // Creeping at creep_speed for the rest of the 3 s run.
  EXPECT_GT(depth, 0.9 * g.creep_speed * (3.0 - t_reach));
  // Tangentially it converges on the target.
  EXPECT_LT(std::abs(p.x() - p_t.x()), 1e-6);
  record("depth_past_target_m", depth);
}

// release_grip_scale: with s = the returned scale and no cap binding, every finger keeps
// at least min_force under the equal-stiffness translation response to any load w with
// |w| <= release_load (force change n_i^T G^-1 w, release_grip.hpp), and, in the cases
// with gravity_direction set (g: a random 3-vector, a planar hand taking its x and y), at
// the peak of a weight's step along g, twice the static change, for any weight up to
// release_load; the bound is reached by the finger that sets s (for w along -G^-1 n_i, or
// the weight release_load along g), s >= release_grip, s is at least the scale without g,
// and no s q_i exceeds max_force.
template <int Dim>
void check_release_grip_scale(std::uint64_t seed) {
  using Vec = inhand::Vector<double, Dim>;
  using Mat = Eigen::Matrix<double, Dim, Dim>;
  auto rng = inhand_test::make_rng(seed);
  std::uniform_int_distribution<int> count(2, 5);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const int cases = scaled(500);
  int binding = 0, capped = 0, along_gravity = 0;
  double worst_margin = 1e9;
  for (int k = 0; k < cases; ++k) {
    const int n = count(rng);
    Eigen::Matrix<double, Dim, Eigen::Dynamic> N(Dim, n);
    Eigen::VectorXd q(n);
    for (int i = 0; i < n; ++i) {
      N.col(i) = inhand_test::random_unit_vector<double, Dim>(rng);
      q(i) = 0.2 + 2.0 * unit(rng);
    }
    inhand::ForceLayerParams<double> fl;
    fl.release_grip = 1.0 + 2.0 * unit(rng);
    fl.release_load = 8.0 * unit(rng);
    fl.rigid_tolerance = 0.01 + 0.3 * unit(rng);
    const double min_force = 0.5 * unit(rng);
    const double max_force = k % 4 == 0 ? 3.0 : 1e3;  // a quarter of the cases with a low cap
    const inhand::ReleaseGrip<double> unknown =
        inhand::release_grip_scale(N, q, fl, min_force, max_force);
    Vec g = Vec::Zero();  // unit, in the hand's space
    if (k % 2 == 1) {
      fl.gravity_direction =
          (0.1 + 10.0 * unit(rng)) * inhand_test::random_unit_vector<double, 3>(rng);
      g = fl.gravity_direction.template head<Dim>();
      g = g.norm() > 1e-9 * (1.0 + fl.gravity_direction.norm()) ? Vec(g.normalized()) : Vec::Zero();
    }
    const inhand::ReleaseGrip<double> rg =
        inhand::release_grip_scale(N, q, fl, min_force, max_force);
    EXPECT_GE(rg.scale, unknown.scale * (1 - 1e-12)) << "case " << k;
    const double s = rg.scale;
    ASSERT_TRUE(std::isfinite(s));
    for (int i = 0; i < n; ++i) ASSERT_LE(s * q(i), max_force * (1 + 1e-12));
    // Capped exactly when the cap is what binds (one finger at max_force, below the asked s).
    const bool cap = std::abs(s * q.maxCoeff() - max_force) <= 1e-12 * max_force;
    EXPECT_EQ(rg.capped, cap && s * q.maxCoeff() < max_force * (1 + 1e-12)) << "case " << k;
    capped += cap ? 1 : 0;
    if (cap) continue;
    EXPECT_GE(s, fl.release_grip);
    Mat G = fl.rigid_tolerance * Mat::Identity();
    for (int i = 0; i < n; ++i) G += N.col(i) * N.col(i).transpose();
    const Mat G_inv = G.inverse();
    double tightest = 1e9, tightest_g = 1e9;
    for (int i = 0; i < n; ++i) {
      const Vec worst = -fl.release_load * (G_inv * N.col(i)).normalized();  // largest loss
      for (int trial = 0; trial < 20; ++trial) {
        const Vec w = trial == 0 ? worst
                                 : Vec(fl.release_load * unit(rng) *
                                       inhand_test::random_unit_vector<double, Dim>(rng));
        const double f = s * q(i) + N.col(i).dot(G_inv * w);
        EXPECT_GE(f, min_force - 1e-9) << "finger " << i << " case " << k;
        if (trial == 0) tightest = std::min(tightest, f - min_force);
      }
      for (const double weight : {fl.release_load, fl.release_load * unit(rng)}) {
        const double peak = s * q(i) + 2.0 * weight * N.col(i).dot(G_inv * g);
        EXPECT_GE(peak, min_force - 1e-9) << "finger " << i << " case " << k;
        if (weight == fl.release_load) tightest_g = std::min(tightest_g, peak - min_force);
      }
    }
    const bool set_by_gravity = tightest_g < tightest - 1e-12;
    tightest = std::min(tightest, tightest_g);
    worst_margin = std::min(worst_margin, tightest);
    if (s > fl.release_grip * (1 + 1e-9) && fl.release_load > 0) {
      EXPECT_NEAR(tightest, 0.0, 1e-9) << "case " << k;  // the finger that sets s is at min_force
      ++binding;
      along_gravity += set_by_gravity ? 1 : 0;
    }
  }
  record("release_grip_scale.cases_sized_by_the_load", binding);
  record("release_grip_scale.cases_sized_along_gravity", along_gravity);
  record("release_grip_scale.cases_capped", capped);
  EXPECT_GT(along_gravity, cases / 20);  // and the weight's step along g sets some of them
  EXPECT_GT(binding, cases / 10);  // the sweep exercises the load bound, not only release_grip
  EXPECT_GT(capped, 0);
}

/// The moment sum_i q_i (p_i - c) x (-n_i) of normal forces about c, in space.
template <int Dim>
Eigen::Vector3d couple(const Eigen::Matrix<double, Dim, Eigen::Dynamic>& P,
                       const Eigen::Matrix<double, Dim, Eigen::Dynamic>& N,
                       const Eigen::VectorXd& q, const Eigen::Vector3d& c) {
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (int i = 0; i < q.size(); ++i) {
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    p.head<Dim>() = P.col(i);
    n.head<Dim>() = N.col(i);
    m += q(i) * (p - c).cross(-n);
  }
  return m;
}

// balancing_shift (grasp_map.hpp): for balanced normal forces (sum q_i n_i = 0, the
// balancing finger b taking what the others leave, as the planner's balancing role does)
// b's contact moved by delta on a flat face (its normal unchanged) leaves no moment across
// n_b -- none at all in the plane -- and the twist about n_b as it was; delta lies in b's
// tangent plane. A finger b with q_b <= 0 gets no shift.
template <int Dim>
void check_balancing_shift(std::uint64_t seed) {
  using Vec = inhand::Vector<double, Dim>;
  auto rng = inhand_test::make_rng(seed);
  std::uniform_int_distribution<int> count(2, 5);
  std::uniform_real_distribution<double> unit(0.0, 1.0), coord(-0.05, 0.05);
  const int cases = scaled(500);
  double worst = 0.0, largest_shift = 0.0;
  for (int k = 0; k < cases; ++k) {
    const int n = count(rng);
    std::uniform_int_distribution<int> pick(0, n - 1);
    const int b = pick(rng);
    Eigen::Matrix<double, Dim, Eigen::Dynamic> P(Dim, n), N(Dim, n);
    Eigen::VectorXd q(n);
    Vec rest = Vec::Zero();
    for (int i = 0; i < n; ++i) {
      for (int d = 0; d < Dim; ++d) P(d, i) = coord(rng);
      if (i == b) continue;
      N.col(i) = inhand_test::random_unit_vector<double, Dim>(rng);
      q(i) = 0.2 + 2.0 * unit(rng);
      rest += q(i) * N.col(i);
    }
    if (!(rest.norm() > 1e-3)) continue;
    q(b) = rest.norm();
    N.col(b) = -rest / q(b);
    const Vec delta = inhand::balancing_shift<double, Dim>(P, N, q, b);
    ASSERT_TRUE(delta.allFinite());
    EXPECT_NEAR(delta.dot(N.col(b)), 0.0, 1e-15) << "case " << k;
    Eigen::Matrix<double, Dim, Eigen::Dynamic> moved = P;
    moved.col(b) += delta;
    Eigen::Vector3d nb = Eigen::Vector3d::Zero();
    nb.template head<Dim>() = N.col(b);
    const Eigen::Vector3d m0 = couple<Dim>(P, N, q, Eigen::Vector3d::Zero());
    const Eigen::Vector3d m1 = couple<Dim>(moved, N, q, Eigen::Vector3d::Zero());
    const double scale = q.sum() * 0.1;  // N m: the forces times the points' spread
    const double across = (m1 - m1.dot(nb) * nb).norm() / scale;
    EXPECT_LT(across, 1e-12) << "case " << k;
    EXPECT_NEAR(m1.dot(nb), m0.dot(nb), 1e-12 * scale) << "case " << k;
    if (Dim == 2) {
      EXPECT_LT(m1.norm() / scale, 1e-12) << "case " << k;
    }
    worst = std::max(worst, across);
    largest_shift = std::max(largest_shift, delta.norm());
    Eigen::VectorXd unloaded = q;
    unloaded(b) = 0.0;
    const Vec none = inhand::balancing_shift<double, Dim>(P, N, unloaded, b);
    EXPECT_EQ(none.norm(), 0.0);
  }
  record("balancing_shift.worst_relative_moment_left", worst);
  record("balancing_shift.largest_shift_m", largest_shift);
  EXPECT_GT(largest_shift, 1e-3);  // the sweep moves fingers, not only balanced grasps
}

TEST(BalancingShift, LeavesNoCoupleAcrossTheBalancingNormalPlanar) { check_balancing_shift<2>(31); }
TEST(BalancingShift, LeavesNoCoupleAcrossTheBalancingNormalSpatial) {
  check_balancing_shift<3>(32);
}

TEST(ReleaseGripScale, EveryFingerKeepsMinForceUnderTheLoadPlanar) {
  check_release_grip_scale<2>(21);
}
TEST(ReleaseGripScale, EveryFingerKeepsMinForceUnderTheLoadSpatial) {
  check_release_grip_scale<3>(22);
}

/// Two opposed fingers along x in Dim dimensions (outward normals +x and -x) with q = 1 N,
/// and release_grip 2, release_load 4 N, eps 0.1: G = diag(2.1, 0.1[, 0.1]).
template <int Dim>
struct OpposedPair {
  Eigen::Matrix<double, Dim, 2> N;
  Eigen::Vector2d q{1.0, 1.0};
  inhand::ForceLayerParams<double> fl;
  OpposedPair() {
    N.col(0) = inhand::Vector<double, Dim>::UnitX();
    N.col(1) = -inhand::Vector<double, Dim>::UnitX();
    fl.release_grip = 2.0;
    fl.release_load = 4.0;
    fl.rigid_tolerance = 0.1;
  }
  inhand::ReleaseGrip<double> scale(double max_force) const {
    return inhand::release_grip_scale(N, q, fl, 0.2, max_force);
  }
};

TEST(ReleaseGripScale, OpposedPairAlongAndAcrossGravity) {
  // min_force 0.2 N. Gravity along -x unloads the finger whose outward normal is +x by
  // W / 2.1 statically, 2 W / 2.1 at the step's peak: s = 0.2 + 8 / 2.1. Gravity along y
  // (carried by friction) unloads neither: s as with gravity unknown, 0.2 + 4 / 2.1 from
  // the load along any direction. Any length; a planar hand ignores z.
  OpposedPair<3> p;
  p.fl.gravity_direction = Eigen::Vector3d(-9.81, 0.0, 0.0);
  EXPECT_NEAR(p.scale(6.0).scale, 0.2 + 8.0 / 2.1, 1e-12);
  p.fl.gravity_direction = Eigen::Vector3d(0.0, 1.0, 0.0);
  EXPECT_NEAR(p.scale(6.0).scale, 0.2 + 4.0 / 2.1, 1e-12);
  OpposedPair<2> planar;
  planar.fl.gravity_direction = Eigen::Vector3d(-1.0, 0.0, -5.0);  // in the plane: -x
  EXPECT_NEAR(planar.scale(6.0).scale, 0.2 + 8.0 / 2.1, 1e-12);
  planar.fl.gravity_direction = Eigen::Vector3d(0.0, 0.0, -9.81);  // normal to the plane
  EXPECT_NEAR(planar.scale(6.0).scale, 0.2 + 4.0 / 2.1, 1e-12);
  // Capped by max_force 3 N and said so.
  p.fl.gravity_direction = Eigen::Vector3d(-1.0, 0.0, 0.0);
  EXPECT_DOUBLE_EQ(p.scale(3.0).scale, 3.0);
  EXPECT_TRUE(p.scale(3.0).capped);
}

TEST(ReleaseGripScale, OpposedPairAndNoLoad) {
  // A load along x takes |w| / (2 + eps) from one finger. With 4 N, eps 0.1, min_force 0.2:
  // s = 0.2 + 4 / 2.1 = 2.105 (above release_grip 2). With no load: release_grip.
  OpposedPair<3> p;
  inhand::ForceLayerParams<double>& fl = p.fl;
  EXPECT_NEAR(p.scale(6.0).scale, 0.2 + 4.0 / 2.1, 1e-12);
  EXPECT_FALSE(p.scale(6.0).capped);
  fl.release_load = 0.0;
  EXPECT_DOUBLE_EQ(p.scale(6.0).scale, 2.0);
  // The cap: max_force 1.5 N with q = 1 N allows s = 1.5 only, and says so.
  fl.release_load = 4.0;
  EXPECT_DOUBLE_EQ(p.scale(1.5).scale, 1.5);
  EXPECT_TRUE(p.scale(1.5).capped);
}

// The aimed normal (grasp.hpp, "Gravity's side"): a unit vector in the plane of n_t and g,
// turned from n_t towards g by atan(tan(tilt) |g_p|) (the full tilt with g in the tangent
// plane, none with g along n_t or unknown).
template <int Dim>
void check_gravity_side_normal(std::uint64_t seed) {
  using Vec = inhand::Vector<double, Dim>;
  auto rng = inhand_test::make_rng(seed);
  GraspParams<double> g;
  for (int k = 0; k < scaled(2000); ++k) {
    g.gravity_tilt = std::uniform_real_distribution<double>(0.0, 0.78)(rng);
    const Vec n_t = inhand_test::random_unit_vector<double, Dim>(rng);
    const Vec grav = inhand_test::random_unit_vector<double, Dim>(rng);
    const Vec a = inhand::gravity_side_normal(n_t, grav, g.gravity_tilt);
    EXPECT_NEAR(a.norm(), 1.0, 1e-12);
    if constexpr (Dim == 3) {
      EXPECT_NEAR(a.dot(n_t.cross(grav)), 0.0, 1e-12);  // in their plane
    }
    const Vec g_p = grav - grav.dot(n_t) * n_t;
    EXPECT_NEAR(std::acos(std::min(1.0, a.dot(n_t))),
                std::atan(std::tan(g.gravity_tilt) * g_p.norm()), 1e-6);
    EXPECT_GE(a.dot(grav), n_t.dot(grav) - 1e-12);  // turned towards g
    EXPECT_LT((inhand::gravity_side_normal(n_t, Vec(Vec::Zero()), g.gravity_tilt) - n_t).norm(),
              1e-15);
    EXPECT_LT((inhand::gravity_side_normal(n_t, Vec(-n_t), g.gravity_tilt) - n_t).norm(), 1e-15);
  }
}

TEST(GravitySideNormal, TurnsTowardsGravityByUpToTheTiltPlanar) {
  check_gravity_side_normal<2>(41);
}
TEST(GravitySideNormal, TurnsTowardsGravityByUpToTheTiltSpatial) {
  check_gravity_side_normal<3>(42);
}

// A pressing finger on a surface, closed loop: its contact slides by the tangential part of
// press_step's velocity each millisecond until placed (at most 5 s). `surface` maps a point
// near it to (the point on it, its outward normal). Returns the placed contact.
struct Placed {
  Eigen::Vector3d point, normal;
  bool placed = false, gravity_side = true;
};
/// A model-free target: on the object's axis (the origin), expected normal +y.
GraspTarget<double, 3> axis_target() {
  GraspTarget<double, 3> target;
  target.contact_point.setZero();
  target.normal = Eigen::Vector3d::UnitY();
  return target;
}
/// A cylinder of radius R about the x axis.
auto cylinder_surface(double R) {
  return [R](const Eigen::Vector3d& p) {
    const Eigen::Vector3d n = Eigen::Vector3d(0.0, p.y(), p.z()).normalized();
    return std::make_pair(Eigen::Vector3d(p.x(), R * n.y(), R * n.z()), n);
  };
}
template <typename Surface>
Placed press_until_placed(const GraspParams<double>& g, const Eigen::Vector3d& start,
                          const Eigen::Vector3d& gravity, Surface&& surface,
                          const GraspTarget<double, 3>& target = axis_target()) {
  inhand::SettleWindow<double, 3> window;
  Placed r;
  std::tie(r.point, r.normal) = surface(start);
  for (int k = 0; k < 5000 && !r.placed; ++k) {
    const auto step = inhand::press_step(g, target, r.point, r.normal, gravity, 1e-3, window);
    r.placed = step.placed;
    const Eigen::Vector3d v = step.velocity - step.velocity.dot(r.normal) * r.normal;
    std::tie(r.point, r.normal) = surface(Eigen::Vector3d(r.point + 1e-3 * v));
  }
  r.gravity_side = window.gravity_side;
  return r;
}

// A finger that misses (grasp.hpp): the virtual contact point has crossed the plane
// through the object's centre normal to the target's normal, whatever its tangential offset.
TEST(PassedObjectCentre, IsTheSideOfTheCentrePlane) {
  const Eigen::Vector3d c(0.01, -0.02, 0.005), n = Eigen::Vector3d(1, 2, -2) / 3.0;
  const Eigen::Vector3d t = Eigen::Vector3d(2, -1, 0).normalized();  // tangential, t . n = 0
  for (const double side : {0.03, 1e-9, -1e-9, -0.03}) {
    for (const double offset : {0.0, 0.05}) {
      const Eigen::Vector3d p = c + side * n + offset * t;
      EXPECT_EQ((inhand::passed_object_centre<double, 3>(p, c, n)), side < 0.0) << side;
    }
  }
  const Eigen::Vector2d c2(0.0, 0.01), n2(0.0, 1.0);
  EXPECT_FALSE((inhand::passed_object_centre<double, 2>(Eigen::Vector2d(0.04, 0.011), c2, n2)));
  EXPECT_TRUE((inhand::passed_object_centre<double, 2>(Eigen::Vector2d(0.04, 0.009), c2, n2)));
}

// On a cylinder (radius 20 mm, axis x) a finger that touches 0.4 rad below or above the
// equator ends 0.05-0.1 rad on gravity's side (gravity -z: below) with the defaults (within
// alignment_tolerance / 2 of the aim, from either side), and at
// the tolerance's edge on its own side with gravity unknown.
TEST(PressStep, EndsOnGravitysSideOfACurvedObject) {
  const double R = 0.02;
  const auto cylinder = cylinder_surface(R);
  const GraspParams<double> g;
  for (const double side : {-1.0, 1.0}) {
    const Eigen::Vector3d start(0.0, R * std::cos(0.4), side * R * std::sin(0.4));
    const Placed told = press_until_placed(g, start, -Eigen::Vector3d::UnitZ(), cylinder);
    ASSERT_TRUE(told.placed) << side;
    EXPECT_TRUE(told.gravity_side) << side;
    const double below = -std::asin(told.normal.z());  // rad towards gravity
    EXPECT_GE(below, g.gravity_tilt - 0.5 * g.alignment_tolerance - 1e-3) << side;
    EXPECT_LE(below, g.gravity_tilt + 0.5 * g.alignment_tolerance + 1e-3) << side;
    const Placed unknown = press_until_placed(g, start, Eigen::Vector3d::Zero(), cylinder);
    ASSERT_TRUE(unknown.placed) << side;
    EXPECT_NEAR(std::asin(unknown.normal.z()), side * g.alignment_tolerance, 2e-3) << side;
  }
}

// Where the surface cannot turn the normal towards gravity -- a flat face across it, or
// the cylinder with gravity along its axis -- the finger is placed within
// position_tolerance of its target; one that slides there over the face stops aiming at
// gravity's side (the flat test).
TEST(PressStep, DropsTheTiltWhereTheSurfaceCannotTurnTheNormal) {
  const GraspParams<double> g;
  auto face = [](const Eigen::Vector3d& p) {
    return std::make_pair(Eigen::Vector3d(p.x(), 0.01, p.z()), Eigen::Vector3d::UnitY().eval());
  };
  const Placed on_face =
      press_until_placed(g, Eigen::Vector3d(0.0, 0.01, -0.005), -Eigen::Vector3d::UnitZ(), face);
  ASSERT_TRUE(on_face.placed);
  EXPECT_FALSE(on_face.gravity_side);
  EXPECT_LE(std::abs(on_face.point.z()), g.position_tolerance);
  const double R = 0.02;
  const auto cylinder = cylinder_surface(R);
  const Placed along_axis =
      press_until_placed(g, Eigen::Vector3d(0.0, R, 0.0), Eigen::Vector3d::UnitX(), cylinder);
  ASSERT_TRUE(along_axis.placed);  // by the scaled tilt or the flat test, near its target
  EXPECT_LE(std::abs(along_axis.point.x()), g.position_tolerance);
  // With the flat test off (flat_curvature 0) the face keeps the tilt, which the finger
  // cannot reach; the tilt's scaling by the point's miss still holds it within
  // position_tolerance of its target (on gravity's side), where it is placed.
  GraspParams<double> keep = g;
  keep.flat_curvature = 0.0;
  const Placed kept =
      press_until_placed(keep, Eigen::Vector3d(0.0, 0.01, -0.005), -Eigen::Vector3d::UnitZ(), face);
  ASSERT_TRUE(kept.placed);
  EXPECT_TRUE(kept.gravity_side);
  EXPECT_LT(kept.point.z(), -0.1 * g.position_tolerance);
  EXPECT_GE(kept.point.z(), -g.position_tolerance);
}

// A surface target on the cylinder (the contact point itself, not the axis): the tilt
// takes the contact no farther than position_tolerance from it.
TEST(PressStep, KeepsASurfaceTargetWithinPositionTolerance) {
  const double R = 0.02;
  const auto cylinder = cylinder_surface(R);
  const GraspParams<double> g;
  GraspTarget<double, 3> target;
  target.contact_point = Eigen::Vector3d(0.0, R, 0.0);
  target.normal = Eigen::Vector3d::UnitY();
  const Placed r =
      press_until_placed(g, target.contact_point, -Eigen::Vector3d::UnitZ(), cylinder, target);
  ASSERT_TRUE(r.placed);
  EXPECT_LT(r.point.z(), 0.0);  // towards gravity
  EXPECT_LE((r.point - target.contact_point).norm(), g.position_tolerance);
}

TEST(GraspParams, ValidationNamesTheField) {
  struct Case {
    const char* field;
    void (*edit)(GraspParams<double>&);
  };
  const std::vector<Case> cases = {
      {"grasp.approach_gain", [](GraspParams<double>& g) { g.approach_gain = 0; }},
      {"grasp.approach_speed", [](GraspParams<double>& g) { g.approach_speed = kNaN; }},
      {"grasp.creep_speed", [](GraspParams<double>& g) { g.creep_speed = 0; }},
      {"grasp.creep_speed", [](GraspParams<double>& g) { g.creep_speed = 1.0; }},
      {"grasp.tangential_gain", [](GraspParams<double>& g) { g.tangential_gain = -1; }},
      {"grasp.force_tolerance", [](GraspParams<double>& g) { g.force_tolerance = 0; }},
      {"grasp.settle_time", [](GraspParams<double>& g) { g.settle_time = -0.1; }},
      {"grasp.gravity_tilt", [](GraspParams<double>& g) { g.gravity_tilt = -0.1; }},
      {"grasp.gravity_tilt", [](GraspParams<double>& g) { g.gravity_tilt = 0.8; }},
      {"grasp.gravity_tilt", [](GraspParams<double>& g) { g.gravity_tilt = kNaN; }},
      {"grasp.flat_curvature", [](GraspParams<double>& g) { g.flat_curvature = -1; }},
      {"grasp.flat_curvature",
       [](GraspParams<double>& g) { g.flat_curvature = std::numeric_limits<double>::infinity(); }},
  };
  EXPECT_TRUE(GraspParams<double>{}.validate().ok());
  for (const Case& c : cases) {
    GraspParams<double> g;
    c.edit(g);
    const inhand::Validation v = g.validate();
    ASSERT_FALSE(v.ok()) << c.field;
    EXPECT_EQ(std::string(v.field), c.field);
  }
}

TEST(GraspTarget, ValidationRejectsNonUnitOrNonFinite) {
  GraspTarget<double, 3> t;
  EXPECT_TRUE(t.validate().ok());
  t.contact_point(1) = kNaN;
  EXPECT_EQ(std::string(t.validate().field), "grasp_target.contact_point");
  t = GraspTarget<double, 3>{};
  t.normal.setZero();
  EXPECT_EQ(std::string(t.validate().field), "grasp_target.normal");
  t.normal = Eigen::Vector3d(3, 0, 0);
  EXPECT_EQ(std::string(t.validate().field), "grasp_target.normal");
  t.normal = Eigen::Vector3d(kNaN, 0, 0);
  EXPECT_EQ(std::string(t.validate().field), "grasp_target.normal");
}

TEST(FingerState, Names) {
  EXPECT_EQ(std::string(inhand::to_string(inhand::FingerState::idle)), "idle");
  EXPECT_EQ(std::string(inhand::to_string(inhand::FingerState::approaching)), "approaching");
  EXPECT_EQ(std::string(inhand::to_string(inhand::FingerState::pressing)), "pressing");
  EXPECT_EQ(std::string(inhand::to_string(inhand::FingerState::in_contact)), "in_contact");
  EXPECT_EQ(std::string(inhand::to_string(inhand::FingerState::reacquiring)), "reacquiring");
}

}  // namespace
