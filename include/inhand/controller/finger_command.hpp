// Layer 3, per finger: the hybrid servo (eqs. 4-7), the contact IK (eq. 3) with the
// joint limits, and the command continuity bound (docs/method.md sections 4 and 6).
//
//   e        = g1(v_desired) + force part            (m/s, world frame)
//   force    = -u n   with u [m/s] from the force layer (into the object along -n;
//              u > 0 presses harder), or none when the finger does not touch
//   qdot     = J^+ e  (damped near singularities; joints that would cross their position
//              limit less ik.joint_limit_margin within dt held and the task re-solved
//              over the others -- a pressing grasp finger's normal weighted by
//              ik.limited_normal_weight -- then scaled to the joint velocity limits)
//   |qdot - qdot_last|_inf <= max_joint_acceleration * dt  (the change is scaled,
//              its direction kept; then clamped back inside the velocity limits and
//              the position box: a joint the continuity bound would carry past its
//              limit is stopped at it, the limit taking precedence)
// Coupled joints (JointCoupling): the IK works in actuated coordinates. A leader's
// column of J gains ratio x its followers' columns, the followers' columns are zero, a
// leader's velocity and position bounds include its followers' (divided by the ratio),
// and each follower's velocity is ratio x its leader's, so every command keeps the
// coupling. The force part of HybridServo is not used: the force layer's loops replace
// it, and its motion PI carries the velocity part. noexcept, no allocation (fixed or
// bounded DOF).
#pragma once

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/controller/controller_status.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/math/cone_residual.hpp"
#include "inhand/math/whole_copy.hpp"

namespace inhand {

/// What layer 3 of one finger remembers from one tick to the next: the servo's
/// integrators and the last command (the continuity bound's reference). The controller
/// saves it with the rest of its state before every tick; FingerServo below holds the
/// rest (what it derives from the chain, the IK's workspace), which nothing carries over.
template <typename Scalar, int Dim, int Dof, int MaxDof = Dof>
struct FingerServoMemory {
  using JointVector = typename ContactIk<Scalar, Dim, Dof, MaxDof>::JointVector;
  HybridServo<Scalar, Dim> servo{};
  detail::WholeCopy<JointVector> last_command{};  ///< rad/s, the last valid tick's joint velocities

  /// Sizes for `dof` joints (allocates only for run-time DOF without a bound), servo
  /// integrators and last command zero.
  void configure(int dof, const ServoGains<Scalar>& gains) {
    servo.set_gains(gains);
    last_command.setZero(dof);
  }
};

/// Layer 3 of one finger: the joint limits and couplings read from its chain, and the
/// IK with its workspace. command() reads and updates a FingerServoMemory.
template <typename Scalar, int Dim, int Dof, int MaxDof = Dof>
class FingerServo {
 public:
  using JointVector = typename ContactIk<Scalar, Dim, Dof, MaxDof>::JointVector;
  using Jacobian = typename ContactIk<Scalar, Dim, Dof, MaxDof>::Jacobian;
  using Vec = Vector<Scalar, Dim>;
  using Memory = FingerServoMemory<Scalar, Dim, Dof, MaxDof>;

  /// Sizes and configures from the finger's chain (allocates only for run-time DOF
  /// without a bound).
  template <typename Chain>
  void configure(const Chain& chain, const IkParams<Scalar>& ik_params) {
    const int dof = chain.dof();
    ik_.set_dof(dof);
    ik_.set_params(ik_params);
    max_velocity_ = chain.velocity_limits();
    lower_ = chain.lower_limits();
    upper_ = chain.upper_limits();
    leader_.setConstant(dof, -1);
    ratio_.setOnes(dof);
    coupled_ = false;
    for (int i = 0; i < dof; ++i) {
      leader_(i) = chain.joints[i].coupling.leader;
      ratio_(i) = chain.joints[i].coupling.ratio;
      if (leader_(i) >= 0) coupled_ = true;
    }
    limits_ = ik_params.joint_limits;
    margin_ = ik_params.joint_limit_margin;
    ja_.setZero(Dim, dof);
    vmax_.setZero(dof);
    lo_.setZero(dof);
    hi_.setZero(dof);
  }

