// Shared support for the inhand test suites: the sweep-size multiplier, seeded
// random numbers, and a small zoo of realistic fingers.
//
// Units: metres, radians, seconds (as in the library).
// Sweep size: randomized tests run `scaled(n)` cases, n times the integer
// multiplier read from the environment variable INHAND_TEST_SCALE (default 1).
// Random numbers: every test seeds its own Rng explicitly, so a failure
// reproduces exactly; the seed is part of each test's source.
//
// Fingers (make_finger): each finger is described in its own finger frame, where
// the links extend along +x (planar) or +z (spatial), and is placed in the world by
// a non-trivial base pose. Spatial fingers follow the human (and Shadow hand)
// layout: an abduction joint about the finger frame's y axis, then flexion joints
// about x (positive flexion curls the tip towards -y, the palm side), with short
// links of 3-5 cm. The 5-DOF finger is a Shadow-style thumb with a general
// (not axis-aligned) base axis. Some joint frames carry a small twist about the
// link axis, and the fingertip frame carries a rotation, so that code mapping the
// description to another library has to get parent_to_joint, axis and joint_to_tip
// right. By construction every finger is FULLY STRETCHED at q = 0 (all joint frames
// on one straight line): a singular configuration of the contact Jacobian.
//
// Chain types: the same geometry is available as an exact-DOF chain
// (FingerChain<S, Dim, n>), a run-time DOF chain with fixed capacity
// (FingerChain<S, 3, Dynamic, 5>), and a heap-sized chain (FingerChain<S, 3, Dynamic>).
// Run-time DOF chains default to the 4-DOF spatial finger (3-DOF planar finger).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "inhand/kinematics/finger_chain.hpp"

