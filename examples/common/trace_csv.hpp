// Per-tick trace of a manipulation run as CSV, for planar (Dim = 2) and spatial
// (Dim = 3) hands. One header row, then one row per control tick.
//
// Columns (world frame, SI units: s, m, rad, N, m/s):
//   time, stage (index), stage_name,
//   des_<p>    desired object pose,
//   meas_<p>   object pose the controller received (sensed, possibly noisy),
//   act_<p>    true object pose (what the metrics compare with the desired one),
//     where <p> is x,y,z,roll,pitch,yaw (Dim 3) or x,y,angle (Dim 2). The orientation
//     is that of R R_ref^T, the rotation from the reference orientation given to the
//     writer (normally the object's initial orientation), as roll-pitch-yaw of
//     euler_from_rotation (R = Rz(yaw) Ry(pitch) Rx(roll)) or as the planar angle. So
//     a rotation of the object by -0.2 rad about world X reads roll = -0.2, whatever
//     its initial orientation (the paper's Fig. 3b plots this angle).
//   per finger f (its name, made CSV safe):
//     f_touching (0/1), f_cx, f_cy[, f_cz] contact point as sensed (the tactile input
//     the controller used; "nan" while not touching), f_fd desired normal force (0 when
//     no force is servoed), f_f measured normal force,
//     f_motion_*, f_force_*, f_total_* the servo command split as in the paper's Fig. 5
//     (eqs. 4-7: motion part e_m, force part e_f, their sum e; m/s), f_state (finger
//     state name), f_ik (IK status name).
// Numbers are printed with 8 significant digits; magnitudes below 1e-15 are printed as
// 0 (far below any resolution that matters here, and it keeps the file small).
// Written through AtomicFile: the file appears when commit() succeeds, never half done.
#pragma once

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "inhand/controller/grasp.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/math/so3.hpp"

namespace inhand::examples {

/// One finger's data for a trace row.
template <int Dim>
struct TraceFinger {
  bool touching = false;
  Vector<double, Dim> contact_point = Vector<double, Dim>::Zero();
  double desired_force = 0.0;
  double measured_force = 0.0;
  ServoCommand<double, Dim> servo{};
  FingerState state = FingerState::idle;
  IkStatus ik_status = IkStatus::ok;
  double stiffness = 0.0;       ///< the force loop's stiffness estimate [N/m]
  double force_integral = 0.0;  ///< the force loop's integrator [N s]
  bool slipping = false;
};

/// One control tick.
template <int Dim>
struct TraceRow {
  double time = 0.0;
  int stage = 0;
  std::string stage_name;
  Pose<double, Dim> desired{}, measured{}, actual{};
  std::vector<TraceFinger<Dim>> fingers;
  double grip = 1.0;      ///< the force layer's grip scale
  unsigned warnings = 0;  ///< ControllerWarning bits of the tick
  /// Load estimate (force; torque) and layer 1's pose-error integral (m s; rad s).
  Twist<double, Dim> load = Twist<double, Dim>::Zero();
  Twist<double, Dim> pose_integral = Twist<double, Dim>::Zero();
};

/// Fills `fingers` from a ReactiveController's input (the tactile data it used) and
/// output (plan, servo parts, states).
template <int Dim, typename Input, typename Output>
void fill_trace_fingers(const Input& in, const Output& out,
                        std::vector<TraceFinger<Dim>>& fingers) {
  fingers.resize(in.fingers.size());
  for (std::size_t i = 0; i < fingers.size(); ++i) {
    TraceFinger<Dim>& f = fingers[i];
    const auto& c = in.fingers[i].contact;
    const auto& o = out.fingers[i];
    f.touching = c.touching;
    f.contact_point = c.contact_point;
    f.measured_force = c.touching ? c.normal_force : 0.0;
    f.desired_force = o.desired_normal_force;
    f.servo = o.servo;
    f.state = o.state;
    f.ik_status = o.ik.status;
    f.stiffness = o.stiffness_estimate;
    f.force_integral = o.force_integral;
    f.slipping = o.slipping;
  }
}

/// The hand-level force-layer and layer-1 states of a row.
template <int Dim, typename Output, typename Row>
void fill_trace_hand(const Output& out, Row& row) {
  row.grip = out.grip;
  row.warnings = static_cast<unsigned>(out.warnings);
  row.load = out.load_estimate;
  row.pose_integral = out.pose_error_integral;
}

/// A whole row for one tick of the scenario runner (a sim::TickRecord of any plant):
/// desired pose, pose as sensed (before the tick's step), true pose (after it), and the
/// tactile input / servo output of each finger.
template <int Dim, typename Record>
void fill_trace_row(const Record& rec, const std::string& stage_name, TraceRow<Dim>& row) {
  row.time = rec.time;
  row.stage = rec.stage;
  row.stage_name = stage_name;
  row.desired = *rec.desired;
  row.measured = rec.input->object_pose;
  row.actual = *rec.actual;
  fill_trace_fingers<Dim>(*rec.input, *rec.output, row.fingers);
  fill_trace_hand<Dim>(*rec.output, row);
}

/// Letters, digits and '_' only (other characters become '_').
inline std::string csv_safe_name(const std::string& s) {
  std::string out = s.empty() ? std::string("finger") : s;
  for (char& c : out) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
    if (!ok) c = '_';
  }
  return out;
}

