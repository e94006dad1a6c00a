// Properties of the force layer (controller/force_layer.hpp): the internal projection,
// the stiffness estimate, the loop's stability over contact stiffness, and the grip.
#include "inhand/controller/force_layer.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <random>

namespace {

using Layer = inhand::ForceLayer<double, 3, 4>;

int sweep_scale() {
  const char* s = std::getenv("INHAND_TEST_SCALE");
  const int k = s ? std::atoi(s) : 1;
  return k > 0 ? k : 1;
}

/// A thumb opposing three fingers on a cylinder of radius 0.02 m along world X.
struct Grasp {
  Layer::Mask touching = Layer::Mask::Ones();
  Layer::Points points, normals;
  Layer::ForceVector measured = Layer::ForceVector::Ones();
  Layer::ForceVector pattern;
  Layer::ForceVector advance = Layer::ForceVector::Zero();
  Grasp() {
    for (int i = 0; i < 3; ++i) {
      points.col(i) = Eigen::Vector3d(-0.02 + 0.02 * i, -0.02, 0.0);
      normals.col(i) = Eigen::Vector3d(0, -1, 0);
    }
    points.col(3) = Eigen::Vector3d(0, 0.02, 0);
    normals.col(3) = Eigen::Vector3d(0, 1, 0);
    pattern << 1, 1, 1, 3;
  }
  Layer::Step step(double dt = 1e-3, bool free = true) const {
    Layer::Step s;
    s.touching = &touching;
    s.points = &points;
    s.normals = &normals;
    s.measured = &measured;
    s.pattern = &pattern;
    s.advance = &advance;
    s.min_force = 0.2;
    s.max_force = 6.0;
    s.object_free = free;
    s.dt = dt;
    return s;
  }
};

/// Resultant wrench of normal forces f (force; torque about the origin).
Eigen::Matrix<double, 6, 1> resultant(const Grasp& g, const Layer::ForceVector& f) {
  Eigen::Matrix<double, 6, 1> w = Eigen::Matrix<double, 6, 1>::Zero();
  for (int i = 0; i < 4; ++i) {
    w.head<3>() += f(i) * g.normals.col(i);
    w.tail<3>() += f(i) * g.points.col(i).cross(g.normals.col(i));
  }
  return w;
}

TEST(ForceLayer, CorrectionIsInternalForRandomGraspsAndForces) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0), pos(0.1, 3.0);
  const int n = 200 * sweep_scale();
  for (int k = 0; k < n; ++k) {
    Grasp g;
    for (int i = 0; i < 4; ++i) {
      g.points.col(i) = 0.03 * Eigen::Vector3d(u(rng), u(rng), u(rng));
      g.normals.col(i) = Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized();
      g.measured(i) = pos(rng);
      g.pattern(i) = pos(rng);
    }
    Layer layer;
    Layer::Result r;
    layer.update(g.step(), r);
    // The force loops' correction target - measured has no resultant (to the
    // projection's regularisation), and the load is the measured resultant.
    const Layer::ForceVector e = r.target - g.measured;
    const double scale = (r.grip * g.pattern - g.measured).norm();
    EXPECT_LT(resultant(g, e).head<3>().norm(), 2e-2 * scale) << k;
    EXPECT_LT((r.load - resultant(g, g.measured)).norm(), 1e-9 * (1.0 + r.load.norm())) << k;
    EXPECT_TRUE(inhand::all_finite(r.velocity));
    EXPECT_GE(r.grip, 1.0);
  }
}

TEST(ForceLayer, CollinearSqueezeIsInternalAndUnbalancedErrorIsIgnored) {
  Grasp g;
  Layer layer;
  Layer::Result r;
  // Measured forces with a net push along +y (a load the normals carry): the loops
  // must not fight it; they only restore the squeeze.
  g.measured << 1, 1, 1, 3.3;
  layer.update(g.step(), r);
  EXPECT_NEAR(resultant(g, r.target - g.measured).head<3>().norm(), 0.0, 1e-3);
  EXPECT_NEAR(r.load(1), 0.3, 1e-12);
  // A squeeze deficit along the pattern is corrected: every finger presses harder.
  g.measured << 0.5, 0.5, 0.5, 1.5;
  layer.update(g.step(), r);
  for (int i = 0; i < 4; ++i) EXPECT_GT(r.velocity(i), 0.0) << i;
}