namespace inhand_test {

// ---------------------------------------------------------------------------
// Sweep size

/// Integer multiplier of randomized sweep sizes, from INHAND_TEST_SCALE (>= 1).
/// Unset, empty, unparsable or < 1 means 1; fractional values round up.
inline int scale() {
  static const int value = [] {
    const char* env = std::getenv("INHAND_TEST_SCALE");
    if (env == nullptr || *env == '\0') return 1;
    char* end = nullptr;
    const double v = std::strtod(env, &end);
    if (end == env || !(v >= 1.0)) return 1;
    return static_cast<int>(std::min(std::ceil(v), 1.0e6));
  }();
  return value;
}

/// `base_count` cases times scale().
inline int scaled(int base_count) { return base_count * scale(); }

/// Records a measured figure (an error bound actually reached, a count) as a test
/// property in the XML/JSON report and prints it, so runs document their margins.
inline void record(const std::string& key, double value) {
  std::ostringstream text;
  if (value == std::floor(value) && std::abs(value) < 1e15) {
    text << static_cast<long long>(value);  // counts
  } else {
    text.precision(3);
    text << value;
  }
  ::testing::Test::RecordProperty(key, text.str());
  const ::testing::TestInfo* info = ::testing::UnitTest::GetInstance()->current_test_info();
  std::cout << "[ measured ] " << (info != nullptr ? info->test_suite_name() : "") << "."
            << (info != nullptr ? info->name() : "") << ": " << key << " = " << text.str() << "\n";
}

// ---------------------------------------------------------------------------
// Random numbers

using Rng = std::mt19937_64;

/// A generator with a fixed seed (each test picks its own seed).
inline Rng make_rng(std::uint64_t seed) { return Rng(seed); }

/// Uniform in [lo, hi] (drawn in double, then converted and clamped to the range).
template <typename Scalar>
Scalar uniform(Rng& rng, Scalar lo, Scalar hi) {
  std::uniform_real_distribution<double> d(static_cast<double>(lo), static_cast<double>(hi));
  const Scalar x = static_cast<Scalar>(d(rng));
  return std::min(std::max(x, lo), hi);
}

/// Log-uniform in [lo, hi], 0 < lo <= hi: every decade equally likely.
template <typename Scalar>
Scalar log_uniform(Rng& rng, Scalar lo, Scalar hi) {
  const double e =
      uniform<double>(rng, std::log(static_cast<double>(lo)), std::log(static_cast<double>(hi)));
  return std::min(std::max(static_cast<Scalar>(std::exp(e)), lo), hi);
}

/// Vector with independent entries uniform in [lo, hi].
template <typename Scalar, int N>
Eigen::Matrix<Scalar, N, 1> random_vector(Rng& rng, Scalar lo, Scalar hi) {
  Eigen::Matrix<Scalar, N, 1> v;
  for (int i = 0; i < N; ++i) v(i) = uniform<Scalar>(rng, lo, hi);
  return v;
}

/// Unit vector uniformly distributed on the sphere (N = 3) or circle (N = 2).
template <typename Scalar, int N = 3>
Eigen::Matrix<Scalar, N, 1> random_unit_vector(Rng& rng) {
  std::normal_distribution<double> g(0.0, 1.0);
  Eigen::Matrix<double, N, 1> v;
  do {
    for (int i = 0; i < N; ++i) v(i) = g(rng);
  } while (v.norm() < 1e-6);
  return (v / v.norm()).template cast<Scalar>().normalized();
}

/// Rotation uniformly distributed on SO(3) (unit quaternion from a 4-D Gaussian).
template <typename Scalar>
inhand::Rotation<Scalar, 3> random_rotation(Rng& rng) {
  const Eigen::Matrix<double, 4, 1> q = random_unit_vector<double, 4>(rng);
  const Eigen::Quaternion<double> quat(q(0), q(1), q(2), q(3));
  return quat.toRotationMatrix().template cast<Scalar>();
}

/// Random rotation in the plane or in space.
template <typename Scalar, int Dim>
inhand::Rotation<Scalar, Dim> random_rotation_dim(Rng& rng) {
  if constexpr (Dim == 2) {
    return inhand::so2_exp<Scalar>(uniform<Scalar>(rng, Scalar(-3.14159), Scalar(3.14159)));
  } else {
    return random_rotation<Scalar>(rng);
  }
}

/// Random pose: position entries uniform in [-max_offset, max_offset], uniform rotation.
template <typename Scalar, int Dim>
inhand::Pose<Scalar, Dim> random_pose(Rng& rng, Scalar max_offset = Scalar(0.2)) {
  inhand::Pose<Scalar, Dim> p;
  p.position = random_vector<Scalar, Dim>(rng, -max_offset, max_offset);
  p.rotation = random_rotation_dim<Scalar, Dim>(rng);
  return p;
}

// ---------------------------------------------------------------------------
// Fingers

/// Plain description of one finger, independent of the chain's DOF storage.
template <typename Scalar, int Dim>
struct FingerSpec {
  inhand::Pose<Scalar, Dim> base{};
  std::vector<inhand::JointDescription<Scalar, Dim>> joints;
  inhand::Pose<Scalar, Dim> joint_to_tip{};
  Scalar fingertip_radius = Scalar(0.01);
};

namespace detail {

inline Eigen::Matrix3d rot(double angle, const Eigen::Vector3d& axis) {
  return Eigen::AngleAxisd(angle, axis.normalized()).toRotationMatrix();
}

template <typename Scalar, int Dim>
inhand::Pose<Scalar, Dim> pose_from(const Eigen::Matrix<double, Dim, 1>& p,
                                    const Eigen::Matrix<double, Dim, Dim>& R) {
  inhand::Pose<Scalar, Dim> out;
  out.position = p.template cast<Scalar>();
  out.rotation = R.template cast<Scalar>();
  return out;
}

template <typename Scalar, int Dim>
inhand::JointDescription<Scalar, Dim> joint(const inhand::Pose<Scalar, Dim>& parent_to_joint,
                                            const Eigen::Vector3d& axis, double lower, double upper,
                                            double max_velocity) {
  inhand::JointDescription<Scalar, Dim> j;
  j.parent_to_joint = parent_to_joint;
  j.axis = axis.normalized().template cast<Scalar>().normalized();
  j.lower = static_cast<Scalar>(lower);
  j.upper = static_cast<Scalar>(upper);
  j.max_velocity = static_cast<Scalar>(max_velocity);
  return j;
}

template <typename Scalar>
inhand::Pose<Scalar, 3> spatial(double x, double y, double z,
                                const Eigen::Matrix3d& R = Eigen::Matrix3d::Identity()) {
  return pose_from<Scalar, 3>(Eigen::Vector3d(x, y, z), R);
}
template <typename Scalar>
inhand::Pose<Scalar, 2> planar(double x, double y, double angle = 0.0) {
  return pose_from<Scalar, 2>(Eigen::Vector2d(x, y), Eigen::Rotation2Dd(angle).toRotationMatrix());
}

}  // namespace detail

/// The built-in finger with `dof` joints: planar dof 2 or 3, spatial dof 3, 4 or 5.
/// Throws std::invalid_argument for other counts.
template <typename Scalar, int Dim>
FingerSpec<Scalar, Dim> finger_spec(int dof) {
  using detail::joint;
  FingerSpec<Scalar, Dim> f;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  if constexpr (Dim == 2) {
    using detail::planar;
    if (dof == 2) {
      // Two-link planar finger (proximal 4.5 cm, distal 3.5 cm to the tip centre).
      f.base = planar<Scalar>(0.03, -0.06, 0.4);
      f.joints.push_back(joint<Scalar, 2>(planar<Scalar>(0, 0), ez, -0.5, 1.6, 3.0));
      f.joints.push_back(joint<Scalar, 2>(planar<Scalar>(0.045, 0), ez, 0.0, 1.8, 4.0));
      f.joint_to_tip = planar<Scalar>(0.035, 0, 0.3);
      f.fingertip_radius = Scalar(0.008);
    } else if (dof == 3) {
      // Three-link planar finger; the distal joint's axis is -z (flexion is q < 0).
      f.base = planar<Scalar>(-0.02, 0.07, -0.9);
      f.joints.push_back(joint<Scalar, 2>(planar<Scalar>(0, 0), ez, -0.6, 1.6, 3.0));
      f.joints.push_back(joint<Scalar, 2>(planar<Scalar>(0.045, 0), ez, 0.0, 1.7, 3.5));
      f.joints.push_back(joint<Scalar, 2>(planar<Scalar>(0.035, 0), -ez, -1.6, 0.2, 4.0));
      f.joint_to_tip = planar<Scalar>(0.03, 0, -0.2);
      f.fingertip_radius = Scalar(0.008);
    } else {
      throw std::invalid_argument("planar test fingers have 2 or 3 joints");
    }
  } else {
    using detail::rot;
    using detail::spatial;
    if (dof == 3) {
      // Abduction + two flexion joints (proximal 5 cm, distal 4 cm to the tip centre).
      f.base = spatial<Scalar>(0.0, 0.03, 0.095, rot(0.35, Eigen::Vector3d(0.3, -1.0, 0.5)));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0), ey, -0.35, 0.35, 3.0));
      f.joints.push_back(
          joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.005, rot(0.08, ez)), ex, -0.26, 1.57, 3.5));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.05), ex, 0.0, 1.75, 4.0));
      f.joint_to_tip = spatial<Scalar>(0, 0, 0.04, rot(0.4, Eigen::Vector3d(1.0, 0.5, -0.2)));
      f.fingertip_radius = Scalar(0.01);
    } else if (dof == 4) {
      // Index finger: abduction and MCP flexion at the knuckle, PIP, DIP
      // (links 4.5 cm, 3.5 cm, 3 cm to the tip centre).
      f.base = spatial<Scalar>(0.033, -0.01, 0.095, rot(0.2, Eigen::Vector3d(1.0, 2.0, 3.0)));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0), ey, -0.35, 0.35, 3.0));
      f.joints.push_back(
          joint<Scalar, 3>(spatial<Scalar>(0, 0, 0, rot(-0.05, ez)), ex, -0.26, 1.57, 3.5));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.045), ex, 0.0, 1.57, 4.0));
      f.joints.push_back(
          joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.035, rot(0.04, ez)), ex, 0.0, 1.57, 4.5));
      f.joint_to_tip = spatial<Scalar>(0, 0, 0.03, rot(-0.6, Eigen::Vector3d(0.2, 1.0, 0.1)));
      f.fingertip_radius = Scalar(0.01);
    } else if (dof == 5) {
      // Shadow-style thumb: base rotation about a general axis, abduction, a
      // two-axis hub after the proximal link, and the distal flexion
      // (links 3.8 cm, 3.2 cm, 2.75 cm to the tip centre).
      f.base =
          spatial<Scalar>(0.034, -0.0085, 0.029, rot(-0.785, ey) * rot(0.3, ex) * rot(0.5, ez));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0), Eigen::Vector3d(0.1, -0.2, 1.0),
                                          -1.047, 1.047, 2.0));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0), ex, 0.0, 1.222, 2.5));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.038), ey, -0.209, 0.209, 3.0));
      f.joints.push_back(
          joint<Scalar, 3>(spatial<Scalar>(0, 0, 0, rot(0.1, ez)), ex, -0.698, 0.698, 3.0));
      f.joints.push_back(joint<Scalar, 3>(spatial<Scalar>(0, 0, 0.032), ex, -0.262, 1.571, 4.0));
      f.joint_to_tip = spatial<Scalar>(0, 0, 0.0275, rot(0.9, Eigen::Vector3d(-0.3, 0.2, 1.0)));
      f.fingertip_radius = Scalar(0.011);
    } else {
      throw std::invalid_argument("spatial test fingers have 3, 4 or 5 joints");
    }
  }
  return f;
}

