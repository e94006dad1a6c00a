// ChainPlan (kinematics/chain_plan.hpp), for every chain type: forward kinematics (and the
// simulator's forward_kinematics_sincos) with the plan of a chain equals it without one bitwise, on
// the built-in fingers (frames that only translate, coordinate axes) and on the same fingers made
// general (every frame turned, every axis off the coordinate axes, a mix of both); a default plan
// equals it to rounding; describes() notices each kind of change a plan depends on.
#include "inhand/kinematics/chain_plan.hpp"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>

#include "common/test_support.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace {

using inhand_test::make_rng;
using inhand_test::same_bits;
using inhand_test::scaled;

template <typename Chain>
class ChainPlanTest : public ::testing::Test {};
TYPED_TEST_SUITE(ChainPlanTest, inhand_test::AllFingerChains, inhand_test::ChainNames);

/// The chain with joint i's frame turned when (mask >> i) & 1, its axis general when
/// (mask >> (i + 8)) & 1 (spatial only: planar axes are +-z), and the tip frame turned
/// when (mask >> 16) & 1.
template <typename Chain>
Chain made_general(Chain chain, unsigned mask, inhand_test::Rng& rng) {
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  for (int i = 0; i < chain.dof(); ++i) {
    auto& j = chain.joints[i];
    if ((mask >> i) & 1u)
      j.parent_to_joint.rotation = inhand_test::random_rotation_dim<S, Dim>(rng);
    if (Dim == 3 && ((mask >> (i + 8)) & 1u)) j.axis = inhand_test::random_unit_vector<S, 3>(rng);
  }
  if ((mask >> 16) & 1u)
    chain.joint_to_tip.rotation = inhand_test::random_rotation_dim<S, Dim>(rng);
  return chain;
}

TYPED_TEST(ChainPlanTest, PlannedForwardKinematicsIsBitwiseTheSame) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  const double tol = 64 * std::numeric_limits<S>::epsilon();
  auto rng = make_rng(911);
  int general_joints = 0, turned_frames = 0;
  for (const int dof : inhand_test::supported_dofs<Chain>()) {
    const Chain builtin = inhand_test::make_finger<Chain>(dof);
    for (int c = 0; c < scaled(20); ++c) {
      // Case 0: the built-in finger; then random masks, every third one all general.
      const unsigned mask =
          c == 0 ? 0u : (c % 3 == 0 ? 0x1ffffu : static_cast<unsigned>(rng()) & 0x1ffffu);
      const Chain chain = made_general(builtin, mask, rng);
      ASSERT_TRUE(chain.validate().ok());
      const inhand::ChainPlan<Chain> plan(chain);
      ASSERT_EQ(plan.dof(), dof);
      ASSERT_TRUE(plan.describes(chain));
      for (int i = 0; i < dof; ++i) {
        S sign = S(0);
        general_joints += plan.coordinate_axis(i, sign) < 0 ? 1 : 0;
        turned_frames += plan.frame_turns(i) ? 1 : 0;
      }
      const inhand::ChainPlan<Chain> assumes_nothing{};
      inhand::FingerKinematics<Chain> tested(chain), planned(chain), unplanned(chain);
      for (int k = 0; k < scaled(20); ++k) {
        const typename Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
        inhand::forward_kinematics(chain, q, tested);
        inhand::forward_kinematics(chain, plan, q, planned);
        ASSERT_TRUE(same_bits(tested, planned)) << "dof " << dof << " mask " << mask;
        if constexpr (Chain::Dim == 3) {  // the simulator's form, from sines and cosines
          const typename Chain::JointVector sq = q.array().sin(), cq = q.array().cos();
          inhand::forward_kinematics_sincos(chain, sq, cq, tested);
          inhand::forward_kinematics_sincos(chain, plan, sq, cq, planned);
          ASSERT_TRUE(same_bits(tested, planned)) << "sincos, dof " << dof << " mask " << mask;
        }
        inhand::forward_kinematics(chain, assumes_nothing, q, unplanned);
        ASSERT_LE(double((tested.joint_origins - unplanned.joint_origins).cwiseAbs().maxCoeff()),
                  tol);
        ASSERT_LE(double((tested.joint_axes - unplanned.joint_axes).cwiseAbs().maxCoeff()), tol);
        ASSERT_LE(
            double(
                (tested.fingertip.position - unplanned.fingertip.position).cwiseAbs().maxCoeff()),
            tol);
        ASSERT_LE(
            double(
                (tested.fingertip.rotation - unplanned.fingertip.rotation).cwiseAbs().maxCoeff()),
            tol);
      }
    }
  }
  // Both branches of the walk were taken.
  EXPECT_GT(turned_frames, 0);
  if (Chain::Dim == 3) {
    EXPECT_GT(general_joints, 0);
  }
}

