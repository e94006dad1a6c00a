// Layer 2, the force layer: normal-force loops of all touching fingers together, the
// grip that follows the load, and slip detection (docs/method.md section 5).
//
// Frames, units, signs: world frame, SI. n_i is the object's OUTWARD unit normal at
// finger i's contact; forces are normal-force magnitudes >= 0 [N]; the force finger i
// exerts on the object is -f_i n_i. The layer's output u_i [m/s] is the fingertip
// velocity INTO the object along -n_i (u_i > 0 presses harder); the controller adds
// -u_i n_i to the finger's motion command (eq. 7).
//
// One equilibrium. A vector of normal forces f splits into
//   rigid    : range(A)          -- the part that has a resultant wrench on the object
//   internal : null(A^T)          -- squeezing that leaves the object in equilibrium
// where row i of A is [n_i^T, ((p_i - p_o) x n_i)^T / L] (A V is the normal velocity of
// the object's material points at the contacts for the twist V; L the RMS lever arm
// makes both halves dimensionless). The rigid part of the measured forces is what
// the normal forces carry of the external load (weight, a push, a sensor bias); the
// object's pose loop (layer 1) owns every rigid direction. The force loops own only
// the internal directions: their error is projected onto null(A^T),
//   e = P_int (s q - f_m),   P_int = I - A (A^T A + eps I)^-1 A^T,
// with q the planner's force pattern and s >= 1 the grip scale, and so is the state
// of their integrator. No direction has two integrators, so nothing can ramp along a
// family of equilibria (the drift of the paper's per-finger loops). At equilibrium
// the measured forces are f_m = P_r f_m + s P_int q: the load share plus the grip.
//
// A loop that does not scale with the contact stiffness. Each finger's loop is
//   u_i = (w_c / k_i) (e_i + w_i z_i),   z_i' = e_i   (z kept internal, bounded)
// with k_i [N/m] an online estimate of the contact stiffness: an exponentially
// weighted least-squares fit of the measured force against the measured normal
// advance of the fingertip into the object (joint motion through the contact
// Jacobian, less the object's commanded motion), over `stiffness_window` seconds,
// updated only while the advance varies by more than `min_excitation` and the fit
// explains at least `min_fit` of the force's variance; it starts at max_stiffness
// (the safe side). A compliant finger servo in series only lowers the stiffness seen
// from the command, so the loop is then slower, never less stable. With k_i = k the loop
// crosses over at w_c whatever the stiffness; the discrete loop with one tick of
// command delay, z^2 - z + a = 0, a = rho w_c T, is stable for a < 1: at the default
// w_c = 40 rad/s and T = 1 ms a stiffness under-estimated by up to rho = 25 times is
// still stable (docs/force_layer.md gives the phase margin with actuator lag).
//
// Grip that follows the load. s is the largest of
//   1                 the nominal grip (the planner's pattern);
//   s_min_force       the least s for which every target force s (P_int q)_i +
//                     (P_r f_m)_i is at least min_force: a normal load taken from a
//                     finger is given back by squeezing harder;
//   s_slip            raised at grip_rise_rate per second while any finger slips, and at
//                     a slip onset at once to friction_margin times the grip at which
//                     it slipped (that grip was just at the friction cone's edge, eq. 8);
//                     it decays back to 1 with time constant grip_decay_time once the
//                     slip stops (the grip falls back when the load goes);
// capped at the largest s for which no target exceeds max_force. When the cap binds
// while a finger slips, or min_force cannot be met, `beyond_capacity` is raised: the
// load exceeds what the hand can hold with this friction.
// Slip: the contact point expressed in the object frame, low-passed with 10 ms and
// with 100 ms; their tangential difference exceeding `slip_distance` means the
// contact moves along the object (a steady slide at v gives 0.09 s * v).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar>
struct ForceLayerParams {
  Scalar bandwidth = Scalar(40);               ///< w_c [rad/s], crossover of each force loop
  Scalar integral_corner = Scalar(10);         ///< w_i [rad/s], PI zero; 0: proportional only
  Scalar min_stiffness = Scalar(200);          ///< [N/m], lower bound of the estimate
  Scalar max_stiffness = Scalar(1e5);          ///< [N/m], upper bound and initial estimate
  Scalar stiffness_window = Scalar(0.2);       ///< [s], estimator memory
  Scalar min_excitation = Scalar(1e-5);        ///< [m], std of the advance needed to update
  Scalar min_fit = Scalar(0.9);                ///< r^2 of the fit needed to update, in (0, 1]
  Scalar max_integral_velocity = Scalar(0.1);  ///< [m/s], bound on (w_c / k) w_i z
  Scalar slip_distance = Scalar(3e-4);         ///< [m], see the file comment
  Scalar grip_rise_rate = Scalar(5);           ///< [1/s], rise of s while slipping
  Scalar friction_margin = Scalar(1.5);        ///< >= 1, grip after a slip onset / grip at onset
  Scalar grip_decay_time = Scalar(20);         ///< [s], s_slip back to 1 once the slip stops
  Scalar rigid_tolerance = Scalar(1e-3);       ///< eps, dimensionless (see the file comment)

