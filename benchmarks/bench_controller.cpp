// The whole controller tick, ReactiveController::update, in the manipulation phase
// with every finger touching (layers 1-3: trajectory and pose feedback, force planner,
// per finger eq. 2 + hybrid servo + IK).
//
// Set-up drives each controller the way an application does: configure(), then
// start_grasp() towards each finger's nominal contact, fed with the finger touching
// there with its grasp force (ReactiveController::grasp_force) until update() reports `grasped`,
// then start_manipulation() with a 5 mm reciprocating translation. It then checks that every
// precomputed input gives ControllerStatus::ok with every finger in_contact, so the timed ticks run
// the manipulation path. The timed tick rotates through kSamples sensed states (object pose, joint
// angles, contacts, forces), advancing the clock by kDt. Every 2^16 ticks the controller is
// re-grasped with the timer paused, which keeps a float clock far from its resolution limit.
//
// controller/<hand>: planar2x2, planar2x3 (two opposing planar fingers), spatial3x3
//   (the three-finger preset), allegro4 (4 fingers x 4 DOF), shadow4 (the Shadow-like
//   preset: 3 fingers x 4 DOF + a 5-DOF thumb), shadow5 (4 fingers x 4 DOF + the
//   5-DOF thumb), shadow4_coupled (shadow4 with coupled distal joints; double, bounded).
//   The joint position limits are on in every hand (the default), not binding.
// scaling/<n>: n = 2..6 fingers of 4 DOF (the 4-joint thumb and n - 1 fingers), for
//   the linear fit of the tick time against the finger count.
#include "bench_support.hpp"

namespace inhand_bench {
namespace {

template <typename Ctrl>
class ControllerFixture {
 public:
  using S = typename Ctrl::Scalar;
  static constexpr int Dim = Ctrl::Dim;
  static constexpr int NumFingers = Ctrl::NumFingers;
  static constexpr long kMaintenancePeriod = 1L << 16;

  ControllerFixture(const HandDef<Dim>& hand, std::uint64_t seed) {
    const int n = hand.finger_count();
    typename Ctrl::Config cfg;
    if constexpr (NumFingers == Dynamic) {
      cfg.fingers.resize(static_cast<std::size_t>(n));
      targets_.resize(static_cast<std::size_t>(n));
    } else if (n != NumFingers) {
      throw std::invalid_argument("hand and controller finger counts differ");
    }
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      cfg.fingers[k].chain = convert_chain<typename Ctrl::Chain, Dim>(hand.fingers[k]);
      cfg.fingers[k].role =
          i == hand.thumb ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
    }
    const inhand::Validation v = ctrl_.configure(cfg);
    if (!v.ok())
      throw std::invalid_argument(std::string("configure: ") + v.field + ": " + v.reason);

    // Grasp: each finger touches at its nominal contact with its grasp force (the force
    // planner's pattern over the targets' normals, controller/grasp.hpp).
    grasp_input_ = ctrl_.make_input();
    grasp_input_.object_pose = hand.object.template cast<S>();
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      const RefChain<Dim>& chain = hand.fingers[k];
      inhand::FingerKinematics<RefChain<Dim>> ws(chain);
      inhand::forward_kinematics(chain, hand.grasp_q[k], ws);
      const Vec<Dim> contact = ws.fingertip.position - chain.fingertip_radius * hand.normals[k];
      targets_[k].contact_point = contact.template cast<S>();
      targets_[k].normal = hand.normals[k].template cast<S>();
      auto& f = grasp_input_.fingers[k];
      f.joint_positions = hand.grasp_q[k].template cast<S>();
      f.contact.touching = true;
      f.contact.contact_point = targets_[k].contact_point;
      f.contact.normal = targets_[k].normal;
    }
    if (!ctrl_.start_grasp(targets_).ok()) throw std::runtime_error("start_grasp");
    for (int i = 0; i < n; ++i)
      grasp_input_.fingers[static_cast<std::size_t>(i)].contact.normal_force = ctrl_.grasp_force(i);
    trajectory_.reset(hand.object.template cast<S>());
    inhand::Twist<S, Dim> d = inhand::Twist<S, Dim>::Zero();
    d(0) = S(0.005);
    constexpr int kCycles = 100000;
    if (!trajectory_.append(
            inhand::TrajectorySegment<S, Dim>::reciprocate(d, S(4 * kCycles), kCycles)))
      throw std::logic_error("trajectory");

    for (const HandSample<Dim>& s : random_hand_samples<Dim>(hand, seed)) {
      typename Ctrl::Input in = ctrl_.make_input();
      in.object_pose = s.object.template cast<S>();
      for (int i = 0; i < n; ++i) {
        const auto k = static_cast<std::size_t>(i);
        auto& f = in.fingers[k];
        f.joint_positions = s.fingers[k].q.template cast<S>();
        f.contact.touching = true;
        f.contact.contact_point = s.fingers[k].contact.template cast<S>();
        f.contact.normal = s.fingers[k].normal.template cast<S>();
        f.contact.normal_force = static_cast<S>(s.fingers[k].force);
      }
      inputs_.push_back(in);
    }
    out_ = ctrl_.make_output();

