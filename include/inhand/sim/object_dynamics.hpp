// Object dynamics of the analytic plant: one free rigid body, Newton-Euler with the
// world-frame inertia I_w = R I R^T. The state is (p, R, v, L) with L = I_w omega the
// world angular momentum; L_dot = tau is the Euler equation I_w omega_dot + omega x
// I_w omega = tau, gyroscopic term included. One step of length h (semi-implicit /
// symplectic Euler, rotation by a second-order midpoint rule on SO(3)):
//   v += h (F/m + g); L += h tau; p += h v;
//   omega_half = omega - (h/2) I_w^-1 (omega x L); R = exp(h omega_half) R.
//
// Units: SI (m, s, kg, N, N m, rad). Frames: p, R, v, omega, L, forces and torques in
// the WORLD frame, about the centre of mass (the object frame's origin); the principal
// inertia in the object frame.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/sim/plant_params.hpp"
#include "inhand/sim/shapes.hpp"

namespace inhand::plant::detail {

/// State of the free object.
struct RigidBody {
  Eigen::Vector3d inertia = Eigen::Vector3d::Ones();      ///< principal moments [kg m^2]
  Eigen::Vector3d inertia_inv = Eigen::Vector3d::Ones();  ///< their inverses
  Pose<double, 3> pose{};
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  Eigen::Vector3d omega = Eigen::Vector3d::Zero();
  Eigen::Vector3d momentum = Eigen::Vector3d::Zero();

  /// I_w w.
  Eigen::Vector3d world_inertia_times(const Eigen::Vector3d& w) const noexcept {
    return pose.rotation * inertia.cwiseProduct(pose.rotation.transpose() * w);
  }
  /// (R I R^T)^-1 L.
  Eigen::Vector3d omega_from(const Eigen::Matrix3d& R, const Eigen::Vector3d& L) const noexcept {
    return R * inertia_inv.cwiseProduct(R.transpose() * L);
  }

  /// One step of length h under the total force and torque (about the centre of mass)
  /// of the current state, and gravity.
  void step(double h, double mass, const Eigen::Vector3d& force, const Eigen::Vector3d& torque,
            const Eigen::Vector3d& gravity) noexcept {
    velocity += h * (force / mass + gravity);
    momentum += h * torque;
    pose.position += h * velocity;
    const Eigen::Matrix3d R0 = pose.rotation;
    const Eigen::Vector3d w0 = omega_from(R0, momentum);
    // omega at the half step to O(h^2): omega_dot = -I_w^-1 (omega x L) with L already
    // holding this step's torque impulse (the Euler equation's gyroscopic term).
    const Eigen::Vector3d w_half = w0 - (0.5 * h) * omega_from(R0, w0.cross(momentum));
    Eigen::Matrix3d R1 = so3_exp<double>(Eigen::Vector3d(h * w_half)) * R0;
    // One Newton step towards orthonormality keeps rounding from accumulating.
    R1 = R1 * (1.5 * Eigen::Matrix3d::Identity() - 0.5 * (R1.transpose() * R1));
    pose.rotation = R1;
    omega = omega_from(R1, momentum);
  }
};

/// The smallest of the mass and I_j / rho_j^2 (rho_j the largest distance of the surface
/// from principal axis j) [kg]: the mass a contact spring acts on at worst.
inline double effective_mass(const ObjectDef& object) noexcept {
  const Eigen::Vector3d I = object.shape.principal_inertia(object.mass);
  const ObjectShape& s = object.shape;
  Eigen::Vector3d rho2 =
      Eigen::Vector3d::Ones();  // squared largest surface distance from each axis
  switch (s.kind) {
    case ObjectShape::Kind::sphere:
      rho2.setConstant(s.radius * s.radius);
      break;
    case ObjectShape::Kind::box: {
      const Eigen::Vector3d e = s.half_extents.cwiseAbs2();
      rho2 = Eigen::Vector3d(e.y() + e.z(), e.x() + e.z(), e.x() + e.y());
      break;
    }
    case ObjectShape::Kind::cylinder: {
      const double r2 = s.radius * s.radius, h2 = s.half_length * s.half_length;
      rho2 = Eigen::Vector3d(r2 + h2, r2 + h2, r2);
      break;
    }
  }
  return std::min(object.mass, I.cwiseQuotient(rho2).minCoeff());
}

/// Checks the fingers, the object, the parameters and the explicit-integration
/// stability of the contact springs on this object: with N fingers, K = N max(k_n,
/// k_t), C = N max(c_n, c_t) and m_eff the smallest of the mass and I_j / rho_j^2
/// (rho_j the largest distance of the surface from principal axis j), it requires
/// h sqrt(K / m_eff) <= 0.5 and h C / m_eff <= 1.
inline Validation validate_plant_setup(const std::vector<PlantFinger>& fingers,
                                       const ObjectDef& object,
                                       const PlantParams& params) noexcept {
  if (fingers.empty()) return Validation::invalid("fingers", "need at least one finger");
  for (std::size_t i = 0; i < fingers.size(); ++i) {
    const Validation v = fingers[i].validate();
    if (!v.ok()) return v.for_finger(static_cast<int>(i));
    if (!(fingers[i].fingertip_radius > 0.0))
      return Validation::invalid("fingertip_radius", "must be > 0", -1, static_cast<int>(i));
  }
  Validation v = object.validate();
  if (!v.ok()) return v;
  v = params.validate();
  if (!v.ok()) return v;
  const double n = static_cast<double>(fingers.size());
  const ContactParams& c = params.contact;
  const double K = n * std::max(c.normal_stiffness, c.tangential_stiffness);
  const double C = n * std::max(c.normal_damping, c.tangential_damping);
  const double m_eff = detail::effective_mass(object);
  const double h = params.time_step;
  if (h * std::sqrt(K / m_eff) > 0.5)
    return Validation::invalid("time_step", "too large for the contact stiffness on this object");
  if (h * C / m_eff > 1.0)
    return Validation::invalid("time_step", "too large for the contact damping on this object");
  return Validation::valid();
}

}  // namespace inhand::plant::detail
