// The campaign's reach check: whether a case's task asks a fingertip to go where its
// joints cannot take it, decided from the hand's kinematics alone, not from what the
// controller did. At the task's start each touching finger's fingertip centre is carried
// with the object along the task's desired poses (the contact held where the grasp put it:
// the fingertip sphere may roll on the object, which moves its centre with the object
// frame either way), and a position IK within the joints' limits looks for joint angles
// that put the centre there. The largest distance left over the path is the case's miss:
// 0 (to the solver's tolerance) when every fingertip can follow, otherwise how far the
// nearest reachable point stays from where the task needs the fingertip. A task with a
// miss is beyond the hand with the grasp it has: the object cannot follow the trajectory
// without a contact sliding or opening, whatever the controller commands.
// Units: m, rad, s. World frame of the plant.
#pragma once

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "inhand/controller/trajectory.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/pose.hpp"

namespace inhand::examples::campaign {

/// Position IK for the fingertip centre within the joint limits, from `q` (updated to the
/// solution): a damped Gauss-Newton step over the free joints, clamped to the limits and
/// halved until it brings the tip closer; a joint at a limit whose gradient points out of
/// the box is held for that step, and a coupled joint follows its leader (q_f = ratio q_l +
/// offset). Its fixed points are the
/// box's local minima of |target - tip(q)|: a local method, it finds the point the joints
/// reach by moving on from q (task_reach warm-starts it along the path, as the fingers
/// move). Returns that distance [m] at the end.
template <typename Chain>
double fingertip_reach(const Chain& chain, typename Chain::JointVector& q,
                       const Eigen::Vector3d& target, int iterations = 500) {
  static_assert(Chain::Dim == 3, "the reach check is for spatial fingers");
  const int n = chain.dof();
  FingerKinematics<Chain> ws(chain);
  Eigen::Matrix<double, 3, Eigen::Dynamic> J(3, n);
  Eigen::VectorXd dq(n);
  typename Chain::JointVector trial = q;
  constexpr double kDamping = 1e-4;  // m: well below the fingers' Jacobian's scale (cm)
  // q + a dq within the limits, the followers set from their leaders.
  const auto step = [&](double a) {
    for (int i = 0; i < n; ++i) {
      const auto& j = chain.joints[i];
      if (!j.coupling.coupled()) trial(i) = std::clamp(q(i) + a * dq(i), j.lower, j.upper);
    }
    for (int i = 0; i < n; ++i) {
      const auto& c = chain.joints[i].coupling;
      if (c.coupled()) trial(i) = c.ratio * trial(c.leader) + c.offset;
    }
  };
  forward_kinematics(chain, q, ws);
  Eigen::Vector3d e = target - ws.fingertip.position;
  for (int it = 0; it < iterations && e.norm() >= 1e-10; ++it) {
    point_jacobian(ws, ws.fingertip.position, J);
    for (int i = 0; i < n; ++i) {  // a follower's column acts through its leader
      const auto& c = chain.joints[i].coupling;
      if (!c.coupled()) continue;
      J.col(c.leader) += c.ratio * J.col(i);
      J.col(i).setZero();
    }
    const Eigen::VectorXd g = J.transpose() * e;  // the descent direction per joint
    for (int i = 0; i < n; ++i) {
      const auto& j = chain.joints[i];
      if ((q(i) <= j.lower && g(i) < 0.0) || (q(i) >= j.upper && g(i) > 0.0)) J.col(i).setZero();
    }
    const Eigen::Matrix3d A = J * J.transpose() + kDamping * kDamping * Eigen::Matrix3d::Identity();
    dq = J.transpose() * A.ldlt().solve(e);
    // Backtracking: a step is taken only if it brings the tip closer (near a singular
    // configuration the full step can overshoot), so the distance never grows.
    bool moved = false;
    for (double a = 1.0; a > 1e-6 && !moved; a *= 0.5) {
      step(a);
      forward_kinematics(chain, trial, ws);
      const Eigen::Vector3d e_trial = target - ws.fingertip.position;
      if (e_trial.norm() < e.norm()) {
        q = trial;
        e = e_trial;
        moved = true;
      }
    }
    if (!moved) break;  // no step within the box brings it closer: a local minimum
    forward_kinematics(chain, q, ws);
  }
  return e.norm();
}

/// The largest miss over a task, and where.
struct ReachMiss {
  int finger = -1;        ///< the finger that misses most (-1: none checked)
  double distance = 0.0;  ///< m
  double at = 0.0;        ///< s into the task
};

/// The task's reach for the fingers given (their chains, joint angles and fingertip centres
/// now, at the task's start): the segments' desired poses, from `start` (the pose the task
/// starts from), sampled every `step` seconds to their end, each finger's IK warm-started
/// from the previous sample (the path the fingers would take).
template <typename Chain>
ReachMiss task_reach(const std::vector<const Chain*>& chains,
                     std::vector<typename Chain::JointVector> q,
                     const std::vector<Eigen::Vector3d>& fingertips, const Pose<double, 3>& start,
                     const std::vector<TrajectorySegment<double, 3>>& segments,
                     double step = 0.01) {
  ObjectTrajectory<double, 3> trajectory;
  trajectory.reset(start);
  double duration = 0.0;
  for (const auto& s : segments) {
    trajectory.append(s);
    duration += s.duration;
  }
  const Pose<double, 3> to_object = start.inverse();
  ReachMiss miss;
  const int samples = static_cast<int>(std::ceil(duration / step));
  for (int k = 1; k <= samples; ++k) {
    const double t = std::min(duration, k * step);
    const Pose<double, 3> moved = trajectory.evaluate(t).pose * to_object;
    for (std::size_t i = 0; i < chains.size(); ++i) {
      const double d = fingertip_reach(*chains[i], q[i], moved.transform_point(fingertips[i]));
      if (miss.finger < 0 || d > miss.distance) miss = {static_cast<int>(i), d, t};
    }
  }
  return miss;
}

}  // namespace inhand::examples::campaign
