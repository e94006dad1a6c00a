// Layer 1: the desired object pose over time, interpolated in SE(3) (docs/method.md
// sections 3 and 7).
//
// A trajectory is a start pose and a sequence of segments. Each segment applies a
// rigid displacement D = (translation dp ; rotation vector dw), both in the WORLD
// frame, about the object reference point, with a minimum-jerk time scaling s(t):
//   p(t) = p_start + s(t) dp,      R(t) = exp(s(t) dw) R_start
// so the feed-forward twist is s'(t) (dp ; dw) (world frame, linear velocity of the
// object reference point, then angular velocity). Kinds of segment:
//   hold        : D = 0 for the duration
//   move        : translate by `amount` metres along a unit axis
//   rotate      : rotate by `amount` radians about a unit axis through the object point
//   reciprocate : go to D and back to the start `cycles` times (s rises 0->1->0 per
//                 cycle), e.g. the paper's Fig. 3a (0.5 cm along X) and Fig. 3b
//                 (0 -> -0.2 rad -> 0 about X).
// Planar trajectories (Dim = 2) use axes in the x-y plane and rotation about +z
// (the rotation axis argument is then the scalar +1 / -1).
// Segments live in a fixed-capacity array: evaluate() is noexcept and allocation-free.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>

#include "inhand/math/pose.hpp"
#include "inhand/math/status.hpp"

namespace inhand {

enum class SegmentKind : unsigned char { hold, move, rotate, reciprocate };

template <typename Scalar, int Dim>
struct TrajectorySegment {
  SegmentKind kind = SegmentKind::hold;
  Scalar duration = Scalar(1);  ///< seconds, > 0
  /// World-frame displacement (dp ; dw) reached at the end of a move/rotate, or the
  /// turning point of a reciprocate. Zero for hold.
  Twist<Scalar, Dim> displacement = Twist<Scalar, Dim>::Zero();
  int cycles = 1;  ///< reciprocate only, >= 1

  static TrajectorySegment hold_for(Scalar seconds) noexcept {
    TrajectorySegment s;
    s.kind = SegmentKind::hold;
    s.duration = seconds;
    return s;
  }
  static TrajectorySegment move(const Vector<Scalar, Dim>& axis, Scalar metres,
                                Scalar seconds) noexcept {
    TrajectorySegment s;
    s.kind = SegmentKind::move;
    s.duration = seconds;
    s.displacement.template head<Dim>() = metres * axis.normalized();
    return s;
  }
  static TrajectorySegment rotate(const AngularVector<Scalar, Dim>& axis, Scalar radians,
                                  Scalar seconds) noexcept {
    TrajectorySegment s;
    s.kind = SegmentKind::rotate;
    s.duration = seconds;
    s.displacement.template tail<SpatialDim<Dim>::kRot>() = radians * axis.normalized();
    return s;
  }
  /// Go to `displacement` and back `n` times; `seconds` is the duration of the whole
  /// segment (all n cycles), so each cycle takes seconds / n.
  static TrajectorySegment reciprocate(const Twist<Scalar, Dim>& displacement, Scalar seconds,
                                       int n = 1) noexcept {
    TrajectorySegment s;
    s.kind = SegmentKind::reciprocate;
    s.duration = seconds;
    s.displacement = displacement;
    s.cycles = n;
    return s;
  }
};

/// Minimum-jerk profile s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 on [0, 1] and its
/// derivative ds/dtau; zero velocity and acceleration at both ends.
template <typename Scalar>
inline void minimum_jerk(Scalar tau, Scalar& s, Scalar& ds) noexcept {
  tau = tau < Scalar(0) ? Scalar(0) : (tau > Scalar(1) ? Scalar(1) : tau);
  const Scalar t2 = tau * tau, t3 = t2 * tau;
  s = t3 * (Scalar(10) - Scalar(15) * tau + Scalar(6) * t2);
  ds = Scalar(30) * t2 * (Scalar(1) - Scalar(2) * tau + t2);
}

template <typename Scalar, int Dim>
struct TrajectorySample {
  Pose<Scalar, Dim> pose{};                               ///< desired object pose
  Twist<Scalar, Dim> twist = Twist<Scalar, Dim>::Zero();  ///< feed-forward twist
  int segment = -1;  ///< index of the active segment; -1 after the end (holding the last pose)
};

template <typename Scalar, int Dim, int MaxSegments = 32>
class ObjectTrajectory {
 public:
  using Segment = TrajectorySegment<Scalar, Dim>;

