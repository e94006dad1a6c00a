// Layer 2: what the force layer observes of each contact, from measurements only
// (docs/method.md section 5, docs/force_layer.md).
//
// StiffnessEstimator: per finger, an exponentially weighted least-squares fit of the
// measured normal force f [N] against the accumulated measured normal advance d [m]
// of the fingertip into the object (d grows when the finger presses in), over a
// memory of `window` seconds. The slope k = cov(d, f) / var(d) [N/m] replaces the
// estimate only once a full window has passed, while the advance varies
// (std(d) > min_excitation) and the fit explains at least min_fit of the force's
// variance (cov^2 >= min_fit var(d) var(f)), clamped to [min_stiffness, max_stiffness].
// Until then the estimate stays where it was (max_stiffness after reset: the safe side
// for a loop whose gain is 1/k).
//
// SlipDetector: per finger, the contact point expressed in the OBJECT frame, low-passed
// with 10 ms and with 100 ms; their difference, less its part along the object-frame
// normal, longer than slip_distance [m] means the contact slides along the object (a
// steady slide at v [m/s] gives 0.09 s * v).
//
// Both are reset per finger at a touch onset (start()); update() touches only the
// touching fingers. noexcept; fixed finger counts never allocate.
#pragma once

#include <algorithm>
#include <cmath>

#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar, int NumFingers>
class StiffnessEstimator {
 public:
  using ForceVector = Eigen::Matrix<Scalar, NumFingers, 1>;
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;

  struct Params {
    Scalar min_stiffness, max_stiffness;  ///< [N/m]
    Scalar window;                        ///< [s]
    Scalar min_excitation;                ///< [m]
    Scalar min_fit;                       ///< in (0, 1]
  };

  void resize(int fingers) {
    for (ForceVector* v : {&stiffness_, &advance_, &m_d_, &m_f_, &m_dd_, &m_df_, &m_ff_, &window_})
      v->setZero(fingers);
  }
  /// Every estimate back to `initial` [N/m].
  void reset(Scalar initial) noexcept { stiffness_.setConstant(initial); }

  /// Touch onset of finger i, first measured force f [N]: a fresh fit.
  void start(int i, Scalar f) noexcept {
    advance_(i) = Scalar(0);
    m_d_(i) = Scalar(0);
    m_f_(i) = f;
    m_dd_(i) = Scalar(0);
    m_df_(i) = Scalar(0);
    m_ff_(i) = f * f;
    window_(i) = Scalar(0);
  }

  /// One tick: `advance` the measured normal advance over the tick [m], `measured` the
  /// normal forces [N], for the touching fingers.
  void update(const Params& p, const Mask& touching, const ForceVector& advance,
              const ForceVector& measured, Scalar dt) noexcept {
    const Scalar a = Scalar(1) - std::exp(-dt / p.window);
    for (int i = 0; i < static_cast<int>(stiffness_.size()); ++i) {
      if (!touching(i)) continue;
      advance_(i) += advance(i);
      const Scalar d = advance_(i), f = measured(i);
      m_d_(i) += a * (d - m_d_(i));
      m_f_(i) += a * (f - m_f_(i));
      m_dd_(i) += a * (d * d - m_dd_(i));
      m_df_(i) += a * (d * f - m_df_(i));
      m_ff_(i) += a * (f * f - m_ff_(i));
      window_(i) += dt;
      const Scalar var = m_dd_(i) - m_d_(i) * m_d_(i);
      const Scalar var_f = m_ff_(i) - m_f_(i) * m_f_(i);
      const Scalar cov = m_df_(i) - m_d_(i) * m_f_(i);
      if (window_(i) >= p.window && var > p.min_excitation * p.min_excitation && cov > Scalar(0) &&
          cov * cov >= p.min_fit * var * var_f) {
        const Scalar k = cov / var;
        if (is_finite(k)) stiffness_(i) = std::min(p.max_stiffness, std::max(p.min_stiffness, k));
      }
    }
  }

  const ForceVector& estimate() const noexcept { return stiffness_; }  ///< [N/m]

 private:
  ForceVector stiffness_, advance_, m_d_, m_f_, m_dd_, m_df_, m_ff_, window_;
};

template <typename Scalar, int Dim, int NumFingers>
class SlipDetector {
 public:
  using Points = Eigen::Matrix<Scalar, Dim, NumFingers>;
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;
  using Vec = Vector<Scalar, Dim>;

  void resize(int fingers) {
    fast_.setZero(Dim, fingers);
    slow_.setZero(Dim, fingers);
  }
  /// Touch onset of finger i at the object-frame contact point c [m].
  void start(int i, const Vec& c) noexcept {
    fast_.col(i) = c;
    slow_.col(i) = c;
  }
  /// One tick; sets slipping(i) for the touching fingers that slide (only when
  /// `object_free`: a held object cannot slip) and returns whether any does. Points and
  /// normals in the world frame; the object pose (R, p_o) maps them into its frame.
  bool update(const Mask& touching, const Points& points, const Points& normals,
              const Rotation<Scalar, Dim>& object_rotation, const Vec& object_position,
              bool object_free, Scalar slip_distance, Scalar dt, Mask& slipping) noexcept {
    const Scalar af = Scalar(1) - std::exp(-dt / Scalar(0.01));
    const Scalar as = Scalar(1) - std::exp(-dt / Scalar(0.1));
    bool any = false;
    for (int i = 0; i < static_cast<int>(fast_.cols()); ++i) {
      if (!touching(i)) continue;
      const Vec c = object_rotation.transpose() * (points.col(i) - object_position);
      fast_.col(i) += af * (c - fast_.col(i));
      slow_.col(i) += as * (c - slow_.col(i));
      const Vec m = object_rotation.transpose() * normals.col(i);
      Vec d = fast_.col(i) - slow_.col(i);
      d -= d.dot(m) * m;
      if (object_free && d.norm() > slip_distance) {
        slipping(i) = 1;
        any = true;
      }
    }
    return any;
  }

 private:
  Points fast_, slow_;
};

}  // namespace inhand
