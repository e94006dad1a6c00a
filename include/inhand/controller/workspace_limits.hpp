// The hand's workspace as a constraint on the object twist (docs/method.md section 4).
//
// A joint the IK holds at its position limit (less ik.joint_limit_margin) keeps its
// finger's contact from moving one way whenever the finger's other actuated joints cannot
// make that motion instead: always for a finger with as many joints as the space has
// dimensions, and for a redundant finger whose other columns lose rank. The contact
// velocities x out of reach are then b^T x > 0, b the unit left null vector of the other
// columns, signed so that b^T x > 0 needs the held joint past its bound
// (FingerServo::for_each_unreachable_direction). With two or more joints held, they are
// also taken together: the free joints' columns may span less than the space although
// each held joint alone is made up by the others (a redundant finger with two joints at
// their limits); each of +n and -n that no joint velocity inside the bounds gives yields
// one more such b (the separating direction of the cone those velocities reach, which
// has b . (+-n) > 0; math/cone_residual.hpp). Along the contact normal n that motion
// cannot be made up by rolling or sliding: a contact asked to follow the object's surface
// along n and held back opens, or is pressed harder, while the other fingers carry the
// object on; the grasp deforms until a contact is lost. The part of b along n,
// b_n = (b . n) n, is what the warning tests. Across n the held contact has to slide on
// the object instead, against friction and against the force layer, which raises the
// grip where it sees a contact slide: once the twist is cut, the whole of b is the
// constraint (a = b), else a = b_n.
//
// The contact point p moves with x = v_o + omega_o x (p - p_o) for the object twist
// V = (v_o; omega_o) [m/s; rad/s, world frame, about the measured object position p_o]
// (eq. 2), linear in V: a^T x = c^T V with c_k = a^T x(e_k) over the basis twists e_k.
// c^T V > 0 asks for what the held joint cannot give: ControllerWarning::workspace_limited
// is raised. With Config::keep_twist_in_reach, and without it while the force layer reports
// the grasp at risk and Config::at_risk_hold after (the caller's `cut`), the twist
// is also projected onto c^T V = 0 (the least change of V in the Euclidean norm of
// (v_o; omega_o); a twist with c^T V <= 0, away from the limit, is left alone; several
// constraints in turn, a second sweep when the first cut something), so the object stops
// at the edge of the hand's workspace: the pose error then grows along the cut.
//
// cut_twist_at_edge makes that cut a saturation with its anti-windup. (1) Once made, the
// cut stays on for as long as the twist goes on asking beyond the edge (the state's
// edge_cut), whatever the risk flags do: the constraint is released when the demand turns
// back or the held joint leaves its bound, not when the grasp, relieved by the cut, stops
// reporting a risk. Released on the risk instead, the cut alternated with the push that
// made the risk (wide campaign seed 481: a cycle of about 104 ms, the held thumb pressed
// to 6.5 N against 4 N, the opposite finger's contact opening once a cycle). (2) While it
// is on, the pose loop does not integrate the error along the direction the cut took out
// (PoseLoop::hold_integral_along): the integral owns that direction only while the twist
// can follow it. Fingers that
// do not touch are not considered. Cost when no joint is within kHeldJointTolerance of a
// held bound: a few comparisons per joint; else the contact Jacobian (from the tick's
// forward kinematics, tick_steps.hpp hand_kinematics) and a Dim x Dim symmetric eigenproblem per
// held joint (one more, and at most C(h, 1) + ... + C(h, Dim) solves of size <= Dim for the cone,
// with h >= 2 joints held).
//
// noexcept, no allocation (fixed or bounded DOF).
#pragma once

#include <cstddef>

#include "inhand/controller/finger_motion.hpp"
#include "inhand/kinematics/contact_kinematics.hpp"

