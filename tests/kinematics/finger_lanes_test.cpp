// ChainLanes (kinematics/finger_lanes.hpp), for every spatial chain type: one to four chains
// of one plan walked side by side give, bitwise (to rounding in a build that fuses
// multiply-adds), what forward_kinematics gives each chain
// (built-in fingers moved, stretched and turned; frames and tips turned or not; coordinate
// axes of random signs); lanes_share_plan() and can_lane() refuse what a lane cannot share.
// HandLanes (controller/hand_kinematics.hpp): which fingers of a configuration are laned.
#include "inhand/kinematics/finger_lanes.hpp"

#include <gtest/gtest.h>

#include <limits>

#include "common/test_support.hpp"
#include "inhand/controller/hand_kinematics.hpp"

namespace finger_lanes_test {

using inhand_test::make_rng;
using inhand_test::same_bits;
using inhand_test::scaled;

template <typename Chain>
class FingerLanesTest : public ::testing::Test {};
using SpatialChains =
    ::testing::Types<inhand_test::Spatial3<float>, inhand_test::Spatial3<double>,
                     inhand_test::Spatial4<double>, inhand_test::Spatial5<float>,
                     inhand_test::Spatial5<double>, inhand_test::SpatialDynamic<double>,
                     inhand_test::SpatialBounded<float>, inhand_test::SpatialBounded<double>>;
TYPED_TEST_SUITE(FingerLanesTest, SpatialChains, inhand_test::ChainNames);
using Scalars = ::testing::Types<float, double>;

/// Whether this build may fuse a multiply and an add into one rounding (x86-64 with FMA,
/// AArch64): the lanes and the chain walk may then round differently.
#if defined(__FMA__) || defined(__aarch64__) || defined(__ARM_FEATURE_FMA)
constexpr bool kMayFuse = true;
#else
constexpr bool kMayFuse = false;
#endif

/// The lanes' workspace against the chain walk's: the same bits, or, where multiply-adds
/// may fuse, within 64 units in the last place of 1 (coordinates of a few decimetres).
template <typename Chain>
bool agree(const inhand::FingerKinematics<Chain>& a, const inhand::FingerKinematics<Chain>& b) {
  if (!kMayFuse) return same_bits(a, b);
  const auto tol = 64 * std::numeric_limits<typename Chain::Scalar>::epsilon();
  return (a.joint_origins - b.joint_origins).cwiseAbs().maxCoeff() <= tol &&
         (a.joint_axes - b.joint_axes).cwiseAbs().maxCoeff() <= tol &&
         (a.fingertip.position - b.fingertip.position).cwiseAbs().maxCoeff() <= tol &&
         (a.fingertip.rotation - b.fingertip.rotation).cwiseAbs().maxCoeff() <= tol;
}

/// A design shared by the chains of one case: which joint frames turn (bit i of `mask`),
/// whether the tip turns (bit 16), and each joint's coordinate axis and sign.
struct Design {
  unsigned mask = 0;
  int axis[8] = {};
  int sign[8] = {};
};

/// One chain of `design`, built from the built-in finger with its own base, offsets and
/// turned frames.
template <typename Chain>
Chain chain_of(const Design& design, int dof, inhand_test::Rng& rng) {
  using S = typename Chain::Scalar;
  Chain c = inhand_test::make_finger<Chain>(dof);
  c.base = inhand_test::random_pose<S, 3>(rng);
  for (int i = 0; i < dof; ++i) {
    auto& j = c.joints[i];
    j.parent_to_joint.position *= inhand_test::uniform<S>(rng, S(0.5), S(1.5));
    j.parent_to_joint.position += S(0.01) * inhand_test::random_unit_vector<S, 3>(rng);
    j.parent_to_joint.rotation = (design.mask >> i) & 1u
                                     ? inhand_test::random_rotation_dim<S, 3>(rng)
                                     : inhand::Rotation<S, 3>::Identity();
    j.axis = inhand::Vector<S, 3>::Zero();
    j.axis(design.axis[i]) = S(design.sign[i]);
  }
  c.joint_to_tip.position *= inhand_test::uniform<S>(rng, S(0.5), S(1.5));
  c.joint_to_tip.rotation = (design.mask >> 16) & 1u ? inhand_test::random_rotation_dim<S, 3>(rng)
                                                     : inhand::Rotation<S, 3>::Identity();
  return c;
}

TYPED_TEST(FingerLanesTest, LanesGiveEachChainsForwardKinematicsBitwise) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  auto rng = make_rng(4242);
  int turned = 0, unturned = 0;
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    for (int c = 0; c < scaled(30); ++c) {
      Design d;
      // Every third case frames and tip unturned (the built-in hands' kind).
      d.mask = c % 3 == 0 ? 0u : static_cast<unsigned>(rng()) & 0x1ffffu;
      for (int i = 0; i < dof; ++i) {
        d.axis[i] = static_cast<int>(rng() % 3u);
        d.sign[i] = rng() % 2u ? 1 : -1;
      }
      const int count = 1 + c % inhand::kFingerLanes;
      Chain chains[inhand::kFingerLanes];
      const Chain* ptr[inhand::kFingerLanes];
      for (int l = 0; l < count; ++l) {
        chains[l] = chain_of<Chain>(d, dof, rng);
        ASSERT_TRUE(chains[l].validate().ok());
        ptr[l] = &chains[l];
      }
      const inhand::ChainPlan<Chain> plan(chains[0]);
      ASSERT_TRUE(inhand::can_lane(plan));
      for (int l = 0; l < count; ++l)
        ASSERT_TRUE(inhand::lanes_share_plan(plan, inhand::ChainPlan<Chain>(chains[l])));
      (d.mask & 0x100ffu) != 0 ? ++turned : ++unturned;
      const inhand::ChainLanes<Chain> lanes(ptr, count, plan);
      ASSERT_EQ(lanes.count(), count);
      ASSERT_EQ(lanes.dof(), dof);
      for (int k = 0; k < scaled(10); ++k) {
        typename Chain::JointVector q[inhand::kFingerLanes];
        inhand::FingerKinematics<Chain> laned[inhand::kFingerLanes], each[inhand::kFingerLanes];
        const S* qp[inhand::kFingerLanes];
        inhand::FingerKinematics<Chain>* wp[inhand::kFingerLanes];
        for (int l = 0; l < count; ++l) {
          q[l] = inhand_test::random_joint_angles(chains[l], rng);
          if (k == 1) q[l] *= S(40);  // beyond a few pi: the reduction's other quadrants
          laned[l] = inhand::FingerKinematics<Chain>(chains[l]);
          each[l] = inhand::FingerKinematics<Chain>(chains[l]);
          qp[l] = q[l].data();
          wp[l] = &laned[l];
        }
        lanes.forward_kinematics(qp, wp);
        for (int l = 0; l < count; ++l) {
          inhand::forward_kinematics(chains[l], plan, q[l], each[l]);
          ASSERT_TRUE(agree(laned[l], each[l]))
              << "dof " << dof << " case " << c << " lane " << l << " of " << count << " mask "
              << d.mask << "\n"
              << laned[l].joint_origins << "\n\n"
              << each[l].joint_origins << "\n\n"
              << laned[l].fingertip.rotation - each[l].fingertip.rotation;
        }
      }
    }
  }
  EXPECT_GT(turned, 0);
  EXPECT_GT(unturned, 0);
}

