// A finger's read-only kinematic description: its base pose, revolute joints and
// spherical fingertip (docs/method.md section 4). Forward kinematics and the contact
// Jacobian are in finger_chain.hpp.
//
// Model: the finger base is a Pose in the world (hand) frame. Joint i sits at the
// fixed transform `parent_to_joint` from the previous joint's (rotated) frame, or from
// the base for joint 0, and rotates about `axis` (a unit vector in its own frame) by
// the joint angle q_i (radians, right-hand rule). After the last joint,
// `joint_to_tip` places the fingertip frame, whose origin is the centre of the
// fingertip sphere of radius `fingertip_radius` (metres).
// Planar chains (Dim = 2) live in the world x-y plane: every axis must be +z or -z.
//
// Jacobian: the m x n matrix (m = Dim, n = DOF) of the world velocity of a point
// RIGIDLY ATTACHED to the distal link, currently at world position p (the measured
// contact point, which moves over the fingertip as it rolls), column i = a_i x (p - o_i).
// DOF modes: FingerChain<S, Dim, 4> has exactly 4 joints (all fixed-size);
// FingerChain<S, Dim, Dynamic, 5> has a run-time joint count up to 5, still with
// fixed-capacity storage (mixed-DOF hands without allocation); FingerChain<S, Dim,
// Dynamic> is fully run-time sized and allocates only when built or resized.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/math/status.hpp"

namespace inhand {

/// A joint that is not actuated but follows another joint of the same finger (a URDF
/// mimic joint, a tendon or a linkage): q_follower = ratio * q_leader + offset [rad].
/// leader < 0: the joint is actuated (the default).
template <typename Scalar>
struct JointCoupling {
  int leader = -1;            ///< index of the leading joint in the same finger, or -1
  Scalar ratio = Scalar(1);   ///< dq_follower / dq_leader (dimensionless, != 0)
  Scalar offset = Scalar(0);  ///< rad
  bool coupled() const noexcept { return leader >= 0; }
};

/// One revolute joint of a finger.
template <typename Scalar, int Dim>
struct JointDescription {
  /// Fixed transform from the previous frame to this joint's frame at q = 0.
  Pose<Scalar, Dim> parent_to_joint{};
  /// Unit rotation axis in this joint's frame (planar: (0,0,+-1)).
  Vector<Scalar, 3> axis = Vector<Scalar, 3>::UnitZ();
  /// Joint position limits [rad], lower <= upper.
  Scalar lower = Scalar(-3.14159265358979);
  Scalar upper = Scalar(3.14159265358979);
  /// Joint velocity limit [rad/s], > 0.
  Scalar max_velocity = Scalar(2);
  /// Whether this joint follows another (coupling.leader >= 0) or is actuated.
  JointCoupling<Scalar> coupling{};
};

namespace detail {
/// Joint storage: a std::vector when unbounded (MaxDof == Dynamic), otherwise a
/// fixed-capacity array holding a run-time count (equal to Dof for an exact DOF).
template <typename T, int Dof, int MaxDof>
class JointList {
 public:
  static constexpr bool kHeap = (MaxDof == Dynamic);
  static constexpr int kCapacity = kHeap ? 1 : MaxDof;
  using Storage =
      std::conditional_t<kHeap, std::vector<T>, std::array<T, static_cast<std::size_t>(kCapacity)>>;

  static_assert(kCapacity <= 0xffff, "JointList: at most 65535 joints in fixed storage");

  JointList() : size_(static_cast<std::uint16_t>(Dof == Dynamic ? 0 : Dof)) {}
  int size() const noexcept { return kHeap ? static_cast<int>(storage_.size()) : int{size_}; }
  /// Sets the joint count (run-time DOF only). Returns false if not allowed.
  bool resize(int n) {
    if (Dof != Dynamic) return n == Dof;
    if (n < 0 || (!kHeap && n > kCapacity)) return false;
    if constexpr (kHeap) storage_.resize(static_cast<std::size_t>(n));
    size_ = static_cast<std::uint16_t>(n);
    return true;
  }
  T& operator[](int i) noexcept { return storage_[static_cast<std::size_t>(i)]; }
  const T& operator[](int i) const noexcept { return storage_[static_cast<std::size_t>(i)]; }

 private:
  Storage storage_{};
  std::uint16_t size_;  ///< unsigned: the count is visibly non-negative to the optimiser
};
}  // namespace detail

/// Read-only description of one finger. Dof: exact joint count or inhand::Dynamic;
/// MaxDof: capacity for a run-time count (inhand::Dynamic: unbounded, heap storage).
template <typename Scalar_, int Dim_, int Dof_, int MaxDof_ = Dof_>
struct FingerChain {
  using Scalar = Scalar_;
  static constexpr int Dim = Dim_;
  static constexpr int Dof = Dof_;
  static constexpr int MaxDof = MaxDof_;
  static_assert(Dof == Dynamic || Dof >= 1, "a finger has at least one joint");
  static_assert(Dof == Dynamic || MaxDof == Dof, "MaxDof differs from Dof only for Dynamic Dof");
  /// Eigen compile-time sizes of per-joint vectors and of Jacobian columns.
  static constexpr int Cols = Dof;  // Dynamic == Eigen::Dynamic
  static constexpr int MaxCols = MaxDof;
  using Joint = JointDescription<Scalar, Dim>;
  using JointVector = Eigen::Matrix<Scalar, Cols, 1, Eigen::ColMajor, MaxCols, 1>;
  using Jacobian = Eigen::Matrix<Scalar, Dim, Cols, Eigen::ColMajor, Dim, MaxCols>;

