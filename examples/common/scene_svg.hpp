// Pictures of a 3-D hand scene (the scenario runner's scene_*.svg): three orthographic
// views side by side, drawn with svg_writer.hpp.
//   front: world x to the right, z up (seen from -y, along +y);
//   side:  world y to the right, z up (seen from -x, along +x);
//   top:   world x to the right, y up (seen from +z, along -z).
// Each view is a window of +-kSceneHalfWidth around the world origin (the presets'
// nominal object centre). It shows the object at its true pose (filled silhouette and
// edges; a cylinder's rims, a box's twelve edges, a sphere's outline) and its desired
// pose (dashed silhouette); per finger the links as a polyline through the joint origins
// and the fingertip centre, and the fingertip sphere; where a finger
// touches, the sensed contact point and the object's outward normal as the controller
// reads them (an arrow kSceneNormalPerNewton long per N of sensed normal force, at least
// kSceneMinNormal). Fingers farther from the viewer than the object's centre are drawn
// before it, the others after it. Units: m, N; world frame.
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/svg_writer.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/sim/shapes.hpp"

namespace inhand::examples {

constexpr double kSceneHalfWidth = 0.13;        ///< m, half the width of one view
constexpr double kSceneNormalPerNewton = 0.01;  ///< m of drawn normal per N
constexpr double kSceneMinNormal = 0.006;       ///< m, shortest drawn normal

/// What one picture shows (world frame, m, N).
struct Scene {
  struct Finger {
    std::string name;
    /// Each joint's origin, then the fingertip sphere's centre.
    std::vector<Eigen::Vector3d> links;
    double tip_radius = 0.0;  ///< m
    bool touching = false;
    Eigen::Vector3d contact_point = Eigen::Vector3d::Zero();  ///< as sensed
    Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();        ///< outward, unit
    double normal_force = 0.0;                                ///< N, as sensed
  };
  std::vector<Finger> fingers;
  plant::ObjectShape object;
  Pose<double, 3> actual{}, desired{};
  std::string title, subtitle;
};

namespace scene_detail {

/// The three views: which world axes are horizontal and vertical, and the viewing
/// direction (depth grows away from the viewer).
struct View {
  int h, v;
  Eigen::Vector3d towards;
  const char* name;
};
inline const std::array<View, 3>& views() {
  static const std::array<View, 3> v = {{{0, 2, Eigen::Vector3d::UnitY(), "front: x right, z up"},
                                         {1, 2, Eigen::Vector3d::UnitX(), "side: y right, z up"},
                                         {0, 1, -Eigen::Vector3d::UnitZ(), "top: x right, y up"}}};
  return v;
}

/// Panel k's drawing coordinates of world point p.
inline Eigen::Vector2d project(const View& view, int k, const Eigen::Vector3d& p) {
  return Eigen::Vector2d(p(view.h) + (2 * k + 1) * kSceneHalfWidth, p(view.v));
}

/// Convex hull (counter-clockwise, Andrew's monotone chain).
inline std::vector<Eigen::Vector2d> hull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (p.size() < 3) return p;
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0.0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0.0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k - 1);
  return h;
}

/// The object's wireframe in the world: polylines (rims, edges) at `pose`.
inline std::vector<std::vector<Eigen::Vector3d>> wireframe(const plant::ObjectShape& s,
                                                           const Pose<double, 3>& pose) {
  constexpr double kTwoPi = 6.283185307179586;
  constexpr int kSegments = 36;
  std::vector<std::vector<Eigen::Vector3d>> lines;
  auto world = [&](const Eigen::Vector3d& local) { return pose.transform_point(local); };
  if (s.kind == plant::ObjectShape::Kind::box) {
    const Eigen::Vector3d h = s.half_extents;
    for (int axis = 0; axis < 3; ++axis)
      for (int a = -1; a <= 1; a += 2)
        for (int b = -1; b <= 1; b += 2) {
          Eigen::Vector3d p0, p1;
          const int u = (axis + 1) % 3, w = (axis + 2) % 3;
          p0(axis) = -h(axis);
          p1(axis) = h(axis);
          p0(u) = p1(u) = a * h(u);
          p0(w) = p1(w) = b * h(w);
          lines.push_back({world(p0), world(p1)});
        }
  } else if (s.kind == plant::ObjectShape::Kind::cylinder) {
    for (int end = -1; end <= 1; end += 2) {
      std::vector<Eigen::Vector3d> rim;
      for (int k = 0; k <= kSegments; ++k) {
        const double a = kTwoPi * k / kSegments;
        rim.push_back(world(
            Eigen::Vector3d(s.radius * std::cos(a), s.radius * std::sin(a), end * s.half_length)));
      }
      lines.push_back(rim);
    }
    for (int k = 0; k < 4; ++k) {
      const double a = kTwoPi * k / 4;
      const Eigen::Vector2d c(s.radius * std::cos(a), s.radius * std::sin(a));
      lines.push_back({world(Eigen::Vector3d(c.x(), c.y(), -s.half_length)),
                       world(Eigen::Vector3d(c.x(), c.y(), s.half_length))});
    }
  } else {  // sphere: three great circles
    for (int plane = 0; plane < 3; ++plane) {
      std::vector<Eigen::Vector3d> circle;
      for (int k = 0; k <= kSegments; ++k) {
        const double a = kTwoPi * k / kSegments;
        Eigen::Vector3d p = Eigen::Vector3d::Zero();
        p((plane + 1) % 3) = s.radius * std::cos(a);
        p((plane + 2) % 3) = s.radius * std::sin(a);
        circle.push_back(world(p));
      }
      lines.push_back(circle);
    }
  }
  return lines;
}

