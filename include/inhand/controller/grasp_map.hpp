// Layer 2: the grasp map of the touching fingers' normal forces, and the split of the
// normal-force space into rigid and internal parts (docs/method.md section 5,
// docs/force_layer.md).
//
// Frames, units, signs: world frame, SI. n_i is the object's OUTWARD unit normal at
// finger i's contact, p_i the contact point, p_o the object's reference point. Row i
// of A (NumFingers x W, W = 6 in 3-D, 3 in the plane) is
//   [n_i^T, ((p_i - p_o) x n_i)^T / L]
// (zero for a finger that does not touch), L the RMS lever arm of the touching
// contacts (bounded below by 1e-6 m), so both halves are dimensionless. A^T f is the
// wrench of normal forces f (force; torque / L); A V is the normal velocity at the
// contacts of the object's material points for the twist V.
//   rigid    : range(A)   -- forces with a resultant wrench on the object
//   internal : null(A^T)  -- squeezing that leaves the object in equilibrium
//   P_int = I - A (A^T A + eps I)^-1 A^T   (eps > 0 keeps it defined when A is
//                                           rank-deficient: fewer than W contacts)
// A direction of A^T with singular value sigma counts as rigid by the fraction
// sigma^2 / (sigma^2 + eps): one whose wrench is small (sigma << sqrt(eps): nearly
// collinear normals whose tilt, or lever, is a few per cent) stays internal, so that
// squeezing a grasp whose contacts lie slightly off the object's equator is still a
// squeeze. The projection never holds a rigid component: it shrinks it by
// eps / (sigma^2 + eps) < 1 every tick.
// Evaluated as P_int = eps (A A^T + eps I)^-1 (the same matrix: A (A^T A + eps I)^-1 =
// (A A^T + eps I)^-1 A), an n x n system for n fingers instead of a W x W one: build()
// factorises A A^T + eps I (Cholesky; its eigenvalues are >= eps > 0) once per tick, and
// project_internal() is two triangular substitutions. noexcept; fixed finger counts never
// allocate.
#pragma once

#include <cmath>

#include "inhand/math/types.hpp"

namespace inhand {

template <typename Scalar, int Dim, int NumFingers>
class GraspMap {
 public:
  static constexpr int W = SpatialDim<Dim>::kTwist;  ///< wrench size
  static constexpr int R = SpatialDim<Dim>::kRot;
  using ForceVector = Eigen::Matrix<Scalar, NumFingers, 1>;
  using Points = Eigen::Matrix<Scalar, Dim, NumFingers>;  ///< one column per finger
  using Mask = Eigen::Matrix<unsigned char, NumFingers, 1>;
  using Wrench = Eigen::Matrix<Scalar, W, 1>;  ///< (force; torque about p_o)
  using Vec = Vector<Scalar, Dim>;

  /// Sizes the map (allocates only for a run-time finger count).
  void resize(int fingers) {
    a_.setZero(fingers, W);
    chol_.setIdentity(fingers, fingers);  // with eps_ = 1: P_int = I until build()
    inv_diag_.setOnes(fingers);
  }

  /// Builds A for the touching fingers (columns of `points` / `normals` of the others
  /// are ignored) and factorises A A^T + eps I (eps > 0).
  void build(const Mask& touching, const Points& points, const Points& normals,
             const Vec& object_position, Scalar eps) noexcept {
    const int n = static_cast<int>(a_.rows());
    Scalar sum = Scalar(0);
    int k = 0;
    for (int i = 0; i < n; ++i) {
      if (!touching(i)) continue;
      sum += (points.col(i) - object_position).squaredNorm();
      ++k;
    }
    lever_ = k > 0 ? std::sqrt(sum / Scalar(k)) : Scalar(0);
    if (!(lever_ > Scalar(1e-6))) lever_ = Scalar(1e-6);
    for (int i = 0; i < n; ++i) {
      if (!touching(i)) {
        a_.row(i).setZero();
        continue;
      }
      const Vec nrm = normals.col(i);
      a_.row(i).template head<Dim>() = nrm.transpose();
      a_.row(i).template tail<R>() =
          (moment(Vec(points.col(i) - object_position), nrm) / lever_).transpose();
    }
    eps_ = eps;
    // Lower Cholesky factor of A A^T + eps I into chol_, column by column (a row of a
    // finger that does not touch is zero: its pivot is sqrt(eps), its column zero below).
    for (int c = 0; c < n; ++c) {
      Scalar d = a_.row(c).squaredNorm() + eps;
      for (int p = 0; p < c; ++p) d -= chol_(c, p) * chol_(c, p);
      d = std::sqrt(d);
      chol_(c, c) = d;
      inv_diag_(c) = Scalar(1) / d;
      for (int r = c + 1; r < n; ++r) {
        Scalar v = a_.row(r).dot(a_.row(c));
        for (int p = 0; p < c; ++p) v -= chol_(r, p) * chol_(c, p);
        chol_(r, c) = v * inv_diag_(c);
      }
    }
  }

