// libFuzzer target: ReactiveController::update on arbitrary input sequences.
//
// Hand: the plant's three-finger preset as a fixed-size ReactiveController<double, 3,
// 3, 3> (3 fingers of 3 joints, no allocation per tick). The fuzz bytes are decoded as
//   header  1 byte : bit 0 start in the manipulation phase (a perfect grasp tick, then
//                    a reciprocating trajectory) instead of the grasp phase; bit 1 a
//                    finite max_joint_acceleration; bits 2-4 external kinematics for
//                    fingers 0-2; bits 5-7 select the force servo limits
//   ticks   repeated, at most 64: 1 byte touching mask (bits 0-2) and edit count
//           (bits 3-7), 1 byte time step (value < 240: (value + 1) * 50 us; otherwise
//           a fuzzed value, which may be absurd or non-finite), then per edit 1 byte
//           slot selector (any scalar of the Input: time, object pose, per finger joint
//           positions, contact point, normal, force, Jacobian, virtual contact point)
//           and an encoded value: a special (quiet/signalling NaN, +-inf, +-0, +-max,
//           +-min, denormal, +-1e300, +-1e-300, epsilon), raw 8 bytes, or a small
//           offset from the nominal value.
// Each tick starts from a smooth nominal input, so most ticks are valid and the
// controller's state evolves; the edits make them hostile.
// Properties (each violation executes __builtin_trap(), which libFuzzer reports as a
// crash with the reproducing input): every joint velocity command finite and |qdot_i|
// <= max_velocity_i; an invalid_input or numerical_fault tick commands exactly zero;
// every floating-point member of the Output is finite, diagnostics included (an absurd
// finite input such as an object 1e308 m away gives numerical_fault, which names the
// stage). update()
// is noexcept (static_assert): an exception escaping it would terminate the process,
// which libFuzzer also reports; configure/start calls outside update() are wrapped and
// trap on any exception.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include "inhand/controller/reactive_controller.hpp"
#include "inhand/sim/presets.hpp"

namespace {

using Ctrl = inhand::ReactiveController<double, 3, 3, 3>;
constexpr int kFingers = 3;
constexpr int kMaxTicks = 64;

struct Reader {
  const std::uint8_t* data;
  std::size_t size;
  std::size_t pos = 0;
  bool empty() const { return pos >= size; }
  std::uint8_t byte() { return pos < size ? data[pos++] : 0; }
  double raw_double() {
    std::uint8_t b[8] = {};
    for (auto& x : b) x = byte();
    double d;
    std::memcpy(&d, b, sizeof d);
    return d;
  }
  /// A value for a scalar whose nominal value is `nominal`.
  double value(double nominal) {
    const std::uint8_t sel = byte();
    constexpr double inf = std::numeric_limits<double>::infinity();
    switch (sel % 24) {
      case 0:
        return std::numeric_limits<double>::quiet_NaN();
      case 1:
        return std::numeric_limits<double>::signaling_NaN();
      case 2:
        return inf;
      case 3:
        return -inf;
      case 4:
        return 0.0;
      case 5:
        return -0.0;
      case 6:
        return std::numeric_limits<double>::max();
      case 7:
        return -std::numeric_limits<double>::max();
      case 8:
        return std::numeric_limits<double>::min();
      case 9:
        return std::numeric_limits<double>::denorm_min();
      case 10:
        return 1e300;
      case 11:
        return -1e300;
      case 12:
        return 1e-300;
      case 13:
        return std::numeric_limits<double>::epsilon();
      case 14:
        return raw_double();
      case 15:
        return nominal * 1e6;
      case 16:
        return -nominal;
      default: {  // nominal plus a small signed offset, scaled by a fuzzed decade
        const auto hi = static_cast<std::int8_t>(byte());
        const int decade = static_cast<int>(byte() % 12);
        return nominal + static_cast<double>(hi) * std::pow(10.0, -decade);
      }
    }
  }
};

struct Setup {
  Ctrl::Config config{};
  Ctrl::Vec centre = Ctrl::Vec::Zero();
  std::array<inhand::GraspTarget<double, 3>, kFingers> targets{};
  std::array<Ctrl::JointVector, kFingers> q0{};
  inhand::Pose<double, 3> object{};