TYPED_TEST(FingerLanesTest, ChainsOfAnotherDesignDoNotShareLanes) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  auto rng = make_rng(77);
  const int dof = inhand_test::default_dof<Chain>();
  Design d;
  for (int i = 0; i < dof; ++i) {
    d.axis[i] = i % 3;
    d.sign[i] = 1;
  }
  const Chain a = chain_of<Chain>(d, dof, rng);
  const inhand::ChainPlan<Chain> pa(a);
  ASSERT_TRUE(inhand::lanes_share_plan(pa, inhand::ChainPlan<Chain>(chain_of<Chain>(d, dof, rng))));
  auto refused = [&](const Design& e) {
    return !inhand::lanes_share_plan(pa, inhand::ChainPlan<Chain>(chain_of<Chain>(e, dof, rng)));
  };
  Design other_axis = d, other_sign = d, turned_frame = d, turned_tip = d;
  other_axis.axis[dof - 1] = (d.axis[dof - 1] + 1) % 3;
  other_sign.sign[0] = -1;
  turned_frame.mask = 1u << 1;
  turned_tip.mask = 1u << 16;
  EXPECT_TRUE(refused(other_axis));
  EXPECT_TRUE(refused(other_sign));
  EXPECT_TRUE(refused(turned_frame));
  EXPECT_TRUE(refused(turned_tip));
  // A general axis cannot be laned at all.
  Chain general = a;
  general.joints[0].axis = inhand_test::random_unit_vector<S, 3>(rng);
  EXPECT_FALSE(inhand::can_lane(inhand::ChainPlan<Chain>(general)));
  EXPECT_FALSE(inhand::lanes_share_plan(inhand::ChainPlan<Chain>(general),
                                        inhand::ChainPlan<Chain>(general)));
  // Another joint count.
  const std::vector<int> dofs = inhand_test::supported_dofs<Chain>();
  if (dofs.size() > 1) {
    const int other = dofs.front() == dof ? dofs.back() : dofs.front();
    Design e = d;
    for (int i = 0; i < other; ++i) e.axis[i] = i % 3, e.sign[i] = 1;
    EXPECT_FALSE(
        inhand::lanes_share_plan(pa, inhand::ChainPlan<Chain>(chain_of<Chain>(e, other, rng))));
  }
}

