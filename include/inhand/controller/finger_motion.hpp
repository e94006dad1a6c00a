// Layer 2, per finger: where the finger is servoed and the Jacobian of that point,
// from either kinematics source -- the one place the source is resolved
// (docs/method.md sections 2 and 8).
//
// The servoed point, world frame [m]:
//   manipulation, touching  the measured contact point p_c (eq. 2 is evaluated there);
//   grasp phase, touching   the fingertip sphere's centre (the object is held, so the
//                           contact LOCATION follows the centre, not a material point);
//   not touching            the virtual contact point: the fingertip surface point that
//                           faces an object whose outward normal there is n,
//                           centre - radius * n.
// KinematicsSource::chain computes the centre, the virtual point and the Jacobian from
// the finger's chain after forward kinematics; KinematicsSource::external takes them
// from the FingerInput (the Jacobian and the virtual contact point as given; the
// centre is the measured contact point, since the user's Jacobian is of that point).
// noexcept, no allocation.
#pragma once

#include <cmath>

#include "inhand/controller/controller_io.hpp"
#include "inhand/kinematics/finger_chain.hpp"

namespace inhand {

/// One finger's kinematics this tick, resolved from its configured source.
template <typename Types>
class FingerPoints {
 public:
  using Scalar = typename Types::Chain::Scalar;
  using Vec = typename Types::Vec;
  using Kinematics = FingerKinematics<typename Types::Chain>;

  /// Chain fingers: `kin` already holds forward kinematics at the measured joint
  /// positions (the controller's tick runs them for the whole hand first,
  /// hand_kinematics.hpp).
  FingerPoints(const typename Types::FingerConfig& config, const typename Types::FingerInput& input,
               const Kinematics& kin) noexcept
      : config_(config), input_(input), kin_(kin) {}

  /// Chain fingers touching: whether the measured contact is implausible for the
  /// fingertip sphere (ControllerConfig::contact_tolerance). External: never.
  bool implausible_contact(Scalar tolerance) const noexcept {
    if (!chain() || !input_.contact.touching) return false;
    const Vec d = kin_.fingertip.position - input_.contact.contact_point;
    return std::abs(d.norm() - config_.chain.fingertip_radius) > tolerance ||
           input_.contact.normal.dot(d) < Scalar(0);
  }
  /// The fingertip sphere's centre (external: the measured contact point).
  Vec centre() const noexcept {
    return chain() ? kin_.fingertip.position : input_.contact.contact_point;
  }
  /// The virtual contact point facing an object whose outward normal there is n.
  Vec virtual_point(const Vec& n) const noexcept {
    return chain() ? fingertip_surface_point(config_.chain, kin_, n) : input_.virtual_contact_point;
  }
  /// The point a finger that misses is judged by (grasp.hpp): the fingertip sphere's centre
  /// (external: the virtual contact point, the only point known without contact).
  Vec miss_point() const noexcept {
    return chain() ? kin_.fingertip.position : input_.virtual_contact_point;
  }
  /// The Jacobian (Dim x DOF) of the point p attached to the fingertip.
  void jacobian(const Vec& p, typename Types::Jacobian& J) const noexcept {
    if (chain()) {
      point_jacobian(kin_, p, J);
    } else {
      J = input_.jacobian;
    }
  }

 private:
  bool chain() const noexcept { return config_.kinematics == KinematicsSource::chain; }
  const typename Types::FingerConfig& config_;
  const typename Types::FingerInput& input_;
  const Kinematics& kin_;
};

}  // namespace inhand