/// Joint count make_finger<Chain>() uses when none is given.
template <typename Chain>
constexpr int default_dof() {
  if constexpr (Chain::Dof != inhand::Dynamic) {
    return Chain::Dof;
  } else {
    constexpr int preferred = Chain::Dim == 2 ? 3 : 4;
    return (Chain::MaxDof == inhand::Dynamic || Chain::MaxDof >= preferred) ? preferred
                                                                            : Chain::MaxDof;
  }
}

/// Joint counts of the built-in fingers that a Chain type can hold.
template <typename Chain>
std::vector<int> supported_dofs() {
  const std::vector<int> all = Chain::Dim == 2 ? std::vector<int>{2, 3} : std::vector<int>{3, 4, 5};
  std::vector<int> out;
  for (int n : all) {
    const bool fits = Chain::Dof != inhand::Dynamic
                          ? n == Chain::Dof
                          : (Chain::MaxDof == inhand::Dynamic || n <= Chain::MaxDof);
    if (fits) out.push_back(n);
  }
  return out;
}

/// Copies a FingerSpec into a chain of any DOF mode. Throws if it does not fit.
template <typename Chain>
Chain to_chain(const FingerSpec<typename Chain::Scalar, Chain::Dim>& spec) {
  Chain chain;
  const int n = static_cast<int>(spec.joints.size());
  if (!chain.joints.resize(n))
    throw std::invalid_argument("joint count does not fit the chain type");
  chain.base = spec.base;
  for (int i = 0; i < n; ++i) chain.joints[i] = spec.joints[static_cast<std::size_t>(i)];
  chain.joint_to_tip = spec.joint_to_tip;
  chain.fingertip_radius = spec.fingertip_radius;
  return chain;
}

