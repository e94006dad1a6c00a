// Tests of the trajectory layer (controller/trajectory.hpp): the minimum-jerk profile,
// pose and feed-forward twist continuity across segment boundaries, the feed-forward
// twist against central finite differences of the pose (position derivative and
// so3_log(R(t+h) R(t-h)^T) / 2h), reciprocation, the paper's rotation about X by
// -0.2 rad, hold, the planar version, capacity, invalid segments and NaN time; and the
// pose loop's integral held along a cut twist (controller/pose_feedback.hpp).
#include "inhand/controller/trajectory.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/pose_feedback.hpp"

namespace {

using inhand::ObjectTrajectory;
using inhand::Pose;
using inhand::SegmentKind;
using inhand::TrajectorySegment;
using inhand_test::record;
using inhand_test::scaled;

using Traj3 = ObjectTrajectory<double, 3>;
using Seg3 = TrajectorySegment<double, 3>;
using Traj2 = ObjectTrajectory<double, 2>;
using Seg2 = TrajectorySegment<double, 2>;
using V3 = Eigen::Vector3d;
using V2 = Eigen::Vector2d;
using Twist3 = inhand::Twist<double, 3>;
using Twist2 = inhand::Twist<double, 2>;

Pose<double, 3> start_pose_3d() {
  Pose<double, 3> p;
  p.position = V3(0.01, -0.02, 0.15);
  p.rotation = inhand::rotation_from_euler<double>(V3(0.3, -0.2, 0.7));
  return p;
}

/// A trajectory using every segment kind, with translation and rotation mixed.
Traj3 mixed_trajectory() {
  Traj3 tr;
  tr.reset(start_pose_3d());
  EXPECT_TRUE(tr.append(Seg3::hold_for(0.25)));
  EXPECT_TRUE(tr.append(Seg3::move(V3(1, 0, 0), 0.005, 1.0)));
  EXPECT_TRUE(tr.append(Seg3::rotate(V3(1, 2, 3), 0.3, 1.5)));
  Twist3 d;
  d << 0.002, -0.003, 0.001, -0.1, 0.05, 0.2;
  EXPECT_TRUE(tr.append(Seg3::reciprocate(d, 2.0, 2)));
  EXPECT_TRUE(tr.append(Seg3::move(V3(0, 1, -1), -0.004, 0.7)));
  EXPECT_TRUE(tr.append(Seg3::rotate(V3(1, 0, 0), -0.2, 0.8)));
  return tr;
}

double rotation_distance(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return inhand::so3_log<double>(Eigen::Matrix3d(a * b.transpose())).norm();
}

// ---------------------------------------------------------------------------

TEST(MinimumJerk, EndpointsMidpointAndDerivative) {
  double s = -1, ds = -1;
  inhand::minimum_jerk(0.0, s, ds);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(ds, 0.0);
  inhand::minimum_jerk(1.0, s, ds);
  EXPECT_EQ(s, 1.0);
  EXPECT_EQ(ds, 0.0);
  inhand::minimum_jerk(0.5, s, ds);
  EXPECT_NEAR(s, 0.5, 1e-15);
  EXPECT_NEAR(ds, 1.875, 1e-15);  // peak speed 15/8 of the mean
  // Clamped outside [0, 1].
  inhand::minimum_jerk(-0.3, s, ds);
  EXPECT_EQ(s, 0.0);
  EXPECT_EQ(ds, 0.0);
  inhand::minimum_jerk(1.7, s, ds);
  EXPECT_EQ(s, 1.0);
  EXPECT_EQ(ds, 0.0);
  // ds is the derivative of s, and s is monotone.
  double prev = 0.0, worst = 0.0;
  const double h = 1e-6;
  for (int k = 1; k < 1000; ++k) {
    const double tau = k / 1000.0;
    double sp, dsp, sm, dsm;
    inhand::minimum_jerk(tau + h, sp, dsp);
    inhand::minimum_jerk(tau - h, sm, dsm);
    inhand::minimum_jerk(tau, s, ds);
    worst = std::max(worst, std::abs((sp - sm) / (2 * h) - ds));
    EXPECT_GT(s, prev);
    prev = s;
  }
  EXPECT_LT(worst, 1e-8);
}

TEST(ObjectTrajectory, EmptyTrajectoryHoldsTheStartPose) {
  Traj3 tr;
  tr.reset(start_pose_3d());
  EXPECT_EQ(tr.size(), 0);
  EXPECT_EQ(tr.duration(), 0.0);
  for (double t : {-1.0, 0.0, 0.5, 100.0}) {
    const auto s = tr.evaluate(t);
    EXPECT_EQ(s.segment, -1);
    EXPECT_TRUE(s.pose.position == start_pose_3d().position);
    EXPECT_TRUE(s.pose.rotation == start_pose_3d().rotation);
    EXPECT_TRUE(s.twist.isZero(0.0));
  }
}

TEST(ObjectTrajectory, SegmentBoundariesAreContinuousInPoseAndTwist) {
  const Traj3 tr = mixed_trajectory();
  ASSERT_EQ(tr.size(), 6);
  EXPECT_NEAR(tr.duration(), 0.25 + 1.0 + 1.5 + 2.0 + 0.7 + 0.8, 1e-15);
  // At a boundary both sides are at rest (minimum jerk: zero velocity and acceleration),
  // so over h the pose may move by at most ~ jerk h^3 and the twist by ~ jerk h^2.
  const double h = 1e-5;
  double worst_pose = 0.0, worst_twist = 0.0;
  for (int i = 0; i <= tr.size(); ++i) {
    const double tb = tr.segment_start_time(i);
    const auto at = tr.evaluate(tb);
    const auto before = tr.evaluate(tb - h);
    const auto after = tr.evaluate(tb + h);
    EXPECT_EQ(at.segment, i < tr.size() ? i : -1) << "boundary " << i;
    for (const auto* side : {&before, &after}) {
      if (i == 0 && side == &before) continue;  // before the start: the start pose
      worst_pose = std::max(worst_pose, (side->pose.position - at.pose.position).norm());
      worst_pose = std::max(worst_pose, rotation_distance(side->pose.rotation, at.pose.rotation));
      worst_twist = std::max(worst_twist, side->twist.norm());
    }
    // Exactly at the boundary the twist is zero.
    EXPECT_LT(at.twist.norm(), 1e-15) << "boundary " << i;
  }
  EXPECT_LT(worst_pose, 1e-12);
  EXPECT_LT(worst_twist, 1e-7);
  record("boundary_pose_jump", worst_pose);
  record("boundary_twist", worst_twist);
  // Zero twist at both ends, start pose at 0 and before.
  const auto s0 = tr.evaluate(0.0);
  EXPECT_TRUE(s0.twist.isZero(0.0));
  EXPECT_LT((s0.pose.position - start_pose_3d().position).norm(), 1e-15);
  const auto send = tr.evaluate(tr.duration() + 1.0);
  EXPECT_EQ(send.segment, -1);
  EXPECT_TRUE(send.twist.isZero(0.0));
  const auto neg = tr.evaluate(-0.5);
  EXPECT_TRUE(neg.twist.isZero(0.0));
  EXPECT_TRUE(neg.pose.position == start_pose_3d().position);
}

TEST(ObjectTrajectory, FinalPoseIsTheComposedDisplacement) {
  const Traj3 tr = mixed_trajectory();
  // Expected end pose: move, rotate, (reciprocate returns), move, rotate, all in the
  // world frame about the object reference point.
  Pose<double, 3> p = start_pose_3d();
  p.position += 0.005 * V3::UnitX();
  p.rotation = inhand::so3_exp<double>(0.3 * V3(1, 2, 3).normalized()) * p.rotation;
  p.position += -0.004 * V3(0, 1, -1).normalized();
  p.rotation = inhand::so3_exp<double>(-0.2 * V3::UnitX()) * p.rotation;
  const auto end = tr.evaluate(tr.duration() + 0.1);
  EXPECT_LT((end.pose.position - p.position).norm(), 1e-15);
  EXPECT_LT(rotation_distance(end.pose.rotation, p.rotation), 1e-14);
}

TEST(ObjectTrajectory, FeedForwardTwistIsTheDerivativeOfThePose) {
  const Traj3 tr = mixed_trajectory();
  auto rng = inhand_test::make_rng(20240601);
  const double h = 1e-5;
  const int n = scaled(2000);
  double worst_lin = 0.0, worst_ang = 0.0, peak = 0.0;
  for (int k = 0; k < n; ++k) {
    const double t = inhand_test::uniform(rng, 0.0, tr.duration());
    // Stay h away from boundaries (segments and reciprocation half-cycles): the
    // central difference would straddle two polynomial pieces there.
    bool near_boundary = false;
    for (int i = 0; i <= tr.size(); ++i)
      if (std::abs(t - tr.segment_start_time(i)) < 2 * h) near_boundary = true;
    const double rec0 = tr.segment_start_time(3);
    for (int q = 0; q <= 4; ++q)
      if (std::abs(t - (rec0 + 0.5 * q)) < 2 * h) near_boundary = true;
    if (near_boundary) continue;
    const auto s = tr.evaluate(t);
    const auto sp = tr.evaluate(t + h);
    const auto sm = tr.evaluate(t - h);
    const V3 v_fd = (sp.pose.position - sm.pose.position) / (2 * h);
    const V3 w_fd =
        inhand::so3_log<double>(Eigen::Matrix3d(sp.pose.rotation * sm.pose.rotation.transpose())) /
        (2 * h);
    worst_lin = std::max(worst_lin, (v_fd - s.twist.head<3>()).norm());
    worst_ang = std::max(worst_ang, (w_fd - s.twist.tail<3>()).norm());
    peak = std::max(peak, s.twist.norm());
  }
  // Truncation error ~ h^2 |s'''| |D| / 6 with |s'''| <= 60 / T^3 (T >= 0.5 s):
  // <= 1e-10 * 480 * 0.3 / 6 ~ 3e-9 for the angular part; rounding ~ 1e-16 / h.
  EXPECT_LT(worst_lin, 1e-9);
  EXPECT_LT(worst_ang, 1e-8);
  EXPECT_GT(peak, 0.2);  // the sweep did see motion
  record("ff_linear_error", worst_lin);
  record("ff_angular_error", worst_ang);
}

TEST(ObjectTrajectory, ReciprocateReturnsToStartAndReachesTheDisplacementAtMidCycle) {
  Twist3 d;
  d << 0.005, 0, 0, 0, 0, 0;  // the paper's Fig. 3a: 0.5 cm along X
  Traj3 tr;
  tr.reset(start_pose_3d());
  ASSERT_TRUE(tr.append(Seg3::reciprocate(d, 3.0, 3)));  // 3 cycles of 1 s
  const V3 p0 = start_pose_3d().position;
  for (int c = 0; c < 3; ++c) {
    const auto mid = tr.evaluate(c + 0.5);
    EXPECT_LT((mid.pose.position - (p0 + d.head<3>())).norm(), 1e-15) << "cycle " << c;
    EXPECT_LT(mid.twist.norm(), 1e-15);
    const auto beg = tr.evaluate(static_cast<double>(c));
    EXPECT_LT((beg.pose.position - p0).norm(), 1e-15) << "cycle " << c;
    EXPECT_LT(beg.twist.norm(), 1e-15);
    // Going out in the first half, coming back in the second.
    EXPECT_GT(tr.evaluate(c + 0.25).twist(0), 0.0);
    EXPECT_LT(tr.evaluate(c + 0.75).twist(0), 0.0);
    // Never beyond the turning point.
    for (int k = 0; k < 100; ++k) {
      const double x = (tr.evaluate(c + k / 100.0).pose.position - p0)(0);
      EXPECT_GE(x, -1e-18);
      EXPECT_LE(x, 0.005 + 1e-18);
    }
  }
  const auto end = tr.evaluate(3.5);
  EXPECT_EQ(end.segment, -1);
  EXPECT_LT((end.pose.position - p0).norm(), 1e-15);
  EXPECT_LT(rotation_distance(end.pose.rotation, start_pose_3d().rotation), 1e-15);
  // The segment after a reciprocation starts from the start pose.
  ASSERT_TRUE(tr.append(Seg3::move(V3::UnitY(), 0.01, 1.0)));
  const auto after = tr.evaluate(3.0 + 1.0 + 1e-9);
  EXPECT_LT((after.pose.position - (p0 + 0.01 * V3::UnitY())).norm(), 1e-15);
}

TEST(ObjectTrajectory, RotateAboutXByMinusPointTwoReachesThatRollAngle) {
  // The paper's Fig. 3b: Euler angle alpha (roll about world X) from 0 to -0.2 rad.
  Traj3 tr;
  tr.reset(Pose<double, 3>::identity());
  ASSERT_TRUE(tr.append(Seg3::rotate(V3::UnitX(), -0.2, 2.0)));
  const V3 rpy_end = inhand::euler_from_rotation<double>(tr.evaluate(5.0).pose.rotation);
  EXPECT_NEAR(rpy_end(0), -0.2, 1e-15);
  EXPECT_NEAR(rpy_end(1), 0.0, 1e-15);
  EXPECT_NEAR(rpy_end(2), 0.0, 1e-15);
  // In between the roll follows -0.2 s(t / T), pitch and yaw stay zero, and the
  // angular velocity is about X only.
  for (int k = 0; k <= 40; ++k) {
    const double t = 2.0 * k / 40.0;
    double s, ds;
    inhand::minimum_jerk(t / 2.0, s, ds);
    const auto smp = tr.evaluate(t);
    const V3 rpy = inhand::euler_from_rotation<double>(smp.pose.rotation);
    EXPECT_NEAR(rpy(0), -0.2 * s, 1e-15) << "t = " << t;
    EXPECT_NEAR(rpy(1), 0.0, 1e-15);
    EXPECT_NEAR(rpy(2), 0.0, 1e-15);
    EXPECT_NEAR(smp.twist(3), -0.2 * ds / 2.0, 1e-15);
    EXPECT_EQ(smp.twist(4), 0.0);
    EXPECT_EQ(smp.twist(5), 0.0);
    EXPECT_TRUE(smp.twist.head<3>().isZero(0.0));
    EXPECT_TRUE(smp.pose.position.isZero(0.0));
  }
  // And back to 0 with a reciprocation of the same displacement.
  Traj3 back;
  back.reset(Pose<double, 3>::identity());
  Twist3 d = Twist3::Zero();
  d(3) = -0.2;
  ASSERT_TRUE(back.append(Seg3::reciprocate(d, 4.0)));
  EXPECT_NEAR(inhand::euler_from_rotation<double>(back.evaluate(2.0).pose.rotation)(0), -0.2,
              1e-15);
  EXPECT_NEAR(inhand::euler_from_rotation<double>(back.evaluate(4.0).pose.rotation)(0), 0.0, 1e-15);
}

TEST(ObjectTrajectory, HoldKeepsThePoseWithZeroTwist) {
  Traj3 tr;
  tr.reset(start_pose_3d());
  ASSERT_TRUE(tr.append(Seg3::move(V3(0, 0, 1), 0.02, 1.0)));
  ASSERT_TRUE(tr.append(Seg3::hold_for(2.0)));
  const V3 held = start_pose_3d().position + V3(0, 0, 0.02);
  for (int k = 0; k <= 50; ++k) {
    const double t = 1.0 + 2.0 * k / 50.0;
    const auto s = tr.evaluate(t);
    if (k < 50) {
      EXPECT_EQ(s.segment, 1);
    }
    EXPECT_TRUE(s.twist.isZero(0.0));
    EXPECT_LT((s.pose.position - held).norm(), 1e-15);
    EXPECT_LT(rotation_distance(s.pose.rotation, start_pose_3d().rotation), 1e-15);
  }
  EXPECT_EQ(tr.evaluate(3.0).segment, -1);
  EXPECT_EQ(tr.segment(1).kind, SegmentKind::hold);
  EXPECT_TRUE(tr.segment(1).displacement.isZero(0.0));
}

TEST(ObjectTrajectory, PlanarTrajectory) {
  Pose<double, 2> start;
  start.position = V2(0.02, -0.01);
  start.rotation = inhand::so2_exp(0.4);
  Traj2 tr;
  tr.reset(start);
  ASSERT_TRUE(tr.append(Seg2::move(V2(1, 1), 0.01, 1.0)));
  ASSERT_TRUE(tr.append(Seg2::rotate(inhand::AngularVector<double, 2>(-1.0), 0.3, 1.0)));
  Twist2 d;
  d << -0.004, 0.002, 0.15;
  ASSERT_TRUE(tr.append(Seg2::reciprocate(d, 1.0)));
  // End of the move, end of the rotation (clockwise: axis -1), mid reciprocation.
  const auto e1 = tr.evaluate(1.0);
  EXPECT_LT((e1.pose.position - (start.position + 0.01 * V2(1, 1).normalized())).norm(), 1e-15);
  const auto e2 = tr.evaluate(2.0);
  EXPECT_NEAR(inhand::so2_log<double>(e2.pose.rotation), 0.4 - 0.3, 1e-15);
  const auto mid = tr.evaluate(2.5);
  EXPECT_LT((mid.pose.position - (e1.pose.position + d.head<2>())).norm(), 1e-15);
  EXPECT_NEAR(inhand::so2_log<double>(mid.pose.rotation), 0.1 + 0.15, 1e-15);
  const auto end = tr.evaluate(3.0);
  EXPECT_LT((end.pose.position - e1.pose.position).norm(), 1e-15);
  EXPECT_NEAR(inhand::so2_log<double>(end.pose.rotation), 0.1, 1e-15);
  // Feed-forward twist against central differences.
  const double h = 1e-5;
  double worst = 0.0;
  for (int k = 1; k < 300; ++k) {
    const double t = 3.0 * k / 300.0 + 0.0037;
    if (std::abs(t - 1.0) < 2 * h || std::abs(t - 2.0) < 2 * h || std::abs(t - 2.5) < 2 * h)
      continue;
    const auto s = tr.evaluate(t), sp = tr.evaluate(t + h), sm = tr.evaluate(t - h);
    Twist2 fd;
    fd.head<2>() = (sp.pose.position - sm.pose.position) / (2 * h);
    fd(2) =
        inhand::so2_log<double>(Eigen::Matrix2d(sp.pose.rotation * sm.pose.rotation.transpose())) /
        (2 * h);
    worst = std::max(worst, (fd - s.twist).norm());
  }
  EXPECT_LT(worst, 1e-8);
  record("planar_ff_error", worst);
}

TEST(ObjectTrajectory, FloatInstantiation) {
  ObjectTrajectory<float, 3, 4> tr;
  tr.reset(Pose<float, 3>::identity());
  ASSERT_TRUE(
      tr.append(TrajectorySegment<float, 3>::rotate(Eigen::Vector3f::UnitX(), -0.2f, 1.0f)));
  const auto s = tr.evaluate(2.0f);
  EXPECT_NEAR(inhand::euler_from_rotation<float>(s.pose.rotation)(0), -0.2f, 1e-6f);
}

TEST(ObjectTrajectory, CapacityIsRespected) {
  ObjectTrajectory<double, 3, 4> tr;
  tr.reset(start_pose_3d());
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(tr.append(Seg3::move(V3::UnitX(), 0.001, 0.5)));
  EXPECT_EQ(tr.size(), 4);
  EXPECT_FALSE(tr.append(Seg3::move(V3::UnitX(), 0.001, 0.5)));
  EXPECT_EQ(tr.size(), 4);
  EXPECT_DOUBLE_EQ(tr.duration(), 2.0);
  const auto end = tr.evaluate(10.0);
  EXPECT_LT((end.pose.position - (start_pose_3d().position + V3(0.004, 0, 0))).norm(), 1e-15);
  // reset() empties it.
  tr.reset(start_pose_3d());
  EXPECT_EQ(tr.size(), 0);
  EXPECT_EQ(tr.duration(), 0.0);
  EXPECT_TRUE(tr.append(Seg3::hold_for(1.0)));
}

TEST(ObjectTrajectory, InvalidSegmentsAreRefusedAndNamed) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Case {
    const char* name;
    Seg3 seg;
    const char* field;
  };
  Twist3 bad = Twist3::Zero();
  bad(4) = nan;
  Seg3 zero_cycles = Seg3::reciprocate(Twist3::Ones() * 0.01, 1.0, 0);
  Seg3 inf_disp = Seg3::reciprocate(Twist3::Ones() * inf, 1.0, 1);
  const std::vector<Case> cases = {
      {"zero duration", Seg3::hold_for(0.0), "segment.duration"},
      {"negative duration", Seg3::move(V3::UnitX(), 0.01, -1.0), "segment.duration"},
      {"NaN duration", Seg3::rotate(V3::UnitZ(), 0.1, nan), "segment.duration"},
      {"infinite duration", Seg3::hold_for(inf), "segment.duration"},
      {"NaN displacement", Seg3::reciprocate(bad, 1.0, 1), "segment.displacement"},
      {"NaN amount", Seg3::move(V3::UnitX(), nan, 1.0), "segment.displacement"},
      {"infinite displacement", inf_disp, "segment.displacement"},
      {"zero cycles", zero_cycles, "segment.cycles"},
  };
  for (const Case& c : cases) {
    Traj3 tr;
    tr.reset(start_pose_3d());
    ASSERT_TRUE(tr.append(Seg3::hold_for(1.0)));
    const inhand::Validation v = Traj3::validate_segment(c.seg);
    ASSERT_FALSE(v.ok()) << c.name;
    EXPECT_EQ(std::string(v.field), c.field) << c.name;
    EXPECT_NE(v.reason, nullptr);
    EXPECT_FALSE(tr.append(c.seg)) << c.name;
    EXPECT_EQ(tr.size(), 1) << c.name;
    EXPECT_EQ(tr.duration(), 1.0) << c.name;
  }
  EXPECT_TRUE(Traj3::validate_segment(Seg3::reciprocate(Twist3::Ones() * 0.01, 1.0, 1)).ok());
}

