// Layer 2, forces: the desired normal force of every finger (docs/method.md section 5).
//
// For local manipulation the contact normals are (near) collinear and the planner
// keeps the resultant normal force zero:  sum_i f_i n_i = 0,
// where n_i is the object's OUTWARD unit normal at finger i's contact and f_i >= 0 the
// magnitude of the normal force finger i presses with (the force on the object is
// -f_i n_i). Fingers have one of two roles:
//   preset    : f_i = nominal_force (the paper presets every finger to 1 N);
//   balancing : f_i chosen so the resultant vanishes (the paper's thumb), by the
//               regularised least squares
//     min_f |sum_b f_b n_b + R|^2 + rho |f - f_nominal|^2,   R = sum_preset f_i n_i,
//   which for a single balancing finger is f = (rho f_nom - R . n) / (1 + rho) ~ -R . n.
// Results outside [min_force, max_force] are limited to that range and the status says
// so (never silently); fingers not touching contribute nothing and receive their
// nominal force (what they will press with once they touch again).
// Optionally the plan is low-passed with time constant `filter_time` (seconds).
// This planner does NOT handle non-collinear (global) grasps, where the grasp-matrix
// equilibrium G f = -F_e with friction cones (eqs. 8-9) is needed; `residual` reports
// how far from zero the resultant remains.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include "inhand/math/flags.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

enum class FingerRole : unsigned char { preset, balancing };

template <typename Scalar>
struct ForcePlannerParams {
  Scalar nominal_force = Scalar(1);      ///< N, > 0
  Scalar min_force = Scalar(0.2);        ///< N, >= 0
  Scalar max_force = Scalar(6);          ///< N, >= min_force
  Scalar regularisation = Scalar(1e-3);  ///< rho, dimensionless, > 0
  Scalar filter_time = Scalar(0.02);     ///< s, >= 0 (0: no filtering)

  Validation validate() const noexcept {
    if (!is_finite(nominal_force) || !(nominal_force > Scalar(0)))
      return Validation::invalid("force_planner.nominal_force", "must be finite and > 0");
    if (!is_finite(min_force) || !(min_force >= Scalar(0)))
      return Validation::invalid("force_planner.min_force", "must be finite and >= 0");
    if (!is_finite(max_force) || !(max_force >= min_force))
      return Validation::invalid("force_planner.max_force", "must be finite and >= min_force");
    if (!(nominal_force >= min_force && nominal_force <= max_force))
      return Validation::invalid("force_planner.nominal_force",
                                 "must lie in [min_force, max_force]");
    if (!is_finite(regularisation) || !(regularisation > Scalar(0)))
      return Validation::invalid("force_planner.regularisation", "must be finite and > 0");
    if (!is_finite(filter_time) || !(filter_time >= Scalar(0)))
      return Validation::invalid("force_planner.filter_time", "must be finite and >= 0");
    return Validation::valid();
  }
};

enum class ForcePlanStatus : unsigned {
  ok = 0,
  limited = 1u << 0,               ///< some balancing force was limited to [min_force, max_force]
  no_balancing_contact = 1u << 1,  ///< no balancing finger touches: resultant not balanced
  invalid_input = 1u << 2,
};
template <>
struct is_flags<ForcePlanStatus> : std::true_type {};

/// Planner for NumFingers fingers (fixed, or inhand::Dynamic sized at construction).
template <typename Scalar, int Dim, int NumFingers>
class ForcePlanner {
 public:
  static constexpr int MaxF = NumFingers;  // Dynamic == Eigen::Dynamic
  using ForceVector = Eigen::Matrix<Scalar, NumFingers, 1>;
  using Normals = Eigen::Matrix<Scalar, Dim, NumFingers>;
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;

  explicit ForcePlanner(int fingers = (NumFingers == Dynamic ? 0 : NumFingers)) { resize(fingers); }

  /// Sets the finger count (allocates only for a run-time NumFingers); all preset.
  void resize(int fingers) {
    roles_.assign(static_cast<std::size_t>(fingers), FingerRole::preset);
    filtered_.setZero(fingers);
    nb_.setZero(Dim, fingers);
    gram_.setZero(fingers, fingers);
    rhs_.setZero(fingers);
    primed_ = false;
  }

  int size() const noexcept { return static_cast<int>(roles_.size()); }
  void set_params(const ForcePlannerParams<Scalar>& p) noexcept { params_ = p; }
  const ForcePlannerParams<Scalar>& params() const noexcept { return params_; }
  void set_role(int finger, FingerRole r) noexcept { roles_[static_cast<std::size_t>(finger)] = r; }
  FingerRole role(int finger) const noexcept { return roles_[static_cast<std::size_t>(finger)]; }
  void reset() noexcept { primed_ = false; }