  ObjectTrajectory() = default;

  /// Clears the segments and sets the start pose.
  void reset(const Pose<Scalar, Dim>& start) noexcept {
    start_ = start;
    count_ = 0;
    total_ = Scalar(0);
  }
  /// Appends a segment; false (nothing appended) when full or the segment is invalid.
  bool append(const Segment& s) noexcept {
    if (count_ >= MaxSegments || !validate_segment(s).ok()) return false;
    segments_[static_cast<std::size_t>(count_)] = s;
    segment_start_[static_cast<std::size_t>(count_)] = end_pose_of(count_);
    ++count_;
    total_ += s.duration;
    return true;
  }
  /// Bounds that keep evaluate() finite in any Scalar: a duration (and, for a
  /// reciprocate, the duration of one cycle) of at least kMinDuration, so that the rate
  /// 1 / duration cannot overflow (a finite but denormal duration would make it
  /// infinite), at most kMaxDuration, and a displacement of norm at most
  /// kMaxDisplacement (m, or rad for the angular part).
  static constexpr double kMinDuration = 1e-6;     ///< s
  static constexpr double kMaxDuration = 1e9;      ///< s (about 30 years)
  static constexpr double kMaxDisplacement = 1e6;  ///< m and rad
  static Validation validate_segment(const Segment& s) noexcept {
    if (!is_finite(s.duration) || !(s.duration >= Scalar(kMinDuration)) ||
        !(s.duration <= Scalar(kMaxDuration)))
      return Validation::invalid("segment.duration", "must be finite, in [1e-6 s, 1e9 s]");
    if (!all_finite(s.displacement))
      return Validation::invalid("segment.displacement", "must be finite");
    if (!(s.displacement.template head<Dim>().norm() <= Scalar(kMaxDisplacement)) ||
        !(s.displacement.template tail<SpatialDim<Dim>::kRot>().norm() <= Scalar(kMaxDisplacement)))
      return Validation::invalid("segment.displacement", "each part must be at most 1e6 (m, rad)");
    if (s.kind == SegmentKind::reciprocate && s.cycles < 1)
      return Validation::invalid("segment.cycles", "must be >= 1");
    if (s.kind == SegmentKind::reciprocate &&
        !(s.duration / Scalar(s.cycles) >= Scalar(kMinDuration)))
      return Validation::invalid("segment.cycles", "each cycle must last at least 1e-6 s");
    return Validation::valid();
  }
  /// The whole trajectory: a finite start pose with a proper rotation (to 1e-6, or 100
  /// epsilons of Scalar) and valid segments (append() admits no other).
  Validation validate() const noexcept {
    const Scalar tol = std::max(Scalar(1e-6), Scalar(100) * std::numeric_limits<Scalar>::epsilon());
    if (!start_.is_finite()) return Validation::invalid("trajectory.start_pose", "must be finite");
    if (!start_.has_rotation(tol))
      return Validation::invalid("trajectory.start_pose.rotation",
                                 "must be a rotation (orthonormal, det +1)");
    for (int i = 0; i < count_; ++i) {
      const Validation v = validate_segment(segments_[static_cast<std::size_t>(i)]);
      if (!v.ok()) return Validation::invalid("trajectory.segments", v.reason, i);
    }
    return Validation::valid();
  }