    restart();
    for (int k = 0; k < kSamples; ++k) {
      const inhand::ControllerStatus st = tick();
      if (st != inhand::ControllerStatus::ok)
        throw std::runtime_error(std::string("manipulation tick returned ") +
                                 inhand::to_string(st));
      for (const auto& fo : out_.fingers)
        if (fo.state != inhand::FingerState::in_contact)
          throw std::runtime_error("a finger is not in contact");
    }
    restart();
  }

  void maintain() { restart(); }

  [[gnu::noinline]] inhand::ControllerStatus tick() noexcept {
    typename Ctrl::Input& in = inputs_[next_++ & (kSamples - 1)];
    clock_ += kDt;
    in.time = static_cast<S>(clock_);
    return ctrl_.update(in, out_);
  }

 private:
  /// Re-grasps from scratch and starts the manipulation (not timed).
  void restart() {
    ctrl_.reset();
    clock_ = 0.0;
    if (!ctrl_.start_grasp(targets_).ok()) throw std::runtime_error("start_grasp");
    inhand::ControllerStatus st = inhand::ControllerStatus::grasping;
    for (int k = 0; k < 5000 && st != inhand::ControllerStatus::grasped; ++k) {
      clock_ += kDt;
      grasp_input_.time = static_cast<S>(clock_);
      st = ctrl_.update(grasp_input_, out_);
    }
    if (st != inhand::ControllerStatus::grasped)
      throw std::runtime_error("the grasp did not complete");
    if (!ctrl_.start_manipulation(trajectory_).ok()) throw std::runtime_error("start_manipulation");
  }

  Ctrl ctrl_{};
  inhand::detail::FingerArray<inhand::GraspTarget<S, Dim>, NumFingers> targets_{};
  typename Ctrl::Trajectory trajectory_{};
  typename Ctrl::Input grasp_input_{};
  std::vector<typename Ctrl::Input> inputs_;
  typename Ctrl::Output out_{};
  double clock_ = 0.0;
  std::size_t next_ = 0;
};

template <typename S, int Dim, int NumFingers, int Dof, int MaxDof = Dof>
void add_controller(const std::string& area, const std::string& label, const std::string& storage,
                    const HandDef<Dim>& hand) {
  using Ctrl = inhand::ReactiveController<S, Dim, NumFingers, Dof, MaxDof>;
  add<ControllerFixture<Ctrl>>(area + "/" + label + "/" + scalar_name<S>() + "/" + storage, true,
                               hand, std::uint64_t{505});
}

/// fixed (only for hands whose fingers share one DOF), bounded and dynamic storage.
template <typename S, int Dim, int NumFingers, int UniformDof>
void add_controller_grid(const HandDef<Dim>& hand) {
  constexpr int kCapacity = Dim == 2 ? 3 : 5;
  if constexpr (UniformDof != Dynamic)
    add_controller<S, Dim, NumFingers, UniformDof>("controller", hand.name, "fixed", hand);
  add_controller<S, Dim, NumFingers, Dynamic, kCapacity>("controller", hand.name, "bounded", hand);
  add_controller<S, Dim, Dynamic, Dynamic, Dynamic>("controller", hand.name, "dynamic", hand);
}

/// The four-finger and five-finger hands, whose float/double comparison the report makes.
template <typename S>
void add_large_hand_grid() {
  add_controller_grid<S, 3, 4, 4>(allegro4_hand());
  add_controller_grid<S, 3, 4, Dynamic>(shadow4_hand());
  add_controller_grid<S, 3, 5, Dynamic>(shadow5_hand());
}

/// Every hand in double; float only for the large hands (each float instantiation of the
/// controller costs about half a minute of compile, and the small hands' float figures
/// said nothing the large hands' do not).
void add_hand_grid() {
  add_controller_grid<double, 2, 2, 2>(planar_hand(2));
  add_controller_grid<double, 2, 2, 3>(planar_hand(3));
  add_controller_grid<double, 3, 3, 3>(three_finger_hand());
  add_large_hand_grid<double>();
  add_large_hand_grid<float>();
}

template <int N>
void add_scaling() {
  const HandDef<3> hand = four_dof_hand(N);
  add_controller<double, 3, N, 4>("scaling", std::to_string(N), "fixed", hand);
  add_controller<double, 3, Dynamic, Dynamic, Dynamic>("scaling", std::to_string(N), "dynamic",
                                                       hand);
}

}  // namespace

void register_controller_benchmarks() {
  add_controller<double, 3, 4, Dynamic, 5>("controller", "shadow4_coupled", "bounded",
                                           shadow4_coupled_hand());
  add_hand_grid();
  add_scaling<2>();
  add_scaling<3>();
  add_scaling<4>();
  add_scaling<5>();
  add_scaling<6>();
}

}  // namespace inhand_bench
