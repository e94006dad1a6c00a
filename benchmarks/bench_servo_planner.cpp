// Per-tick cost of the hybrid servo (eqs. 4-7, one finger) and of the force planner
// (section 5, whole hand, every finger touching).
#include "bench_support.hpp"

namespace inhand_bench {
namespace {

template <typename S, int Dim>
class ServoFixture {
 public:
  static constexpr long kMaintenancePeriod = 0;

  ServoFixture(const HandDef<Dim>& hand, std::uint64_t seed) {
    for (const FingerSample<Dim>& s : random_finger_samples<Dim>(hand, 0, seed)) {
      velocity_.push_back(s.velocity.template cast<S>());
      normal_.push_back(s.normal.template cast<S>());
      force_.push_back(static_cast<S>(s.force));
    }
  }

  [[gnu::noinline]] S tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    const inhand::ServoStatus st =
        servo_.update(velocity_[k], S(1), force_[k], normal_[k], true, S(kDt), command_);
    return command_.total(0) + static_cast<S>(st);
  }

 private:
  inhand::HybridServo<S, Dim> servo_{};
  inhand::ServoCommand<S, Dim> command_{};
  std::vector<inhand::Vector<S, Dim>> velocity_;
  std::vector<inhand::Vector<S, Dim>> normal_;
  std::vector<S> force_;
  std::size_t next_ = 0;
};

template <typename S, int NumFingers>
class PlannerFixture {
 public:
  using Planner = inhand::ForcePlanner<S, 3, NumFingers>;
  static constexpr long kMaintenancePeriod = 0;

  PlannerFixture(const HandDef<3>& hand, std::uint64_t seed) : planner_(hand.finger_count()) {
    const int n = hand.finger_count();
    planner_.set_role(hand.thumb, inhand::FingerRole::balancing);
    touching_ = Planner::Mask::Ones(n);
    desired_ = Planner::ForceVector::Zero(n);
    for (const HandSample<3>& s : random_hand_samples<3>(hand, seed)) {
      typename Planner::Normals N(3, n);
      for (int i = 0; i < n; ++i)
        N.col(i) = s.fingers[static_cast<std::size_t>(i)].normal.template cast<S>();
      normals_.push_back(N);
    }
  }

  [[gnu::noinline]] S tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    const inhand::ForcePlanStatus st =
        planner_.plan(touching_, normals_[k], S(kDt), desired_, residual_);
    return desired_(0) + static_cast<S>(st);
  }

 private:
  Planner planner_;
  typename Planner::Mask touching_;
  typename Planner::ForceVector desired_;
  inhand::Vector<S, 3> residual_ = inhand::Vector<S, 3>::Zero();
  std::vector<typename Planner::Normals> normals_;
  std::size_t next_ = 0;
};

template <typename S, int N>
void add_planner(const HandDef<3>& hand, const std::string& storage) {
  add<PlannerFixture<S, N>>("planner/" + hand.name + "/" + scalar_name<S>() + "/" + storage, true,
                            hand, std::uint64_t{303});
}

}  // namespace

void register_servo_planner_benchmarks() {
  const HandDef<3> shadow = shadow4_hand();
  add<ServoFixture<double, 3>>("servo/spatial/double/fixed", true, shadow, std::uint64_t{304});
  add<ServoFixture<float, 3>>("servo/spatial/float/fixed", true, shadow, std::uint64_t{304});
  add<ServoFixture<double, 2>>("servo/planar/double/fixed", true, planar_hand(2),
                               std::uint64_t{304});
  const HandDef<3> shadow5 = shadow5_hand();
  add_planner<double, 4>(shadow, "fixed");
  add_planner<double, Dynamic>(shadow, "dynamic");
  add_planner<float, 4>(shadow, "fixed");
  add_planner<double, 5>(shadow5, "fixed");
  add_planner<double, Dynamic>(shadow5, "dynamic");
}

}  // namespace inhand_bench
