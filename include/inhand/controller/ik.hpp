// Inverse kinematics of one finger's contact point (eq. 3: theta_dot = J_F^-1 x_dot).
//
// J_F is the m x n Jacobian of the CONTACT POINT (kinematics/finger_chain.hpp), m = Dim.
//   m = n: exact inverse; n > m: minimum-norm pseudo-inverse; n < m: least squares.
// Near a singularity (sigma_min < DampingSchedule::singular_threshold) the damped
// least-squares solution of math/damped_least_squares.hpp is used and the status says
// `damped`; |theta_dot| <= gain_bound() * |x_dot| always holds.
// Redundant fingers (n > m) may add a joint-velocity preference z projected onto the
// null space: theta_dot += (I - J^+ J) z.
// Joint-velocity limits: if any |theta_dot_i| exceeds its limit, the WHOLE vector is
// scaled by the largest factor s in (0, 1] that respects every limit, so the direction
// of the Cartesian motion is kept; the status says `limited` and reports s.
// Joint position limits (the overload taking a box): lo <= theta_dot <= hi [rad/s] with
// lo <= 0 <= hi, the velocities that keep each joint inside its limits over the tick
// (joint_position_box()). If the solution above leaves the box, the joints that would
// cross are held at their bound and the task is re-solved over the others: the result
// minimises |J theta_dot - x_dot|^2 + lambda^2 |theta_dot|^2 over the box
// (math/box_least_squares.hpp), so the contact velocity is still met whenever the free
// joints can meet it; the null-space term is then dropped. The status says
// `position_limited`; the report names the held joints (bit i = joint i) and the task
// error left. Whenever the solution is inside the box it is returned unchanged. The
// velocity scaling below follows and keeps the box (it only shrinks towards 0).
// Normal priority (the overload also taking the contact normal n): the free joints may not
// meet x_dot in every direction, and plain least squares spreads the miss over the normal
// too (a finger that cannot slide presses harder). It then minimises |W (J theta_dot -
// x_dot)|^2 + lambda^2 |theta_dot|^2, W = I + (w - 1) n n^T, w = limited_normal_weight: the
// miss lands in the tangent plane. W acts only when joints are held.
// Invalid input (non-finite J, x_dot, limits, box or z, or finite values so large that
// the solution overflows, e.g. |J|^2 > the largest Scalar): theta_dot = 0, status
// invalid_input. Units: x_dot in m/s, theta_dot in rad/s. noexcept; a fixed or bounded DOF
// never allocates, and a bounded one runs the fixed-DOF code of its joint count.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

#include "inhand/controller/ik_params.hpp"
#include "inhand/controller/ik_report.hpp"
#include "inhand/math/box_least_squares.hpp"
#include "inhand/math/damped_least_squares.hpp"
#include "inhand/math/flags.hpp"

namespace inhand {

/// Contact-point IK for a Dim x Dof Jacobian. Dof and MaxDof follow FingerChain:
/// exact, run-time bounded (Dynamic, MaxDof), or run-time unbounded (Dynamic, Dynamic).
template <typename Scalar, int Dim, int Dof, int MaxDof = Dof>
class ContactIk {
  static constexpr int N = Dof;
  static constexpr int MaxN = MaxDof;

 public:
  using Jacobian = Eigen::Matrix<Scalar, Dim, N, Eigen::ColMajor, Dim, MaxN>;
  using CartesianVector = Eigen::Matrix<Scalar, Dim, 1>;
  using JointVector = Eigen::Matrix<Scalar, N, 1, Eigen::ColMajor, MaxN, 1>;
  using PseudoInverse = Eigen::Matrix<Scalar, N, Dim, Eigen::ColMajor, MaxN, Dim>;

  // The default argument is spelled IkParams<Scalar>() rather than {}: GCC 12 at -O3
  // reports the {}-initialised temporary as "used uninitialized" (a false positive)
  // when a ContactIk is value-initialised inside an aggregate such as std::array.
  explicit ContactIk(int dof = (N == Eigen::Dynamic ? 0 : N),
                     const IkParams<Scalar>& params = IkParams<Scalar>())
      : params_(params), dls_(dof), box_(dof) {
    ns_.setZero(dof);
    pinv_.setZero(dof, Dim);
    weighted_.setZero(Dim, dof);
  }
  /// Re-sizes in place for a finger with `dof` joints (run-time DOF only).
  void set_dof(int dof) {
    dls_.set_cols(dof);
    box_.set_cols(dof);
    ns_.setZero(dof);
    pinv_.setZero(dof, Dim);
    weighted_.setZero(Dim, dof);
  }