  Validation validate() const noexcept {
    const Scalar inf = std::numeric_limits<Scalar>::infinity();
    struct Field {
      const char* name;
      Scalar value, lo, hi;
      bool lo_open;
    };
    const Field fields[] = {
        {"force_layer.bandwidth", bandwidth, Scalar(0), inf, true},
        {"force_layer.integral_corner", integral_corner, Scalar(0), inf, false},
        {"force_layer.min_stiffness", min_stiffness, Scalar(0), inf, true},
        {"force_layer.max_stiffness", max_stiffness, min_stiffness, inf, false},
        {"force_layer.stiffness_window", stiffness_window, Scalar(0), inf, true},
        {"force_layer.min_excitation", min_excitation, Scalar(0), inf, true},
        {"force_layer.min_fit", min_fit, Scalar(0), Scalar(1) + Scalar(1e-12), true},
        {"force_layer.max_integral_velocity", max_integral_velocity, Scalar(0), inf, true},
        {"force_layer.slip_distance", slip_distance, Scalar(0), inf, true},
        {"force_layer.grip_rise_rate", grip_rise_rate, Scalar(0), inf, false},
        {"force_layer.friction_margin", friction_margin, Scalar(1), inf, false},
        {"force_layer.grip_decay_time", grip_decay_time, Scalar(0), inf, true},
        {"force_layer.rigid_tolerance", rigid_tolerance, Scalar(0), inf, true},
    };
    for (const Field& f : fields) {
      const bool ok =
          is_finite(f.value) && (f.lo_open ? f.value > f.lo : f.value >= f.lo) && f.value < f.hi;
      if (!ok)
        return Validation::invalid(
            f.name, f.lo_open ? "must be finite and > its lower bound (see the header)"
                              : "must be finite and >= its lower bound (see the header)");
    }
    return Validation::valid();
  }
};

/// What the force layer reports each tick (bit flags).
enum class ForceLayerStatus : unsigned {
  ok = 0,
  slipping = 1u << 0,          ///< some finger's contact slides along the object
  grip_raised = 1u << 1,       ///< s > 1: the grip is above the nominal pattern
  beyond_capacity = 1u << 2,   ///< the load needs more than max_force (or min_force is unreachable)
  integral_limited = 1u << 3,  ///< some force integrator reached max_integral_velocity
};
constexpr ForceLayerStatus operator|(ForceLayerStatus a, ForceLayerStatus b) noexcept {
  return static_cast<ForceLayerStatus>(static_cast<unsigned>(a) | static_cast<unsigned>(b));
}
constexpr bool has(ForceLayerStatus s, ForceLayerStatus flag) noexcept {
  return (static_cast<unsigned>(s) & static_cast<unsigned>(flag)) != 0u;
}

/// Normal-force loops of NumFingers fingers (fixed, or Dynamic sized by resize()).
template <typename Scalar, int Dim, int NumFingers>
class ForceLayer {
 public:
  static constexpr int W = SpatialDim<Dim>::kTwist;  ///< wrench size
  static constexpr int R = SpatialDim<Dim>::kRot;
  using ForceVector = Eigen::Matrix<Scalar, NumFingers, 1>;
  using Points = Eigen::Matrix<Scalar, Dim, NumFingers>;  ///< one column per finger
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;
  using Wrench = Eigen::Matrix<Scalar, W, 1>;  ///< (force; torque about p_o)
  using Vec = Vector<Scalar, Dim>;

