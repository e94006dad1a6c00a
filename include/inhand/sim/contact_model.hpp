// Contact model of the analytic plant, one contact per finger: penetration delta = r_tip -
// signed_distance(tip centre) (exact for a sphere against a convex solid). n is the OBJECT's
// outward unit normal at the contact, pointing towards the fingertip; the contact point is the
// middle of the overlap, p_c = object surface point - (delta / 2) n.
//   normal force   f_n = max(0, k_n delta + c_n delta_dot)            (>= 0, no adhesion)
//   friction       elasto-plastic bristle (a tangential spring to an anchor that
//                  slides), f_t acting on the fingertip: z += v_t h; if k_t |z| <= mu f_n
//                  the contact sticks and f_t = -(k_t z + c_t v_t), clipped to
//                  |f_t| <= mu f_n; otherwise the anchor slides so that k_t |z| = mu f_n
//                  and f_t = -k_t z (Coulomb, magnitude exactly mu f_n).
// v_t is the tangential velocity of the fingertip relative to the object at p_c and
// z the bristle deflection (fingertip relative to the anchor on the object), kept in
// the current tangent plane. The cone |f_t| <= mu f_n holds exactly (up to rounding);
// the only regularisation is the bristle compliance: a sticking contact deflects
// elastically by at most mu f_n / k_t (0.4 mm at 1 N with the defaults) and then holds
// without creep under any constant load below mu f_n; above it the anchor slides.
// Rolling needs no special treatment: v_t is the relative velocity of the two material
// points at the contact, zero for pure rolling.
// Reported contact forces are those acting ON THE OBJECT: -f_n n + friction, so the
// friction on the object drags it along with the fingertip.
//
// Units: SI (m, m/s, N, N s/m, N/m). Frame: WORLD; the shape is queried in the object
// frame (shapes.hpp).
#pragma once

#include <algorithm>

#include "inhand/sim/finger_model.hpp"
#include "inhand/sim/object_dynamics.hpp"
#include "inhand/sim/plant_params.hpp"
#include "inhand/sim/plant_readings.hpp"
#include "inhand/sim/shapes.hpp"

namespace inhand::plant::detail {

/// Evaluates finger f's contact with the object (f.contact) and adds its force on the
/// object to force_sum and its torque about the centre of mass to torque_sum.
/// dt is the bristle integration interval: h in a step, 0 for a re-evaluation.
inline void evaluate_contact(FingerModel& f, const ContactParams& cp, const ObjectShape& shape,
                             const RigidBody& body, double dt, Eigen::Vector3d& force_sum,
                             Eigen::Vector3d& torque_sum) noexcept {
  ContactState& cs = f.contact;
  const Eigen::Vector3d& centre = f.ws.fingertip.position;
  const Eigen::Matrix3d& R = body.pose.rotation;
  const SurfaceQuery sq = shape.query(R.transpose() * (centre - body.pose.position));
  const double pen = f.chain.fingertip_radius - sq.distance;
  if (!(pen > 0.0)) {
    cs.active = false;
    cs.sliding = false;
    cs.penetration = 0.0;
    cs.normal_force = 0.0;
    cs.point = centre;
    cs.normal.setZero();
    cs.friction_force.setZero();
    cs.force.setZero();
    cs.deflection.setZero();
    cs.relative_velocity.setZero();
    return;
  }
  const Eigen::Vector3d n = R * sq.normal;
  const Eigen::Vector3d point = body.pose.position + R * sq.closest - (0.5 * pen) * n;
  const Eigen::Vector3d r_obj = point - body.pose.position;
  const Eigen::Vector3d v_rel = (f.tip_velocity + f.tip_omega.cross(point - centre)) -
                                (body.velocity + body.omega.cross(r_obj));
  const double vn = n.dot(v_rel);
  const double fn = std::max(0.0, cp.normal_stiffness * pen - cp.normal_damping * vn);
  const Eigen::Vector3d vt = v_rel - vn * n;

  // Bristle: keep the deflection tangential, advance it, then stick or slide.
  Eigen::Vector3d z = cs.deflection - cs.deflection.dot(n) * n;
  z += dt * vt;
  const double fmax = cp.friction * fn;
  const double kz = cp.tangential_stiffness * z.norm();
  Eigen::Vector3d ft;  // friction on the fingertip
  bool sliding = false;
  if (kz <= fmax) {
    ft = -(cp.tangential_stiffness * z + cp.tangential_damping * vt);
    const double m = ft.norm();
    if (m > fmax) ft *= fmax / m;
  } else {
    const Eigen::Vector3d z_new = (fmax / kz) * z;
    cs.slip_distance += (z - z_new).norm();
    z = z_new;
    ft = -cp.tangential_stiffness * z;
    sliding = true;
  }
  cs.active = true;
  cs.sliding = sliding;
  cs.penetration = pen;
  cs.normal_force = fn;
  cs.point = point;
  cs.normal = n;
  cs.friction_force = -ft;
  cs.force = -fn * n - ft;
  cs.deflection = z;
  cs.relative_velocity = v_rel;
  force_sum += cs.force;
  torque_sum += r_obj.cross(cs.force);
}

}  // namespace inhand::plant::detail
