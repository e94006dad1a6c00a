// The grasp forces of controller/grasp.hpp, computed independently of the controller
// for the tests that check them: the force planner's pattern over the grasp targets'
// expected normals, every finger counted as touching, from a replica planner of the
// configuration (preset fingers nominal_force, balancing fingers what cancels the
// resultant), scaled by force_layer.release_grip, or less so that none exceeds max_force.
// Units: N.
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
    normals.col(i) = targets[static_cast<std::size_t>(i)].normal;
  }
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> f(n);
  inhand::Vector<Scalar, Dim> residual;
  planner.plan(touching, normals, Scalar(1e-3), f, residual);
  // One scale for every finger: release_grip, or the largest that keeps all within max_force.
  const Scalar scale = std::min(static_cast<Scalar>(config.force_layer.release_grip),
                                config.force_planner.max_force / f.maxCoeff());
  std::vector<Scalar> out(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = scale * f(i);
  return out;
}

}  // namespace inhand_test
