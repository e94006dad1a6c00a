// Layer 2: what the force layer observes of each contact, from measurements only
// (docs/method.md section 5, docs/force_layer.md).
//
// Both read the contact's relative step over the tick: the fingertip's material point at
// the contact against the object's material point there, from measurements only. With
// p_c the measured contact point, n its outward normal, (R, p_o) the measured object pose,
//   d_tip = J (q_k - q_{k-1})                     the fingertip's measured step there,
//   d_obj = p_c - (R_{k-1} c + p_{o,k-1}),  c = R_k^T (p_c - p_{o,k})
//                                                 the object's measured step there,
//   d     = d_tip - d_obj                         (ContactMotion).
// Its normal part -n . d is the contact's advance (the change of its compression), its
// tangential part (I - n n^T) d the contact's slide.
//
// StiffnessEstimator: per finger, an exponentially weighted least-squares fit of the
// measured normal force f [N] against the accumulated advance a = sum(-n . d) [m]
// (a grows when the finger presses in), over a memory of `window` seconds. The slope
// k = cov(a, f) / var(a) [N/m] replaces the estimate only once a full window has passed,
// while the advance varies (std(a) > min_excitation) and the fit explains at least
// min_fit of the force's variance (cov^2 >= min_fit var(a) var(f)), clamped to
// [min_stiffness, max_stiffness]. Until then the estimate stays where it was
// (max_stiffness after reset: the safe side for a loop whose gain is 1/k). The object's
// own measured motion is taken out of the advance: a finger that follows a moving
// object (with an actuator's lag, or pushing it) has not compressed its contact by its
// own travel. Noise in the measured pose lowers the fit (min_fit then holds the
// estimate) rather than biasing it by more than 1 - min_fit.
// press(): the stiffness the press direction is computed with (joint_servo.hpp,
// servo_press_direction). The fit's, once one has been trusted since reset(); before
// that the secant since the touch, (f - f_touch) / a, once a > min_excitation (f_touch:
// the force at the touch onset, which arrives with no advance measured), clamped like
// the fit. The loop's gain keeps the safe side until the fit is trusted; the press
// direction has no safe side, only a best estimate: pressed along the servo's direction
// alone (the initial max_stiffness) on a soft contact, a grasp stores friction that a
// fixture holds and lets go at release (docs/force_layer.md, the MuJoCo boxes).
//
// SlipDetector: per finger, the contact's slip s = sum((I - n n^T) d) [m] since the touch.
// Rolling (the object turning on its contacts) moves the contact point along the object
// and along the fingertip alike and leaves s unchanged; only sliding grows it. (A
// detector that watches the contact point move along the object alone flags every
// rolling contact: a released object that turns 20 mrad on a 20 mm cylinder moves its
// contact points 0.4 mm.) s is low-passed with 10 ms (s_f) and with 100 ms (s_s). The
// contact slides when |s_f - s_s| > slip_distance [m] (a steady slide at v [m/s] gives
// 0.09 s * v) AND it still moves: |s - s_f| >= slip_distance / 18, half the lead of a
// steady slide at the threshold speed slip_distance / 0.09 s. The second condition ends
// the flag some 30 ms after a step: a compliant pad that shears by 0.4 mm when the
// released object settles on it has moved, but it holds (it is not sliding). Noise in
// the measured pose and joint angles does not accumulate: the sums of the steps telescope.
// update() also reports the sliding fingers' largest lead |s - s_f|, the slide's speed.
//
// Both are reset per finger at a touch onset (start()); update() touches only the
// touching fingers. noexcept; fixed finger counts never allocate.
#pragma once

#include <algorithm>
#include <cmath>

#include "inhand/math/types.hpp"

namespace inhand {

/// The contacts' relative steps d over the tick and their advances -n . d (file comment).
template <typename Scalar, int Dim, int NumFingers>
class ContactMotion {
 public:
  using Points = Eigen::Matrix<Scalar, Dim, NumFingers>;
  using ForceVector = Eigen::Matrix<Scalar, NumFingers, 1>;
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;
  using Vec = Vector<Scalar, Dim>;
  using Rot = Rotation<Scalar, Dim>;