  /// Plans desired forces. `touching(i)` != 0 when finger i is in contact; `normals`
  /// column i is its measured outward normal (ignored when not touching). dt > 0 is
  /// the tick for the filter. Writes `desired` and the resultant sum f_i n_i to
  /// `residual`. Invalid input (dt not finite and > 0, or a touching finger's normal
  /// not finite): returns invalid_input, `desired` = the last plan (zero before the
  /// first), `residual` = 0, and nothing else changes.
  ForcePlanStatus plan(const Mask& touching, const Normals& normals, Scalar dt,
                       ForceVector& desired, Vector<Scalar, Dim>& residual) noexcept {
    const int n = size();
    ForcePlanStatus status = ForcePlanStatus::ok;
    if (!is_finite(dt) || !(dt > Scalar(0))) {
      desired = filtered_;
      residual.setZero();
      return ForcePlanStatus::invalid_input;
    }
    for (int i = 0; i < n; ++i) {
      if (touching(i) && !all_finite(normals.col(i))) {
        desired = filtered_;
        residual.setZero();
        return ForcePlanStatus::invalid_input;
      }
    }
    const Scalar f0 = params_.nominal_force;
    Vector<Scalar, Dim> preset_sum = Vector<Scalar, Dim>::Zero();
    int k = 0;
    for (int i = 0; i < n; ++i) {
      desired(i) = f0;
      if (!touching(i)) continue;
      if (roles_[static_cast<std::size_t>(i)] == FingerRole::preset) {
        preset_sum += f0 * normals.col(i);
      } else {
        nb_.col(k++) = normals.col(i);
      }
    }
    if (k == 0) {
      status = status | ForcePlanStatus::no_balancing_contact;
    } else {
      // (Nb^T Nb + rho I) f = -Nb^T R + rho f0 over the k touching balancing fingers.
      const Scalar rho = params_.regularisation;
      auto G = gram_.topLeftCorner(k, k);
      G.noalias() = nb_.leftCols(k).transpose() * nb_.leftCols(k);
      G.diagonal().array() += rho;
      auto b = rhs_.head(k);
      // Negating the fixed-size right-hand side, not the product: a negated product
      // is evaluated into a temporary, which allocates for a run-time finger count.
      b.noalias() = nb_.leftCols(k).transpose() * Vector<Scalar, Dim>(-preset_sum);
      b.array() += rho * f0;
      solve_small(k);
      int j = 0;
      for (int i = 0; i < n; ++i) {
        if (!touching(i) || roles_[static_cast<std::size_t>(i)] != FingerRole::balancing) continue;
        Scalar f = rhs_(j++);
        if (f < params_.min_force || f > params_.max_force || !is_finite(f)) {
          status = status | ForcePlanStatus::limited;
          f = is_finite(f) ? (f < params_.min_force ? params_.min_force : params_.max_force)
                           : params_.max_force;
        }
        desired(i) = f;
      }
    }
    // First-order filter (exact discretisation), primed on the first call.
    if (!primed_ || params_.filter_time <= Scalar(0)) {
      filtered_ = desired;
      primed_ = true;
    } else {
      const Scalar a = Scalar(1) - std::exp(-dt / params_.filter_time);
      filtered_ += a * (desired - filtered_);
      desired = filtered_;
    }
    residual.setZero();
    for (int i = 0; i < n; ++i)
      if (touching(i)) residual += desired(i) * normals.col(i);
    return status;
  }

 private:
  using Gram = Eigen::Matrix<Scalar, NumFingers, NumFingers>;
  /// In-place solve of the leading k x k SPD block, result in rhs_.head(k).
  void solve_small(int k) noexcept {
    // Cholesky by hand on the leading block: k is tiny and variable, and this keeps
    // the fixed-size storage without a run-time sized factorisation object.
    for (int c = 0; c < k; ++c) {
      Scalar d = gram_(c, c);
      for (int p = 0; p < c; ++p) d -= gram_(c, p) * gram_(c, p);
      d = std::sqrt(d > Scalar(0) ? d : Eigen::NumTraits<Scalar>::epsilon());
      gram_(c, c) = d;
      for (int r = c + 1; r < k; ++r) {
        Scalar v = gram_(r, c);
        for (int p = 0; p < c; ++p) v -= gram_(r, p) * gram_(c, p);
        gram_(r, c) = v / d;
      }
    }
    for (int r = 0; r < k; ++r) {  // L y = b
      Scalar v = rhs_(r);
      for (int p = 0; p < r; ++p) v -= gram_(r, p) * rhs_(p);
      rhs_(r) = v / gram_(r, r);
    }
    for (int r = k - 1; r >= 0; --r) {  // L^T x = y
      Scalar v = rhs_(r);
      for (int p = r + 1; p < k; ++p) v -= gram_(p, r) * rhs_(p);
      rhs_(r) = v / gram_(r, r);
    }
  }

  ForcePlannerParams<Scalar> params_{};
  std::vector<FingerRole> roles_;
  ForceVector filtered_;
  Normals nb_;
  Gram gram_;
  ForceVector rhs_;
  bool primed_ = false;
};

}  // namespace inhand