  /// Per-tick input: touching fingers' measured contact points, outward normals and
  /// normal forces (columns / entries of the others are ignored), the planner's
  /// pattern q, the object pose, the min/max force bounds of the planner, and whether
  /// the object is free (manipulation; false while the grasp holds it fixed: every
  /// direction is then internal and the grip stays at 1).
  struct Step {
    const Mask* touching = nullptr;
    const Points* points = nullptr;
    const Points* normals = nullptr;
    const ForceVector* measured = nullptr;
    const ForceVector* pattern = nullptr;
    /// Per finger, the measured normal advance into the object over the last tick [m]:
    /// -n . (fingertip displacement - the object's commanded displacement there).
    const ForceVector* advance = nullptr;
    Vec object_position = Vec::Zero();
    Rotation<Scalar, Dim> object_rotation = Rotation<Scalar, Dim>::Identity();
    Scalar min_force = Scalar(0);
    Scalar max_force = std::numeric_limits<Scalar>::infinity();
    bool object_free = true;
    Scalar dt = Scalar(1e-3);
  };

  struct Result {
    ForceVector velocity;  ///< u_i [m/s] into the object along -n_i (0 when not touching)
    ForceVector target;    ///< the force each loop drives to [N]
    Mask slipping;         ///< per finger
    Wrench load =
        Wrench::Zero();       ///< external wrench the normal forces balance, -sum(-f n; r x -f n)
    Scalar grip = Scalar(1);  ///< s
    ForceLayerStatus status = ForceLayerStatus::ok;
  };

  explicit ForceLayer(int fingers = (NumFingers == Dynamic ? 0 : NumFingers)) { resize(fingers); }

  /// Sizes the state (allocates only for a run-time finger count) and resets it.
  void resize(int fingers) {
    n_ = fingers;
    z_.setZero(fingers);
    u_prev_.setZero(fingers);
    stiffness_.setZero(fingers);
    advance_.setZero(fingers);
    m_d_.setZero(fingers);
    m_f_.setZero(fingers);
    m_dd_.setZero(fingers);
    m_df_.setZero(fingers);
    m_ff_.setZero(fingers);
    window_.setZero(fingers);
    was_touching_.setZero(fingers);
    slip_fast_.setZero(Dim, fingers);
    slip_slow_.setZero(Dim, fingers);
    a_.setZero(fingers, W);
    e_.setZero(fingers);
    q_int_.setZero(fingers);
    r_load_.setZero(fingers);
    // A factorisation in a defined state (an uncomputed Eigen::LDLT holds indeterminate
    // members, which copying the layer would read).
    ldlt_.compute(Eigen::Matrix<Scalar, W, W>::Identity());
    reset();
  }
  int size() const noexcept { return n_; }
  void set_params(const ForceLayerParams<Scalar>& p) noexcept { params_ = p; }
  const ForceLayerParams<Scalar>& params() const noexcept { return params_; }

  /// Clears integrators, estimates (back to max_stiffness), slip filters and the grip.
  void reset() noexcept {
    z_.setZero();
    u_prev_.setZero();
    stiffness_.setConstant(params_.max_stiffness);
    was_touching_.setZero();
    grip_slip_ = Scalar(1);
    was_slipping_ = false;
  }

  const ForceVector& stiffness_estimate() const noexcept { return stiffness_; }
  /// Integrator states z_i [N s] (internal by construction).
  const ForceVector& integral() const noexcept { return z_; }

