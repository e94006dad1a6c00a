// Contact-point IK per tick: ContactIk::solve (eq. 3) with the joint velocity limits.
//   m x n = 2x2, 3x3      exact inverse (planar 2-joint, spatial 3-joint finger)
//   2x3, 3x4, 3x5         minimum-norm pseudo-inverse (planar 3-joint, Shadow-like
//                         finger, Shadow-like thumb)
//   3x3_damped, 3x4_damped  near-singular (almost straight) fingers: the damped
//                         least-squares path (sigma_min below the damping threshold)
// Jacobians are the fingers' contact-point Jacobians at the sampled configurations;
// the set-up checks that every regular input is solved undamped and every
// near-singular one damped, so each benchmark times the path its name says.
#include "bench_support.hpp"

namespace inhand_bench {
namespace {

template <typename S, int Dim, int Dof, int MaxDof>
class IkFixture {
 public:
  using Ik = inhand::ContactIk<S, Dim, Dof, MaxDof>;
  using Chain = inhand::FingerChain<S, Dim, Dof, MaxDof>;
  static constexpr long kMaintenancePeriod = 0;

  IkFixture(const HandDef<Dim>& hand, int finger, Conditioning mode, std::uint64_t seed)
      : ik_(hand.fingers[static_cast<std::size_t>(finger)].dof()) {
    const Chain chain = convert_chain<Chain, Dim>(hand.fingers[static_cast<std::size_t>(finger)]);
    inhand::FingerKinematics<Chain> ws(chain);
    // Element-wise: GCC 12 reports a false -Wstringop-overflow for the move
    // assignment of a bounded (MaxRows = 5) vector here.
    max_velocity_.resize(chain.dof());
    for (int i = 0; i < chain.dof(); ++i) max_velocity_(i) = chain.joints[i].max_velocity;
    theta_dot_.setZero(chain.dof());
    for (const FingerSample<Dim>& s : random_finger_samples<Dim>(hand, finger, seed, mode)) {
      typename Chain::Jacobian J(Dim, chain.dof());
      inhand::forward_kinematics(chain, s.q.template cast<S>(), ws);
      inhand::point_jacobian(ws, s.contact.template cast<S>(), J);
      jacobian_.push_back(J);
      velocity_.push_back(s.velocity.template cast<S>());
      const inhand::IkReport<S> r = ik_.solve(J, velocity_.back(), max_velocity_, theta_dot_);
      if (inhand::has(r.status, inhand::IkStatus::damped) != (mode == Conditioning::near_singular))
        throw std::runtime_error("set-up: an input takes the other IK path than the benchmark's");
    }
  }

  [[gnu::noinline]] S tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    const inhand::IkReport<S> r = ik_.solve(jacobian_[k], velocity_[k], max_velocity_, theta_dot_);
    return r.limit_scale + theta_dot_(0);
  }

 private:
  Ik ik_;
  typename Ik::JointVector max_velocity_;
  typename Ik::JointVector theta_dot_;
  std::vector<typename Ik::Jacobian> jacobian_;
  std::vector<typename Ik::CartesianVector> velocity_;
  std::size_t next_ = 0;
};

template <typename S, int Dim, int Dof, int MaxDof>
void add_ik(const std::string& label, const std::string& storage, const HandDef<Dim>& hand,
            int finger, Conditioning mode) {
  add<IkFixture<S, Dim, Dof, MaxDof>>("ik/" + label + "/" + scalar_name<S>() + "/" + storage, true,
                                      hand, finger, mode, std::uint64_t{202});
}

/// double and float with fixed sizes; with `all_storage` also double bounded and dynamic.
template <int Dim, int N>
void add_ik_grid(const std::string& label, const HandDef<Dim>& hand, int finger, Conditioning mode,
                 bool all_storage) {
  constexpr int kCapacity = Dim == 2 ? 3 : 5;
  add_ik<double, Dim, N, N>(label, "fixed", hand, finger, mode);
  if (all_storage) {
    add_ik<double, Dim, Dynamic, kCapacity>(label, "bounded", hand, finger, mode);
    add_ik<double, Dim, Dynamic, Dynamic>(label, "dynamic", hand, finger, mode);
  }
  add_ik<float, Dim, N, N>(label, "fixed", hand, finger, mode);
}

}  // namespace

void register_ik_benchmarks() {
  const HandDef<3> shadow = shadow4_hand();
  const HandDef<3> three = three_finger_hand();
  add_ik_grid<2, 2>("2x2", planar_hand(2), 0, Conditioning::regular, false);
  add_ik_grid<2, 3>("2x3", planar_hand(3), 0, Conditioning::regular, false);
  add_ik_grid<3, 3>("3x3", three, 0, Conditioning::regular, false);
  add_ik_grid<3, 4>("3x4", shadow, 0, Conditioning::regular, true);
  add_ik_grid<3, 5>("3x5", shadow, shadow.thumb, Conditioning::regular, true);
  add_ik_grid<3, 3>("3x3_damped", three, 0, Conditioning::near_singular, false);
  add_ik_grid<3, 4>("3x4_damped", shadow, 0, Conditioning::near_singular, true);
}

}  // namespace inhand_bench