TEST(ObjectTrajectory, NaNTimeHoldsTheStartPoseWithFiniteOutput) {
  const Traj3 tr = mixed_trajectory();
  for (double t :
       {std::numeric_limits<double>::quiet_NaN(), -std::numeric_limits<double>::infinity()}) {
    const auto s = tr.evaluate(t);
    EXPECT_TRUE(s.pose.is_finite());
    EXPECT_TRUE(inhand::all_finite(s.twist));
    EXPECT_TRUE(s.twist.isZero(0.0));
    EXPECT_TRUE(s.pose.position == start_pose_3d().position);
    EXPECT_TRUE(s.pose.rotation == start_pose_3d().rotation);
  }
  // +inf is "after the end": the final pose, zero twist.
  const auto s = tr.evaluate(std::numeric_limits<double>::infinity());
  EXPECT_EQ(s.segment, -1);
  EXPECT_TRUE(s.twist.isZero(0.0));
  EXPECT_TRUE(s.pose.is_finite());
}

// A finite but denormal duration makes 1 / duration infinite and the sample NaN: such
// segments are refused when appended, with the field named, as are durations whose
// reciprocate cycles are that short and displacements large enough to overflow.
TEST(ObjectTrajectory, SegmentsThatWouldOverflowAreRefused) {
  using Seg = TrajectorySegment<double, 3>;
  using Traj = ObjectTrajectory<double, 3>;
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const struct {
    const char* name;
    Seg seg;
    const char* field;
  } cases[] = {
      {"denormal move", Seg::move(x, 0.005, 1e-310), "segment.duration"},
      {"denormal rotate", Seg::rotate(x, 0.1, 4.9e-324), "segment.duration"},
      {"smallest normal duration", Seg::move(x, 0.005, 2.3e-308), "segment.duration"},
      {"sub-microsecond", Seg::move(x, 0.005, 1e-7), "segment.duration"},
      {"longer than 1e9 s", Seg::hold_for(1e300), "segment.duration"},
      {"enormous move", Seg::move(x, 1e300, 1.0), "segment.displacement"},
      {"reciprocate cycles too short",
       Seg::reciprocate(inhand::Twist<double, 3>::Constant(1e-3), 1e-3, 100000), "segment.cycles"},
  };
  for (const auto& c : cases) {
    const inhand::Validation v = Traj::validate_segment(c.seg);
    ASSERT_FALSE(v.ok()) << c.name;
    EXPECT_STREQ(v.field, c.field) << c.name;
    Traj t;
    t.reset(Pose<double, 3>{});
    EXPECT_FALSE(t.append(c.seg)) << c.name;
    EXPECT_EQ(t.size(), 0) << c.name;
    EXPECT_TRUE(t.validate().ok()) << c.name;
  }
  // The shortest accepted segment still samples finitely.
  Traj t;
  t.reset(Pose<double, 3>{});
  ASSERT_TRUE(t.append(Seg::move(x, 0.005, 1e-6)));
  const auto sample = t.evaluate(0.5e-6);
  EXPECT_TRUE(sample.pose.is_finite());
  EXPECT_TRUE(inhand::all_finite(sample.twist));
  // A start pose that is not a rotation is refused by validate().
  Pose<double, 3> bad;
  bad.rotation *= 2.0;
  Traj u;
  u.reset(bad);
  EXPECT_STREQ(u.validate().field, "trajectory.start_pose.rotation");
}

