// One finger's share of a control tick, and the latency floor it is judged against.
//
// finger/<case>: forward_kinematics (with the chain's plan, as the controller) +
//   point_jacobian at the contact point + hybrid
//   servo update + ContactIk::solve: everything the controller does per touching
//   finger (layer 3) apart from the bookkeeping.
// floor/sincos4: the 4-joint finger's unavoidable transcendental work, the sines and
//   cosines of its 4 joint angles by inhand::sin_cos (math/sin_cos.hpp), as forward
//   kinematics evaluates them; floor/sincos4_libm: the same by std::sin and std::cos, one
//   angle at a time (the floor before forward kinematics used sin_cos).
// floor/solve3x4: the dependency chain of the 3x4 minimum-norm solve at its bare
//   minimum: Gram matrix J J^T, 3x3 Cholesky (3 square roots, 3 reciprocals), the
//   two triangular substitutions and x = J^T y, with no checks, no singular-value
//   estimate and no damping decision.
// The floor of the 4-joint finger is the sum of the two.
#include "bench_support.hpp"

namespace inhand_bench {
namespace {

template <bool kLibm>
class SinCosFloorFixture {
 public:
  static constexpr long kMaintenancePeriod = 0;

  explicit SinCosFloorFixture(std::uint64_t seed) {
    const HandDef<3> shadow = shadow4_hand();
    for (const FingerSample<3>& s : random_finger_samples<3>(shadow, 0, seed)) {
      angles_.push_back({s.q(0), s.q(1), s.q(2), s.q(3)});
    }
  }

  [[gnu::noinline]] double tick() noexcept {
    const std::array<double, 4>& a = angles_[next_++ & (kSamples - 1)];
    if constexpr (kLibm) {
      for (std::size_t i = 0; i < 4; ++i) {
        out_[i] = std::sin(a[i]);
        out_[4 + i] = std::cos(a[i]);
      }
    } else {
      inhand::sin_cos(a.data(), out_.data(), out_.data() + 4, 4);
    }
    return out_[0];
  }

 private:
  std::vector<std::array<double, 4>> angles_;
  std::array<double, 8> out_{};
  std::size_t next_ = 0;
};

class SolveFloorFixture {
 public:
  static constexpr long kMaintenancePeriod = 0;

  explicit SolveFloorFixture(std::uint64_t seed) {
    const HandDef<3> shadow = shadow4_hand();
    using Chain = inhand::FingerChain<double, 3, 4>;
    const Chain chain = convert_chain<Chain, 3>(shadow.fingers[0]);
    inhand::FingerKinematics<Chain> ws(chain);
    for (const FingerSample<3>& s : random_finger_samples<3>(shadow, 0, seed)) {
      Chain::Jacobian J;
      inhand::forward_kinematics(chain, s.q, ws);
      inhand::point_jacobian(ws, s.contact, J);
      jacobian_.push_back(J);
      rhs_.push_back(s.velocity);
    }
  }

  [[gnu::noinline]] double tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    const Eigen::Matrix<double, 3, 4>& J = jacobian_[k];
    const Eigen::Vector3d& b = rhs_[k];
    Eigen::Matrix3d G;
    G.noalias() = J * J.transpose();
    const double l00 = std::sqrt(G(0, 0)), i00 = 1.0 / l00;
    const double l10 = G(1, 0) * i00, l20 = G(2, 0) * i00;
    const double l11 = std::sqrt(G(1, 1) - l10 * l10), i11 = 1.0 / l11;
    const double l21 = (G(2, 1) - l20 * l10) * i11;
    const double l22 = std::sqrt(G(2, 2) - l20 * l20 - l21 * l21), i22 = 1.0 / l22;
    const double y0 = b(0) * i00, y1 = (b(1) - l10 * y0) * i11,
                 y2 = (b(2) - l20 * y0 - l21 * y1) * i22;
    const double z2 = y2 * i22, z1 = (y1 - l21 * z2) * i11, z0 = (y0 - l10 * z1 - l20 * z2) * i00;
    x_.noalias() = J.transpose() * Eigen::Vector3d(z0, z1, z2);
    return x_(0);
  }