  void set_params(const IkParams<Scalar>& p) noexcept { params_ = p; }
  const IkParams<Scalar>& params() const noexcept { return params_; }
  int dof() const noexcept { return dls_.cols(); }

  /// theta_dot for contact velocity x_dot; `max_velocity` holds the per-joint limits
  /// (rad/s, > 0; +inf for none).
  IkReport<Scalar> solve(const Jacobian& J, const CartesianVector& x_dot,
                         const JointVector& max_velocity, JointVector& theta_dot) noexcept {
    return solve_impl(J, x_dot, max_velocity, nullptr, theta_dot, nullptr, nullptr);
  }
  /// As solve(), adding the null-space projection of `null_space_velocity` (n > m only;
  /// for n <= m the null space is empty and the term is ignored).
  IkReport<Scalar> solve(const Jacobian& J, const CartesianVector& x_dot,
                         const JointVector& max_velocity, const JointVector& null_space_velocity,
                         JointVector& theta_dot) noexcept {
    return solve_impl(J, x_dot, max_velocity, &null_space_velocity, theta_dot, nullptr, nullptr);
  }
  /// As solve(), keeping theta_dot inside the box [lo, hi] (rad/s, lo <= 0 <= hi; see
  /// joint_position_box()) as described at the top of this file.
  IkReport<Scalar> solve(const Jacobian& J, const CartesianVector& x_dot,
                         const JointVector& max_velocity, const JointVector& lo,
                         const JointVector& hi, JointVector& theta_dot) noexcept {
    return solve_impl(J, x_dot, max_velocity, nullptr, theta_dot, &lo, &hi);
  }
  /// As the box overload, with `normal` (length > 0; else ignored) weighted by
  /// IkParams::limited_normal_weight in the re-solve over the box (top of this file).
  IkReport<Scalar> solve(const Jacobian& J, const CartesianVector& x_dot,
                         const JointVector& max_velocity, const JointVector& lo,
                         const JointVector& hi, const CartesianVector& normal,
                         JointVector& theta_dot) noexcept {
    return solve_impl(J, x_dot, max_velocity, nullptr, theta_dot, &lo, &hi, &normal);
  }

  /// The (damped, per the schedule) pseudo-inverse J^+ that solve() applies.
  IkReport<Scalar> pseudo_inverse(const Jacobian& J, PseudoInverse& out) noexcept;

  /// Upper bound of |theta_dot| / |x_dot| before velocity limiting (no null-space term).
  Scalar gain_bound() const noexcept { return params_.damping.gain_bound(); }

 private:
  IkReport<Scalar> solve_impl(const Jacobian& J, const CartesianVector& x_dot,
                              const JointVector& max_velocity, const JointVector* z,
                              JointVector& theta_dot, const JointVector* lo, const JointVector* hi,
                              const CartesianVector* normal = nullptr) noexcept;

  struct Given {  ///< the caller's J, box and theta_dot (the box re-solve, the null space)
    const Jacobian& J;
    const JointVector* lo;
    const JointVector* hi;
    JointVector& theta_dot;
  };
  /// The solve of the top of this file over views V of the joint vectors and JV of J:
  /// the caller's own types, or fixed-size maps of them (solve_sized).
  template <typename JV, typename V, typename OutV>
  IkReport<Scalar> solve_views(const JV& J, const CartesianVector& x_dot, const V& max_velocity,
                               const JointVector* z, OutV& theta_dot, const V* lo, const V* hi,
                               const CartesianVector* normal, const Given& given) noexcept;

