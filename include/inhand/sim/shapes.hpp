// Object shapes of the simulated plant: closed-form surface queries and mass properties.
//
// Units: metres, kilograms; inertia in kg m^2.
// Frame: every query takes and returns coordinates in the OBJECT frame, whose origin
// is the shape's centre (its centre of mass at uniform density) and whose axes are the
// shape's symmetry axes: a box has half extents (hx, hy, hz) along (x, y, z); a
// cylinder's axis is the object z axis (|z| <= half_length), its radius is in x-y.
// Signs: the signed distance is > 0 outside, 0 on the surface, < 0 inside. The
// normal is the OUTWARD unit normal of the surface at the closest point; for a point
// outside it equals (p - closest) / distance, for a point inside it is the outward
// normal of the nearest face (ties go to the first of x, y, z for a box and to the
// side over the caps for a cylinder; a point on an axis picks the +x / +z side).
// Pure functions: noexcept, no allocation.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>

#include "inhand/math/status.hpp"
#include "inhand/math/types.hpp"

namespace inhand::plant {

/// Result of a closest-point query, in the object frame.
struct SurfaceQuery {
  /// Signed distance from the query point to the surface [m], > 0 outside.
  double distance = 0.0;
  /// The surface point nearest to the query point.
  Eigen::Vector3d closest = Eigen::Vector3d::Zero();
  /// Outward unit normal of the surface at `closest` (nearest face for inside points).
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
};

/// A convex solid of uniform density: sphere, box or cylinder (axis = object z).
struct ObjectShape {
  enum class Kind { sphere, box, cylinder };

  Kind kind = Kind::sphere;
  /// Box half extents along the object axes [m] (box only).
  Eigen::Vector3d half_extents = Eigen::Vector3d::Zero();
  /// Sphere or cylinder radius [m].
  double radius = 0.0;
  /// Cylinder half length along the object z axis [m].
  double half_length = 0.0;

  static ObjectShape sphere(double r) noexcept {
    ObjectShape s;
    s.kind = Kind::sphere;
    s.radius = r;
    return s;
  }
  static ObjectShape box(double hx, double hy, double hz) noexcept {
    ObjectShape s;
    s.kind = Kind::box;
    s.half_extents = Eigen::Vector3d(hx, hy, hz);
    return s;
  }
  static ObjectShape cylinder(double r, double half_len) noexcept {
    ObjectShape s;
    s.kind = Kind::cylinder;
    s.radius = r;
    s.half_length = half_len;
    return s;
  }

  /// Every dimension the kind uses must be finite and > 0.
  Validation validate() const noexcept {
    switch (kind) {
      case Kind::sphere:
        if (!is_finite(radius) || !(radius > 0.0))
          return Validation::invalid("shape.radius", "must be finite and > 0");
        return Validation::valid();
      case Kind::box:
        for (int i = 0; i < 3; ++i)
          if (!is_finite(half_extents(i)) || !(half_extents(i) > 0.0))
            return Validation::invalid("shape.half_extents", "must be finite and > 0", i);
        return Validation::valid();
      case Kind::cylinder:
        if (!is_finite(radius) || !(radius > 0.0))
          return Validation::invalid("shape.radius", "must be finite and > 0");
        if (!is_finite(half_length) || !(half_length > 0.0))
          return Validation::invalid("shape.half_length", "must be finite and > 0");
        return Validation::valid();
    }
    return Validation::invalid("shape.kind", "unknown kind");
  }

  /// Closest surface point, signed distance and outward normal for point p.
  SurfaceQuery query(const Eigen::Vector3d& p) const noexcept {
    switch (kind) {
      case Kind::sphere:
        return query_sphere(p);
      case Kind::box:
        return query_box(p);
      case Kind::cylinder:
        return query_cylinder(p);
    }
    return SurfaceQuery{};
  }
  double signed_distance(const Eigen::Vector3d& p) const noexcept { return query(p).distance; }
  Eigen::Vector3d closest_point(const Eigen::Vector3d& p) const noexcept {
    return query(p).closest;
  }
  Eigen::Vector3d outward_normal(const Eigen::Vector3d& p) const noexcept {
    return query(p).normal;
  }

  /// Volume [m^3].
  double volume() const noexcept {
    constexpr double kPi = 3.14159265358979323846;
    switch (kind) {
      case Kind::sphere:
        return 4.0 / 3.0 * kPi * radius * radius * radius;
      case Kind::box:
        return 8.0 * half_extents.prod();
      case Kind::cylinder:
        return kPi * radius * radius * 2.0 * half_length;
    }
    return 0.0;
  }