// ---------------------------------------------------------------------------
/// The measured pose whose error from `desired` is e: pose_error(desired, result) = e.
Pose<double, 3> measured_with_error(const Pose<double, 3>& desired,
                                    const inhand::Twist<double, 3>& e) {
  Pose<double, 3> m = desired;
  m.position -= e.head<3>();
  m.rotation = inhand::rotation_exp<double>(V3(-e.tail<3>())) * desired.rotation;
  return m;
}

// The pose loop's integral band (PoseFeedback::position_integral_band,
// orientation_integral_band; pose_feedback.hpp). (1) An error inside both bands is integrated
// as by a loop without bands, bitwise; beyond a band, that part of the integral grows by dt b
// along the error. (2) Closed loop on an object that follows the twist, x' = V + d (d a
// constant rate the lower layers fail to realise, up to 2.5 K_p b, beyond the band): from
// initial errors of 0.5-10 mm and 20-120 mrad the error returns to zero and K_i I to -d (the one
// equilibrium), and with d = 0 (a release transient) the overshoot past zero along the initial
// error is at most the unbanded loop's, which the band cuts to below half for errors of ten
// bands or more.
TEST(PoseLoop, IntegralBandBoundsTheTransientsShareAndKeepsTheEquilibrium) {
  using Loop = inhand::PoseLoop<double, 3>;
  using Tw = Loop::TwistT;
  const double dt = 1e-3, inf = std::numeric_limits<double>::infinity();
  inhand::PoseFeedback<double> pf;  // default gains K_p 8, K_i 10
  pf.position_integral_band = 5e-4;
  pf.orientation_integral_band = 0.01;
  pf.position_integral_limit = pf.orientation_integral_limit = 1.0;  // out of play
  pf.max_linear_speed = pf.max_angular_speed = 100.0;
  inhand::PoseFeedback<double> open = pf;
  open.position_integral_band = open.orientation_integral_band = inf;
  const double bp = pf.position_integral_band, br = pf.orientation_integral_band;
  const Tw zero = Tw::Zero();
  Pose<double, 3> desired;
  desired.position = V3(0.01, -0.02, 0.15);
  auto measured_at = [&](const Tw& e) { return measured_with_error(desired, e); };
  auto rng = inhand_test::make_rng(2207);
  for (int c = 0; c < scaled(20); ++c) {
    const std::string at = "case " + std::to_string(c);
    // (1) Inside the bands: the same integral; beyond them: dt b along the error.
    Loop banded, unbanded;
    const V3 up = inhand_test::random_unit_vector<double, 3>(rng);
    const V3 ur = inhand_test::random_unit_vector<double, 3>(rng);
    for (int t = 0; t < 20; ++t) {
      Tw e;
      e << 0.9 * bp * up * std::sin(0.3 * t), 0.9 * br * ur * std::cos(0.2 * t);
      banded.update(pf, desired, zero, measured_at(e), dt);
      unbanded.update(open, desired, zero, measured_at(e), dt);
    }
    EXPECT_TRUE(banded.integral() == unbanded.integral()) << at;
    Tw big;
    big << 7.0 * bp * up, 3.0 * br * ur;
    const Tw before = banded.integral();
    const auto step = banded.update(pf, desired, zero, measured_at(big), dt);
    EXPECT_LT((step.pose_error - big).norm(), 1e-12) << at;
    Tw grown;
    grown << dt * bp * up, dt * br * ur;
    EXPECT_LT((banded.integral() - before - grown).norm(), 1e-15) << at;

    // (2) Closed loop.
    const double e0p = inhand_test::uniform<double>(rng, 5e-4, 1e-2);
    const double e0r = inhand_test::uniform<double>(rng, 0.02, 0.12);
    Tw e0;
    e0 << e0p * inhand_test::random_unit_vector<double, 3>(rng),
        e0r * inhand_test::random_unit_vector<double, 3>(rng);
    Tw d;
    d << inhand_test::uniform<double>(rng, 0.0, 2.5) * pf.position_gain * bp *
             inhand_test::random_unit_vector<double, 3>(rng),
        inhand_test::uniform<double>(rng, 0.0, 2.5) * pf.orientation_gain * br *
            inhand_test::random_unit_vector<double, 3>(rng);
    auto run = [&](const inhand::PoseFeedback<double>& g, const Tw& rate, double& overshoot) {
      Loop loop;
      Pose<double, 3> m = measured_at(e0);
      overshoot = 0.0;
      Tw e = e0;
      for (int t = 0; t < 15000; ++t) {
        const auto s = loop.update(g, desired, zero, m, dt);
        e = s.pose_error;
        overshoot = std::max(overshoot, -e.head<3>().dot(e0.head<3>()) / e0p);
        const Tw v = s.commanded_twist + rate;
        m.position += dt * v.head<3>();
        m.rotation = inhand::rotation_exp<double>(V3(dt * v.tail<3>())) * m.rotation;
      }
      return std::make_pair(e, Tw(loop.integral()));
    };
    double os_banded = 0.0, os_open = 0.0;
    const auto held = run(pf, d, os_banded);
    EXPECT_LT(held.first.head<3>().norm(), 1e-9) << at;
    EXPECT_LT(held.first.tail<3>().norm(), 1e-7) << at;
    Tw ki_i = held.second;
    ki_i.head<3>() *= pf.position_integral_gain;
    ki_i.tail<3>() *= pf.orientation_integral_gain;
    EXPECT_LT((ki_i + d).norm(), 1e-6 * (1.0 + d.norm())) << at;
    run(pf, zero, os_banded);
    run(open, zero, os_open);
    EXPECT_LE(os_banded, os_open + 1e-12) << at;
    if (e0p >= 10.0 * bp) {
      EXPECT_LT(os_banded, 0.5 * os_open) << at;
    }
  }
}

