// Finger kinematics per tick: forward_kinematics (joint frames and fingertip, with the
// chain's plan, as the controller) followed
// by point_jacobian at the measured contact point, i.e. what the controller computes
// for one finger before its IK. Cases: planar 2 and 3 joints, spatial 3 (the
// three-finger hand's finger), 4 (a Shadow-like finger) and 5 (the Shadow-like thumb).
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

}  // namespace

void register_kinematics_benchmarks() {
  add_kinematics_grid<2, 2>(planar_hand(2), 0, "planar2");
  add_kinematics_grid<2, 3>(planar_hand(3), 0, "planar3");
  add_kinematics_grid<3, 3>(three_finger_hand(), 0, "spatial3");
  const HandDef<3> shadow = shadow4_hand();
  add_kinematics_grid<3, 4>(shadow, 0, "spatial4");
  add_kinematics_grid<3, 5>(shadow, shadow.thumb, "spatial5");
}

}  // namespace inhand_bench
