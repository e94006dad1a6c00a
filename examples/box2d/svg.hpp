// The scene snapshot of the planar Box2D demo, drawn with examples/common/svg_writer.hpp:
// finger links as thick lines, fingertip pads as circles, the object's outline (solid:
// actual pose; dashed: desired pose; a radius marks the body x axis), contact
// points and the object's outward contact normals as the controller senses them (arrows
// of kNormalArrow u per N). World coordinates in u (planar_world.hpp), y up; the writer
// flips y for SVG.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "common/svg_writer.hpp"
#include "planar_scenario.hpp"

namespace inhand::box2d_demo {

using SvgWriter = inhand::examples::SvgWriter;

/// Length of a drawn normal: this many u per N of sensed normal force, at least 0.8 u.
constexpr double kNormalArrow = 1.5;

/// The object's outline at `pose` (a polygon; the circle as 48 segments).
inline std::vector<Vec2> object_outline(const ObjectSpec& o, const Pose<double, 2>& pose) {
  std::vector<Vec2> local;
  if (o.shape == ObjectShape::box) {
    const Vec2 h = o.half_extents;
    local = {Vec2(-h.x(), -h.y()), Vec2(h.x(), -h.y()), Vec2(h.x(), h.y()), Vec2(-h.x(), h.y())};
  } else {
    for (int k = 0; k < 48; ++k) {
      const double a = 2.0 * 3.14159265358979323846 * k / 48.0;
      local.emplace_back(o.radius * std::cos(a), o.radius * std::sin(a));
    }
  }
  std::vector<Vec2> out;
  for (const Vec2& p : local) out.push_back(pose.transform_point(p));
  return out;
}

/// The scene at one tick: truth geometry from the world, contacts as sensed.
inline std::string scene_svg(const TickRecord& r, const std::string& title) {
  const PlanarWorld& w = *r.plant;
  SvgWriter svg(-12.0, -9.0, 12.0, 7.0, 30.0);
  // The palm (the finger bases' line), the object with an orientation mark (its body
  // x axis), then the desired pose dashed on top.
  const ObjectSpec& o = w.object_spec();
  const Vec2 b0 = w.hand().fingers[0].base, b1 = w.hand().fingers[1].base;
  svg.line(Vec2(b0 - Vec2(1.0, 0.6)), Vec2(b1 + Vec2(1.0, -0.6)), "#999999", 6.0);
  svg.polygon(object_outline(o, *r.actual), "#f3d9a4", "#8a5a00", 2.0);
  const double mark = 0.6 * o.size() / 2.0;
  svg.line(r.actual->position, r.actual->transform_point(Vec2(mark, 0.0)), "#8a5a00", 2.0);
  svg.circle(r.actual->position, 0.12, "#8a5a00", "none", 0.0);
  svg.polygon(object_outline(o, *r.desired), "none", "#444444", 1.2, " stroke-dasharray=\"6,4\"");
  svg.line(r.desired->position, r.desired->transform_point(Vec2(mark, 0.0)), "#444444", 1.2,
           " stroke-dasharray=\"4,3\"");
  if (w.params().gravity > 0.0) {
    svg.arrow(Vec2(10.0, 4.0), Vec2(10.0, 2.5), "#555555", 2.0);
    svg.text(Vec2(10.3, 3.1), "g", 14.0, "#555555");
  }
  const double link_px = w.hand().link_width * 30.0;
  for (int i = 0; i < kFingers; ++i) {
    const auto p = w.finger_points(i);
    const std::string colour = i == 0 ? "#2b5c8a" : "#3d7a3d";
    for (int j = 0; j < kLinks; ++j)
      svg.line(p[static_cast<std::size_t>(j)], p[static_cast<std::size_t>(j + 1)], colour, link_px,
               " stroke-opacity=\"0.85\"");
    for (int j = 0; j < kLinks; ++j)
      svg.circle(p[static_cast<std::size_t>(j)], 0.22, "white", colour, 2.0);
    svg.circle(w.pad_centre(i), w.hand().pad_radius, "#d0d8e0", colour, 2.0,
               " fill-opacity=\"0.8\"");
    const auto& c = r.input->fingers[static_cast<std::size_t>(i)].contact;
    if (c.touching) {
      const double len = std::max(0.8, kNormalArrow * c.normal_force);
      svg.arrow(c.contact_point, Vec2(c.contact_point + len * c.normal), "#c00000", 2.0);
      svg.circle(c.contact_point, 0.15, "#c00000", "none", 0.0);
    }
  }
  svg.text(Vec2(-11.6, 6.2), title, 16.0);
  char b[160];
  const auto force = [&](int i) {
    const auto& c = r.input->fingers[static_cast<std::size_t>(i)].contact;
    return c.touching ? c.normal_force : 0.0;
  };
  std::snprintf(b, sizeof b, "t = %.3f s   object (%.3f, %.3f) u, %.4f rad   forces %.2f / %.2f N",
                r.time, r.actual->position.x(), r.actual->position.y(),
                so2_log<double>(r.actual->rotation), force(0), force(1));
  svg.text(Vec2(-11.6, 5.5), b, 12.0, "#333333");
  svg.text(Vec2(-11.6, -8.6),
           "1 u = 1 cm; dashed: desired pose; red: contact point and outward normal (1.5 u/N)",
           11.0, "#555555");
  return svg.str();
}

}  // namespace inhand::box2d_demo