  /// One tick. Inputs must be finite (the controller checks them); dt > 0.
  void update(const Step& in, Result& out) noexcept {
    const ForceLayerParams<Scalar>& p = params_;
    const Scalar dt = in.dt;
    out.velocity.setZero(n_);
    out.target.setZero(n_);
    out.slipping.setZero(n_);
    out.status = ForceLayerStatus::ok;
    // Touch onsets: fresh integrator, estimator window and slip filters.
    for (int i = 0; i < n_; ++i) {
      const bool t = (*in.touching)(i) != 0;
      if (t && !was_touching_(i)) {
        z_(i) = Scalar(0);
        u_prev_(i) = Scalar(0);
        advance_(i) = Scalar(0);
        m_d_(i) = Scalar(0);
        m_f_(i) = (*in.measured)(i);
        m_dd_(i) = Scalar(0);
        m_df_(i) = Scalar(0);
        m_ff_(i) = m_f_(i) * m_f_(i);
        window_(i) = Scalar(0);
        const Vec c = in.object_rotation.transpose() * (in.points->col(i) - in.object_position);
        slip_fast_.col(i) = c;
        slip_slow_.col(i) = c;
      }
      was_touching_(i) = t ? 1 : 0;
    }
    estimate_stiffness(in);
    const bool slipping = detect_slip(in, out);

    // Rigid / internal split of the touching fingers' normal-force space.
    build_grasp_map(in);
    // q_int = P_int q, r_load = P_r f_m, and the load the normal forces balance.
    for (int i = 0; i < n_; ++i) {
      const bool t = (*in.touching)(i) != 0;
      q_int_(i) = t ? (*in.pattern)(i) : Scalar(0);
      r_load_(i) = t ? (*in.measured)(i) : Scalar(0);
    }
    if (in.object_free) {
      project_internal(q_int_);
      Wrench w;
      w.noalias() = a_.transpose() * r_load_;  // sum f_i [n_i; r_i x n_i / L]
      out.load = w;
      out.load.template tail<R>() *= lever_;
      // r_load = f_m - P_int f_m = P_r f_m
      e_ = r_load_;
      project_internal(e_);
      r_load_ -= e_;
    } else {
      out.load.setZero();
      r_load_.setZero();
    }

    // Grip scale s.
    Scalar s_lo = Scalar(1), s_hi = std::numeric_limits<Scalar>::infinity();
    bool infeasible = false;
    if (in.object_free) {
      for (int i = 0; i < n_; ++i) {
        if (!(*in.touching)(i)) continue;
        const Scalar q = q_int_(i), r = r_load_(i);
        if (q > Scalar(1e-9)) {
          s_lo = std::max(s_lo, (in.min_force - r) / q);
          s_hi = std::min(s_hi, (in.max_force - r) / q);
        } else if (r < in.min_force) {
          infeasible = true;
        }
      }
      if (slipping) {
        if (!was_slipping_) grip_slip_ = std::max(grip_slip_, p.friction_margin * grip_);
        grip_slip_ += p.grip_rise_rate * dt;
      } else {
        grip_slip_ = Scalar(1) + (grip_slip_ - Scalar(1)) * std::exp(-dt / p.grip_decay_time);
      }
      was_slipping_ = slipping;
    } else {
      grip_slip_ = Scalar(1);
      was_slipping_ = false;
    }
    Scalar s = std::max(s_lo, grip_slip_);
    if (s > s_hi) {
      s = std::max(Scalar(1), s_hi);
      if (slipping || s_lo > s_hi) infeasible = true;
      grip_slip_ = std::min(grip_slip_, s);  // no windup above the cap
    }
    grip_ = s;
    out.grip = s;
    if (s > Scalar(1) + Scalar(1e-6)) out.status = out.status | ForceLayerStatus::grip_raised;
    if (infeasible) out.status = out.status | ForceLayerStatus::beyond_capacity;
    if (slipping) out.status = out.status | ForceLayerStatus::slipping;

    // Internal force error (the rigid part belongs to the pose loop) and the loops.
    for (int i = 0; i < n_; ++i)
      e_(i) = (*in.touching)(i) ? s * (*in.pattern)(i) - (*in.measured)(i) : Scalar(0);
    if (in.object_free) project_internal(e_);
    for (int i = 0; i < n_; ++i) {
      const bool t = (*in.touching)(i) != 0;
      out.target(i) = t ? (*in.measured)(i) + e_(i) : Scalar(0);
      z_(i) = t ? z_(i) + dt * e_(i) : Scalar(0);
    }
    if (in.object_free) project_internal(z_);
    bool limited = false;
    for (int i = 0; i < n_; ++i) {
      if (!(*in.touching)(i)) continue;
      const Scalar kp = p.bandwidth / stiffness_(i);
      const Scalar zmax = p.integral_corner > Scalar(0)
                              ? p.max_integral_velocity / (kp * p.integral_corner)
                              : Scalar(0);
      if (std::abs(z_(i)) > zmax) {
        z_(i) = z_(i) > Scalar(0) ? zmax : -zmax;
        limited = limited || p.integral_corner > Scalar(0);
      }
      out.velocity(i) = kp * (e_(i) + p.integral_corner * z_(i));
    }
    if (limited) out.status = out.status | ForceLayerStatus::integral_limited;
    u_prev_ = out.velocity;
  }

