// Finger kinematics per tick: forward_kinematics (joint frames and fingertip, with the
// chain's plan, as the controller) followed
// by point_jacobian at the measured contact point, i.e. what the controller computes
// for one finger before its IK. Cases: planar 2 and 3 joints, spatial 3 (the
// three-finger hand's finger), 4 (a Shadow-like finger) and 5 (the Shadow-like thumb).
//
// fingers4x4/{each,lanes}: forward kinematics of the five-finger Shadow-like hand's four
// 4-DOF fingers (one plan: the same axes, no turned frame), finger after finger as the
// controller runs it (`each`), against the same four evaluated side by side in the lanes
// of Eigen arrays (`lanes`: one array of 4 doubles per coordinate, each joint's step
// applied to all four fingers at once: kinematics/finger_lanes.hpp, what the controller
// runs for such fingers). The fixture checks at set-up that both give the same values
// (bitwise without fused multiply-adds; within 1e-14 with them).
#include "bench_support.hpp"

namespace inhand_bench {
namespace {

template <typename Chain>
class KinematicsFixture {
 public:
  using S = typename Chain::Scalar;
  static constexpr int Dim = Chain::Dim;
  static constexpr long kMaintenancePeriod = 0;

  KinematicsFixture(const HandDef<Dim>& hand, int finger, std::uint64_t seed)
      : chain_(convert_chain<Chain, Dim>(hand.fingers[static_cast<std::size_t>(finger)])),
        plan_(chain_),
        ws_(chain_),
        jacobian_(Dim, chain_.dof()) {
    jacobian_.setZero();
    for (const FingerSample<Dim>& s : random_finger_samples<Dim>(hand, finger, seed)) {
      q_.push_back(s.q.template cast<S>());
      contact_.push_back(s.contact.template cast<S>());
    }
  }

  [[gnu::noinline]] S tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    inhand::forward_kinematics(chain_, plan_, q_[k], ws_);
    inhand::point_jacobian(ws_, contact_[k], jacobian_);
    return jacobian_(0, 0);
  }

 private:
  Chain chain_;
  inhand::ChainPlan<Chain> plan_;
  inhand::FingerKinematics<Chain> ws_;
  typename Chain::Jacobian jacobian_;
  std::vector<typename Chain::JointVector> q_;
  std::vector<inhand::Vector<S, Dim>> contact_;
  std::size_t next_ = 0;
};

template <typename S, int Dim, int Dof, int MaxDof>
void add_kinematics(const std::string& storage, const HandDef<Dim>& hand, int finger,
                    const std::string& label) {
  using Chain = inhand::FingerChain<S, Dim, Dof, MaxDof>;
  add<KinematicsFixture<Chain>>("kinematics/" + label + "/" + scalar_name<S>() + "/" + storage,
                                true, hand, finger, std::uint64_t{101});
}

/// double: fixed, bounded and dynamic storage; float: fixed.
template <int Dim, int N>
void add_kinematics_grid(const HandDef<Dim>& hand, int finger, const std::string& label) {
  constexpr int kCapacity = Dim == 2 ? 3 : 5;
  add_kinematics<double, Dim, N, N>("fixed", hand, finger, label);
  add_kinematics<double, Dim, Dynamic, kCapacity>("bounded", hand, finger, label);
  add_kinematics<double, Dim, Dynamic, Dynamic>("dynamic", hand, finger, label);
  add_kinematics<float, Dim, N, N>("fixed", hand, finger, label);
}

/// The four 4-DOF fingers' forward kinematics; `kLanes`: side by side (file comment).
template <bool kLanes>
class FingersFixture {
 public:
  using Chain = inhand::FingerChain<double, 3, 4, 4>;
  static constexpr int kFingers = 4;
  static constexpr long kMaintenancePeriod = 0;
  using Ws = inhand::FingerKinematics<Chain>;

  explicit FingersFixture(const HandDef<3>& hand) {
    const Chain* chains[kFingers];
    for (int f = 0; f < kFingers; ++f) {
      chains_[f] = convert_chain<Chain, 3>(hand.fingers[static_cast<std::size_t>(f)]);
      plans_[f] = inhand::ChainPlan<Chain>(chains_[f]);
      ws_[f] = Ws(chains_[f]);
      ws_ptr_[f] = &ws_[f];
      chains[f] = &chains_[f];
      for (const FingerSample<3>& s : random_finger_samples<3>(hand, f, std::uint64_t{103}))
        q_[f].push_back(s.q);
      if (!inhand::lanes_share_plan(plans_[0], plans_[f]))
        throw std::runtime_error("the fingers do not share one plan");
    }
    lanes_ = inhand::ChainLanes<Chain>(chains, kFingers, plans_[0]);
    // Both forms give the same values: bitwise without fused multiply-adds, to rounding with
    // them (-march=native).
    Ws each[kFingers];
    for (int f = 0; f < kFingers; ++f) {
      inhand::forward_kinematics(chains_[f], plans_[f], q_[f][0], ws_[f]);
      each[f] = ws_[f];
    }
    tick();
    next_ = 0;
    for (int f = 0; f < kFingers; ++f)
      if (kLanes &&
          !((each[f].joint_origins - ws_[f].joint_origins).cwiseAbs().maxCoeff() <= 1e-14 &&
            (each[f].joint_axes - ws_[f].joint_axes).cwiseAbs().maxCoeff() <= 1e-14 &&
            (each[f].fingertip.position - ws_[f].fingertip.position).cwiseAbs().maxCoeff() <=
                1e-14 &&
            (each[f].fingertip.rotation - ws_[f].fingertip.rotation).cwiseAbs().maxCoeff() <=
                1e-14))
        throw std::runtime_error("lanes and each differ");
  }

  [[gnu::noinline]] double tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    if constexpr (kLanes) {
      const double* q[kFingers];
      for (int f = 0; f < kFingers; ++f) q[f] = q_[f][k].data();
      lanes_.forward_kinematics(q, ws_ptr_);
    } else {
      for (int f = 0; f < kFingers; ++f)
        inhand::forward_kinematics(chains_[f], plans_[f], q_[f][k], ws_[f]);
    }
    return ws_[0].fingertip.position(0) + ws_[kFingers - 1].fingertip.position(0);
  }

 private:
  Chain chains_[kFingers];
  inhand::ChainPlan<Chain> plans_[kFingers];
  inhand::ChainLanes<Chain> lanes_;
  Ws ws_[kFingers];
  Ws* ws_ptr_[kFingers];
  std::vector<typename Chain::JointVector> q_[kFingers];
  std::size_t next_ = 0;
};

}  // namespace

void register_kinematics_benchmarks() {
  add_kinematics_grid<2, 2>(planar_hand(2), 0, "planar2");
  add_kinematics_grid<2, 3>(planar_hand(3), 0, "planar3");
  add_kinematics_grid<3, 3>(three_finger_hand(), 0, "spatial3");
  const HandDef<3> shadow = shadow4_hand();
  add_kinematics_grid<3, 4>(shadow, 0, "spatial4");
  add_kinematics_grid<3, 5>(shadow, shadow.thumb, "spatial5");
  const HandDef<3> shadow5 = shadow5_hand();
  add<FingersFixture<false>>("kinematics/fingers4x4/double/each", true, shadow5);
  add<FingersFixture<true>>("kinematics/fingers4x4/double/lanes", true, shadow5);
}

}  // namespace inhand_bench
