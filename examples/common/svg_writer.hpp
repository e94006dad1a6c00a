// A small SVG writer (plain text, no library) for the demos' scene pictures: lines,
// circles, polygons, polylines, arrows and text in world coordinates, drawn into a
// window [x0, x1] x [y0, y1] of the world at a fixed scale. World y points up; the writer
// flips it for SVG. Units are the caller's (the Box2D demo: u; the 3-D scenes: m).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace inhand::examples {

class SvgWriter {
 public:
  /// A drawing of the world window [x0, x1] x [y0, y1] (u) at `px_per_unit`.
  /// `max_head`: the longest arrow head, in world units.
  SvgWriter(double x0, double y0, double x1, double y1, double px_per_unit, double max_head = 0.3)
      : x0_(x0), y1_(y1), s_(px_per_unit), max_head_(max_head) {
    const double w = (x1 - x0) * s_, h = (y1 - y0) * s_;
    out_ << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fmt(w) << "\" height=\""
         << fmt(h) << "\" viewBox=\"0 0 " << fmt(w) << ' ' << fmt(h) << "\">\n"
         << "<rect x=\"0\" y=\"0\" width=\"" << fmt(w) << "\" height=\"" << fmt(h)
         << "\" fill=\"white\"/>\n";
  }

  void line(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::string& stroke,
            double width_px, const std::string& extra = "") {
    out_ << "<line x1=\"" << fmt(px(a)) << "\" y1=\"" << fmt(py(a)) << "\" x2=\"" << fmt(px(b))
         << "\" y2=\"" << fmt(py(b)) << "\" stroke=\"" << stroke << "\" stroke-width=\""
         << fmt(width_px) << "\" stroke-linecap=\"round\"" << extra << "/>\n";
  }
  void circle(const Eigen::Vector2d& c, double radius_u, const std::string& fill,
              const std::string& stroke, double width_px, const std::string& extra = "") {
    out_ << "<circle cx=\"" << fmt(px(c)) << "\" cy=\"" << fmt(py(c)) << "\" r=\""
         << fmt(radius_u * s_) << "\" fill=\"" << fill << "\" stroke=\"" << stroke
         << "\" stroke-width=\"" << fmt(width_px) << '"' << extra << "/>\n";
  }
  template <typename Points>
  void polygon(const Points& pts, const std::string& fill, const std::string& stroke,
               double width_px, const std::string& extra = "") {
    out_ << "<polygon points=\"";
    for (const Eigen::Vector2d& p : pts) out_ << fmt(px(p)) << ',' << fmt(py(p)) << ' ';
    out_ << "\" fill=\"" << fill << "\" stroke=\"" << stroke << "\" stroke-width=\""
         << fmt(width_px) << '"' << extra << "/>\n";
  }
  /// Open polyline through `pts`.
  template <typename Points>
  void polyline(const Points& pts, const std::string& stroke, double width_px,
                const std::string& extra = "") {
    out_ << "<polyline points=\"";
    for (const Eigen::Vector2d& p : pts) out_ << fmt(px(p)) << ',' << fmt(py(p)) << ' ';
    out_ << "\" fill=\"none\" stroke=\"" << stroke << "\" stroke-width=\"" << fmt(width_px)
         << "\" stroke-linejoin=\"round\" stroke-linecap=\"round\"" << extra << "/>\n";
  }
  /// Arrow from `a` to `b` with a small head (at most max_head long).
  void arrow(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const std::string& stroke,
             double width_px) {
    line(a, b, stroke, width_px);
    const Eigen::Vector2d d = b - a;
    const double len = d.norm();
    if (len <= 0.0) return;
    const Eigen::Vector2d u = d / len, n(-u.y(), u.x());
    const double head = std::min(max_head_, 0.4 * len);
    line(b, Eigen::Vector2d(b - head * u + 0.5 * head * n), stroke, width_px);
    line(b, Eigen::Vector2d(b - head * u - 0.5 * head * n), stroke, width_px);
  }
  void text(const Eigen::Vector2d& at, const std::string& s, double size_px,
            const std::string& fill = "black") {
    out_ << "<text x=\"" << fmt(px(at)) << "\" y=\"" << fmt(py(at))
         << "\" font-family=\"sans-serif\" font-size=\"" << fmt(size_px) << "\" fill=\"" << fill
         << "\">" << escape(s) << "</text>\n";
  }
  std::string str() const { return out_.str() + "</svg>\n"; }
  void save(const std::string& path) const {
    std::ofstream f(path);
    if (!f) throw std::runtime_error("cannot write " + path);
    f << str();
  }

 private:
  double px(const Eigen::Vector2d& p) const { return (p.x() - x0_) * s_; }
  double py(const Eigen::Vector2d& p) const { return (y1_ - p.y()) * s_; }
  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
  }
  static std::string escape(const std::string& s) {
    std::string o;
    for (char c : s) {
      if (c == '<')
        o += "&lt;";
      else if (c == '>')
        o += "&gt;";
      else if (c == '&')
        o += "&amp;";
      else
        o += c;
    }
    return o;
  }
  double x0_, y1_, s_, max_head_;
  std::ostringstream out_;
};

}  // namespace inhand::examples