  Pose<Scalar, Dim> base{};
  /// The joints, base to tip. For a run-time DOF set the count with joints.resize(n).
  detail::JointList<Joint, Dof, MaxDof> joints{};
  Pose<Scalar, Dim> joint_to_tip{};
  Scalar fingertip_radius = Scalar(0.01);

  int dof() const noexcept { return static_cast<int>(joints.size()); }
  /// Number of actuated joints (those that follow no other joint).
  int actuated_dof() const noexcept {
    int n = 0;
    for (int i = 0; i < dof(); ++i) n += joints[i].coupling.coupled() ? 0 : 1;
    return n;
  }

  JointVector lower_limits() const {
    JointVector v(dof());
    for (int i = 0; i < dof(); ++i) v(i) = joints[i].lower;
    return v;
  }
  JointVector upper_limits() const {
    JointVector v(dof());
    for (int i = 0; i < dof(); ++i) v(i) = joints[i].upper;
    return v;
  }
  JointVector velocity_limits() const {
    JointVector v(dof());
    for (int i = 0; i < dof(); ++i) v(i) = joints[i].max_velocity;
    return v;
  }

  /// Checks finiteness, proper rotations in every frame (base, each joint's
  /// parent_to_joint, joint_to_tip: orthonormal to rotation_tolerance() and det +1),
  /// unit axes (planar: +-z), limits order and positive speeds. Field names are relative
  /// to the chain ("joints.parent_to_joint.rotation", index = the joint); with
  /// `in_hand` they are relative to the controller Config
  /// ("fingers.chain.joints.parent_to_joint.rotation", the caller sets the finger).
  Validation validate(bool in_hand = false) const noexcept {
    auto name = [in_hand](const char* own, const char* hand) { return in_hand ? hand : own; };
    const Scalar rtol = rotation_tolerance();
    if (dof() < 1)
      return Validation::invalid(name("joints", "fingers.chain.joints"),
                                 "a finger needs at least one joint");
    if (!base.is_finite())
      return Validation::invalid(name("base", "fingers.chain.base"), "must be finite");
    if (!base.has_rotation(rtol))
      return Validation::invalid(name("base.rotation", "fingers.chain.base.rotation"),
                                 "must be a rotation (orthonormal, det +1)");
    if (!joint_to_tip.is_finite())
      return Validation::invalid(name("joint_to_tip", "fingers.chain.joint_to_tip"),
                                 "must be finite");
    if (!joint_to_tip.has_rotation(rtol))
      return Validation::invalid(
          name("joint_to_tip.rotation", "fingers.chain.joint_to_tip.rotation"),
          "must be a rotation (orthonormal, det +1)");
    if (!(fingertip_radius >= Scalar(0)) || !is_finite(fingertip_radius))
      return Validation::invalid(name("fingertip_radius", "fingers.chain.fingertip_radius"),
                                 "must be finite and >= 0");
    const Scalar tol = std::sqrt(Eigen::NumTraits<Scalar>::epsilon()) * Scalar(10);
    for (int i = 0; i < dof(); ++i) {
      const Joint& j = joints[i];
      if (!j.parent_to_joint.is_finite())
        return Validation::invalid(
            name("joints.parent_to_joint", "fingers.chain.joints.parent_to_joint"),
            "must be finite", i);
      if (!j.parent_to_joint.has_rotation(rtol))
        return Validation::invalid(name("joints.parent_to_joint.rotation",
                                        "fingers.chain.joints.parent_to_joint.rotation"),
                                   "must be a rotation (orthonormal, det +1)", i);
      if (!all_finite(j.axis) || std::abs(j.axis.norm() - Scalar(1)) > tol)
        return Validation::invalid(name("joints.axis", "fingers.chain.joints.axis"),
                                   "must be a finite unit vector", i);
      if (Dim == 2 && (std::abs(j.axis.x()) > tol || std::abs(j.axis.y()) > tol))
        return Validation::invalid(name("joints.axis", "fingers.chain.joints.axis"),
                                   "planar joints rotate about +z or -z", i);
      if (!is_finite(j.lower) || !is_finite(j.upper) || !(j.lower <= j.upper))
        return Validation::invalid(name("joints.lower/upper", "fingers.chain.joints.lower/upper"),
                                   "must be finite with lower <= upper", i);
      if (!is_finite(j.max_velocity) || !(j.max_velocity > Scalar(0)))
        return Validation::invalid(name("joints.max_velocity", "fingers.chain.joints.max_velocity"),
                                   "must be finite and > 0", i);
      if (j.coupling.coupled()) {
        const int l = j.coupling.leader;
        if (l >= dof() || l == i || joints[l].coupling.coupled())
          return Validation::invalid(
              name("joints.coupling.leader", "fingers.chain.joints.coupling.leader"),
              "must name another, actuated joint of the same finger", i);
        if (!is_finite(j.coupling.ratio) || j.coupling.ratio == Scalar(0))
          return Validation::invalid(
              name("joints.coupling.ratio", "fingers.chain.joints.coupling.ratio"),
              "must be finite and non-zero", i);
        if (!is_finite(j.coupling.offset))
          return Validation::invalid(
              name("joints.coupling.offset", "fingers.chain.joints.coupling.offset"),
              "must be finite", i);
      }
    }
    return Validation::valid();
  }

  /// Tolerance of the rotation check, dimensionless: max |R^T R - I| <= 1e-6 (double),
  /// or 100 machine epsilons for a coarser Scalar (float: 1.2e-5).
  static Scalar rotation_tolerance() noexcept {
    return std::max(Scalar(1e-6), Scalar(100) * Eigen::NumTraits<Scalar>::epsilon());
  }
};

}  // namespace inhand
