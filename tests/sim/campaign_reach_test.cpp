// The campaign's reach check (examples/campaign/campaign_reach.hpp): its IK puts the
// fingertip centre on every target the joints reach, and where they cannot it reports the
// distance to the nearest point they do reach; over a task it follows the object.
#include "campaign/campaign_reach.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "inhand/sim/presets.hpp"
#include "inhand/sim/presets_allegro.hpp"
#include "inhand/sim/presets_coupled.hpp"
#include "test_util.hpp"

namespace campaign_reach_test {

namespace ip = inhand::plant;
using inhand::examples::campaign::fingertip_reach;
using inhand::examples::campaign::ReachMiss;
using inhand::examples::campaign::task_reach;

/// A follower joint set from its leader, as the plant does.
void apply_couplings(const ip::PlantFinger& f, ip::PlantFinger::JointVector& q) {
  for (int i = 0; i < f.dof(); ++i) {
    const auto& c = f.joints[i].coupling;
    if (c.coupled()) q(i) = c.ratio * q(c.leader) + c.offset;
  }
}

/// A one-joint finger about +z through the origin, its tip at (r, 0, 0) at q = 0 and its
/// joint within +-0.5 rad.
ip::PlantFinger swing_finger(double r) {
  ip::PlantFinger f = plant_test::probe(Eigen::Vector3d(r, 0.0, 0.0), Eigen::Vector3d::UnitZ(),
                                        Eigen::Vector3d(r, 0.0, 0.0));
  f.joints[0].lower = -0.5;
  f.joints[0].upper = 0.5;
  return f;
}

Eigen::Vector3d tip_of(const ip::PlantFinger& f, const ip::PlantFinger::JointVector& q) {
  inhand::FingerKinematics<ip::PlantFinger> ws(f);
  inhand::forward_kinematics(f, q, ws);
  return ws.fingertip.position;
}

// Targets the joints reach (the fingertip at random joint angles at least a quarter of each
// joint's range, or 0.3 rad, inside its limits; couplings kept) are met to 1 um from a start
// up to 0.05 rad away per joint, on every finger of the presets: the campaign's use, where
// each sample of the task's path starts from the last one's solution, a fingertip step of
// 0.1 mm or less. The method is local: from farther away it can end in another local
// minimum (one start 0.2 rad away in 40 000 on the Shadow-like thumb stayed 31 mm off), and
// from a start at a limit where a finger lies straight (a singular configuration) it can stay
// there.
TEST(CampaignReach, MeetsEveryTargetTheJointsReach) {
  std::mt19937_64 rng(20261207);
  std::uniform_real_distribution<double> u(0.0, 1.0), off(-1.0, 1.0);
  const int samples = 40 * plant_test::test_scale();
  for (const ip::HandPreset& hand : {ip::shadow_like_hand(), ip::three_finger_hand(),
                                     ip::shadow_like_coupled_hand(), ip::allegro_like_hand()}) {
    for (std::size_t k = 0; k < hand.fingers.size(); ++k) {
      const ip::PlantFinger& f = hand.fingers[k];
      for (int s = 0; s < samples; ++s) {
        ip::PlantFinger::JointVector q_true(f.dof()), q(f.dof());
        for (int i = 0; i < f.dof(); ++i) {
          const auto& j = f.joints[i];
          const double m = std::min(0.3, (j.upper - j.lower) / 4.0);
          q_true(i) = j.lower + m + (j.upper - j.lower - 2.0 * m) * u(rng);
          q(i) = q_true(i) + 0.05 * off(rng);
        }
        apply_couplings(f, q_true);
        apply_couplings(f, q);
        const Eigen::Vector3d target = tip_of(f, q_true);
        const double miss = fingertip_reach(f, q, target);
        ASSERT_LT(miss, 1e-6) << hand.name << " finger " << k << " sample " << s;
        EXPECT_LT((tip_of(f, q) - target).norm(), 1e-6);
        for (int i = 0; i < f.dof(); ++i) {
          EXPECT_GE(q(i), f.joints[i].lower - 1e-12);
          EXPECT_LE(q(i), f.joints[i].upper + 1e-12);
        }
      }
    }
  }
}

// A one-joint finger swinging its tip on a circle of radius r, its joint within +-0.5 rad:
// a target on the circle at angle a beyond the limit is missed by the chord from the limit's
// point, 2 r sin((a - 0.5) / 2); one inside is met, the joint at its angle.
TEST(CampaignReach, MissIsTheDistanceToTheNearestReachablePoint) {
  const double r = 0.05;
  const ip::PlantFinger f = swing_finger(r);
  for (const double a : {0.6, 0.9, -1.2, 2.0}) {
    ip::PlantFinger::JointVector q = ip::PlantFinger::JointVector::Zero(1);
    const Eigen::Vector3d target(r * std::cos(a), r * std::sin(a), 0.0);
    const double expected = 2.0 * r * std::sin((std::abs(a) - 0.5) / 2.0);
    EXPECT_NEAR(fingertip_reach(f, q, target), expected, 1e-9) << "angle " << a;
    EXPECT_NEAR(q(0), a > 0 ? 0.5 : -0.5, 1e-12);
  }
  ip::PlantFinger::JointVector q = ip::PlantFinger::JointVector::Zero(1);
  EXPECT_LT(fingertip_reach(f, q, Eigen::Vector3d(r * std::cos(0.3), r * std::sin(0.3), 0.0)),
            1e-10);
  EXPECT_NEAR(q(0), 0.3, 1e-9);
}

// Over a task the fingertip is carried with the object: a rotation about the joint's own axis
// through its pivot (the object's origin) within the limit is followed; one that goes 0.2
// rad past it is missed by the chord of 0.2 rad, at the turning point, halfway through.
TEST(CampaignReach, TaskReachCarriesTheFingertipWithTheObject) {
  const double r = 0.05;
  const ip::PlantFinger f = swing_finger(r);
  const std::vector<const ip::PlantFinger*> chains{&f};
  const std::vector<ip::PlantFinger::JointVector> q{ip::PlantFinger::JointVector::Zero(1)};
  const std::vector<Eigen::Vector3d> tips{Eigen::Vector3d(r, 0.0, 0.0)};
  const inhand::Pose<double, 3> start{};
  inhand::Twist<double, 3> d = inhand::Twist<double, 3>::Zero();
  d(5) = 0.4;
  const ReachMiss within = task_reach(
      chains, q, tips, start, {inhand::TrajectorySegment<double, 3>::reciprocate(d, 2.0, 1)});
  EXPECT_EQ(within.finger, 0);
  EXPECT_LT(within.distance, 1e-9);
  d(5) = 0.7;
  const ReachMiss past = task_reach(chains, q, tips, start,
                                    {inhand::TrajectorySegment<double, 3>::reciprocate(d, 2.0, 1)});
  EXPECT_EQ(past.finger, 0);
  EXPECT_NEAR(past.distance, 2.0 * r * std::sin(0.1), 1e-9);
  EXPECT_NEAR(past.at, 1.0, 1e-9);
}

}  // namespace campaign_reach_test