/// The built-in finger with `dof` joints as a Chain (FingerChain<S, Dim, Dof, MaxDof>).
template <typename Chain>
Chain make_finger(int dof = default_dof<Chain>()) {
  return to_chain<Chain>(finger_spec<typename Chain::Scalar, Chain::Dim>(dof));
}

/// Joint angles uniform within the chain's joint limits.
template <typename Chain>
typename Chain::JointVector random_joint_angles(const Chain& chain, Rng& rng) {
  typename Chain::JointVector q(chain.dof());
  for (int i = 0; i < chain.dof(); ++i) {
    q(i) = uniform<typename Chain::Scalar>(rng, chain.joints[i].lower, chain.joints[i].upper);
  }
  return q;
}

/// Joint velocities with entries uniform in [-fraction * limit, fraction * limit].
template <typename Chain>
typename Chain::JointVector random_joint_velocities(const Chain& chain, Rng& rng,
                                                    typename Chain::Scalar fraction = 1) {
  typename Chain::JointVector v(chain.dof());
  for (int i = 0; i < chain.dof(); ++i) {
    const auto m = fraction * chain.joints[i].max_velocity;
    v(i) = uniform<typename Chain::Scalar>(rng, -m, m);
  }
  return v;
}

/// A point on the fingertip sphere in FINGERTIP-FRAME coordinates (|p| = radius).
/// ws.fingertip.transform_point(p) is its world position; it is rigidly attached to
/// the distal link, so the contact Jacobian at that world point gives its velocity.
template <typename Chain>
inhand::Vector<typename Chain::Scalar, Chain::Dim> random_fingertip_offset(const Chain& chain,
                                                                           Rng& rng) {
  return chain.fingertip_radius * random_unit_vector<typename Chain::Scalar, Chain::Dim>(rng);
}