  /// x <- P_int x = eps (A A^T + eps I)^-1 x.
  void project_internal(ForceVector& x) const noexcept {
    const int n = static_cast<int>(x.size());
    for (int r = 0; r < n; ++r) {  // L y = x
      Scalar v = x(r);
      for (int p = 0; p < r; ++p) v -= chol_(r, p) * x(p);
      x(r) = v * inv_diag_(r);
    }
    for (int r = n - 1; r >= 0; --r) {  // L^T z = y
      Scalar v = x(r);
      for (int p = r + 1; p < n; ++p) v -= chol_(p, r) * x(p);
      x(r) = v * inv_diag_(r);
    }
    x *= eps_;
  }

  /// The wrench (force N; torque N m about p_o) that normal forces f balance:
  /// sum f_i [n_i; (p_i - p_o) x n_i].
  Wrench balanced_wrench(const ForceVector& f) const noexcept {
    Wrench w;
    w.noalias() = a_.transpose() * f;
    w.template tail<R>() *= lever_;
    return w;
  }

  Scalar lever() const noexcept { return lever_; }  ///< L [m]

 private:
  static AngularVector<Scalar, Dim> moment(const Vector<Scalar, 3>& r,
                                           const Vector<Scalar, 3>& n) noexcept {
    return r.cross(n);
  }
  static AngularVector<Scalar, Dim> moment(const Vector<Scalar, 2>& r,
                                           const Vector<Scalar, 2>& n) noexcept {
    return AngularVector<Scalar, Dim>(r.x() * n.y() - r.y() * n.x());
  }

  Eigen::Matrix<Scalar, NumFingers, W> a_;
  Eigen::Matrix<Scalar, NumFingers, NumFingers> chol_;  ///< lower factor of A A^T + eps I
  ForceVector inv_diag_;                                ///< 1 / its diagonal
  Scalar eps_ = Scalar(1);
  Scalar lever_ = Scalar(1);
};

/// The shift delta [m] of balancing finger b's contact, in its tangent plane, that removes
/// the couple of the normal forces `pattern` (n, N) across n_b (grasp.hpp, "A squeeze
/// without a couple"). points, normals: Dim x n, world frame, OUTWARD unit normals; the
/// force of finger i on the object is -pattern_i n_i. With M = sum_i q_i (p_i - c) x (-n_i),
/// c the q-weighted centroid of the points, moving b by delta changes M by
/// -q_b delta x n_b, so delta = n_b x M / q_b leaves (M . n_b) n_b, since
/// (n x M) x n = M - (M . n) n: exact on a flat face, a first step on a curved one (the
/// normal turns as b moves). Planar (Dim 2): M about z. Zero unless q_b > 0. noexcept.
template <typename Scalar, int Dim, typename DerivedP, typename DerivedN, typename DerivedQ>
Vector<Scalar, Dim> balancing_shift(const Eigen::MatrixBase<DerivedP>& points,
                                    const Eigen::MatrixBase<DerivedN>& normals,
                                    const Eigen::MatrixBase<DerivedQ>& pattern, int b) noexcept {
  using V3 = Vector<Scalar, 3>;
  const auto lift = [](const auto& v) {  // a point or vector of the plane in space
    V3 r = V3::Zero();
    r.template head<Dim>() = v;
    return r;
  };
  const int n = static_cast<int>(pattern.size());
  Scalar sum = Scalar(0);
  V3 c = V3::Zero();
  for (int i = 0; i < n; ++i) {
    sum += pattern(i);
    c += pattern(i) * lift(points.col(i));
  }
  if (!(pattern(b) > Scalar(0)) || !(sum > Scalar(0))) return Vector<Scalar, Dim>::Zero();
  c /= sum;
  V3 m = V3::Zero();
  for (int i = 0; i < n; ++i)
    m += pattern(i) * (lift(points.col(i)) - c).cross(V3(-lift(normals.col(i))));
  return (lift(normals.col(b)).cross(m) / pattern(b)).template head<Dim>();
}

}  // namespace inhand