  /// One tick: contact velocity v [m/s] and force velocity `force` [m/s] (-u n, or zero
  /// when no force is servoed) at the point whose Jacobian is J, joint positions q [rad];
  /// `normal` the measured normal (unused by the motion part). Updates `memory` (servo
  /// integrators, last command); writes the servo command and status, the IK report
  /// and the joint velocities; returns the warnings raised. `normal_priority` (with a
  /// force servoed): when joints are held at their limits, the miss of the re-solve goes to
  /// the tangent plane rather than along `normal` (ContactIk's normal-priority solve).
  template <typename FingerOutput>
  ControllerWarning command(Memory& memory, const Jacobian& J, const JointVector& q, const Vec& v,
                            const Vec& normal, const Vec* force, Scalar max_joint_acceleration,
                            Scalar dt, FingerOutput& fo, bool normal_priority = false) noexcept {
    ControllerWarning w = ControllerWarning::none;
    fo.servo_status = memory.servo.update(v, Scalar(0), Scalar(0), normal, false, dt, fo.servo);
    if (force != nullptr) {
      fo.servo.force = *force;
      fo.servo.total = fo.servo.motion + fo.servo.force;
    }
    if (fo.servo_status != ServoStatus::ok) w |= ControllerWarning::servo_saturated;
    actuated_problem(J, q, dt);
    // Without couplings the actuated problem is the joint one: no copy of J or the limits.
    const Jacobian& ja = coupled_ ? ja_ : J;
    const JointVector& vmax = coupled_ ? vmax_ : max_velocity_;
    if (limits_ && normal_priority && force != nullptr)
      fo.ik = ik_.solve(ja, fo.servo.total, vmax, lo_, hi_, normal, fo.joint_velocities);
    else if (limits_)
      fo.ik = ik_.solve(ja, fo.servo.total, vmax, lo_, hi_, fo.joint_velocities);
    else
      fo.ik = ik_.solve(ja, fo.servo.total, vmax, fo.joint_velocities);
    follow_leaders(fo.joint_velocities);
    if (has(fo.ik.status, IkStatus::damped)) w |= ControllerWarning::ik_damped;
    if (has(fo.ik.status, IkStatus::limited)) w |= ControllerWarning::joint_velocity_limited;
    if (has(fo.ik.status, IkStatus::position_limited))
      w |= ControllerWarning::joint_position_limited;
    const Scalar max_step = max_joint_acceleration * dt;
    if (max_step < std::numeric_limits<Scalar>::infinity()) {
      const Scalar largest = (fo.joint_velocities - memory.last_command).cwiseAbs().maxCoeff();
      if (largest > max_step) {
        fo.joint_velocities = memory.last_command +
                              (max_step / largest) * (fo.joint_velocities - memory.last_command);
        // A convex combination of two commands within the velocity limits: only rounding
        // can leave them; clamp it away (this only shrinks the step). The position box
        // may be left (last tick's command was for last tick's box): stop there.
        fo.joint_velocities = fo.joint_velocities.cwiseMin(vmax).cwiseMax(-vmax);
        if (limits_) {
          for (int i = 0; i < static_cast<int>(lo_.size()); ++i) {
            const Scalar c = std::min(std::max(fo.joint_velocities(i), lo_(i)), hi_(i));
            if (c != fo.joint_velocities(i)) w |= ControllerWarning::joint_position_limited;
            fo.joint_velocities(i) = c;
          }
        }
        follow_leaders(fo.joint_velocities);
        w |= ControllerWarning::rate_limited;
      }
    }
    memory.last_command = fo.joint_velocities;
    return w;
  }

  /// Whether some joint is within `tolerance` [rad] of the bound the IK holds it at (its
  /// position limit less ik.joint_limit_margin), or past it; false when joint limits are
  /// off. Followers count too: their bounds fold into their leaders'. q [rad]. No
  /// kinematics: two comparisons per joint.
  bool at_position_limit(const JointVector& q, Scalar tolerance) const noexcept {
    if (!limits_) return false;
    for (int i = 0; i < static_cast<int>(q.size()); ++i)
      if (q(i) >= upper_(i) - margin_ - tolerance || q(i) <= lower_(i) + margin_ + tolerance)
        return true;
    return false;
  }