  Setup() {
    const inhand::plant::HandPreset hand = inhand::plant::three_finger_hand();
    for (int i = 0; i < kFingers; ++i) {
      const auto& f = hand.fingers[static_cast<std::size_t>(i)];
      auto& c = config.fingers[static_cast<std::size_t>(i)].chain;
      c.base = f.base;
      for (int j = 0; j < 3; ++j) c.joints[j] = f.joints[j];
      c.joint_to_tip = f.joint_to_tip;
      c.fingertip_radius = f.fingertip_radius;
      config.fingers[static_cast<std::size_t>(i)].role =
          i == hand.thumb ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
      q0[static_cast<std::size_t>(i)] = hand.grasp_configuration[static_cast<std::size_t>(i)];
    }
    config.grasp.settle_time = 0.0;  // the perfect tick completes the grasp at once
    std::array<Ctrl::Vec, kFingers> tips;
    for (int i = 0; i < kFingers; ++i) {
      const auto& c = config.fingers[static_cast<std::size_t>(i)].chain;
      inhand::FingerKinematics<Ctrl::Chain> ws(c);
      inhand::forward_kinematics(c, q0[static_cast<std::size_t>(i)], ws);
      tips[static_cast<std::size_t>(i)] = ws.fingertip.position;
      centre += ws.fingertip.position / kFingers;
    }
    for (int i = 0; i < kFingers; ++i) {
      auto& t = targets[static_cast<std::size_t>(i)];
      t.normal = (tips[static_cast<std::size_t>(i)] - centre).normalized();
      t.contact_point = tips[static_cast<std::size_t>(i)] - 0.01 * t.normal;
    }
    object.position = centre;
  }