 private:
  /// Exponentially weighted least squares of f against the commanded advance d.
  void estimate_stiffness(const Step& in) noexcept {
    const ForceLayerParams<Scalar>& p = params_;
    const Scalar a = Scalar(1) - std::exp(-in.dt / p.stiffness_window);
    for (int i = 0; i < n_; ++i) {
      if (!(*in.touching)(i)) continue;
      advance_(i) += (*in.advance)(i);
      const Scalar d = advance_(i), f = (*in.measured)(i);
      m_d_(i) += a * (d - m_d_(i));
      m_f_(i) += a * (f - m_f_(i));
      m_dd_(i) += a * (d * d - m_dd_(i));
      m_df_(i) += a * (d * f - m_df_(i));
      m_ff_(i) += a * (f * f - m_ff_(i));
      window_(i) += in.dt;
      const Scalar var = m_dd_(i) - m_d_(i) * m_d_(i);
      const Scalar var_f = m_ff_(i) - m_f_(i) * m_f_(i);
      const Scalar cov = m_df_(i) - m_d_(i) * m_f_(i);
      if (window_(i) >= p.stiffness_window && var > p.min_excitation * p.min_excitation &&
          cov > Scalar(0) && cov * cov >= p.min_fit * var * var_f) {
        const Scalar k = cov / var;
        if (is_finite(k)) stiffness_(i) = std::min(p.max_stiffness, std::max(p.min_stiffness, k));
      }
    }
  }

  bool detect_slip(const Step& in, Result& out) noexcept {
    const Scalar af = Scalar(1) - std::exp(-in.dt / Scalar(0.01));
    const Scalar as = Scalar(1) - std::exp(-in.dt / Scalar(0.1));
    bool any = false;
    for (int i = 0; i < n_; ++i) {
      if (!(*in.touching)(i)) continue;
      const Vec c = in.object_rotation.transpose() * (in.points->col(i) - in.object_position);
      slip_fast_.col(i) += af * (c - slip_fast_.col(i));
      slip_slow_.col(i) += as * (c - slip_slow_.col(i));
      const Vec m = in.object_rotation.transpose() * in.normals->col(i);
      Vec d = slip_fast_.col(i) - slip_slow_.col(i);
      d -= d.dot(m) * m;
      if (in.object_free && d.norm() > params_.slip_distance) {
        out.slipping(i) = 1;
        any = true;
      }
    }
    return any;
  }

  static AngularVector<Scalar, Dim> moment(const Vector<Scalar, 3>& r,
                                           const Vector<Scalar, 3>& n) noexcept {
    return r.cross(n);
  }
  static AngularVector<Scalar, Dim> moment(const Vector<Scalar, 2>& r,
                                           const Vector<Scalar, 2>& n) noexcept {
    return AngularVector<Scalar, Dim>(r.x() * n.y() - r.y() * n.x());
  }

  void build_grasp_map(const Step& in) noexcept {
    Scalar sum = Scalar(0);
    int k = 0;
    for (int i = 0; i < n_; ++i) {
      if (!(*in.touching)(i)) continue;
      sum += (in.points->col(i) - in.object_position).squaredNorm();
      ++k;
    }
    lever_ = k > 0 ? std::sqrt(sum / Scalar(k)) : Scalar(0);
    if (!(lever_ > Scalar(1e-6))) lever_ = Scalar(1e-6);
    for (int i = 0; i < n_; ++i) {
      if (!(*in.touching)(i)) {
        a_.row(i).setZero();
        continue;
      }
      const Vec n = in.normals->col(i);
      a_.row(i).template head<Dim>() = n.transpose();
      a_.row(i).template tail<R>() =
          (moment(Vec(in.points->col(i) - in.object_position), n) / lever_).transpose();
    }
    Eigen::Matrix<Scalar, W, W> m;
    m.noalias() = a_.transpose() * a_;
    m.diagonal().array() += params_.rigid_tolerance;
    ldlt_.compute(m);
  }

  /// x <- (I - A (A^T A + eps I)^-1 A^T) x
  void project_internal(ForceVector& x) const noexcept {
    Wrench w;
    w.noalias() = a_.transpose() * x;
    const Wrench y = ldlt_.solve(w);
    x.noalias() -= a_ * y;
  }

  ForceLayerParams<Scalar> params_{};
  int n_ = 0;
  ForceVector z_, u_prev_, stiffness_, advance_, m_d_, m_f_, m_dd_, m_df_, m_ff_, window_;
  Mask was_touching_;
  Points slip_fast_, slip_slow_;
  Eigen::Matrix<Scalar, NumFingers, W> a_;
  Eigen::LDLT<Eigen::Matrix<Scalar, W, W>> ldlt_;
  ForceVector e_, q_int_, r_load_;
  Scalar lever_ = Scalar(1);
  Scalar grip_ = Scalar(1);
  Scalar grip_slip_ = Scalar(1);
  bool was_slipping_ = false;
};

}  // namespace inhand