  void resize(int fingers) {
    steps_.setZero(Dim, fingers);
    advance_.setZero(fingers);
    reset();
  }
  /// Forgets the last object pose: the next update() takes d_obj as zero.
  void reset() noexcept { has_pose_ = false; }
  /// One tick: for the touching fingers, contact points and outward unit normals, and
  /// `tip_steps` the fingertip's measured step at the contact (d_tip), world frame [m];
  /// (R, p_o) the measured object pose. Fingers not touching get d = 0.
  void update(const Mask& touching, const Points& points, const Points& normals,
              const Points& tip_steps, const Rot& object_rotation,
              const Vec& object_position) noexcept {
    for (int i = 0; i < static_cast<int>(advance_.size()); ++i) {
      steps_.col(i).setZero();
      advance_(i) = Scalar(0);
      if (!touching(i)) continue;
      const Vec pc = points.col(i);
      steps_.col(i) = tip_steps.col(i);
      if (has_pose_) {
        const Vec c = object_rotation.transpose() * (pc - object_position);
        steps_.col(i) -= pc - (last_rotation_ * c + last_position_);
      }
      advance_(i) = -normals.col(i).dot(steps_.col(i));
    }
    last_rotation_ = object_rotation;
    last_position_ = object_position;
    has_pose_ = true;
  }
  const Points& steps() const noexcept { return steps_; }           ///< d [m], world frame
  const ForceVector& advance() const noexcept { return advance_; }  ///< -n . d [m]

 private:
  Points steps_;
  ForceVector advance_;
  Rot last_rotation_ = Rot::Identity();
  Vec last_position_ = Vec::Zero();
  bool has_pose_ = false;
};

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
    for (ForceVector* v : {&stiffness_, &press_, &touch_force_, &advance_, &m_d_, &m_f_, &m_dd_,
                           &m_df_, &m_ff_, &window_})
      v->setZero(fingers);
    fitted_.setZero(fingers);
  }
  /// Every estimate back to `initial` [N/m], none fitted.
  void reset(Scalar initial) noexcept {
    stiffness_.setConstant(initial);
    press_.setConstant(initial);
    fitted_.setZero();
  }

  /// Touch onset of finger i, first measured force f [N]: a fresh fit (and secant).
  void start(int i, Scalar f) noexcept {
    touch_force_(i) = f;
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
        if (is_finite(k)) {
          stiffness_(i) = std::min(p.max_stiffness, std::max(p.min_stiffness, k));
          fitted_(i) = 1;
        }
      }
      if (fitted_(i) != 0)
        press_(i) = stiffness_(i);
      else if (d > p.min_excitation && f > touch_force_(i))  // d > 0: finite or +inf
        press_(i) = std::min(p.max_stiffness, std::max(p.min_stiffness, (f - touch_force_(i)) / d));
    }
  }

  const ForceVector& estimate() const noexcept { return stiffness_; }  ///< [N/m]
  const ForceVector& press() const noexcept { return press_; }         ///< [N/m], see above

 private:
  ForceVector stiffness_, press_, touch_force_, advance_, m_d_, m_f_, m_dd_, m_df_, m_ff_, window_;
  Mask fitted_;  ///< a fit trusted since reset()
};

template <typename Scalar, int Dim, int NumFingers>
class SlipDetector {
 public:
  using Points = Eigen::Matrix<Scalar, Dim, NumFingers>;
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;

  void resize(int fingers) {
    slip_.setZero(Dim, fingers);
    fast_.setZero(Dim, fingers);
    slow_.setZero(Dim, fingers);
  }
  /// Touch onset of finger i: its slip and filters start at zero.
  void start(int i) noexcept {
    slip_.col(i).setZero();
    fast_.col(i).setZero();
    slow_.col(i).setZero();
  }
  /// What update() found this tick.
  struct Report {
    bool any = false;  ///< some touching finger slides
    /// The largest lead |s - s_f| [m] of the sliding fingers (0 if none): the slide's speed
    /// as the 10 ms filter sees it, 0.01 s * v for a steady slide at v.
    Scalar lead = Scalar(0);
  };
  /// One tick. For the touching fingers: `steps` the contact's relative step d over the
  /// tick [m] and the outward unit normals (world frame). Sets slipping(i) for the
  /// touching fingers that slide (only when `object_free`: a held object cannot slip).
  Report update(const Mask& touching, const Points& steps, const Points& normals, bool object_free,
                Scalar slip_distance, Scalar dt, Mask& slipping) noexcept {
    const Scalar af = Scalar(1) - std::exp(-dt / Scalar(0.01));
    const Scalar as = Scalar(1) - std::exp(-dt / Scalar(0.1));
    Report r;
    for (int i = 0; i < static_cast<int>(slip_.cols()); ++i) {
      if (!touching(i)) continue;
      slip_.col(i) += steps.col(i) - steps.col(i).dot(normals.col(i)) * normals.col(i);
      fast_.col(i) += af * (slip_.col(i) - fast_.col(i));
      slow_.col(i) += as * (slip_.col(i) - slow_.col(i));
      const Scalar lead = (slip_.col(i) - fast_.col(i)).norm();
      if (object_free && (fast_.col(i) - slow_.col(i)).norm() > slip_distance &&
          Scalar(18) * lead >= slip_distance) {
        slipping(i) = 1;
        r.any = true;
        r.lead = std::max(r.lead, lead);
      }
    }
    return r;
  }

 private:
  Points slip_, fast_, slow_;
};

}  // namespace inhand
