// The Allegro-like hand from its URDF: read the four finger chains, let the reactive
// controller grasp the paper's cylinder (radius 20 mm, along world X) in the analytic
// plant, turn it 0.2 rad about X and back in 4 s, and check the paper's bounds
// (RMS error <= 0.5 mm and 10 mrad, no drop, no contact lost). Units SI, world frame.
#include <cstdio>

#include "inhand/sim/paper_scenarios.hpp"
#include "inhand/sim/presets_allegro.hpp"
#include "inhand/urdf.hpp"

int main() {
  namespace ip = inhand::plant;
  // Finger name, root link, fingertip link (the tip link's collision sphere is the pad).
  const std::vector<inhand::urdf::FingerSpec> specs = {{"index", "palm", "link_3.0_tip"},
                                                       {"middle", "palm", "link_7.0_tip"},
                                                       {"ring", "palm", "link_11.0_tip"},
                                                       {"thumb", "palm", "link_15.0_tip"}};
  const auto urdf = inhand::urdf::read_fingers_file<ip::PlantFinger>(INHAND_ALLEGRO_URDF, specs);
  if (!urdf.ok()) return std::fprintf(stderr, "%s\n", urdf.error.c_str()), 1;

  // Grasp (1 N each, the thumb balancing, pressed x2), hold 2 s, rotate 0 -> -0.2 rad -> 0
  // about X, settle 1 s.
  ip::ScenarioSpec s = ip::paper_scenario(ip::PaperObject::cylinder, ip::PaperTask::rotate, 0);
  s.hand = ip::allegro_like_hand();  // finger roles and open / grasp postures
  s.hand.fingers = urdf.fingers;     // the kinematics: the controller's and the plant's
  s.object = ip::paper_cylinder(s.hand);
  const ip::ScenarioResult r = ip::ScenarioRunner().run(s);

  const ip::StageMetrics& m = r.stages.back();
  std::printf("RMS error %.3f mm, %.2f mrad; final %.3f mm, %.2f mrad\n",
              m.rms_position_error * 1e3, m.rms_orientation_error * 1e3,
              m.final_position_error * 1e3, m.final_orientation_error * 1e3);
  for (std::size_t i = 0; i < m.fingers.size(); ++i)
    std::printf("%-6s force %.3f N (planned %.3f N)\n", specs[i].name.c_str(),
                m.fingers[i].final_measured_force, m.fingers[i].final_desired_force);
  const bool ok = r.failure.empty() && !r.dropped && r.contact_losses == 0 &&
                  m.rms_position_error <= 5e-4 && m.rms_orientation_error <= 0.01;
  std::printf("%s\n", ok ? "within the paper's bounds" : ("FAILED " + r.failure).c_str());
  return ok ? 0 : 1;
}