  /// The contact directions out of reach this tick (workspace_limits.hpp): for each
  /// actuated joint within `tolerance` [rad] of its held bound whose motion the finger's
  /// other actuated joints cannot make (their columns' span has lost a dimension), calls
  /// visit(b) with the unit vector b (world frame) such that a contact velocity x with
  /// b^T x > 0 needs that joint past its bound. J (Dim x DOF) is the Jacobian of the
  /// contact point, q the joint positions [rad], dt [s] the tick.
  /// With `normal` (unit, world frame) and two or more actuated joints held, the held
  /// joints are also taken together: for s = +1 and -1, when no joint velocity inside the
  /// bounds (the free joints either way, each held joint only away from its bound) moves
  /// the contact along s n, visit(b) with b = r / |r|, r the residual of s n from that
  /// cone (math/cone_residual.hpp): b^T x <= 0 for every reachable x and b . (s n) > 0.
  /// This finds what a redundant finger loses with several joints at their limits, which
  /// the one-joint-at-a-time test above misses.
  template <typename Visit>
  void for_each_unreachable_direction(const Jacobian& J, const JointVector& q, Scalar dt,
                                      Scalar tolerance, Visit&& visit,
                                      const Vec* normal = nullptr) noexcept {
    if (!limits_) return;
    actuated_problem(J, q, dt);
    const Jacobian& ja = coupled_ ? ja_ : J;
    using Gram = Eigen::Matrix<Scalar, Dim, Dim>;
    const Scalar rank_tol =
        std::max(Scalar(1e-6), Scalar(100) * Eigen::NumTraits<Scalar>::epsilon());
    for (int j = 0; j < static_cast<int>(q.size()); ++j) {
      bool up = false, down = false;
      if (!held(j, dt, tolerance, up, down)) continue;
      Gram m = Gram::Zero();  // J_o J_o^T over the other actuated columns
      for (int k = 0; k < static_cast<int>(q.size()); ++k)
        if (k != j) m.noalias() += ja.col(k) * ja.col(k).transpose();
      Eigen::SelfAdjointEigenSolver<Gram> eig;
      eig.computeDirect(m);
      const Scalar scale = std::max(eig.eigenvalues()(Dim - 1), ja.col(j).squaredNorm());
      if (!(eig.eigenvalues()(0) <= rank_tol * scale)) continue;  // the others reach it all
      const Vec a = eig.eigenvectors().col(0);  // a^T J_o = 0, so a^T x = s theta_dot_j
      const Scalar s = a.dot(ja.col(j));
      if (!(std::abs(s) > std::sqrt(rank_tol) * ja.col(j).norm())) continue;
      if (up) visit(Vec(s > Scalar(0) ? a : Vec(-a)));
      if (down) visit(Vec(s > Scalar(0) ? Vec(-a) : a));
    }
    if (normal != nullptr)
      held_together(ja, static_cast<int>(q.size()), dt, tolerance, rank_tol, *normal, visit);
  }