/// Closed loop of one finger on a spring of stiffness k with one tick of command delay
/// and a first-order actuator lag tau: returns the worst |f - f_d| over the last second.
double spring_loop(double k, double tau, double seconds, double* k_est = nullptr) {
  Grasp g;
  g.touching << 1, 0, 0, 0;
  g.pattern << 1, 0, 0, 0;
  g.measured.setZero();
  Layer layer;
  Layer::Result r;
  const double dt = 1e-3;
  double x = 0.0, v = 0.0, pending = 0.0, worst = 0.0;
  const int ticks = static_cast<int>(seconds / dt);
  for (int t = 0; t < ticks; ++t) {
    g.measured(0) = std::max(0.0, k * x) + 0.0;
    const double x_before = x;
    layer.update(g.step(dt, false), r);
    // Plant: the command of the last tick acts now (delay), through the lag.
    const double cmd = pending;
    pending = r.velocity(0);
    const int sub = 10;
    for (int s = 0; s < sub; ++s) {
      v += (tau > 0 ? (cmd - v) * (dt / sub) / tau : cmd - v);
      x += v * dt / sub;
    }
    g.advance(0) = x - x_before;
    if (t * dt > seconds - 1.0) worst = std::max(worst, std::abs(k * x - 1.0));
  }
  if (k_est) *k_est = layer.stiffness_estimate()(0);
  return worst;
}

TEST(ForceLayer, LoopConvergesOverContactStiffnessWithSameGains) {
  for (double k : {500.0, 2000.0, 1e4, 5e4}) {
    for (double tau : {0.0, 0.01}) {
      double k_est = 0.0;
      const double err = spring_loop(k, tau, 3.0, &k_est);
      EXPECT_LT(err, 0.02) << "k " << k << " tau " << tau;
      EXPECT_GT(k_est, 0.5 * k) << "k " << k << " tau " << tau;
      EXPECT_LT(k_est, 2.0 * k) << "k " << k << " tau " << tau;
    }
  }
}

TEST(ForceLayer, GripRisesOnSlipAndDecays) {
  Grasp g;
  Layer layer;
  Layer::Result r;
  layer.update(g.step(), r);
  EXPECT_DOUBLE_EQ(r.grip, 1.0);
  // The first finger's contact runs along the object at 20 mm/s.
  for (int t = 0; t < 50; ++t) {
    g.points(0, 0) += 2e-5;
    layer.update(g.step(), r);
  }
  EXPECT_TRUE(inhand::has(r.status, inhand::ForceLayerStatus::slipping));
  EXPECT_EQ(r.slipping(0), 1);
  EXPECT_GE(r.grip, layer.params().friction_margin);
  const double raised = r.grip;
  for (int t = 0; t < 40000; ++t) layer.update(g.step(), r);  // two decay times
  EXPECT_FALSE(inhand::has(r.status, inhand::ForceLayerStatus::slipping));
  EXPECT_LT(r.grip, 1.0 + 0.5 * (raised - 1.0));
}

TEST(ForceLayer, LoadBeyondMaxForceIsReported) {
  Grasp g;
  Layer layer;
  Layer::Result r;
  for (int t = 0; t < 2000; ++t) {
    g.points(0, 0) += 2e-5;  // a slip that never stops
    layer.update(g.step(), r);
  }
  EXPECT_TRUE(inhand::has(r.status, inhand::ForceLayerStatus::beyond_capacity));
  // The cap: no target above max_force.
  EXPECT_LE(r.target.maxCoeff(), 6.0 + 1e-9);
}

TEST(ForceLayer, ParamsNameTheField) {
  inhand::ForceLayerParams<double> p;
  EXPECT_TRUE(p.validate().ok());
  p.friction_margin = 0.5;
  EXPECT_STREQ(p.validate().field, "force_layer.friction_margin");
  p = {};
  p.max_stiffness = 0.5 * p.min_stiffness;
  EXPECT_STREQ(p.validate().field, "force_layer.max_stiffness");
}

}  // namespace
