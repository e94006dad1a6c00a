// Forward kinematics of several fingers side by side (docs/method.md section 4;
// docs/benchmarks.md, "SIMD lanes across fingers").
//
// The fingers of a hand mostly repeat one design: the Shadow-like hand's four 4-DOF
// fingers turn about the same axes of frames that only translate, and differ only in
// where they sit and how far each joint's offset reaches. ChainLanes holds up to
// kFingerLanes = 4 such chains with one coordinate per Eigen array of four values (a
// lane per finger), and forward_kinematics() walks them together: each joint's step (the
// offset, the frame's rotation, the turn about the joint's axis) is applied to all four
// fingers at once, so that one vector instruction does the work of several fingers (two
// doubles per SSE2 or NEON register, four per AVX2 register). Plain Eigen arrays, no
// intrinsics.
//
// The chains of one ChainLanes share one ChainPlan (chain_plan.hpp: the same DOF, the same
// frames turned and the same coordinate axis and sign per joint; lanes_share_plan()); a
// joint about an axis other than +-e_k is not laned (can_lane()). The result is what
// forward_kinematics(chain, plan, q, ws) writes for each chain: the same operations in the
// same order on each lane (finger_chain.hpp's rotate() fixes the order of every product's
// sums), so without contracted multiply-adds (x86-64's baseline) the two agree bitwise; a
// build that fuses multiply-adds may round the two differently.
// Frames, units and signs as in finger_chain.hpp. Building a ChainLanes allocates only for
// an unbounded DOF (MaxDof == Dynamic); forward_kinematics() is noexcept and allocation-free.
#pragma once

#include <cmath>
#include <cstddef>
#include <type_traits>

#include "inhand/kinematics/finger_chain.hpp"

namespace inhand {

/// How many fingers one ChainLanes evaluates side by side.
inline constexpr int kFingerLanes = 4;

/// The most joints a laned chain has: its MaxDof, or 8 for an unbounded DOF.
template <typename Chain>
inline constexpr int kMaxLaneDof = Chain::MaxDof == Dynamic ? 8 : Chain::MaxDof;

/// Whether `plan` (of a spatial chain) can be walked in lanes: 1 to kMaxLaneDof joints,
/// each turning about a coordinate axis of its frame (ChainPlan::coordinate_axis() >= 0).
template <typename Chain>
bool can_lane(const ChainPlan<Chain>& plan) noexcept {
  if constexpr (Chain::Dim != 3) {
    return false;
  } else {
    if (plan.dof() < 1 || plan.dof() > kMaxLaneDof<Chain>) return false;
    for (int i = 0; i < plan.dof(); ++i) {
      typename Chain::Scalar sign;
      if (plan.coordinate_axis(i, sign) < 0) return false;
    }
    return true;
  }
}

/// Whether the chain of plan `b` can share lanes with the chain of plan `a`: the same facts
/// (DOF, frames turned, axes and signs) and can_lane().
template <typename Chain>
bool lanes_share_plan(const ChainPlan<Chain>& a, const ChainPlan<Chain>& b) noexcept {
  if (!can_lane(a) || a.dof() != b.dof() || a.tip_turns() != b.tip_turns()) return false;
  for (int i = 0; i < a.dof(); ++i) {
    typename Chain::Scalar sa = 1, sb = 1;
    if (a.frame_turns(i) != b.frame_turns(i) ||
        a.coordinate_axis(i, sa) != b.coordinate_axis(i, sb) || sa != sb)
      return false;
  }
  return true;
}

/// Up to kFingerLanes spatial chains sharing one plan, their constants one lane per chain
/// (the file comment).
template <typename Chain>
class ChainLanes {
 public:
  using Scalar = typename Chain::Scalar;
  using Lane = Eigen::Array<Scalar, kFingerLanes, 1>;
  static_assert(Chain::Dim == 3, "ChainLanes is for spatial chains");

  ChainLanes() = default;
  /// From `count` (1 to kFingerLanes) chains whose plans lanes_share_plan() with `plan`,
  /// the plan of the first. A lane beyond `count` repeats the first chain. Allocates only
  /// for an unbounded DOF.
  ChainLanes(const Chain* const* chains, int count, const ChainPlan<Chain>& plan)
      : plan_(plan), count_(count) {
    joints_.resize(plan.dof());
    for (int l = 0; l < kFingerLanes; ++l) {
      const Chain& c = *chains[l < count ? l : 0];
      for (int r = 0; r < 3; ++r) {
        base_p_[r](l) = c.base.position(r);
        tip_p_[r](l) = c.joint_to_tip.position(r);
        for (int k = 0; k < 3; ++k) {
          base_r_[r][k](l) = c.base.rotation(r, k);
          tip_r_[r][k](l) = c.joint_to_tip.rotation(r, k);
        }
        for (int i = 0; i < plan.dof(); ++i) {
          joints_[i].offset[r](l) = c.joints[i].parent_to_joint.position(r);
          for (int k = 0; k < 3; ++k)
            joints_[i].frame[r][k](l) = c.joints[i].parent_to_joint.rotation(r, k);
        }
      }
    }
  }