// ---------------------------------------------------------------------------
// The pose loop's conditional integration against a cut twist (PoseLoop::hold_integral_along,
// used at the workspace's edge: workspace_limits.hpp), with equal and with unequal integral
// gains K = diag(k_p, k_o). A constant pose error with a part along the cut's direction is
// integrated for 50 ticks, then for 200 more with the cut on: what the integral adds to the
// twist along the removed direction r (r . K I) stays where the cut found it (a loop without
// the cut adds 200 dt r . K e), every part of I across d = K r / |K r| integrates as in that
// loop, and the norm stays below that loop's (the norm bounds kept out of play). The give-back
// never takes the part along d below zero (an integral that one tick lifts from below zero
// ends at zero), and leaves a part below zero alone. An error pointing away from the cut, a
// zero or a non-finite removed twist leave the integral bitwise as without the call.
TEST(PoseLoop, HeldIntegralDoesNotWindUpAlongTheCutAndIntegratesAcrossIt) {
  using Loop = inhand::PoseLoop<double, 3>;
  using Tw = Loop::TwistT;
  const double dt = 1e-3;
  Pose<double, 3> measured;
  measured.position = V3(0.01, -0.02, 0.15);
  auto desired_at = [&](const Tw& e) {
    Pose<double, 3> desired = measured;
    desired.position += e.head<3>();
    desired.rotation = inhand::rotation_exp<double>(V3(e.tail<3>())) * measured.rotation;
    return desired;
  };
  const Twist3 zero = Twist3::Zero();
  auto rng = inhand_test::make_rng(1511);
  for (const std::pair<double, double>& gains :
       {std::pair<double, double>{10.0, 10.0}, {10.0, 3.0}, {2.0, 10.0}, {0.0, 10.0}}) {
    inhand::PoseFeedback<double> pf;
    pf.position_integral_gain = gains.first;
    pf.orientation_integral_gain = gains.second;
    pf.position_integral_limit = 1.0;  // the norm bounds and the bands kept out of play
    pf.orientation_integral_limit = 1.0;
    pf.position_integral_band = std::numeric_limits<double>::infinity();
    pf.orientation_integral_band = std::numeric_limits<double>::infinity();
    Tw k;
    k << Eigen::Vector3d::Constant(gains.first), Eigen::Vector3d::Constant(gains.second);
    for (int c = 0; c < scaled(100); ++c) {
      const Tw r = inhand_test::random_unit_vector<double, 6>(rng);
      const Tw d = Tw(k.cwiseProduct(r)).normalized();
      Tw e = inhand_test::random_vector<double, 6>(rng, -0.01, 0.01);
      if (d.dot(e) < 0) e = -e;
      const Pose<double, 3> desired = desired_at(e);
      Loop held, free;
      for (int t = 0; t < 50; ++t) {
        held.update(pf, desired, zero, measured, dt);
        free.update(pf, desired, zero, measured, dt);
      }
      const double along = r.dot(k.cwiseProduct(held.integral()));
      ASSERT_GT(along, 0.0);
      for (int t = 0; t < 200; ++t) {
        const auto step = held.update(pf, desired, zero, measured, dt);
        held.hold_integral_along(pf, 0.3 * r, step.pose_error, dt);
        free.update(pf, desired, zero, measured, dt);
      }
      const Tw hi = held.integral(), fi = free.integral();
      const std::string at = "gains " + std::to_string(gains.first) + "/" +
                             std::to_string(gains.second) + " case " + std::to_string(c);
      EXPECT_NEAR(r.dot(k.cwiseProduct(hi)), along, 1e-12 * (1 + k.maxCoeff())) << at;
      EXPECT_GT(r.dot(k.cwiseProduct(fi)), along + 150 * dt * r.dot(k.cwiseProduct(e))) << at;
      EXPECT_LE((Tw(hi - d.dot(hi) * d) - Tw(fi - d.dot(fi) * d)).norm(), 1e-12) << at;
      EXPECT_LE(hi.norm(), fi.norm()) << at;
      // One tick lifts the part along d from -g/2 to +g/2: the give-back stops at zero.
      // Two ticks below (-2g, lifted to -g): left alone.
      const Pose<double, 3> away_half = desired_at(Tw(-0.5 * e)), away = desired_at(Tw(-e));
      Loop lifted, below, below_free;
      lifted.update(pf, away_half, zero, measured, dt);
      const auto lift = lifted.update(pf, desired, zero, measured, dt);
      lifted.hold_integral_along(pf, 0.3 * r, lift.pose_error, dt);
      EXPECT_NEAR(d.dot(lifted.integral()), 0.0, 1e-15) << at;
      for (Loop* l : {&below, &below_free}) {
        l->update(pf, away, zero, measured, dt);
        l->update(pf, away, zero, measured, dt);
      }
      const auto up = below.update(pf, desired, zero, measured, dt);
      below_free.update(pf, desired, zero, measured, dt);
      below.hold_integral_along(pf, 0.3 * r, up.pose_error, dt);
      EXPECT_LT(d.dot(below.integral()), -0.5 * dt * d.dot(e)) << at;
      EXPECT_TRUE(below.integral() == below_free.integral()) << at;
      // Away from the cut, nothing removed, or a removed twist that is not finite.
      for (const Tw& removed :
           {Tw(-r), Tw(Tw::Zero()), Tw(Tw::Constant(std::numeric_limits<double>::quiet_NaN())),
            Tw(Tw::Constant(std::numeric_limits<double>::infinity()))}) {
        Loop a = held, b = held;
        const auto step = a.update(pf, desired, zero, measured, dt);
        b.update(pf, desired, zero, measured, dt);
        a.hold_integral_along(pf, removed, step.pose_error, dt);
        EXPECT_TRUE(a.integral() == b.integral()) << at;
      }
    }
  }
}