/// Whether two forward-kinematics workspaces hold the same bits.
template <typename Chain>
bool same_bits(const inhand::FingerKinematics<Chain>& a, const inhand::FingerKinematics<Chain>& b) {
  auto same = [](const auto& x, const auto& y) {
    return x.size() == y.size() &&
           std::memcmp(x.data(), y.data(),
                       sizeof(typename Chain::Scalar) * static_cast<std::size_t>(x.size())) == 0;
  };
  return same(a.joint_origins, b.joint_origins) && same(a.joint_axes, b.joint_axes) &&
         same(a.fingertip.position, b.fingertip.position) &&
         same(a.fingertip.rotation, b.fingertip.rotation);
}

// ---------------------------------------------------------------------------
// Typed-suite support

template <typename Scalar>
using Planar2 = inhand::FingerChain<Scalar, 2, 2>;
template <typename Scalar>
using Planar3 = inhand::FingerChain<Scalar, 2, 3>;
template <typename Scalar>
using Spatial3 = inhand::FingerChain<Scalar, 3, 3>;
template <typename Scalar>
using Spatial4 = inhand::FingerChain<Scalar, 3, 4>;
template <typename Scalar>
using Spatial5 = inhand::FingerChain<Scalar, 3, 5>;
/// Heap-sized run-time DOF (make_finger builds the 4-DOF finger by default).
template <typename Scalar>
using SpatialDynamic = inhand::FingerChain<Scalar, 3, inhand::Dynamic>;
/// Run-time DOF with capacity 5 (make_finger builds the 4-DOF finger by default).
template <typename Scalar>
using SpatialBounded = inhand::FingerChain<Scalar, 3, inhand::Dynamic, 5>;

/// Every finger chain instantiation, float and double.
using AllFingerChains =
    ::testing::Types<Planar2<float>, Planar2<double>, Planar3<float>, Planar3<double>,
                     Spatial3<float>, Spatial3<double>, Spatial4<float>, Spatial4<double>,
                     Spatial5<float>, Spatial5<double>, SpatialDynamic<float>,
                     SpatialDynamic<double>, SpatialBounded<float>, SpatialBounded<double>>;
/// The double-precision instantiations only.
using DoubleFingerChains =
    ::testing::Types<Planar2<double>, Planar3<double>, Spatial3<double>, Spatial4<double>,
                     Spatial5<double>, SpatialDynamic<double>, SpatialBounded<double>>;

/// Readable name of a chain type, e.g. "spatial4_double", "spatial_dyn5_float".
template <typename Chain>
std::string chain_name() {
  std::string s = Chain::Dim == 2 ? "planar" : "spatial";
  if (Chain::Dof != inhand::Dynamic) {
    s += std::to_string(Chain::Dof);
  } else if (Chain::MaxDof == inhand::Dynamic) {
    s += "_dyn";
  } else {
    s += "_dyn" + std::to_string(Chain::MaxDof);
  }
  s += std::is_same<typename Chain::Scalar, float>::value ? "_float" : "_double";
  return s;
}

/// Name generator for TYPED_TEST_SUITE(Suite, Types, inhand_test::ChainNames).
struct ChainNames {
  template <typename Chain>
  static std::string GetName(int) {
    return chain_name<Chain>();
  }
};

/// Name generator for suites typed on a bare Scalar (float, double).
struct ScalarNames {
  template <typename Scalar>
  static std::string GetName(int) {
    return std::is_same<Scalar, float>::value ? "float" : "double";
  }
};

}  // namespace inhand_test