/// The configuration of `n` chain fingers; finger i a copy of `design[i]`.
template <typename Types>
typename Types::Config hand_config(const std::vector<typename Types::Chain>& chains) {
  typename Types::Config c;
  if constexpr (Types::kNumFingers == inhand::Dynamic) c.fingers.resize(chains.size());
  for (std::size_t i = 0; i < chains.size(); ++i) c.fingers[i].chain = chains[i];
  return c;
}

template <typename Types>
std::vector<int> laned_fingers(const typename Types::Config& c) {
  inhand::HandLanes<Types> lanes;
  std::vector<inhand::ChainPlan<typename Types::Chain>> plans;
  for (const auto& f : c.fingers) plans.emplace_back(f.chain);
  lanes.build(
      c, [&](int i) -> const auto& { return plans[static_cast<std::size_t>(i)]; });
  std::vector<int> out;
  for (int i = 0; i < static_cast<int>(c.fingers.size()); ++i)
    if (lanes.laned(i)) out.push_back(i);
  out.push_back(-lanes.group_count());  // last: minus the group count
  return out;
}

template <typename Scalar>
class HandLanesGrouping : public ::testing::Test {};
TYPED_TEST_SUITE(HandLanesGrouping, Scalars, inhand_test::ScalarNames);

TYPED_TEST(HandLanesGrouping, GroupsChainFingersOfOneDesignWherePaying) {
  using Types = inhand::ControllerTypes<TypeParam, 3, inhand::Dynamic, inhand::Dynamic, 5>;
  using Chain = typename Types::Chain;
  // Three fingers share four lanes where a lane fits one vector register of the build.
  const bool three = inhand::kMinLaneGroup<TypeParam> == 3;
  ASSERT_TRUE(three || inhand::kMinLaneGroup<TypeParam> == inhand::kFingerLanes);
  auto rng = make_rng(5);
  Design four, five;
  for (int i = 0; i < 5; ++i) four.axis[i] = five.axis[i] = i % 3, four.sign[i] = five.sign[i] = 1;
  five.axis[0] = 2;
  auto f4 = [&] { return chain_of<Chain>(four, 4, rng); };
  auto t5 = [&] { return chain_of<Chain>(five, 5, rng); };
  using V = std::vector<int>;
  // The Shadow-like hand's kind: four fingers of one design and a thumb.
  EXPECT_EQ(laned_fingers<Types>(hand_config<Types>({f4(), f4(), f4(), f4(), t5()})),
            (V{0, 1, 2, 3, -1}));
  // Three of a kind and a thumb; two of a kind are never laned.
  EXPECT_EQ(laned_fingers<Types>(hand_config<Types>({f4(), t5(), f4(), f4()})),
            (three ? V{0, 2, 3, -1} : V{0}));
  EXPECT_EQ(laned_fingers<Types>(hand_config<Types>({f4(), t5(), f4()})), (V{0}));
  // Six of a kind: a group of four; the two left over run alone.
  EXPECT_EQ(laned_fingers<Types>(hand_config<Types>({f4(), f4(), f4(), f4(), f4(), f4()})),
            (V{0, 1, 2, 3, -1}));
  // Seven: four, then three where three pay.
  EXPECT_EQ(laned_fingers<Types>(hand_config<Types>({f4(), f4(), f4(), f4(), f4(), f4(), f4()})),
            (three ? V{0, 1, 2, 3, 4, 5, 6, -2} : V{0, 1, 2, 3, -1}));
  // A finger whose kinematics the user supplies is not evaluated.
  auto c = hand_config<Types>({f4(), f4(), f4(), f4(), f4(), t5()});
  c.fingers[1].kinematics = inhand::KinematicsSource::external;
  EXPECT_EQ(laned_fingers<Types>(c), (V{0, 2, 3, 4, -1}));
}