template <int Dim>
class TraceCsvWriter {
 public:
  /// Opens the (temporary) output and writes the header.
  TraceCsvWriter(
      const std::string& path, const std::vector<std::string>& finger_names,
      const Rotation<double, Dim>& reference_rotation = Rotation<double, Dim>::Identity())
      : file_(path), fingers_(finger_names.size()), reference_(reference_rotation) {
    std::string h = "time,stage,stage_name";
    const char* pose_cols3[] = {"x", "y", "z", "roll", "pitch", "yaw"};
    const char* pose_cols2[] = {"x", "y", "angle"};
    for (const char* prefix : {"des_", "meas_", "act_"}) {
      if constexpr (Dim == 3) {
        for (const char* c : pose_cols3) h += std::string(",") + prefix + c;
      } else {
        for (const char* c : pose_cols2) h += std::string(",") + prefix + c;
      }
    }
    const char* axes[] = {"x", "y", "z"};
    for (const std::string& raw : finger_names) {
      const std::string n = csv_safe_name(raw);
      h += "," + n + "_touching";
      for (int k = 0; k < Dim; ++k) h += "," + n + "_c" + axes[k];
      h += "," + n + "_fd," + n + "_f";
      for (const char* part : {"_motion_", "_force_", "_total_"})
        for (int k = 0; k < Dim; ++k) h += "," + n + part + axes[k];
      h += "," + n + "_state," + n + "_ik";
      h += "," + n + "_k," + n + "_z," + n + "_slip";
    }
    h += ",grip,warnings";
    const char* wrench3[] = {"fx", "fy", "fz", "tx", "ty", "tz"};
    const char* wrench2[] = {"fx", "fy", "tz"};
    for (const char* prefix : {"load_", "pint_"}) {
      if constexpr (Dim == 3) {
        for (const char* c : wrench3) h += std::string(",") + prefix + c;
      } else {
        for (const char* c : wrench2) h += std::string(",") + prefix + c;
      }
    }
    h += "\n";
    file_.write(h);
  }

  /// Appends one row; row.fingers must have one entry per finger name.
  void write(const TraceRow<Dim>& row) {
    if (row.fingers.size() != fingers_)
      throw std::invalid_argument("trace row: wrong finger count");
    std::FILE* f = file_.stream();
    std::fprintf(f, "%.6f,%d,%s", row.time, row.stage, csv_safe_name(row.stage_name).c_str());
    pose(f, row.desired);
    pose(f, row.measured);
    pose(f, row.actual);
    for (const TraceFinger<Dim>& t : row.fingers) {
      std::fprintf(f, ",%d", t.touching ? 1 : 0);
      if (t.touching)
        vec(f, t.contact_point);
      else
        for (int k = 0; k < Dim; ++k) std::fputs(",nan", f);
      num(f, t.desired_force);
      num(f, t.measured_force);
      vec(f, t.servo.motion);
      vec(f, t.servo.force);
      vec(f, t.servo.total);
      std::fprintf(f, ",%s,%s", to_string(t.state), to_string(t.ik_status));
      num(f, t.stiffness);
      num(f, t.force_integral);
      std::fprintf(f, ",%d", t.slipping ? 1 : 0);
    }
    num(f, row.grip);
    std::fprintf(f, ",%u", row.warnings);
    vec(f, row.load);
    vec(f, row.pose_integral);
    std::fputc('\n', f);
    ++rows_;
  }

  long rows() const noexcept { return rows_; }
  /// Makes the file appear at its path; throws on I/O errors.
  void commit() { file_.commit(); }
  /// The output file, e.g. to commit it together with others (commit_together()).
  AtomicFile& file() noexcept { return file_; }

 private:
  void pose(std::FILE* f, const Pose<double, Dim>& p) const {
    vec(f, p.position);
    const Rotation<double, Dim> rel = p.rotation * reference_.transpose();
    if constexpr (Dim == 3) {
      vec(f, euler_from_rotation<double>(rel));
    } else {
      num(f, so2_log<double>(rel));
    }
  }
  static void num(std::FILE* f, double x) {
    if (std::abs(x) < 1e-15)
      std::fputs(",0", f);
    else
      std::fprintf(f, ",%.8g", x);
  }
  template <typename V>
  static void vec(std::FILE* f, const V& v) {
    for (int k = 0; k < v.size(); ++k) num(f, v(k));
  }

  AtomicFile file_;
  std::size_t fingers_;
  Rotation<double, Dim> reference_;
  long rows_ = 0;
};

}  // namespace inhand::examples
