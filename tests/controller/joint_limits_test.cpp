// Joint position limits and coupled joints in layer 3 (controller/ik.hpp,
// math/box_least_squares.hpp, controller/finger_command.hpp):
//  - the box-constrained solve reaches the least objective the box allows, checked
//    against a brute-force enumeration of every held set (3^n of them);
//  - a seeded sweep of ContactIk calls near and at the limits never commands a joint
//    across its limit less the margin within the tick, returns the unconstrained
//    solution bit for bit whenever that is inside the box, and flags the held joints;
//  - a finger whose distal joint follows the middle one commands both in ratio and
//    still meets the contact velocity; in a closed loop a joint driven at its limit
//    stops at the limit less the margin, with the continuity bound active;
//  - with the contact normal weighted (the normal-priority solve), the miss of a held
//    re-solve moves off the normal into the tangent plane, never more along the normal
//    than the plain solve's, at the least weighted objective the box allows;
//  - a joint held at its bound puts the contact velocities on its side of the other
//    joints' columns out of reach (the IK misses them, meets the other side) for a finger
//    with as many joints as dimensions; a redundant finger reaches around it;
//  - the configuration checks name the coupling, margin and normal-weight fields.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/finger_command.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/math/box_least_squares.hpp"

namespace {

using Eigen::Dynamic;
using inhand::IkStatus;
using inhand_test::make_rng;
using inhand_test::scaled;
using inhand_test::uniform;
using MatXd = Eigen::MatrixXd;
using VecXd = Eigen::VectorXd;

/// |J z - b|^2 + lambda2 |z|^2.
double objective(const MatXd& J, const VecXd& b, double lambda2, const VecXd& z) {
  return (J * z - b).squaredNorm() + lambda2 * z.squaredNorm();
}

/// The least objective over the box by enumeration: for every assignment of each
/// coordinate to {free, lower, upper}, the minimum-norm optimum over the free ones
/// (complete orthogonal decomposition of [J_F; lambda I]); the best feasible one.
double brute_force_minimum(const MatXd& J, const VecXd& b, double lambda2, const VecXd& lo,
                           const VecXd& hi) {
  const int n = static_cast<int>(J.cols()), m = static_cast<int>(J.rows());
  int patterns = 1;
  for (int i = 0; i < n; ++i) patterns *= 3;
  double best = std::numeric_limits<double>::infinity();
  for (int p = 0; p < patterns; ++p) {
    VecXd z = VecXd::Zero(n);
    std::vector<int> free;
    int code = p;
    for (int i = 0; i < n; ++i, code /= 3) {
      if (code % 3 == 0) free.push_back(i);
      if (code % 3 == 1) z(i) = lo(i);
      if (code % 3 == 2) z(i) = hi(i);
    }
    const int k = static_cast<int>(free.size());
    if (k > 0) {
      MatXd A = MatXd::Zero(m + k, k);
      VecXd r = VecXd::Zero(m + k);
      r.head(m) = b - J * z;
      for (int c = 0; c < k; ++c) {
        A.block(0, c, m, 1) = J.col(free[static_cast<std::size_t>(c)]);
        A(m + c, c) = std::sqrt(lambda2);
      }
      const VecXd zf = A.completeOrthogonalDecomposition().solve(r);
      for (int c = 0; c < k; ++c) z(free[static_cast<std::size_t>(c)]) = zf(c);
    }
    const double slack = 1e-12 * (1.0 + hi.cwiseAbs().maxCoeff() + lo.cwiseAbs().maxCoeff());
    if (((z - lo).array() >= -slack).all() && ((hi - z).array() >= -slack).all())
      best = std::min(best, objective(J, b, lambda2, z));
  }
  return best;
}

/// A random box with lo <= 0 <= hi; some bounds are exactly 0 (a joint at its limit).
VecXd random_bound(inhand_test::Rng& rng, int n, double sign) {
  VecXd v(n);
  for (int i = 0; i < n; ++i)
    v(i) = uniform(rng, 0.0, 1.0) < 0.2 ? 0.0 : sign * uniform(rng, 0.0, 1.0);
  return v;
}

template <int M>
void check_box_least_squares_against_brute_force(std::uint64_t seed) {
  auto rng = make_rng(seed);
  const int cases = scaled(400);
  double worst = 0.0;
  for (int c = 0; c < cases; ++c) {
    const int n = 1 + c % 5;
    MatXd J = MatXd::Random(M, n);
    if (c % 7 == 0 && n > 1) J.col(n - 1) = J.col(0) * uniform(rng, -2.0, 2.0);  // degenerate
    const VecXd b = VecXd::Random(M) * uniform(rng, 0.1, 3.0);
    const double lambda2 = c % 3 == 0 ? uniform(rng, 0.0, 0.3) : 0.0;
    const VecXd lo = random_bound(rng, n, -1.0), hi = random_bound(rng, n, 1.0);
    inhand::BoxLeastSquares<double, M, Dynamic, 5> box(n);
    Eigen::Matrix<double, M, Dynamic, Eigen::ColMajor, M, 5> Jf = J;
    Eigen::Matrix<double, Dynamic, 1, Eigen::ColMajor, 5, 1> z, lof = lo, hif = hi;
    const auto res = box.solve(Jf, Eigen::Matrix<double, M, 1>(b), lambda2, lof, hif, z);
    ASSERT_TRUE(res.converged) << "case " << c;
    ASSERT_TRUE(((z.array() >= lof.array()) && (z.array() <= hif.array())).all()) << "case " << c;
    const double ours = objective(J, b, lambda2, z);
    const double best = brute_force_minimum(J, b, lambda2, lo, hi);
    const double tol = 1e-10 * (1.0 + b.squaredNorm());
    ASSERT_LE(ours, best + tol) << "case " << c << " n " << n << " lambda2 " << lambda2;
    worst = std::max(worst, ours - best);
    // The held bits name exactly the coordinates at a bound with a free one inside.
    for (int i = 0; i < n; ++i) {
      const bool held = (res.held >> i) & 1u;
      if (!held) continue;
      ASSERT_TRUE(z(i) == lof(i) || z(i) == hif(i)) << "case " << c << " joint " << i;
    }
  }
  inhand_test::record("box_least_squares_excess_over_brute_force_" + std::to_string(M), worst);
}

TEST(BoxLeastSquares, ReachesTheBruteForceMinimumThreeRows) {
  check_box_least_squares_against_brute_force<3>(11);
}
TEST(BoxLeastSquares, ReachesTheBruteForceMinimumTwoRows) {
  check_box_least_squares_against_brute_force<2>(12);
}

TEST(BoxLeastSquares, InsideTheBoxIsTheUnconstrainedSolution) {
  inhand::BoxLeastSquares<double, 3, 4> box;
  Eigen::Matrix<double, 3, 4> J;
  J << 1, 0, 0.5, 0, 0, 1, 0, 0.3, 0, 0, 1, 1;
  const Eigen::Vector3d b(0.01, -0.02, 0.005);
  const Eigen::Vector4d lo = Eigen::Vector4d::Constant(-1), hi = Eigen::Vector4d::Constant(1);
  Eigen::Vector4d z;
  const auto res = box.solve(J, b, 0.0, lo, hi, z);
  EXPECT_EQ(res.held, 0u);
  EXPECT_EQ(res.iterations, 0);
  const Eigen::Vector4d expected = J.transpose() * (J * J.transpose()).ldlt().solve(b);
  EXPECT_LT((z - expected).norm(), 1e-14);
}

// ---- ContactIk with the position box -------------------------------------------------

struct Sweep {
  int calls = 0, limited = 0, equal_unconstrained = 0, brute_checked = 0;
};

/// Random contact Jacobians of n columns and joints near, at or beyond their limits.
template <int N>
Sweep sweep_position_limits(std::uint64_t seed, int calls) {
  using Ik = inhand::ContactIk<double, 3, N>;
  using JV = typename Ik::JointVector;
  using Jac = typename Ik::Jacobian;
  auto rng = make_rng(seed);
  Ik ik;
  Sweep s;
  const double dt = 1e-3, margin = 0.01;
  for (int c = 0; c < calls; ++c) {
    const Jac J = Jac::Random() * 0.08;
    const Eigen::Vector3d x = Eigen::Vector3d::Random() * uniform(rng, 0.001, 0.2);
    JV lower, upper, q, vmax;
    for (int i = 0; i < N; ++i) {
      lower(i) = uniform(rng, -1.0, 0.0);
      upper(i) = lower(i) + uniform(rng, 0.05, 2.0);
      const double u = uniform(rng, 0.0, 1.0);
      // 30 % at the bound less the margin, 20 % just inside, 10 % beyond, the rest anywhere.
      const bool up = uniform(rng, 0.0, 1.0) < 0.5;
      const double edge = up ? upper(i) - margin : lower(i) + margin;
      const double in = up ? -1.0 : 1.0;
      if (u < 0.3)
        q(i) = edge;
      else if (u < 0.5)
        q(i) = edge + in * uniform(rng, 0.0, 2e-3);
      else if (u < 0.6)
        q(i) = edge - in * uniform(rng, 0.0, 0.05);
      else
        q(i) = uniform(rng, lower(i), upper(i));
      vmax(i) = c % 4 == 0 ? uniform(rng, 0.5, 5.0) : 1e6;  // a quarter velocity-limited
    }
    JV lo, hi, qd, free_qd, unscaled;
    inhand::joint_position_box(q, lower, upper, margin, dt, lo, hi);
    const auto rep = ik.solve(J, x, vmax, lo, hi, qd);
    ik.solve(J, x, vmax, free_qd);
    ik.solve(J, x, JV::Constant(1e300), unscaled);  // before the velocity scaling
    ++s.calls;
    EXPECT_FALSE(inhand::has(rep.status, IkStatus::invalid_input));
    for (int i = 0; i < N; ++i) {
      const double next = q(i) + qd(i) * dt;
      const double top = std::max(upper(i) - margin, q(i)),
                   bottom = std::min(lower(i) + margin, q(i));
      if (next > top + 1e-12 || next < bottom - 1e-12) {
        ADD_FAILURE() << "call " << c << " joint " << i << " crosses: q " << q(i) << " -> " << next
                      << " in [" << bottom << ", " << top << "]";
        return s;
      }
      if (std::abs(qd(i)) > vmax(i)) {
        ADD_FAILURE() << "call " << c << " joint " << i << " beyond its velocity limit";
        return s;
      }
    }
    const bool inside =
        ((unscaled.array() >= lo.array()) && (unscaled.array() <= hi.array())).all();
    if (inside) {
      if (!(qd == free_qd) || inhand::has(rep.status, IkStatus::position_limited)) {
        ADD_FAILURE() << "call " << c << ": the unconstrained solution was feasible";
        return s;
      }
      ++s.equal_unconstrained;
    } else {
      ++s.limited;
      // Flagged exactly when a joint is held (a solution that left the box by rounding
      // only may come back inside with none held).
      EXPECT_EQ(inhand::has(rep.status, IkStatus::position_limited), rep.held_joints != 0u)
          << "call " << c;
      // The residual of the returned command, to the rounding of J qd - x (n + 1 terms per
      // row, summed in any order: at most (n + 1) eps (|J| |qd| + |x|) per row).
      const double rounding = (N + 1) * std::numeric_limits<double>::epsilon() *
                              ((J.cwiseAbs() * qd.cwiseAbs()).norm() + x.norm());
      EXPECT_NEAR(rep.task_error, (J * qd - x).norm(), rounding) << "call " << c;
      // Without velocity scaling the task error is the least the box allows.
      if (rep.limit_scale == 1.0 && c % 10 == 1) {
        const double l2 = rep.damping * rep.damping;
        const double best = brute_force_minimum(J, x, l2, lo, hi);
        const double ours = objective(J, x, l2, qd.template cast<double>());
        EXPECT_LE(ours, best + 1e-12 * (1.0 + x.squaredNorm())) << "call " << c;
        ++s.brute_checked;
      }
    }
  }
  return s;
}

TEST(ContactIkPositionLimits, SweepNeverCrossesAndKeepsFeasibleSolutions) {
  const int per_shape = scaled(35000);  // three shapes: > 10^5 calls at the default scale
  Sweep total;
  for (const Sweep& s :
       {sweep_position_limits<3>(21, per_shape), sweep_position_limits<4>(22, per_shape),
        sweep_position_limits<5>(23, per_shape)}) {
    total.calls += s.calls;
    total.limited += s.limited;
    total.equal_unconstrained += s.equal_unconstrained;
    total.brute_checked += s.brute_checked;
  }
  EXPECT_EQ(total.calls, 3 * per_shape);
  // Both regimes occur often enough to mean something.
  EXPECT_GT(total.limited, total.calls / 10);
  EXPECT_GT(total.equal_unconstrained, total.calls / 10);
  EXPECT_GT(total.brute_checked, 100);
  inhand_test::record("position_limit_sweep_calls", total.calls);
  inhand_test::record("position_limit_sweep_limited", total.limited);
}

/// Every way a box or a velocity limit can be invalid, on every joint, for a fixed-size and a
/// run-time-bounded solver: -inf < lo <= 0 <= hi < +inf and max_velocity > 0 are required,
/// NaN fails each; the edges of the valid set (lo = hi = 0, an unlimited velocity) pass.
template <int N, int MaxN>
void check_box_validation() {
  using Ik = inhand::ContactIk<double, 3, N, MaxN>;
  using JV = typename Ik::JointVector;
  constexpr int n = 4;
  Ik ik(n);
  typename Ik::Jacobian J(3, n);
  J << 1, 0, 0, 0.5, 0, 1, 0, 0.2, 0, 0, 1, -0.3;
  const Eigen::Vector3d x(0.01, -0.02, 0.03);
  const JV vmax0 = JV::Constant(n, 10.0), lo0 = JV::Constant(n, -1.0), hi0 = JV::Constant(n, 1.0);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  auto status = [&](const JV& vmax, const JV& lo, const JV& hi) {
    JV qd = JV::Constant(n, 7.0);
    const auto s = ik.solve(J, x, vmax, lo, hi, qd).status;
    const bool invalid = inhand::has(s, IkStatus::invalid_input);
    if (invalid) {
      EXPECT_TRUE(qd.isZero(0));
    }
    return invalid;
  };
  EXPECT_FALSE(status(vmax0, lo0, hi0));
  EXPECT_FALSE(status(JV::Constant(n, inf), JV::Zero(n), JV::Zero(n)));
  for (int i = 0; i < n; ++i) {
    for (double bad : {0.5, -inf, nan}) {  // lo > 0: theta_dot = 0 would not be feasible
      JV lo = lo0;
      lo(i) = bad;
      EXPECT_TRUE(status(vmax0, lo, hi0)) << "lo(" << i << ") = " << bad;
    }
    for (double bad : {-0.5, inf, nan}) {
      JV hi = hi0;
      hi(i) = bad;
      EXPECT_TRUE(status(vmax0, lo0, hi)) << "hi(" << i << ") = " << bad;
    }
    for (double bad : {0.0, -1.0, -inf, nan}) {
      JV vmax = vmax0;
      vmax(i) = bad;
      EXPECT_TRUE(status(vmax, lo0, hi0)) << "max_velocity(" << i << ") = " << bad;
    }
  }
}
TEST(ContactIkPositionLimits, EveryInvalidBoxOrLimitIsRejectedOnEveryJoint) {
  check_box_validation<4, 4>();
  check_box_validation<Eigen::Dynamic, 6>();
}

/// Random boxes that hold joints, solved plainly and with the normal weighted: the weighted
/// solve stays in the box, leaves no more miss along the normal than the plain one (its
/// objective weighs that miss w^2 times as much, the plain one's is the least unweighted
/// miss: adding the two optimality inequalities gives (w^2 - 1) miss_w <= (w^2 - 1) miss_p),
/// reaches the least weighted objective the box allows, and changes nothing when nothing is
/// held or w = 1.
template <int N>
int sweep_normal_priority(std::uint64_t seed, int calls) {
  using Ik = inhand::ContactIk<double, 3, N>;
  using JV = typename Ik::JointVector;
  using Jac = typename Ik::Jacobian;
  auto rng = make_rng(seed);
  inhand::IkParams<double> params;
  params.limited_normal_weight = 10.0;
  Ik ik(N, params);
  inhand::IkParams<double> equal = params;
  equal.limited_normal_weight = 1.0;
  Ik ik_equal(N, equal);
  const JV vmax = JV::Constant(1e300);  // no velocity scaling: the misses compare directly
  int held = 0;
  for (int c = 0; c < calls; ++c) {
    const Jac J = Jac::Random() * 0.08;
    const Eigen::Vector3d x = Eigen::Vector3d::Random() * uniform(rng, 0.001, 0.2);
    const Eigen::Vector3d n = Eigen::Vector3d::Random().normalized() * uniform(rng, 0.5, 2.0);
    JV lo, hi;
    for (int i = 0; i < N; ++i) {  // about half the joints with little room either way
      const bool tight = uniform(rng, 0.0, 1.0) < 0.5;
      lo(i) = tight ? -uniform(rng, 0.0, 0.05) : -10.0;
      hi(i) = tight ? uniform(rng, 0.0, 0.05) : 10.0;
    }
    JV plain, weighted, unit_weight, free_qd;
    const auto rp = ik.solve(J, x, vmax, lo, hi, plain);
    const auto rw = ik.solve(J, x, vmax, lo, hi, n, weighted);
    ik_equal.solve(J, x, vmax, lo, hi, n, unit_weight);
    ik.solve(J, x, vmax, free_qd);
    EXPECT_TRUE(unit_weight == plain) << "call " << c << ": w = 1 must be the plain solve";
    EXPECT_TRUE((weighted.array() >= lo.array()).all() && (weighted.array() <= hi.array()).all())
        << "call " << c;
    if (((free_qd.array() >= lo.array()) && (free_qd.array() <= hi.array())).all()) {
      EXPECT_TRUE(weighted == free_qd) << "call " << c << ": nothing held, nothing may change";
      continue;
    }
    if (rp.held_joints == 0u && rw.held_joints == 0u) continue;
    ++held;
    const Eigen::Vector3d u = n.normalized();
    const double miss_w = std::abs(u.dot(J * weighted - x)),
                 miss_p = std::abs(u.dot(J * plain - x));
    EXPECT_LE(miss_w, miss_p + 1e-9 * (1.0 + x.norm())) << "call " << c;
    if (c % 10 == 1) {
      const Eigen::Matrix3d W = Eigen::Matrix3d::Identity() + 9.0 * u * u.transpose();
      const MatXd WJ = W * J;
      const VecXd Wx = W * x;
      const double l2 = rw.damping * rw.damping;
      const double best = brute_force_minimum(WJ, Wx, l2, lo, hi);
      EXPECT_LE(objective(WJ, Wx, l2, weighted), best + 1e-12 * (1.0 + Wx.squaredNorm()))
          << "call " << c;
    }
  }
  return held;
}

TEST(ContactIkPositionLimits, NormalPriorityMovesTheMissIntoTheTangentPlane) {
  const int per_shape = scaled(4000);
  const int held = sweep_normal_priority<3>(31, per_shape) +
                   sweep_normal_priority<4>(32, per_shape) +
                   sweep_normal_priority<5>(33, per_shape);
  EXPECT_GT(held, per_shape / 2);  // the held regime is exercised
  inhand_test::record("normal_priority_sweep_held", held);
}

TEST(ContactIkPositionLimits, NormalPriorityMeetsTheNormalWhenOneJointIsHeld) {
  // Three joints, the third held at 0 (its box is [0, 0]): the free two move the contact
  // along x and along (0, 1, 1). Asked for 0.1 m/s along z (tangential) with the normal along
  // y, the plain solve splits the miss between the two; the weighted one keeps the normal.
  inhand::ContactIk<double, 3, 3> ik;
  Eigen::Matrix3d J;
  J << 1.0, 0.0, 0.0,  //
      0.0, 1.0, 0.0,   //
      0.0, 1.0, 1.0;
  const Eigen::Vector3d x(0.0, 0.0, 0.1), normal(0.0, 1.0, 0.0);
  const Eigen::Vector3d vmax = Eigen::Vector3d::Constant(100.0);
  const Eigen::Vector3d lo(-1.0, -1.0, 0.0), hi(1.0, 1.0, 0.0);
  Eigen::Vector3d plain, weighted;
  ik.solve(J, x, vmax, lo, hi, plain);
  const auto r = ik.solve(J, x, vmax, lo, hi, normal, weighted);
  EXPECT_TRUE(inhand::has(r.status, IkStatus::position_limited));
  // Plain: joint 2 free moves (y, z) = (t, t), least squares t = 0.05: 0.05 m/s along the
  // normal. Weighted (w = 10): t = 0.1 / 101, about 1 mm/s along the normal.
  EXPECT_NEAR((J * plain - x).y(), 0.05, 1e-12);
  EXPECT_NEAR((J * weighted - x).y(), 0.1 / 101.0, 1e-12);
}

TEST(ContactIkPositionLimits, NormalWeightValidationNamesTheField) {
  inhand::IkParams<double> p;
  p.limited_normal_weight = 0.5;
  EXPECT_STREQ(p.validate().field, "ik.limited_normal_weight");
  p.limited_normal_weight = std::numeric_limits<double>::quiet_NaN();
  EXPECT_STREQ(p.validate().field, "ik.limited_normal_weight");
  p.limited_normal_weight = 1.0;
  EXPECT_TRUE(p.validate().ok());
}

// ---- FingerServo: coupling and the closed loop at a limit ---------------------------

using Chain4 = inhand::FingerChain<double, 3, 4>;
using Servo4 = inhand::FingerServo<double, 3, 4>;

/// The Shadow-like finger (abduction, three flexions) with the distal joint following
/// the middle one with `ratio`.
Chain4 coupled_finger(double ratio) {
  const auto spec = inhand_test::finger_spec<double, 3>(4);
  Chain4 c;
  c.base = spec.base;
  for (int i = 0; i < 4; ++i) c.joints[i] = spec.joints[static_cast<std::size_t>(i)];
  c.joint_to_tip = spec.joint_to_tip;
  c.fingertip_radius = spec.fingertip_radius;
  c.joints[3].coupling.leader = 2;
  c.joints[3].coupling.ratio = ratio;
  return c;
}

struct FingerOut {
  inhand::ServoCommand<double, 3> servo{};
  inhand::ServoStatus servo_status{};
  inhand::IkReport<double> ik{};
  Eigen::Vector4d joint_velocities = Eigen::Vector4d::Zero();
};

TEST(CoupledJoints, CommandsKeepTheRatioAndMeetTheTask) {
  for (double ratio : {1.0, 0.7, -0.5}) {
    Chain4 chain = coupled_finger(ratio);
    ASSERT_TRUE(chain.validate().ok());
    EXPECT_EQ(chain.actuated_dof(), 3);
    inhand::ServoGains<double> gains;
    inhand::IkParams<double> ikp;
    ikp.joint_limits = false;
    auto rng = make_rng(31);
    for (int k = 0; k < scaled(200); ++k) {
      Servo4 servo;
      Servo4::Memory memory;
      servo.configure(chain, ikp);
      memory.configure(4, gains);
      Eigen::Vector4d q;
      for (int i = 0; i < 4; ++i)
        q(i) = uniform(rng, chain.joints[i].lower * 0.5, chain.joints[i].upper * 0.5);
      q(3) = ratio * q(2);
      inhand::FingerKinematics<Chain4> ws(chain);
      inhand::forward_kinematics(chain, q, ws);
      Eigen::Matrix<double, 3, 4> J;
      inhand::point_jacobian(ws, ws.fingertip.position, J);
      const Eigen::Vector3d v = Eigen::Vector3d::Random() * 0.01;
      FingerOut fo;
      servo.command(memory, J, q, v, Eigen::Vector3d::UnitY(), nullptr,
                    std::numeric_limits<double>::infinity(), 1e-3, fo);
      EXPECT_DOUBLE_EQ(fo.joint_velocities(3), ratio * fo.joint_velocities(2)) << "ratio " << ratio;
      if (fo.ik.status == IkStatus::ok) {
        // The whole-joint Jacobian applied to the coupled command gives the servo's
        // velocity: the followers' motion is accounted for.
        EXPECT_LT((J * fo.joint_velocities - fo.servo.total).norm(), 1e-12 * (1 + v.norm()))
            << "ratio " << ratio << " case " << k;
      }
    }
  }
}

TEST(CoupledJoints, ClosedLoopStopsAtTheLimitLessTheMargin) {
  Chain4 chain = coupled_finger(1.0);
  chain.joints[2].upper = 0.9;  // the leader's limit
  chain.joints[3].upper = 0.6;  // the follower's tighter limit binds the pair
  inhand::ServoGains<double> gains;
  inhand::IkParams<double> ikp;
  ikp.joint_limit_margin = 0.02;
  Servo4 servo;
  Servo4::Memory memory;
  servo.configure(chain, ikp);
  memory.configure(4, gains);
  Eigen::Vector4d q(0.0, 0.3, 0.3, 0.3);
  inhand::FingerKinematics<Chain4> ws(chain);
  bool flagged = false;
  const double dt = 1e-3;
  for (int k = 0; k < 3000; ++k) {
    inhand::forward_kinematics(chain, q, ws);
    Eigen::Matrix<double, 3, 4> J;
    inhand::point_jacobian(ws, ws.fingertip.position, J);
    // Ask for the fingertip motion of the coupled pair flexing at about 1 rad/s: drives
    // both towards their limits.
    const Eigen::Vector3d v = J.col(2) + J.col(3);
    FingerOut fo;
    const auto w = servo.command(memory, J, q, v, Eigen::Vector3d::UnitY(), nullptr, 200.0, dt, fo);
    flagged = flagged || inhand::has(w, inhand::ControllerWarning::joint_position_limited);
    q += fo.joint_velocities * dt;
    ASSERT_LE(q(3), 0.6 - 0.02 + 1e-12) << "tick " << k;
    ASSERT_LE(q(2), 0.9 - 0.02 + 1e-12) << "tick " << k;
    ASSERT_DOUBLE_EQ(q(3), q(2)) << "tick " << k;
  }
  EXPECT_TRUE(flagged);
  EXPECT_GT(q(3), 0.6 - 0.02 - 1e-3);  // it did reach the limit
}

TEST(CoupledJoints, ValidationNamesTheField) {
  Chain4 chain = coupled_finger(1.0);
  chain.joints[3].coupling.leader = 3;
  auto v = chain.validate(true);
  EXPECT_STREQ(v.field, "fingers.chain.joints.coupling.leader");
  EXPECT_EQ(v.index, 3);
  chain.joints[3].coupling.leader = 2;
  chain.joints[2].coupling.leader = 1;  // a leader that itself follows
  v = chain.validate();
  EXPECT_STREQ(v.field, "joints.coupling.leader");
  chain.joints[2].coupling.leader = -1;
  chain.joints[3].coupling.ratio = 0.0;
  EXPECT_STREQ(chain.validate().field, "joints.coupling.ratio");
  chain.joints[3].coupling.ratio = 1.0;
  chain.joints[3].coupling.offset = std::numeric_limits<double>::infinity();
  EXPECT_STREQ(chain.validate().field, "joints.coupling.offset");
  inhand::IkParams<double> ikp;
  ikp.joint_limit_margin = -0.1;
  EXPECT_STREQ(ikp.validate().field, "ik.joint_limit_margin");
}

// ---- FingerServo: the contact directions a held joint puts out of reach ---------------

/// The directions for_each_unreachable_direction() reports for the fingertip point.
template <typename Chain, typename Servo>
std::vector<Eigen::Vector3d> unreachable(Servo& servo, const Chain& chain,
                                         const typename Servo::JointVector& q,
                                         typename Servo::Jacobian& J) {
  inhand::FingerKinematics<Chain> ws(chain);
  inhand::forward_kinematics(chain, q, ws);
  inhand::point_jacobian(ws, ws.fingertip.position, J);
  std::vector<Eigen::Vector3d> out;
  servo.for_each_unreachable_direction(J, q, 1e-3, 1e-4,
                                       [&](const Eigen::Vector3d& b) { out.push_back(b); });
  return out;
}

TEST(WorkspaceLimits, AHeldJointOfASquareFingerPutsOneSideOutOfReach) {
  using Chain3 = inhand::FingerChain<double, 3, 3>;
  using Servo3 = inhand::FingerServo<double, 3, 3>;
  const Chain3 chain = inhand_test::make_finger<Chain3>(3);
  inhand::IkParams<double> ikp;
  ikp.joint_limit_margin = 0.01;
  inhand::ServoGains<double> gains;
  auto rng = make_rng(47);
  int checked = 0, met = 0;
  for (int k = 0; k < scaled(300); ++k) {
    Servo3 servo;
    Servo3::Memory memory;
    servo.configure(chain, ikp);
    memory.configure(3, gains);
    Eigen::Vector3d q;  // every joint well inside its range, then joint j at a bound
    for (int i = 0; i < 3; ++i)
      q(i) = chain.joints[i].lower +
             uniform(rng, 0.2, 0.8) * (chain.joints[i].upper - chain.joints[i].lower);
    const int j = static_cast<int>(uniform(rng, 0.0, 2.999));
    const bool up = uniform(rng, 0.0, 1.0) < 0.5;
    Eigen::Matrix3d J;
    // Away from the held bound (by more than the tolerance): nothing is out of reach.
    q(j) = up ? chain.joints[j].upper - 0.01 - 1e-3 : chain.joints[j].lower + 0.01 + 1e-3;
    EXPECT_FALSE(servo.at_position_limit(q, 1e-4)) << "case " << k;
    EXPECT_TRUE(unreachable(servo, chain, q, J).empty()) << "case " << k;
    // At the held bound: one direction, normal to the other joints' columns, on the
    // held joint's side.
    q(j) = up ? chain.joints[j].upper - 0.01 : chain.joints[j].lower + 0.01;
    EXPECT_TRUE(servo.at_position_limit(q, 1e-4)) << "case " << k;
    const std::vector<Eigen::Vector3d> b = unreachable(servo, chain, q, J);
    if (J.jacobiSvd().singularValues()(2) < 1e-3) continue;  // near-singular: the IK's damping
    ++checked;
    ASSERT_EQ(b.size(), 1u) << "case " << k;
    EXPECT_NEAR(b[0].norm(), 1.0, 1e-12);
    for (int i = 0; i < 3; ++i) {
      if (i == j) continue;
      EXPECT_LT(std::abs(b[0].dot(J.col(i))), 1e-9 * J.norm()) << "case " << k;
    }
    EXPECT_GT((up ? 1.0 : -1.0) * b[0].dot(J.col(j)), 0.0) << "case " << k;
    // The IK agrees: a velocity into b is missed (the joint is held), one away from it
    // is met.
    struct {
      inhand::ServoCommand<double, 3> servo{};
      inhand::ServoStatus servo_status{};
      inhand::IkReport<double> ik{};
      Eigen::Vector3d joint_velocities = Eigen::Vector3d::Zero();
    } fo;
    const double inf = std::numeric_limits<double>::infinity();
    servo.command(memory, J, q, 0.01 * b[0], Eigen::Vector3d::UnitY(), nullptr, inf, 1e-3, fo);
    EXPECT_TRUE(inhand::has(fo.ik.status, IkStatus::position_limited)) << "case " << k;
    EXPECT_GT(fo.ik.task_error, 1e-3) << "case " << k;
    memory.configure(3, gains);
    servo.command(memory, J, q, -0.01 * b[0], Eigen::Vector3d::UnitY(), nullptr, inf, 1e-3, fo);
    if (fo.ik.status == IkStatus::ok) {  // neither damped nor scaled to the speed limits
      ++met;
      EXPECT_LT(fo.ik.task_error, 1e-9) << "case " << k;
    }
  }
  EXPECT_GT(checked, scaled(300) / 2);
  EXPECT_GT(met, 0);
  // Joint limits off: nothing is held, nothing out of reach.
  ikp.joint_limits = false;
  Servo3 off;
  off.configure(chain, ikp);
  Eigen::Vector3d q(chain.joints[0].upper, 0.3, 0.3);
  Eigen::Matrix3d J;
  EXPECT_FALSE(off.at_position_limit(q, 1e-4));
  EXPECT_TRUE(unreachable(off, chain, q, J).empty());
}

TEST(WorkspaceLimits, ARedundantFingerReachesAroundAHeldJoint) {
  const Chain4 chain = inhand_test::make_finger<Chain4>(4);
  inhand::IkParams<double> ikp;
  auto rng = make_rng(53);
  int free = 0;
  for (int k = 0; k < scaled(300); ++k) {
    Servo4 servo;
    servo.configure(chain, ikp);
    Eigen::Vector4d q;
    for (int i = 0; i < 4; ++i)
      q(i) = chain.joints[i].lower +
             uniform(rng, 0.2, 0.8) * (chain.joints[i].upper - chain.joints[i].lower);
    const int j = static_cast<int>(uniform(rng, 0.0, 3.999));
    q(j) = chain.joints[j].upper - ikp.joint_limit_margin;
    Eigen::Matrix<double, 3, 4> J;
    const std::vector<Eigen::Vector3d> b = unreachable(servo, chain, q, J);
    Eigen::Matrix3d others;
    for (int i = 0, c = 0; i < 4; ++i)
      if (i != j) others.col(c++) = J.col(i);
    const double smin = others.jacobiSvd().singularValues()(2);
    // The other three columns span the space: every contact velocity stays in reach.
    if (smin > 1e-2 * J.norm()) {
      ++free;
      EXPECT_TRUE(b.empty()) << "case " << k << " joint " << j;
    }
    // Whatever is reported is (to the rank tolerance, sigma ratio 1e-3) normal to the
    // other columns.
    for (const Eigen::Vector3d& d : b)
      EXPECT_LT((d.transpose() * others).norm(), 1.01e-3 * J.norm()) << "case " << k;
  }
  EXPECT_GT(free, 0);
}

/// Two joints of a 4-joint finger at their bounds leave two free columns, which span a
/// plane: with the contact normal given, the held joints are taken together
/// (FingerServo::held_together). Whatever that adds separates s n from every reachable
/// contact velocity, and the IK, asked for a velocity along s n, misses it by at least
/// what that separation says; where nothing is added, the IK meets it.
TEST(WorkspaceLimits, TwoHeldJointsOfARedundantFingerAreTakenTogether) {
  const Chain4 chain = inhand_test::make_finger<Chain4>(4);
  inhand::IkParams<double> ikp;
  inhand::ServoGains<double> gains;
  auto rng = make_rng(59);
  const double inf = std::numeric_limits<double>::infinity();
  int added = 0, met = 0;
  for (int k = 0; k < scaled(300); ++k) {
    Servo4 servo;
    Servo4::Memory memory;
    servo.configure(chain, ikp);
    memory.configure(4, gains);
    Eigen::Vector4d q;
    for (int i = 0; i < 4; ++i)
      q(i) = chain.joints[i].lower +
             uniform(rng, 0.2, 0.8) * (chain.joints[i].upper - chain.joints[i].lower);
    const int j1 = static_cast<int>(uniform(rng, 0.0, 3.999));
    const int j2 = (j1 + 1 + static_cast<int>(uniform(rng, 0.0, 2.999))) % 4;
    double allowed[4] = {0, 0, 0, 0};  // the sign a held joint may still move with
    for (const int j : {j1, j2}) {
      const bool up = uniform(rng, 0.0, 1.0) < 0.5;
      q(j) = up ? chain.joints[j].upper - ikp.joint_limit_margin
                : chain.joints[j].lower + ikp.joint_limit_margin;
      allowed[j] = up ? -1.0 : 1.0;
    }
    Eigen::Vector3d n(uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0));
    n.normalize();
    Eigen::Matrix<double, 3, 4> J;
    const std::vector<Eigen::Vector3d> alone = unreachable(servo, chain, q, J);
    std::vector<Eigen::Vector3d> together;
    servo.for_each_unreachable_direction(
        J, q, 1e-3, 1e-4, [&](const Eigen::Vector3d& b) { together.push_back(b); }, &n);
    // The one-joint tests come first, unchanged.
    ASSERT_GE(together.size(), alone.size()) << "case " << k;
    for (std::size_t i = 0; i < alone.size(); ++i) EXPECT_EQ(together[i], alone[i]) << k;
    bool reported[2] = {false, false};
    for (std::size_t i = alone.size(); i < together.size(); ++i) {
      const Eigen::Vector3d& b = together[i];
      EXPECT_NEAR(b.norm(), 1.0, 1e-12);
      for (int c = 0; c < 4; ++c) {
        if (allowed[c] == 0.0)  // free: b is normal to its column (the rank tolerance)
          EXPECT_LT(std::abs(b.dot(J.col(c))), 1.01e-3 * J.norm()) << "case " << k;
        else  // held: its allowed motion does not move the contact along b
          EXPECT_LT(allowed[c] * b.dot(J.col(c)), 1.01e-3 * J.norm()) << "case " << k;
      }
      const double along = b.dot(n);
      ASSERT_GT(std::abs(along), 1e-3) << "case " << k;
      reported[along > 0 ? 0 : 1] = true;
    }
    if (together.size() > alone.size()) ++added;
    for (int side = 0; side < 2; ++side) {
      FingerOut fo;
      memory.configure(4, gains);
      const Eigen::Vector3d v = (side == 0 ? 0.01 : -0.01) * n;
      servo.command(memory, J, q, v, Eigen::Vector3d::UnitY(), nullptr, inf, 1e-3, fo);
      const Eigen::Vector3d x = fo.servo.total;
      if (reported[side]) {
        // |x - x'| >= b^T (x - x') >= b^T x for every reachable x' (b^T x' <= 0).
        double bound = 0.0;
        for (std::size_t i = alone.size(); i < together.size(); ++i)
          bound = std::max(bound, together[i].dot(x));
        EXPECT_GE(fo.ik.task_error, 0.999 * bound - 1e-15) << "case " << k;
      } else if (fo.ik.status == IkStatus::ok || fo.ik.status == IkStatus::position_limited) {
        ++met;  // within the rank tolerance of the cone, and neither damped nor scaled
        EXPECT_LT(fo.ik.task_error, 1.01e-3 * x.norm() + 1e-12) << "case " << k;
      }
    }
  }
  EXPECT_GT(added, scaled(300) / 20);
  EXPECT_GT(met, scaled(300) / 4);
  inhand_test::record("cases_with_a_direction_added", added);
}

}  // namespace