 private:
  /// Whether actuated joint j is held this tick: within `tolerance` [rad] of the bound the
  /// IK holds it at, upward (up) or downward (down); false for a follower (it moves with
  /// its leader). Reads this tick's box (actuated_problem()).
  bool held(int j, Scalar dt, Scalar tolerance, bool& up, bool& down) const noexcept {
    up = hi_(j) * dt <= tolerance;
    down = lo_(j) * dt >= -tolerance;
    return leader_(j) < 0 && (up || down);
  }
  /// The held joints together (for_each_unreachable_direction with a normal): P projects
  /// onto the left null space of the free actuated columns, each held joint gives the ray
  /// P (+-ja_h) of its allowed sign (none when held both ways), and s n is out of reach
  /// when P (s n) is outside their cone.
  template <typename Visit>
  void held_together(const Jacobian& ja, int n, Scalar dt, Scalar tolerance, Scalar rank_tol,
                     const Vec& normal, Visit& visit) const noexcept {
    using Gram = Eigen::Matrix<Scalar, Dim, Dim>;
    int count = 0;
    Scalar scale = Scalar(0);
    Gram m = Gram::Zero();  // over the free actuated columns (followers' are zero)
    for (int k = 0; k < n; ++k) {
      bool up = false, down = false;
      if (held(k, dt, tolerance, up, down)) {
        ++count;
        scale = std::max(scale, ja.col(k).squaredNorm());
      } else {
        m.noalias() += ja.col(k) * ja.col(k).transpose();
      }
    }
    if (count < 2) return;  // one held joint: the test of for_each_unreachable_direction
    Eigen::SelfAdjointEigenSolver<Gram> eig;
    eig.computeDirect(m);
    scale = std::max(scale, eig.eigenvalues()(Dim - 1));
    Gram P = Gram::Zero();
    for (int k = 0; k < Dim; ++k)
      if (eig.eigenvalues()(k) <= rank_tol * scale)
        P.noalias() += eig.eigenvectors().col(k) * eig.eigenvectors().col(k).transpose();
    const auto ray = [&](int j, Vec& g) {
      bool up = false, down = false;
      if (!held(j, dt, tolerance, up, down) || (up && down)) return false;  // or not moving
      g.noalias() = P * ja.col(j);
      if (up) g = -g;
      return true;
    };
    for (const Scalar sign : {Scalar(1), Scalar(-1)}) {
      const Vec y = P * (sign * normal);
      Vec r;
      const Scalar r2 = detail::cone_residual<Scalar, Dim>(y, n, ray, r);
      if (r2 > rank_tol && is_finite(r2)) visit(Vec(r / std::sqrt(r2)));
    }
  }
  /// lo_, hi_ and, for a chain with couplings, ja_ and vmax_: this tick's problem in
  /// actuated coordinates (followers' columns zero and bounds 0, folded into their leaders).
  void actuated_problem(const Jacobian& J, const JointVector& q, Scalar dt) noexcept {
    if (limits_) joint_position_box(q, lower_, upper_, margin_, dt, lo_, hi_);
    if (!coupled_) return;
    ja_ = J;
    vmax_ = max_velocity_;
    for (int i = 0; i < static_cast<int>(leader_.size()); ++i) {
      const int l = leader_(i);
      if (l < 0) continue;
      const Scalar r = ratio_(i);
      ja_.col(l) += r * J.col(i);
      ja_.col(i).setZero();
      vmax_(l) = std::min(vmax_(l), max_velocity_(i) / std::abs(r));
      vmax_(i) = std::numeric_limits<Scalar>::infinity();
      if (limits_) {
        const Scalar a = lo_(i) / r, b = hi_(i) / r;  // r < 0 swaps them
        lo_(l) = std::max(lo_(l), std::min(a, b));
        hi_(l) = std::min(hi_(l), std::max(a, b));
        lo_(i) = hi_(i) = Scalar(0);
      }
    }
  }
  /// Each follower's velocity from its leader's.
  void follow_leaders(JointVector& qd) const noexcept {
    for (int i = 0; i < static_cast<int>(leader_.size()); ++i)
      if (leader_(i) >= 0) qd(i) = ratio_(i) * qd(leader_(i));
  }

  using IndexVector = Eigen::Matrix<int, Dof, 1, Eigen::ColMajor, MaxDof, 1>;
  ContactIk<Scalar, Dim, Dof, MaxDof> ik_{};
  JointVector max_velocity_{};     ///< rad/s, per joint (> 0)
  JointVector lower_{}, upper_{};  ///< rad, position limits
  IndexVector leader_{};           ///< per joint: its leader, or -1 (actuated)
  JointVector ratio_{};            ///< per joint: its coupling ratio
  bool limits_ = true;
  bool coupled_ = false;  ///< some joint follows a leader
  Scalar margin_ = Scalar(0);
  // This tick's actuated problem (written and read within command()).
  Jacobian ja_{};
  JointVector vmax_{}, lo_{}, hi_{};
};

}  // namespace inhand
