// Consumer compiled with strict warnings as errors (-Wall -Wextra -Wconversion
// -Wsign-conversion -Werror, inhand's include directory NOT a system directory, so
// inhand's own headers are checked): the spatial controller with 3 fingers of 4
// joints, in double and in float, configured and run through a grasp. Returns
// non-zero unless both configure and tick.
#include <inhand/inhand.hpp>

namespace {

template <typename Scalar>
int run() {
  using Controller = inhand::ReactiveController<Scalar, 3, 3, 4>;
  using Vec3 = inhand::Vector<Scalar, 3>;
  typename Controller::Config config;
  for (std::size_t i = 0; i < config.fingers.size(); ++i) {
    auto& chain = config.fingers[i].chain;
    const Scalar side = static_cast<Scalar>(i) - Scalar(1);
    chain.base.position = Vec3(Scalar(0.03) * side, Scalar(-0.05), Scalar(0));
    chain.joints[0].axis = Vec3::UnitY();
    for (int j = 1; j < 4; ++j) {
      chain.joints[j].parent_to_joint.position = Vec3(Scalar(0), Scalar(0.03), Scalar(0));
      chain.joints[j].axis = -Vec3::UnitX();
    }
    chain.joint_to_tip.position = Vec3(Scalar(0), Scalar(0.025), Scalar(0));
    chain.fingertip_radius = Scalar(0.01);
    config.fingers[i].role = i == 0 ? inhand::FingerRole::balancing : inhand::FingerRole::preset;
  }
  Controller controller;
  if (!controller.configure(config).ok()) return 1;

  typename Controller::Input in = controller.make_input();
  typename Controller::Output out = controller.make_output();
  inhand::detail::FingerArray<inhand::GraspTarget<Scalar, 3>, 3> targets{};
  for (std::size_t i = 0; i < targets.size(); ++i) {
    targets[i].contact_point =
        Vec3(Scalar(0.03) * (static_cast<Scalar>(i) - Scalar(1)), Scalar(0.02), Scalar(0.05));
    targets[i].normal = -Vec3::UnitY();
  }
  if (!controller.start_grasp(targets).ok()) return 2;
  int ticks = 0;
  for (int k = 1; k <= 100; ++k) {
    in.time = 1e-3 * k;
    for (std::size_t i = 0; i < in.fingers.size(); ++i) {
      in.fingers[i].joint_positions.setConstant(Scalar(0.2));
      in.fingers[i].contact.touching = k > 50;
      in.fingers[i].contact.contact_point = targets[i].contact_point;
      in.fingers[i].contact.normal = targets[i].normal;
      in.fingers[i].contact.normal_force = Scalar(0.5);
    }
    if (controller.update(in, out) != inhand::ControllerStatus::invalid_input) ++ticks;
  }
  return ticks == 100 ? 0 : 3;
}

}  // namespace

int main() {
  const int d = run<double>();
  const int f = run<float>();
  return d != 0 ? d : f;
}