TEST(HandLanes, RunWritesEveryChainFingersForwardKinematics) {
  using Types = inhand::ControllerTypes<double, 3, 5, inhand::Dynamic, 5>;
  using Chain = Types::Chain;
  auto rng = make_rng(6);
  Design four, five;
  for (int i = 0; i < 5; ++i) four.axis[i] = five.axis[i] = i % 3, four.sign[i] = five.sign[i] = 1;
  five.axis[0] = 2;
  std::vector<Chain> chains = {chain_of<Chain>(four, 4, rng), chain_of<Chain>(four, 4, rng),
                               chain_of<Chain>(five, 5, rng), chain_of<Chain>(four, 4, rng),
                               chain_of<Chain>(four, 4, rng)};
  const Types::Config c = hand_config<Types>(chains);
  std::vector<inhand::ChainPlan<Chain>> plans;
  for (const Chain& ch : chains) plans.emplace_back(ch);
  inhand::HandLanes<Types> lanes;
  lanes.build(
      c, [&](int i) -> const auto& { return plans[static_cast<std::size_t>(i)]; });
  ASSERT_EQ(lanes.group_count(), 1);
  Types::Input in;
  std::vector<inhand::FingerKinematics<Chain>> ws, each;
  for (const Chain& ch : chains) {
    ws.emplace_back(ch);
    each.emplace_back(ch);
  }
  for (int k = 0; k < scaled(20); ++k) {
    for (std::size_t i = 0; i < chains.size(); ++i)
      in.fingers[i].joint_positions = inhand_test::random_joint_angles(chains[i], rng);
    lanes.run(
        c, in, [&](int i) -> const auto& { return plans[static_cast<std::size_t>(i)]; },
        [&](int i) -> auto& { return ws[static_cast<std::size_t>(i)]; });
    for (std::size_t i = 0; i < chains.size(); ++i) {
      inhand::forward_kinematics(chains[i], plans[i], in.fingers[i].joint_positions, each[i]);
      ASSERT_TRUE(agree(ws[i], each[i])) << "finger " << i;
    }
  }
}

}  // namespace finger_lanes_test