  /// Bounded run-time DOF (MaxDof fixed, at most kMaxSized): the solve runs on fixed-size
  /// maps of J and the vectors for the joint count K = J.cols(), one instantiation per K,
  /// whose loops unroll as for a fixed Dof (the fixed-Dof solver's operations). Other
  /// sizes, the null-space term and mismatched vector sizes use the views as given.
  static constexpr int kMaxSized = 8;
  static constexpr bool kSized = N == Eigen::Dynamic && MaxN != Eigen::Dynamic && MaxN <= kMaxSized;
  template <int K>
  IkReport<Scalar> solve_sized(const Jacobian& J, const CartesianVector& x_dot,
                               const JointVector& max_velocity, JointVector& theta_dot,
                               const JointVector* lo, const JointVector* hi,
                               const CartesianVector* normal) noexcept {
    if constexpr (K <= MaxN) {
      if (J.cols() != K)
        return solve_sized<K + 1>(J, x_dot, max_velocity, theta_dot, lo, hi, normal);
      using JMap = Eigen::Map<const Eigen::Matrix<Scalar, Dim, K>>;
      using VMap = Eigen::Map<const Eigen::Matrix<Scalar, K, 1>>;
      using OutMap = Eigen::Map<Eigen::Matrix<Scalar, K, 1>>;
      theta_dot.resize(K);
      const JMap Jk(J.data());
      const VMap vk(max_velocity.data());
      const bool boxed = lo != nullptr && hi != nullptr;
      const VMap lok(boxed ? lo->data() : max_velocity.data());
      const VMap hik(boxed ? hi->data() : max_velocity.data());
      OutMap out(theta_dot.data());
      return solve_views(Jk, x_dot, vk, nullptr, out, boxed ? &lok : nullptr,
                         boxed ? &hik : nullptr, normal, Given{J, lo, hi, theta_dot});
    } else {
      return solve_views(J, x_dot, max_velocity, nullptr, theta_dot, lo, hi, normal,
                         Given{J, lo, hi, theta_dot});
    }
  }

  /// Factorises J by the damping schedule and copies the factorisation's figures into
  /// `report`; false, with `report.status` invalid_input, if it is not valid (J not finite).
  template <typename JV>
  bool factorize(const JV& J, IkReport<Scalar>& report) noexcept {
    const auto f = dls_.factorize(J, params_.damping, params_.exact_min_singular_value);
    if (!f.valid) {
      report.status = IkStatus::invalid_input;
      return false;
    }
    report.min_singular_value = f.min_singular_value;
    report.min_singular_value_exact = f.min_singular_value_exact;
    report.damping = f.damping;
    if (f.damped) report.status = report.status | IkStatus::damped;
    return true;
  }