  int size() const noexcept { return count_; }
  const Segment& segment(int i) const noexcept { return segments_[static_cast<std::size_t>(i)]; }
  Scalar duration() const noexcept { return total_; }
  const Pose<Scalar, Dim>& start_pose() const noexcept { return start_; }
  /// Start time of segment i relative to the trajectory start.
  Scalar segment_start_time(int i) const noexcept {
    Scalar t = Scalar(0);
    for (int k = 0; k < i && k < count_; ++k) t += segments_[static_cast<std::size_t>(k)].duration;
    return t;
  }

  /// Desired pose and feed-forward twist at time t (seconds from the start). Before 0
  /// it holds the start pose; after the end it holds the final pose with zero twist.
  TrajectorySample<Scalar, Dim> evaluate(Scalar t) const noexcept {
    TrajectorySample<Scalar, Dim> out;
    if (!(t >= Scalar(0)) || count_ == 0) {  // also catches NaN t
      out.pose = start_;
      out.segment = count_ == 0 ? -1 : 0;
      return out;
    }
    Scalar t0 = Scalar(0);
    for (int i = 0; i < count_; ++i) {
      const Segment& s = segments_[static_cast<std::size_t>(i)];
      if (t < t0 + s.duration) {
        sample_segment(i, t - t0, out);
        return out;
      }
      t0 += s.duration;
    }
    out.pose = end_pose_of(count_);
    out.segment = -1;
    return out;
  }

 private:
  void sample_segment(int i, Scalar local_t, TrajectorySample<Scalar, Dim>& out) const noexcept {
    const Segment& s = segments_[static_cast<std::size_t>(i)];
    Scalar sv = Scalar(0), ds = Scalar(0);
    Scalar rate = Scalar(1) / s.duration;  // dtau/dt
    if (s.kind == SegmentKind::reciprocate) {
      // Each cycle: out (first half) and back (second half).
      const Scalar cycle_t = s.duration / Scalar(s.cycles);
      Scalar u = std::fmod(local_t, cycle_t) / cycle_t;  // [0, 1)
      rate = Scalar(2) / cycle_t;
      Scalar m = Scalar(0), dm = Scalar(0);
      if (u < Scalar(0.5)) {
        minimum_jerk(Scalar(2) * u, m, dm);
        sv = m;
        ds = dm * rate;
      } else {
        minimum_jerk(Scalar(2) * u - Scalar(1), m, dm);
        sv = Scalar(1) - m;
        ds = -dm * rate;
      }
    } else if (s.kind != SegmentKind::hold) {
      minimum_jerk(local_t * rate, sv, ds);
      ds *= rate;
    }
    const Pose<Scalar, Dim>& p0 = segment_start_[static_cast<std::size_t>(i)];
    out.pose = displaced(p0, s.displacement, sv);
    out.twist = ds * s.displacement;
    out.segment = i;
  }

  static Pose<Scalar, Dim> displaced(const Pose<Scalar, Dim>& p0, const Twist<Scalar, Dim>& d,
                                     Scalar s) noexcept {
    Pose<Scalar, Dim> p;
    p.position = p0.position + s * d.template head<Dim>();
    p.rotation = rotation_exp<Scalar>(
                     AngularVector<Scalar, Dim>(s * d.template tail<SpatialDim<Dim>::kRot>())) *
                 p0.rotation;
    return p;
  }

  /// Pose at the end of the first `n` segments.
  Pose<Scalar, Dim> end_pose_of(int n) const noexcept {
    if (n == 0) return start_;
    const Segment& s = segments_[static_cast<std::size_t>(n - 1)];
    const Pose<Scalar, Dim>& p0 = segment_start_[static_cast<std::size_t>(n - 1)];
    const bool returns = s.kind == SegmentKind::reciprocate || s.kind == SegmentKind::hold;
    return returns ? p0 : displaced(p0, s.displacement, Scalar(1));
  }

  Pose<Scalar, Dim> start_{};
  std::array<Segment, static_cast<std::size_t>(MaxSegments)> segments_{};
  std::array<Pose<Scalar, Dim>, static_cast<std::size_t>(MaxSegments)> segment_start_{};
  int count_ = 0;
  Scalar total_ = Scalar(0);
};

}  // namespace inhand