  int count() const noexcept { return count_; }  ///< chains held (lanes in use)
  int dof() const noexcept { return plan_.dof(); }

  /// ws[l] <- forward_kinematics(chain l, plan, q[l]) for l < count(): q[l] points at
  /// chain l's dof() joint angles [rad] (contiguous), ws[l] at its workspace, sized for
  /// the chain (FingerKinematics(chain)). noexcept, no allocation.
  void forward_kinematics(const Scalar* const* q,
                          FingerKinematics<Chain>* const* ws) const noexcept {
    // Every lane's angles first, joint-major, then their sines and cosines at once: the
    // scalar stores of the gather are done before the vector loads read them.
    constexpr std::size_t kAngles = static_cast<std::size_t>(kFingerLanes * kMaxLaneDof<Chain>);
    alignas(64) Scalar q_all[kAngles], sin_all[kAngles], cos_all[kAngles];
    const int n = dof();
    for (int l = 0; l < kFingerLanes; ++l) {
      const Scalar* ql = q[l < count_ ? l : 0];
      for (int i = 0; i < n; ++i) q_all[i * kFingerLanes + l] = ql[i];
    }
    if constexpr (std::is_same<Scalar, double>::value) {
      sin_cos<Scalar>(q_all, sin_all, cos_all, n * kFingerLanes);
    } else {
      for (int a = 0; a < n * kFingerLanes; ++a)
        detail::joint_sin_cos<Scalar>(q_all[a], sin_all[a], cos_all[a]);
    }
    Lane R[3][3], p[3];
    for (int r = 0; r < 3; ++r) {
      p[r] = base_p_[r];
      for (int k = 0; k < 3; ++k) R[r][k] = base_r_[r][k];
    }
    for (int i = 0; i < n; ++i) {
      const Joint& j = joints_[i];
      for (int r = 0; r < 3; ++r)
        p[r] += R[r][0] * j.offset[0] + R[r][1] * j.offset[1] + R[r][2] * j.offset[2];
      if (plan_.frame_turns(i)) turn_by(R, j.frame);
      const Lane s = Eigen::Map<const Lane>(sin_all + i * kFingerLanes);
      const Lane c = Eigen::Map<const Lane>(cos_all + i * kFingerLanes);
      Scalar sign = Scalar(1);
      const int k = plan_.coordinate_axis(i, sign);
      for (int l = 0; l < count_; ++l)
        for (int r = 0; r < 3; ++r) {
          ws[l]->joint_origins(r, i) = p[r](l);
          ws[l]->joint_axes(r, i) = sign * R[r][k](l);
        }
      const int a = (k + 1) % 3, b = (k + 2) % 3;
      const Lane ss = sign * s;
      for (int r = 0; r < 3; ++r) {
        const Lane ca = R[r][a], cb = R[r][b];
        R[r][a] = c * ca + ss * cb;
        R[r][b] = c * cb - ss * ca;
      }
    }
    for (int r = 0; r < 3; ++r) {
      const Lane tip = p[r] + (R[r][0] * tip_p_[0] + R[r][1] * tip_p_[1] + R[r][2] * tip_p_[2]);
      for (int l = 0; l < count_; ++l) ws[l]->fingertip.position(r) = tip(l);
    }
    if (plan_.tip_turns()) turn_by(R, tip_r_);
    for (int l = 0; l < count_; ++l)
      for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k) ws[l]->fingertip.rotation(r, k) = R[r][k](l);
  }

 private:
  struct Joint {
    Lane offset[3];    ///< m, parent_to_joint.position
    Lane frame[3][3];  ///< parent_to_joint.rotation
  };
  /// R <- R F, lane by lane, each entry summed in the order of detail::rotate().
  static void turn_by(Lane (&R)[3][3], const Lane (&F)[3][3]) noexcept {
    Lane out[3][3];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k)
        out[r][k] = R[r][0] * F[0][k] + R[r][1] * F[1][k] + R[r][2] * F[2][k];
    for (int r = 0; r < 3; ++r)
      for (int k = 0; k < 3; ++k) R[r][k] = out[r][k];
  }

  ChainPlan<Chain> plan_{};
  int count_ = 0;
  Lane base_r_[3][3], base_p_[3], tip_r_[3][3], tip_p_[3];
  detail::JointList<Joint, Chain::Dof, Chain::MaxDof> joints_{};
};

}  // namespace inhand
