// Forward kinematics of the whole hand, once per tick (docs/method.md section 4), with the
// fingers that repeat one design evaluated side by side (kinematics/finger_lanes.hpp).
//
// HandLanes is derived from the configuration once (configure()): the fingers whose
// kinematics come from their chain are grouped, in finger order, with the later fingers
// whose chain plan they share (lanes_share_plan), up to kFingerLanes a group. A group of
// kMinLaneGroup<Scalar> or more runs as one ChainLanes; every other chain finger runs
// forward_kinematics(chain, plan, q, ws) alone. A ChainLanes costs the work of four fingers
// whatever it holds: three fingers pay when a lane's four values fit one vector register of
// the build (float with SSE2 or NEON, double with AVX), four otherwise (double with SSE2:
// three Shadow-like fingers in lanes executed 1 % more instructions a tick than alone, four
// 2 % fewer; docs/benchmarks.md, "SIMD lanes across fingers"). Fingers with
// KinematicsSource::external are not evaluated. Either way each finger's workspace
// holds what forward_kinematics() writes (finger_lanes.hpp says to which rounding).
// run() is noexcept and allocation-free; building allocates only for run-time sizes.
#pragma once

#include <cstddef>
#include <type_traits>

#include "inhand/controller/controller_io.hpp"
#include "inhand/kinematics/finger_lanes.hpp"

namespace inhand {

/// The fewest fingers evaluated as one ChainLanes (the file comment): 3 when a lane of
/// kFingerLanes Scalars fits the widest vector register Eigen aligns for, else kFingerLanes.
template <typename Scalar>
inline constexpr int kMinLaneGroup =
    static_cast<int>(kFingerLanes * sizeof(Scalar)) <= EIGEN_MAX_STATIC_ALIGN_BYTES ? 3
                                                                                    : kFingerLanes;

template <typename Types>
class HandLanes {
 public:
  using Chain = typename Types::Chain;
  static constexpr int kNumFingers = Types::kNumFingers;
  static constexpr int kMinGroup = kMinLaneGroup<typename Types::ScalarType>;
  /// At most one group per kMinGroup fingers.
  static constexpr int kMaxGroups =
      kNumFingers == Dynamic ? Dynamic : (kNumFingers >= kMinGroup ? kNumFingers / kMinGroup : 1);

  /// Groups the chain fingers of `config`; plan(i) gives finger i's ChainPlan. Allocates
  /// only for run-time sizes.
  template <typename PlanOf>
  void build(const typename Types::Config& config, PlanOf&& plan) {
    const int n = static_cast<int>(config.fingers.size());
    if constexpr (kNumFingers == Dynamic) {
      laned_.assign(static_cast<std::size_t>(n), 0);
      groups_.clear();
    } else {
      laned_.fill(0);
    }
    group_count_ = 0;
    if constexpr (Types::kDim == 3) {
      for (int i = 0; i < n; ++i) {
        if (laned_[idx(i)] || !chain_finger(config, i) || !can_lane(plan(i))) continue;
        int members[kFingerLanes] = {i};
        int count = 1;
        for (int j = i + 1; j < n && count < kFingerLanes; ++j)
          if (!laned_[idx(j)] && chain_finger(config, j) && lanes_share_plan(plan(i), plan(j)))
            members[count++] = j;
        if (count < kMinGroup) continue;
        const Chain* chains[kFingerLanes];
        for (int l = 0; l < count; ++l) {
          chains[l] = &config.fingers[idx(members[l])].chain;
          laned_[idx(members[l])] = 1;
        }
        Group g{ChainLanes<Chain>(chains, count, plan(i)), {}};
        for (int l = 0; l < count; ++l) g.members[l] = members[l];
        if constexpr (kMaxGroups == Dynamic) {
          groups_.push_back(g);
        } else {
          groups_[idx(group_count_)] = g;
        }
        ++group_count_;
      }
    }
  }

  /// Number of groups evaluated in lanes.
  int group_count() const noexcept { return group_count_; }
  /// Whether finger i is evaluated in one of the groups.
  bool laned(int i) const noexcept { return laned_[idx(i)] != 0; }

  /// Forward kinematics of every chain finger at in.fingers[i].joint_positions:
  /// kinematics(i) is finger i's workspace, plan(i) its ChainPlan. noexcept, no allocation.
  template <typename PlanOf, typename KinematicsOf>
  void run(const typename Types::Config& config, const typename Types::Input& in, PlanOf&& plan,
           KinematicsOf&& kinematics) const noexcept {
    if constexpr (Types::kDim == 3) {
      for (int g = 0; g < group_count_; ++g) {
        const Group& grp = groups_[idx(g)];
        const typename Chain::Scalar* q[kFingerLanes];
        FingerKinematics<Chain>* ws[kFingerLanes];
        const int count = grp.lanes.count();
        for (int l = 0; l < count; ++l) {
          q[l] = in.fingers[idx(grp.members[l])].joint_positions.data();
          ws[l] = &kinematics(grp.members[l]);
        }
        grp.lanes.forward_kinematics(q, ws);
      }
    }
    for (int i = 0; i < static_cast<int>(config.fingers.size()); ++i)
      if (!laned_[idx(i)] && chain_finger(config, i))
        forward_kinematics(config.fingers[idx(i)].chain, plan(i),
                           in.fingers[idx(i)].joint_positions, kinematics(i));
  }

 private:
  struct Group {
    /// (A planar hand has no groups: a placeholder.)
    std::conditional_t<Types::kDim == 3, ChainLanes<Chain>, char> lanes;
    int members[kFingerLanes];
  };
  static std::size_t idx(int i) noexcept { return static_cast<std::size_t>(i); }
  static bool chain_finger(const typename Types::Config& config, int i) noexcept {
    return config.fingers[idx(i)].kinematics == KinematicsSource::chain;
  }

  detail::FingerArray<unsigned char, kNumFingers> laned_{};
  detail::FingerArray<Group, kMaxGroups> groups_{};
  int group_count_ = 0;
};

}  // namespace inhand