namespace inhand::detail {

/// Within this distance [rad] of the bound the IK holds a joint at, the joint counts as
/// held: a joint that reaches its bound through an actuator lag gets there asymptotically.
template <typename Scalar>
constexpr Scalar kHeldJointTolerance = Scalar(1e-4);

/// The file comment, for every touching finger of `tick` (its config, input, gated
/// object pose, dt); `scratch` holds each finger's FingerServo, and a finger's
/// state.fingers[i].jacobian is written with its contact Jacobian (what layer 3 writes
/// there later in the tick: call after the force layer, which reads last tick's).
/// Returns true when the twist asked for motion a held joint cannot give; with `cut` the
/// twist is also projected as the file comment says.
template <typename Types, typename Tick, typename State, typename Scratch>
bool keep_twist_in_reach(const Tick& tick, State& state, Scratch& scratch,
                         typename Types::TwistT& twist, bool cut) noexcept {
  using Scalar = typename Types::ScalarType;
  using Vec = typename Types::Vec;
  using TwistT = typename Types::TwistT;
  constexpr Scalar tol = kHeldJointTolerance<Scalar>;
  bool asked = false;
  for (int sweep = 0; sweep < (cut ? 2 : 1); ++sweep) {
    for (std::size_t i = 0; i < tick.in.fingers.size(); ++i) {
      const typename Types::FingerInput& f = tick.in.fingers[i];
      auto& servo = scratch.fingers[i].layer3;
      if (!f.contact.touching || !servo.at_position_limit(f.joint_positions, tol)) continue;
      const FingerPoints<Types> points(tick.config.fingers[i], f, scratch.fingers[i].kinematics);
      typename Types::Jacobian& J = state.fingers[i].jacobian;
      points.jacobian(f.contact.contact_point, J);
      const Vec n = f.contact.normal.normalized();
      servo.for_each_unreachable_direction(
          J, f.joint_positions, tick.dt, tol,
          [&](const Vec& b) {
            const Vec a = cut ? b : Vec(b.dot(n) * n);
            TwistT c;
            for (int k = 0; k < c.size(); ++k)
              c(k) = a.dot(contact_point_velocity<Scalar, Types::kDim>(
                  TwistT::Unit(c.size(), k), f.contact.contact_point, tick.object.position));
            const Scalar along = c.dot(twist), cc = c.squaredNorm();
            // A contact point so far out that c overflows gives no usable constraint.
            if (!(along > Scalar(0) && cc > Scalar(0) && is_finite(cc) && is_finite(along))) return;
            asked = true;
            if (cut) twist -= (along / cc) * c;
          },
          &n);
    }
    if (!asked) break;  // nothing cut: a second sweep would find the same
  }
  return asked;
}

/// The twist at the workspace's edge for the manipulation phase (the file comment):
/// `twist` is the pose loop's commanded twist (`pose`'s) on entry and what the fingers
/// follow on return; `at_risk` is the state's hold_risk for this tick. Cuts with
/// Config::keep_twist_in_reach, at risk, or while the state's edge_cut says the last
/// tick's cut is still asked for; returns workspace_limited when the twist asked beyond the
/// edge, with workspace_cut when it was cut.
template <typename Types, typename Tick, typename State, typename Scratch, typename Step>
ControllerWarning cut_twist_at_edge(const Tick& tick, State& state, Scratch& scratch,
                                    const Step& pose, bool at_risk,
                                    typename Types::TwistT& twist) noexcept {
  const bool cut = at_risk || tick.config.keep_twist_in_reach || state.edge_cut;
  const bool asked = keep_twist_in_reach<Types>(tick, state, scratch, twist, cut);
  state.edge_cut = cut && asked;
  if (!asked) return ControllerWarning::none;
  if (!cut) return ControllerWarning::workspace_limited;
  state.pose_loop.hold_integral_along(tick.config.pose_feedback, pose.commanded_twist - twist,
                                      pose.pose_error, tick.dt);
  return ControllerWarning::workspace_limited | ControllerWarning::workspace_cut;
}

}  // namespace inhand::detail