 private:
  std::vector<Eigen::Matrix<double, 3, 4>> jacobian_;
  std::vector<Eigen::Vector3d> rhs_;
  Eigen::Vector4d x_ = Eigen::Vector4d::Zero();
  std::size_t next_ = 0;
};

template <typename Chain>
class FingerFixture {
 public:
  using S = typename Chain::Scalar;
  static constexpr int Dim = Chain::Dim;
  static constexpr long kMaintenancePeriod = 0;
  using Ik = inhand::ContactIk<S, Dim, Chain::Dof, Chain::MaxDof>;

  FingerFixture(const HandDef<Dim>& hand, int finger, std::uint64_t seed)
      : chain_(convert_chain<Chain, Dim>(hand.fingers[static_cast<std::size_t>(finger)])),
        plan_(chain_),
        ws_(chain_),
        ik_(chain_.dof()),
        jacobian_(Dim, chain_.dof()) {
    jacobian_.setZero();
    max_velocity_ = chain_.velocity_limits();
    theta_dot_.setZero(chain_.dof());
    for (const FingerSample<Dim>& s : random_finger_samples<Dim>(hand, finger, seed)) {
      q_.push_back(s.q.template cast<S>());
      contact_.push_back(s.contact.template cast<S>());
      normal_.push_back(s.normal.template cast<S>());
      velocity_.push_back(s.velocity.template cast<S>());
      force_.push_back(static_cast<S>(s.force));
    }
  }

  [[gnu::noinline]] S tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    inhand::forward_kinematics(chain_, plan_, q_[k], ws_);
    inhand::point_jacobian(ws_, contact_[k], jacobian_);
    servo_.update(velocity_[k], S(1), force_[k], normal_[k], true, S(kDt), command_);
    const inhand::IkReport<S> r = ik_.solve(jacobian_, command_.total, max_velocity_, theta_dot_);
    return r.limit_scale + theta_dot_(0);
  }

 private:
  Chain chain_;
  inhand::ChainPlan<Chain> plan_;
  inhand::FingerKinematics<Chain> ws_;
  Ik ik_;
  inhand::HybridServo<S, Dim> servo_{};
  inhand::ServoCommand<S, Dim> command_{};
  typename Chain::Jacobian jacobian_;
  typename Chain::JointVector max_velocity_;
  typename Chain::JointVector theta_dot_;
  std::vector<typename Chain::JointVector> q_;
  std::vector<inhand::Vector<S, Dim>> contact_, normal_, velocity_;
  std::vector<S> force_;
  std::size_t next_ = 0;
};

template <typename S, int Dof, int MaxDof>
void add_finger(const std::string& label, const std::string& storage, const HandDef<3>& hand,
                int finger) {
  using Chain = inhand::FingerChain<S, 3, Dof, MaxDof>;
  add<FingerFixture<Chain>>("finger/" + label + "/" + scalar_name<S>() + "/" + storage, true, hand,
                            finger, std::uint64_t{404});
}

}  // namespace

void register_floor_benchmarks() {
  add<SinCosFloorFixture<false>>("floor/sincos4/double", true, std::uint64_t{404});
  add<SinCosFloorFixture<true>>("floor/sincos4_libm/double", true, std::uint64_t{404});
  add<SolveFloorFixture>("floor/solve3x4/double", true, std::uint64_t{404});
}

void register_finger_benchmarks() {
  const HandDef<3> shadow = shadow4_hand();
  add_finger<double, 4, 4>("spatial4", "fixed", shadow, 0);
  add_finger<double, Dynamic, 5>("spatial4", "bounded", shadow, 0);
  add_finger<double, Dynamic, Dynamic>("spatial4", "dynamic", shadow, 0);
  add_finger<float, 4, 4>("spatial4", "fixed", shadow, 0);
  add_finger<double, 3, 3>("spatial3", "fixed", three_finger_hand(), 0);
  add_finger<double, 5, 5>("spatial5", "fixed", shadow, shadow.thumb);
}

}  // namespace inhand_bench
