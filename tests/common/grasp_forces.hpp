// The grasp forces of controller/grasp.hpp, computed independently of the controller
// for the tests that check them: the force planner's pattern over the grasp targets'
// expected normals, every finger counted as touching, from a replica planner of the
// configuration (preset fingers nominal_force, balancing fingers what cancels the
// resultant), scaled by s_g: force_layer.release_grip, or more where a load of
// force_layer.release_load along any direction would take some finger below min_force
// under the equal-stiffness translation response, or twice release_load along
// force_layer.gravity_direction where it is set (release_grip.hpp), or less so that none
// exceeds max_force. Units: N.
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

#include "inhand/controller/force_planner.hpp"

namespace inhand_test {

/// `config`: a ReactiveController Config (fingers[i].role, force_planner); `targets`:
/// one GraspTarget per finger. Returns f_g per finger.
template <typename Scalar, int Dim, typename Config, typename Targets>
std::vector<Scalar> grasp_forces(const Config& config, const Targets& targets) {
  const int n = static_cast<int>(targets.size());
  inhand::ForcePlanner<Scalar, Dim, inhand::Dynamic> planner(n);
  planner.set_params(config.force_planner);
  Eigen::Matrix<unsigned char, Eigen::Dynamic, 1> touching =
      Eigen::Matrix<unsigned char, Eigen::Dynamic, 1>::Ones(n);
  Eigen::Matrix<Scalar, Dim, Eigen::Dynamic> normals(Dim, n);
  for (int i = 0; i < n; ++i) {
    planner.set_role(i, config.fingers[static_cast<std::size_t>(i)].role);
    normals.col(i) = targets[static_cast<std::size_t>(i)].normal.normalized();
  }
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> f(n);
  inhand::Vector<Scalar, Dim> residual;
  planner.plan(touching, normals, Scalar(1e-3), f, residual);
  // One scale for every finger: release_grip, raised so that each finger keeps min_force
  // when it loses release_load |G^-1 n_i| (G = sum n n^T + rigid_tolerance I), then the
  // largest that keeps all within max_force.
  Eigen::Matrix<Scalar, Dim, Dim> G =
      config.force_layer.rigid_tolerance * Eigen::Matrix<Scalar, Dim, Dim>::Identity();
  for (int i = 0; i < n; ++i) G += normals.col(i) * normals.col(i).transpose();
  // Along gravity (a planar hand: its part in the plane): the fingers the weight unloads,
  // each by twice its static share.
  inhand::Vector<Scalar, Dim> g = config.force_layer.gravity_direction.template head<Dim>();
  if (g.norm() > Scalar(1e-6))
    g.normalize();
  else
    g.setZero();
  const inhand::Vector<Scalar, Dim> share = G.ldlt().solve(g);
  Scalar wanted = static_cast<Scalar>(config.force_layer.release_grip);
  for (int i = 0; i < n; ++i) {
    const Scalar any = G.ldlt().solve(normals.col(i).eval()).norm();
    const Scalar along = Scalar(2) * std::max(Scalar(0), -normals.col(i).dot(share));
    const Scalar loss = config.force_layer.release_load * std::max(any, along);
    if (f(i) > Scalar(0)) wanted = std::max(wanted, (config.force_planner.min_force + loss) / f(i));
  }
  const Scalar scale = std::min(wanted, config.force_planner.max_force / f.maxCoeff());
  std::vector<Scalar> out(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = scale * f(i);
  return out;
}

}  // namespace inhand_test
