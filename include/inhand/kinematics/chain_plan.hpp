// What forward kinematics can learn about a finger's chain once, before it sees a joint
// angle (docs/method.md section 4): which fixed frames turn (a parent_to_joint or
// joint_to_tip rotation other than exactly the identity) and which joints turn about a
// coordinate axis of their own frame (an axis of exactly +-e_k). Real fingers mostly have
// both: frames that only translate, axes along x, y or z. forward_kinematics(chain, plan,
// q, ws) reads these facts from the plan instead of testing the chain's 3 x 3 rotations
// and axes on every call (finger_chain.hpp); given the plan of the same chain its result
// is bitwise that of forward_kinematics(chain, q, ws), which makes the tests itself.
//
// A plan describes the chain it was built from: rebuild it when that chain's frames or
// axes change; describes(chain) tells whether it still does. A default-constructed plan
// assumes nothing (every frame turns, every axis is general), so it is right for any chain,
// with the general formulas (Rodrigues' rotation, a full 3 x 3 product; the same result to
// rounding). Building a plan allocates only for a chain with unbounded DOF (MaxDof ==
// Dynamic); reading it is noexcept and allocation-free.
#pragma once

#include "inhand/kinematics/chain_model.hpp"

namespace inhand {

namespace detail {
/// k when `axis` is exactly +e_k or -e_k (sign set to +1 or -1), otherwise -1.
template <typename Scalar>
inline int coordinate_axis(const Vector<Scalar, 3>& axis, Scalar& sign) noexcept {
  for (int k = 0; k < 3; ++k) {
    const Scalar a = axis(k);
    if ((a == Scalar(1) || a == Scalar(-1)) && axis((k + 1) % 3) == Scalar(0) &&
        axis((k + 2) % 3) == Scalar(0)) {
      sign = a;
      return k;
    }
  }
  return -1;
}

/// Exactly the identity (the common case of a joint frame not turned at q = 0).
template <typename Scalar, int Dim>
inline bool is_identity(const Rotation<Scalar, Dim>& R) noexcept {
  return R == Rotation<Scalar, Dim>::Identity();
}

/// The facts a ChainPlan holds, found by testing the chain on every call (forward
/// kinematics without a plan).
template <typename Chain>
class ChainTests {
 public:
  using Scalar = typename Chain::Scalar;
  explicit ChainTests(const Chain& chain) noexcept : chain_(chain) {}
  bool frame_turns(int i) const noexcept {
    return !is_identity(chain_.joints[i].parent_to_joint.rotation);
  }
  bool tip_turns() const noexcept { return !is_identity(chain_.joint_to_tip.rotation); }
  int coordinate_axis(int i, Scalar& sign) const noexcept {
    return detail::coordinate_axis(chain_.joints[i].axis, sign);
  }

 private:
  const Chain& chain_;
};
}  // namespace detail

/// The file comment. Indices are the chain's joint indices; a joint beyond the plan's own
/// count (a default plan of a run-time DOF) reads as turned and general.
template <typename Chain>
class ChainPlan {
 public:
  using Scalar = typename Chain::Scalar;

  ChainPlan() = default;
  explicit ChainPlan(const Chain& chain) {
    joints_.resize(chain.dof());
    const detail::ChainTests<Chain> tests(chain);
    for (int i = 0; i < chain.dof(); ++i) {
      Joint& j = joints_[i];
      j.frame_turns = tests.frame_turns(i);
      j.axis = tests.coordinate_axis(i, j.sign);
    }
    tip_turns_ = tests.tip_turns();
  }

  /// Number of joints described (the chain's DOF; a default plan: Dof, or 0 if run-time).
  int dof() const noexcept { return joints_.size(); }
  /// Whether joint i's parent_to_joint rotation is other than exactly the identity.
  bool frame_turns(int i) const noexcept { return i < dof() ? joints_[i].frame_turns : true; }
  /// Whether joint_to_tip's rotation is other than exactly the identity.
  bool tip_turns() const noexcept { return tip_turns_; }
  /// k when joint i turns about exactly +-e_k of its frame (sign set to +-1), else -1.
  int coordinate_axis(int i, Scalar& sign) const noexcept {
    if (i >= dof()) return -1;
    sign = joints_[i].sign;
    return joints_[i].axis;
  }
  /// Whether the plan still describes `chain` (the same DOF, frames and axes classified
  /// alike). noexcept, no allocation.
  bool describes(const Chain& chain) const noexcept {
    if (chain.dof() != dof()) return false;
    const detail::ChainTests<Chain> tests(chain);
    for (int i = 0; i < dof(); ++i) {
      Scalar sign = Scalar(1);
      const int k = tests.coordinate_axis(i, sign);
      if (tests.frame_turns(i) != joints_[i].frame_turns || k != joints_[i].axis ||
          (k >= 0 && sign != joints_[i].sign))
        return false;
    }
    return tests.tip_turns() == tip_turns_;
  }

 private:
  struct Joint {
    bool frame_turns = true;
    int axis = -1;
    Scalar sign = Scalar(1);
  };
  detail::JointList<Joint, Chain::Dof, Chain::MaxDof> joints_{};
  bool tip_turns_ = true;
};

}  // namespace inhand