  IkParams<Scalar> params_;
  DampedLeastSquares<Scalar, Dim, N, MaxN> dls_;
  BoxLeastSquares<Scalar, Dim, N, MaxN> box_;
  JointVector ns_;
  PseudoInverse pinv_;
  Jacobian weighted_;  ///< W J of the normal-priority re-solve
};

// The two solvers are defined out of the class (not inline) so that a program compiling
// the same ContactIk type in several files can declare it `extern template` and compile
// it once (the tests do: tests/common/controller_instances.hpp).

template <typename Scalar, int Dim, int Dof, int MaxDof>
IkReport<Scalar> ContactIk<Scalar, Dim, Dof, MaxDof>::pseudo_inverse(const Jacobian& J,
                                                                     PseudoInverse& out) noexcept {
  IkReport<Scalar> report;
  if (!factorize(J, report)) {
    out.setZero();
    return report;
  }
  dls_.pseudo_inverse(J, out);
  if (!all_finite(out)) {  // finite but enormous J: the Gram matrix overflowed
    out.setZero();
    report = IkReport<Scalar>{};
    report.status = IkStatus::invalid_input;
  }
  return report;
}

template <typename Scalar, int Dim, int Dof, int MaxDof>
IkReport<Scalar> ContactIk<Scalar, Dim, Dof, MaxDof>::solve_impl(
    const Jacobian& J, const CartesianVector& x_dot, const JointVector& max_velocity,
    const JointVector* z, JointVector& theta_dot, const JointVector* lo, const JointVector* hi,
    const CartesianVector* normal) noexcept {
  if constexpr (kSized) {
    const Eigen::Index n = J.cols();
    if (z == nullptr && n >= 1 && n == dls_.cols() && max_velocity.size() == n &&
        (lo == nullptr || hi == nullptr || (lo->size() == n && hi->size() == n)))
      return solve_sized<1>(J, x_dot, max_velocity, theta_dot, lo, hi, normal);
  }
  return solve_views(J, x_dot, max_velocity, z, theta_dot, lo, hi, normal,
                     Given{J, lo, hi, theta_dot});
}

template <typename Scalar, int Dim, int Dof, int MaxDof>
template <typename JV, typename V, typename OutV>
IkReport<Scalar> ContactIk<Scalar, Dim, Dof, MaxDof>::solve_views(
    const JV& J, const CartesianVector& x_dot, const V& max_velocity, const JointVector* z,
    OutV& theta_dot, const V* lo, const V* hi, const CartesianVector* normal,
    const Given& given) noexcept {
  IkReport<Scalar> report;
  const bool boxed = lo != nullptr && hi != nullptr;
  // J is checked by the factorisation below (a non-finite J makes it invalid).
  if (!all_finite(x_dot) || (z != nullptr && !all_finite(*z)) ||
      !detail::ik_limits_valid(max_velocity, lo, hi, static_cast<int>(J.cols()))) {
    given.theta_dot.setZero();
    report.status = IkStatus::invalid_input;
    return report;
  }
  if (!factorize(J, report)) {
    given.theta_dot.setZero();
    return report;
  }
  dls_.solve(J, x_dot, theta_dot);
  if constexpr (std::is_same_v<OutV, JointVector>) {  // the views as given
    if (z != nullptr && dls_.cols() > Dim) {
      dls_.pseudo_inverse(given.J, pinv_);
      // theta_dot += (I - J^+ J) z, evaluated as z - J^+ (J z): no n x n temporary.
      ns_.noalias() = pinv_ * (given.J * (*z));
      theta_dot += *z - ns_;
    }
  }
  if (!all_finite(theta_dot)) {  // finite but enormous J, x_dot or z: overflow
    given.theta_dot.setZero();
    report = IkReport<Scalar>{};
    report.status = IkStatus::invalid_input;
    return report;
  }
  if (boxed &&
      !((theta_dot.array() >= lo->array()).all() && (theta_dot.array() <= hi->array()).all())) {
    // The box re-solve (rare: a joint about to cross its limit) on the caller's types.
    const Scalar l2 = report.damping * report.damping;
    const Scalar length = normal != nullptr ? normal->norm() : Scalar(0);
    const Scalar extra = params_.limited_normal_weight - Scalar(1);  // w - 1
    BoxLeastSquaresResult<Scalar> held;
    if (extra > Scalar(0) && length > Scalar(0) && is_finite(length)) {
      // W J and W x_dot with W = I + (w - 1) n n^T, n the unit normal.
      const CartesianVector n = *normal / length;
      weighted_.noalias() = given.J + (extra * n) * (n.transpose() * given.J);
      const CartesianVector b = x_dot + (extra * n.dot(x_dot)) * n;
      held = box_.solve(weighted_, b, l2, *given.lo, *given.hi, given.theta_dot);
    } else {
      held = box_.solve(given.J, x_dot, l2, *given.lo, *given.hi, given.theta_dot);
    }
    report.held_joints = held.held;
    if (held.held != 0) report.status = report.status | IkStatus::position_limited;
  }
  Scalar s = Scalar(1);
  for (int i = 0; i < theta_dot.size(); ++i) {
    const Scalar a = std::abs(theta_dot(i));
    if (a > max_velocity(i)) s = std::min(s, max_velocity(i) / a);
  }
  if (s < Scalar(1)) {
    theta_dot *= s;
    // s = limit / |theta_i| is rounded, so the product can exceed the limit by an
    // ulp; clamp that rounding away so the limits hold exactly.
    for (int i = 0; i < theta_dot.size(); ++i)
      theta_dot(i) = std::min(std::max(theta_dot(i), -max_velocity(i)), max_velocity(i));
    report.status = report.status | IkStatus::limited;
  }
  report.limit_scale = s;
  report.task_error = (columns_times(J, theta_dot) - x_dot).norm();
  return report;
}

}  // namespace inhand