TYPED_TEST(ChainPlanTest, DescribesNoticesEachChangeItDependsOn) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  using Axis = inhand::Vector<S, 3>;
  auto rng = make_rng(912);
  // The built-in finger (some of its frames turn, some of its axes are general) with
  // joint 0 and the tip made plain: a frame that only translates, an axis along +y (+z
  // planar), a tip frame that does not turn.
  Chain chain = inhand_test::make_finger<Chain>();
  chain.joints[0].parent_to_joint.rotation.setIdentity();
  chain.joints[0].axis = Dim == 3 ? Axis::UnitY() : Axis::UnitZ();
  chain.joint_to_tip.rotation.setIdentity();
  ASSERT_TRUE(chain.validate().ok());
  const inhand::ChainPlan<Chain> plan(chain);
  ASSERT_TRUE(plan.describes(chain));
  EXPECT_FALSE(plan.frame_turns(0));
  EXPECT_FALSE(plan.tip_turns());
  S sign = S(0);
  EXPECT_EQ(plan.coordinate_axis(0, sign), Dim == 3 ? 1 : 2);
  EXPECT_EQ(sign, S(1));
  {  // What forward kinematics reads as numbers, not as facts, leaves the plan valid.
    Chain c = chain;
    c.joints[0].parent_to_joint.position(0) += S(0.01);
    c.joints[0].lower -= S(0.1);
    c.fingertip_radius *= S(2);
    c.base = inhand_test::random_pose<S, Dim>(rng);
    EXPECT_TRUE(plan.describes(c));
  }
  {  // A frame that starts to turn, and one that stops.
    Chain c = chain;
    c.joints[0].parent_to_joint.rotation = inhand_test::random_rotation_dim<S, Dim>(rng);
    EXPECT_FALSE(plan.describes(c));
    const inhand::ChainPlan<Chain> turned(c);
    EXPECT_TRUE(turned.frame_turns(0));
    EXPECT_FALSE(turned.describes(chain));
  }
  {  // The tip frame that starts to turn, and stops.
    Chain c = chain;
    c.joint_to_tip.rotation = inhand_test::random_rotation_dim<S, Dim>(rng);
    EXPECT_FALSE(plan.describes(c));
    EXPECT_FALSE(inhand::ChainPlan<Chain>(c).describes(chain));
  }
  if constexpr (Dim == 3) {  // An axis off the coordinate axes, along another one, reversed.
    Chain c = chain;
    c.joints[0].axis = inhand_test::random_unit_vector<S, 3>(rng);
    EXPECT_FALSE(plan.describes(c));
    const inhand::ChainPlan<Chain> general(c);
    EXPECT_EQ(general.coordinate_axis(0, sign), -1);
    EXPECT_FALSE(general.describes(chain));
    c.joints[0].axis = Axis::UnitZ();
    EXPECT_FALSE(plan.describes(c));
    c.joints[0].axis = -Axis::UnitY();
    EXPECT_FALSE(plan.describes(c));
  }
  if constexpr (Chain::Dof == inhand::Dynamic) {  // Another joint count.
    Chain c = chain;
    ASSERT_TRUE(c.joints.resize(chain.dof() - 1));
    EXPECT_FALSE(plan.describes(c));
  }
  // A default plan describes no particular chain but reads as "turned, general".
  const inhand::ChainPlan<Chain> assumes_nothing{};
  EXPECT_TRUE(assumes_nothing.frame_turns(0));
  EXPECT_TRUE(assumes_nothing.tip_turns());
  EXPECT_EQ(assumes_nothing.coordinate_axis(0, sign), -1);
}

}  // namespace