  /// The smooth nominal input of tick k (valid, everything touching unless masked).
  void nominal(int k, unsigned touching, Ctrl::Input& in) const {
    in.object_pose = object;
    in.object_pose.position.x() += 1e-4 * std::sin(0.3 * k);
    for (int i = 0; i < kFingers; ++i) {
      auto& f = in.fingers[static_cast<std::size_t>(i)];
      const auto& t = targets[static_cast<std::size_t>(i)];
      const auto& c = config.fingers[static_cast<std::size_t>(i)].chain;
      f.joint_positions = q0[static_cast<std::size_t>(i)];
      f.joint_positions(1) += 0.01 * std::sin(0.2 * k + i);
      f.contact.touching = ((touching >> i) & 1u) != 0;
      f.contact.contact_point = t.contact_point;
      f.contact.normal = t.normal;
      f.contact.normal_force = 1.0 + 0.1 * std::sin(0.4 * k + i);
      inhand::FingerKinematics<Ctrl::Chain> ws(c);
      inhand::forward_kinematics(c, f.joint_positions, ws);
      f.virtual_contact_point = inhand::fingertip_surface_point(c, ws, t.normal);
      inhand::point_jacobian(
          ws, f.contact.touching ? ws.fingertip.position : f.virtual_contact_point, f.jacobian);
    }
  }
};

/// Every scalar of an Input, in a fixed order.
std::vector<double*> input_slots(Ctrl::Input& in) {
  std::vector<double*> s;
  s.push_back(&in.time);
  for (int k = 0; k < 3; ++k) s.push_back(&in.object_pose.position(k));
  for (int k = 0; k < 9; ++k) s.push_back(in.object_pose.rotation.data() + k);
  for (auto& f : in.fingers) {
    for (int k = 0; k < f.joint_positions.size(); ++k) s.push_back(&f.joint_positions(k));
    for (int k = 0; k < 3; ++k) s.push_back(&f.contact.contact_point(k));
    for (int k = 0; k < 3; ++k) s.push_back(&f.contact.normal(k));
    s.push_back(&f.contact.normal_force);
    for (int k = 0; k < f.jacobian.size(); ++k) s.push_back(f.jacobian.data() + k);
    for (int k = 0; k < 3; ++k) s.push_back(&f.virtual_contact_point(k));
  }
  return s;
}

void check(const Ctrl& ctl, inhand::ControllerStatus status, const Ctrl::Output& out) {
  for (int i = 0; i < kFingers; ++i) {
    const auto& qd = out.fingers[static_cast<std::size_t>(i)].joint_velocities;
    const auto& chain = ctl.config().fingers[static_cast<std::size_t>(i)].chain;
    if (qd.size() != chain.dof()) __builtin_trap();
    for (int j = 0; j < qd.size(); ++j) {
      const double v = qd(j);
      if (!std::isfinite(v) || !(std::abs(v) <= chain.joints[j].max_velocity)) __builtin_trap();
      if ((status == inhand::ControllerStatus::invalid_input ||
           status == inhand::ControllerStatus::numerical_fault) &&
          v != 0.0)
        __builtin_trap();
    }
    const auto& f = out.fingers[static_cast<std::size_t>(i)];
    if (!inhand::all_finite(f.desired_contact_velocity) || !inhand::all_finite(f.servo.total) ||
        !inhand::all_finite(f.servo.force) || !inhand::all_finite(f.servo.motion) ||
        !std::isfinite(f.desired_normal_force) || !std::isfinite(f.force_target) ||
        !std::isfinite(f.stiffness_estimate) || !std::isfinite(f.force_integral))
      __builtin_trap();
  }
  // Nothing non-finite leaves update(), diagnostics included.
  if (!out.desired_object_pose.is_finite() || !inhand::all_finite(out.feedforward_twist) ||
      !inhand::all_finite(out.commanded_twist) || !inhand::all_finite(out.pose_error) ||
      !inhand::all_finite(out.pose_error_integral) || !inhand::all_finite(out.force_residual) ||
      !inhand::all_finite(out.load_estimate) || !std::isfinite(out.grip) ||
      !std::isfinite(out.manipulation_time) || !std::isfinite(out.dt))
    __builtin_trap();
  if ((status == inhand::ControllerStatus::numerical_fault) != (out.numerical_fault != nullptr))
    __builtin_trap();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const Setup setup;
  Reader r{data, size};
  static_assert(noexcept(std::declval<Ctrl&>().update(std::declval<const Ctrl::Input&>(),
                                                      std::declval<Ctrl::Output&>())),
                "update() must be noexcept");
  try {
    const std::uint8_t header = r.byte();
    Ctrl::Config cfg = setup.config;
    if (header & 2u) cfg.max_joint_acceleration = 300.0;
    for (int i = 0; i < kFingers; ++i)
      if (header & (4u << i))
        cfg.fingers[static_cast<std::size_t>(i)].kinematics = Ctrl::KinematicsSource::external;
    switch ((header >> 5) & 3u) {
      case 1:
        cfg.servo.force.integral_limit = 0.5;
        cfg.servo.force.output_limit = 0.05;
        break;
      case 2:
        cfg.servo.motion.output_limit = 0.02;
        break;
      case 3:
        cfg.servo.force.ki = 0.0;
        break;
      default:
        break;
    }
    Ctrl ctl;
    if (!ctl.configure(cfg).ok()) __builtin_trap();
    if (!ctl.start_grasp(setup.targets).ok()) __builtin_trap();
    Ctrl::Input in = ctl.make_input();
    Ctrl::Output out = ctl.make_output();
    double t = 1e-3;
    if (header & 1u) {
      setup.nominal(0, 7u, in);
      // Every finger presses with its grasp force (controller/grasp.hpp).
      for (int i = 0; i < kFingers; ++i) {
        auto& f = in.fingers[static_cast<std::size_t>(i)];
        f.contact.normal_force = ctl.grasp_force(i);
        f.joint_positions = setup.q0[static_cast<std::size_t>(i)];
      }
      in.object_pose = setup.object;
      in.time = t;
      const auto st = ctl.update(in, out);
      check(ctl, st, out);
      if (st != inhand::ControllerStatus::grasped)
        __builtin_trap();  // the perfect tick must complete the grasp
      inhand::ObjectTrajectory<double, 3> traj;
      traj.reset(in.object_pose);
      inhand::Twist<double, 3> d;
      d << 0.005, 0.0, 0.0, -0.2, 0.0, 0.0;
      traj.append(inhand::TrajectorySegment<double, 3>::reciprocate(d, 0.2, 1));
      if (!ctl.start_manipulation(traj).ok()) __builtin_trap();
    }
    const std::vector<double*> slots = input_slots(in);
    for (int k = 1; k <= kMaxTicks && !r.empty(); ++k) {
      const std::uint8_t op = r.byte();
      setup.nominal(k, op & 7u, in);
      const std::uint8_t step = r.byte();
      t = step < 240 ? t + (step + 1) * 5e-5 : r.value(t);
      in.time = t;
      const int edits = op >> 3;
      for (int e = 0; e < edits && !r.empty(); ++e) {
        double* slot = slots[r.byte() % slots.size()];
        *slot = r.value(*slot);
      }
      const auto st = ctl.update(in, out);
      check(ctl, st, out);
      // Keep time moving from the last value the controller may have accepted.
      if (!std::isfinite(t)) t = 1e-3 * (k + 1);
    }
  } catch (...) {
    __builtin_trap();
  }
  return 0;
}