// The astray report (PoseFeedback::astray_distance, astray_angle, astray_time;
// pose_feedback.hpp): over random errors and bounds, `astray` is raised exactly on the ticks
// on which the position error's norm has been at least astray_distance, or the orientation
// error's at least astray_angle, on every tick of the last astray_time (the ticks' dt summed as
// the loop sums them); a tick back inside both bounds clears it and starts the count again;
// +infinity never raises it; reset() clears the count.
TEST(PoseLoop, AstrayOnlyAfterTheErrorStaysBeyondItsBoundsForTheTime) {
  using Loop = inhand::PoseLoop<double, 3>;
  using Tw = Loop::TwistT;
  const double dt = 1e-3;
  Pose<double, 3> desired;
  desired.position = V3(-0.01, 0.02, 0.1);
  auto measured_at = [&](const Tw& e) { return measured_with_error(desired, e); };
  auto rng = inhand_test::make_rng(2311);
  int raised = 0, cleared = 0;
  for (int c = 0; c < scaled(40); ++c) {
    const std::string at = "case " + std::to_string(c);
    inhand::PoseFeedback<double> pf;
    pf.astray_distance = inhand_test::uniform<double>(rng, 1e-3, 5e-3);
    pf.astray_angle = inhand_test::uniform<double>(rng, 0.02, 0.2);
    pf.astray_time = c % 5 == 0 ? 0.0 : inhand_test::uniform<double>(rng, 2e-3, 2e-2);
    inhand::PoseFeedback<double> never = pf;
    never.astray_distance = never.astray_angle = std::numeric_limits<double>::infinity();
    Loop loop, off;
    double held = 0.0;  // the sum of dt over the ticks beyond a bound, as the loop sums it
    bool before = false;
    int phase = 0, left = 0;
    for (int t = 0; t < 300; ++t) {
      // Runs of 1-30 ticks: inside both bounds, beyond in position, in orientation, or both.
      if (left-- == 0) {
        phase = static_cast<int>(inhand_test::uniform<double>(rng, 0.0, 3.999));
        left = static_cast<int>(inhand_test::uniform<double>(rng, 1.0, 30.999));
      }
      const bool fp = phase == 1 || phase == 3, fr = phase == 2 || phase == 3;
      const double sp = fp ? inhand_test::uniform<double>(rng, 1.001, 3.0)
                           : inhand_test::uniform<double>(rng, 0.0, 0.999);
      const double sr = fr ? inhand_test::uniform<double>(rng, 1.001, 3.0)
                           : inhand_test::uniform<double>(rng, 0.0, 0.999);
      Tw e;
      e << sp * pf.astray_distance * inhand_test::random_unit_vector<double, 3>(rng),
          sr * pf.astray_angle * inhand_test::random_unit_vector<double, 3>(rng);
      const inhand::PoseLoopStep<double, 3> step =
          loop.update(pf, desired, Tw::Zero(), measured_at(e), dt);
      held = fp || fr ? held + dt : 0.0;
      const bool expect = (fp || fr) && held >= pf.astray_time;
      ASSERT_EQ(step.astray, expect) << at << ", tick " << t << ", beyond for " << held << " s";
      EXPECT_FALSE(off.update(never, desired, Tw::Zero(), measured_at(e), dt).astray) << at;
      raised += step.astray ? 1 : 0;
      cleared += before && !step.astray ? 1 : 0;
      before = step.astray;
    }
    // reset() starts the count again: one tick beyond raises it only with astray_time 0.
    loop.reset();
    Tw far;
    far << 2.0 * pf.astray_distance * V3::UnitX(), V3::Zero();
    EXPECT_EQ(loop.update(pf, desired, Tw::Zero(), measured_at(far), dt).astray,
              pf.astray_time <= dt)
        << at;
  }
  EXPECT_GT(raised, 0);   // the sweep raised it
  EXPECT_GT(cleared, 0);  // and cleared it
}

}  // namespace