  /// Principal moments of inertia about the centre, along the object axes, for a solid
  /// of uniform density and the given mass [kg m^2].
  Eigen::Vector3d principal_inertia(double mass) const noexcept {
    switch (kind) {
      case Kind::sphere:
        return Eigen::Vector3d::Constant(0.4 * mass * radius * radius);
      case Kind::box: {
        const Eigen::Vector3d s = half_extents.cwiseAbs2();  // (2h)^2 / 12 = h^2 / 3
        return (mass / 3.0) * Eigen::Vector3d(s.y() + s.z(), s.x() + s.z(), s.x() + s.y());
      }
      case Kind::cylinder: {
        const double r2 = radius * radius, h2 = half_length * half_length;
        const double side = mass * (r2 / 4.0 + h2 / 3.0);  // m (3 r^2 + L^2) / 12, L = 2h
        return Eigen::Vector3d(side, side, 0.5 * mass * r2);
      }
    }
    return Eigen::Vector3d::Zero();
  }
  /// Inertia tensor about the centre in the object frame (diagonal for these shapes).
  Eigen::Matrix3d inertia(double mass) const noexcept {
    return principal_inertia(mass).asDiagonal();
  }
  /// Radius of the smallest origin-centred sphere containing the shape [m].
  double bounding_radius() const noexcept {
    switch (kind) {
      case Kind::sphere:
        return radius;
      case Kind::box:
        return half_extents.norm();
      case Kind::cylinder:
        return std::sqrt(radius * radius + half_length * half_length);
    }
    return 0.0;
  }

 private:
  SurfaceQuery query_sphere(const Eigen::Vector3d& p) const noexcept {
    SurfaceQuery q;
    const double d = p.norm();
    q.normal = d > 0.0 ? Eigen::Vector3d(p / d) : Eigen::Vector3d::UnitZ();
    q.closest = radius * q.normal;
    q.distance = d - radius;
    return q;
  }

  SurfaceQuery query_box(const Eigen::Vector3d& p) const noexcept {
    SurfaceQuery q;
    const Eigen::Vector3d excess = p.cwiseAbs() - half_extents;  // > 0: outside that slab
    if ((excess.array() > 0.0).any()) {
      q.closest = p.cwiseMax(-half_extents).cwiseMin(half_extents);
      const Eigen::Vector3d delta = p - q.closest;
      q.distance = delta.norm();
      q.normal = delta / q.distance;
      return q;
    }
    // Inside or on the surface: the nearest face is the one with the largest
    // (least negative) excess; the closest point is the projection onto it.
    int i = 0;
    if (excess.y() > excess(i)) i = 1;
    if (excess.z() > excess(i)) i = 2;
    const double side = p(i) >= 0.0 ? 1.0 : -1.0;
    q.distance = excess(i);
    q.closest = p;
    q.closest(i) = side * half_extents(i);
    q.normal = Eigen::Vector3d::Zero();
    q.normal(i) = side;
    return q;
  }

  SurfaceQuery query_cylinder(const Eigen::Vector3d& p) const noexcept {
    SurfaceQuery q;
    const double rho = std::sqrt(p.x() * p.x() + p.y() * p.y());  // metre scale: no overflow
    const Eigen::Vector2d radial =
        rho > 0.0 ? Eigen::Vector2d(p.x() / rho, p.y() / rho) : Eigen::Vector2d(1.0, 0.0);
    const double dr = rho - radius;                   // > 0: outside the side
    const double dz = std::abs(p.z()) - half_length;  // > 0: beyond a cap
    const double zside = p.z() >= 0.0 ? 1.0 : -1.0;
    if (dr > 0.0 || dz > 0.0) {
      const double rc = std::min(rho, radius);
      q.closest = Eigen::Vector3d(rc * radial.x(), rc * radial.y(),
                                  std::clamp(p.z(), -half_length, half_length));
      const Eigen::Vector3d delta = p - q.closest;
      q.distance = delta.norm();
      q.normal = delta / q.distance;
      return q;
    }
    if (dr >= dz) {  // nearer the side
      q.distance = dr;
      q.closest = Eigen::Vector3d(radius * radial.x(), radius * radial.y(), p.z());
      q.normal = Eigen::Vector3d(radial.x(), radial.y(), 0.0);
    } else {  // nearer a cap
      q.distance = dz;
      q.closest = Eigen::Vector3d(p.x(), p.y(), zside * half_length);
      q.normal = Eigen::Vector3d(0.0, 0.0, zside);
    }
    return q;
  }
};

}  // namespace inhand::plant
