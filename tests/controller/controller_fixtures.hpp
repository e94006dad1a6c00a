// Shared fixtures for the inverse-kinematics, damped least-squares, servo and
// real-time tests: matrix shapes, matrices with prescribed singular values,
// double-precision reference solutions, and small finger chains.
//
// Fingers, the sweep multiplier and figure recording come from common/test_support.hpp.
// Every reference quantity is computed in double from the matrix actually handed to
// the code under test (after rounding to its scalar type), so float and double are
// judged against the truth for their own input.
#pragma once

#include <Eigen/Dense>
#include <Eigen/QR>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>

#include "common/test_support.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/damped_least_squares.hpp"

namespace inhand_ctl_test {

using Rng = std::mt19937_64;
using MatXd = Eigen::MatrixXd;
using VecXd = Eigen::VectorXd;

/// Number of random samples of a sweep: `base` times INHAND_TEST_SCALE.
inline int sweep_count(int base = 1000) { return inhand_test::scaled(base); }

/// Machine epsilon of a scalar type, as a double.
template <typename S>
constexpr double eps() {
  return static_cast<double>(std::numeric_limits<S>::epsilon());
}

inline double uniform(Rng& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

inline VecXd gaussian_vector(int n, Rng& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  VecXd v(n);
  for (int i = 0; i < n; ++i) v(i) = nd(rng);
  return v;
}

inline VecXd random_unit_vector(int n, Rng& rng) {
  VecXd v = gaussian_vector(n, rng);
  while (v.norm() < 1e-6) v = gaussian_vector(n, rng);
  return v.normalized();
}

/// Haar-distributed orthogonal n x n matrix (QR of a Gaussian matrix, sign-fixed).
inline MatXd random_orthogonal(int n, Rng& rng) {
  std::normal_distribution<double> nd(0.0, 1.0);
  MatXd g(n, n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) g(i, j) = nd(rng);
  Eigen::HouseholderQR<MatXd> qr(g);
  MatXd q = qr.householderQ() * MatXd::Identity(n, n);
  const MatXd r = qr.matrixQR().triangularView<Eigen::Upper>();
  for (int i = 0; i < n; ++i)
    if (r(i, i) < 0) q.col(i) = -q.col(i);
  return q;
}

/// k = min(m, n) singular values, log-uniform in [lo, hi], sorted descending.
inline VecXd random_singular_values(int k, double lo, double hi, Rng& rng) {
  VecXd s(k);
  for (int i = 0; i < k; ++i) s(i) = std::exp(uniform(rng, std::log(lo), std::log(hi)));
  std::sort(s.data(), s.data() + k, [](double a, double b) { return a > b; });
  return s;
}

/// A = U(:, 0:k) diag(s) V(:, 0:k)^T for the given orthogonal U (m x m), V (n x n).
inline MatXd compose(const MatXd& U, const VecXd& s, const MatXd& V) {
  const int k = static_cast<int>(s.size());
  return U.leftCols(k) * s.asDiagonal() * V.leftCols(k).transpose();
}

/// m x n matrix with exactly the singular values s (size min(m, n)).
inline MatXd matrix_with_singular_values(int m, int n, const VecXd& s, Rng& rng) {
  return compose(random_orthogonal(m, rng), s, random_orthogonal(n, rng));
}

/// Reference pseudo-inverse (Eigen's complete orthogonal decomposition).
inline MatXd reference_pinv(const MatXd& A) {
  Eigen::CompleteOrthogonalDecomposition<MatXd> cod(A);
  return cod.pseudoInverse();
}

inline VecXd singular_values(const MatXd& A) {
  Eigen::JacobiSVD<MatXd> svd(A);
  return svd.singularValues();
}
inline double sigma_min(const MatXd& A) { return singular_values(A).minCoeff(); }
inline double sigma_max(const MatXd& A) { return singular_values(A).maxCoeff(); }
inline double spectral_norm(const MatXd& A) {
  return A.size() == 0 ? 0.0 : singular_values(A).maxCoeff();
}

/// lambda^2 the damping schedule (threshold epsilon, max_damping l) assigns to sigma_min.
inline double schedule_damping_squared(double sigma_min, double threshold, double max_damping) {
  if (sigma_min >= threshold) return 0.0;
  const double r = sigma_min / threshold;
  return max_damping * max_damping * (1.0 - r * r);
}

/// Damped least-squares solution of A x = b for a given lambda^2, by SVD:
/// x = sum_i sigma_i / (sigma_i^2 + lambda^2) (u_i.b) v_i.
inline VecXd reference_damped_solve_l2(const MatXd& A, const VecXd& b, double l2) {
  Eigen::JacobiSVD<MatXd> svd(A, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const VecXd s = svd.singularValues();
  VecXd g(s.size());
  for (int i = 0; i < s.size(); ++i) g(i) = s(i) / (s(i) * s(i) + l2);
  return svd.matrixV() * (g.asDiagonal() * (svd.matrixU().transpose() * b));
}

/// Damped least-squares solution with the damping the schedule assigns to A's TRUE
/// smallest singular value.
inline VecXd reference_damped_solve(const MatXd& A, const VecXd& b, double threshold,
                                    double max_damping) {
  return reference_damped_solve_l2(A, b,
                                   schedule_damping_squared(sigma_min(A), threshold, max_damping));
}

/// A unit vector orthogonal to range(A) (A with more rows than columns).
inline VecXd unit_normal_to_range(const MatXd& A) {
  Eigen::JacobiSVD<MatXd> svd(A, Eigen::ComputeFullU);
  return svd.matrixU().col(A.rows() - 1);
}

/// Orthonormal basis of the null space of A (n x (n - rank)), rank taken as min(m, n).
inline MatXd null_space_basis(const MatXd& A) {
  Eigen::JacobiSVD<MatXd> svd(A, Eigen::ComputeFullV);
  const int k = static_cast<int>(std::min(A.rows(), A.cols()));
  return svd.matrixV().rightCols(A.cols() - k);
}

/// One matrix shape of the typed suites: M x N (N may be Eigen::Dynamic with a
/// capacity MaxN, fixed or Eigen::Dynamic), with the run-time column count RunN.
template <typename S, int M, int N, int MaxN = N, int RunN = N>
struct Shape {
  static_assert(RunN > 0, "run-time column count");
  using Scalar = S;
  static constexpr int kRows = M;
  static constexpr int kCols = RunN;
  using Ik = inhand::ContactIk<S, M, N, MaxN>;
  using Dls = inhand::DampedLeastSquares<S, M, N, MaxN>;
  using Jacobian = typename Ik::Jacobian;
  using JointVector = typename Ik::JointVector;
  using CartesianVector = typename Ik::CartesianVector;
  using PseudoInverse = typename Ik::PseudoInverse;

  static std::string name() {
    std::string s = std::is_same<S, float>::value ? "float_" : "double_";
    s += std::to_string(M) + "x" + std::to_string(RunN);
    if (N == Eigen::Dynamic)
      s += (MaxN == Eigen::Dynamic) ? "_dynamic" : "_bounded" + std::to_string(MaxN);
    return s;
  }
  static Ik make_ik(const inhand::IkParams<S>& p = {}) { return Ik(RunN, p); }
  static Dls make_dls() { return Dls(RunN); }
  static Jacobian jacobian(const MatXd& A) {
    // Element-wise: a cast-assignment into a run-time sized float matrix draws a GCC 12
    // -Wuse-after-free false positive from Eigen's resize path.
    Jacobian J(M, RunN);
    for (int c = 0; c < RunN; ++c)
      for (int r = 0; r < M; ++r) J(r, c) = static_cast<S>(A(r, c));
    return J;
  }
  static JointVector joint_vector(const VecXd& v) {
    JointVector q(RunN);
    for (int i = 0; i < RunN; ++i) q(i) = static_cast<S>(v(i));
    return q;
  }
  static JointVector constant_joints(S value) {
    JointVector q(RunN);
    q.setConstant(value);
    return q;
  }
  static JointVector no_limits() { return constant_joints(std::numeric_limits<S>::infinity()); }
  static CartesianVector cartesian(const VecXd& v) { return v.cast<S>(); }
};

/// gtest name generator for Shape and chain lists (the type's static name()).
struct TypeNames {
  template <typename T>
  static std::string GetName(int) {
    return T::name();
  }
};

/// A spatial finger with two joints (abduction and one flexion): its contact Jacobian
/// is 3 x 2, the least-squares case. Built from the first joints of the 3-DOF test
/// finger, with the second link ending in the fingertip.
template <typename S>
inhand::FingerChain<S, 3, 2> make_two_joint_spatial_finger() {
  auto spec = inhand_test::finger_spec<S, 3>(3);
  spec.joints.pop_back();
  spec.joint_to_tip.position = inhand::Vector<S, 3>(S(0), S(0), S(0.06));
  return inhand_test::to_chain<inhand::FingerChain<S, 3, 2>>(spec);
}

}  // namespace inhand_ctl_test