/// The object's silhouette in panel k of `view` (a sphere: its outline circle).
inline std::vector<Eigen::Vector2d> silhouette(const plant::ObjectShape& s,
                                               const Pose<double, 3>& pose, const View& view,
                                               int k) {
  std::vector<Eigen::Vector2d> pts;
  if (s.kind == plant::ObjectShape::Kind::sphere) {
    constexpr int kSegments = 48;
    const Eigen::Vector2d c = project(view, k, pose.position);
    for (int i = 0; i < kSegments; ++i) {
      const double a = 6.283185307179586 * i / kSegments;
      pts.emplace_back(c + s.radius * Eigen::Vector2d(std::cos(a), std::sin(a)));
    }
    return pts;
  }
  for (const auto& line : wireframe(s, pose))
    for (const Eigen::Vector3d& p : line) pts.push_back(project(view, k, p));
  return hull(pts);
}

inline const char* finger_colour(std::size_t i) {
  static const char* colours[] = {"#2b5c8a", "#3d7a3d", "#7a3d7a", "#8a5a00", "#5a5a5a"};
  return colours[i % 5];
}

}  // namespace scene_detail

/// The picture of `scene` as an SVG document.
inline std::string scene_svg(const Scene& scene) {
  namespace sd = scene_detail;
  const double width = 6.0 * kSceneHalfWidth, top = kSceneHalfWidth + 0.035;
  SvgWriter svg(0.0, -kSceneHalfWidth - 0.012, width, top, 1500.0, 0.004);
  for (int k = 0; k < 3; ++k) {
    const sd::View& view = sd::views()[static_cast<std::size_t>(k)];
    const double x0 = 2 * k * kSceneHalfWidth;
    svg.polygon(std::vector<Eigen::Vector2d>{{x0 + 0.002, -kSceneHalfWidth},
                                             {x0 + 2 * kSceneHalfWidth - 0.002, -kSceneHalfWidth},
                                             {x0 + 2 * kSceneHalfWidth - 0.002, kSceneHalfWidth},
                                             {x0 + 0.002, kSceneHalfWidth}},
                "#fafafa", "#cccccc", 1.0);
    svg.text(Eigen::Vector2d(x0 + 0.006, kSceneHalfWidth - 0.009), view.name, 12.0, "#555555");
    const double object_depth = scene.actual.position.dot(view.towards);
    auto draw_object = [&]() {
      svg.polygon(sd::silhouette(scene.object, scene.actual, view, k), "#f3d9a4", "#8a5a00", 1.5,
                  " fill-opacity=\"0.7\"");
      for (const auto& line : sd::wireframe(scene.object, scene.actual)) {
        std::vector<Eigen::Vector2d> pts;
        for (const Eigen::Vector3d& p : line) pts.push_back(sd::project(view, k, p));
        svg.polyline(pts, "#8a5a00", 0.8, " stroke-opacity=\"0.6\"");
      }
      svg.polygon(sd::silhouette(scene.object, scene.desired, view, k), "none", "#444444", 1.0,
                  " stroke-dasharray=\"5,4\"");
    };
    auto draw_finger = [&](std::size_t i) {
      const Scene::Finger& f = scene.fingers[i];
      const char* colour = sd::finger_colour(i);
      std::vector<Eigen::Vector2d> pts;
      for (const Eigen::Vector3d& p : f.links) pts.push_back(sd::project(view, k, p));
      svg.polyline(pts, colour, 9.0, " stroke-opacity=\"0.8\"");
      for (std::size_t j = 0; j + 1 < pts.size(); ++j)
        svg.circle(pts[j], 0.0015, "white", colour, 1.5);
      if (!pts.empty())
        svg.circle(pts.back(), f.tip_radius, "#d0d8e0", colour, 1.5, " fill-opacity=\"0.85\"");
      if (f.touching) {
        const double len = std::max(kSceneMinNormal, kSceneNormalPerNewton * f.normal_force);
        const Eigen::Vector2d c = sd::project(view, k, f.contact_point);
        svg.arrow(c, sd::project(view, k, f.contact_point + len * f.normal), "#c00000", 1.8);
        svg.circle(c, 0.0012, "#c00000", "none", 0.0);
      }
    };
    std::vector<std::size_t> far, near;
    for (std::size_t i = 0; i < scene.fingers.size(); ++i) {
      const auto& links = scene.fingers[i].links;
      double depth = 0.0;
      for (const Eigen::Vector3d& p : links) depth += p.dot(view.towards);
      depth /= std::max<std::size_t>(1, links.size());
      (depth > object_depth ? far : near).push_back(i);
    }
    for (std::size_t i : far) draw_finger(i);
    draw_object();
    for (std::size_t i : near) draw_finger(i);
  }
  svg.text(Eigen::Vector2d(0.006, top - 0.012), scene.title, 15.0);
  svg.text(Eigen::Vector2d(0.006, top - 0.024), scene.subtitle, 11.0, "#333333");
  std::string legend =
      "views 26 cm wide; dashed: desired pose; red: sensed contact and outward "
      "normal (10 mm/N); fingers:";
  for (std::size_t i = 0; i < scene.fingers.size(); ++i)
    legend += " " + scene.fingers[i].name + (i + 1 < scene.fingers.size() ? "," : "");
  svg.text(Eigen::Vector2d(0.006, -kSceneHalfWidth - 0.008), legend, 10.0, "#555555");
  return svg.str();
}

}  // namespace inhand::examples
