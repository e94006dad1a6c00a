// HandPlant's per-tick calls (commands, step, sensing, ground truth) never allocate:
// the global operator new of this test executable counts every heap allocation.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "inhand/sim/presets.hpp"

namespace {
std::atomic<long> g_allocations{0};
}  // namespace

void* operator new(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t size) { return operator new(size); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }

namespace {

TEST(HandPlantRealtime, TicksDoNotAllocate) {
  const auto hand = inhand::plant::shadow_like_hand();
  inhand::plant::PlantParams p = inhand::plant::default_plant_params();
  p.sensing.normal_force_std = 0.05;
  p.sensing.normal_angle_std = 0.02;
  p.sensing.object_rotation_std = 1e-3;
  p.joint_velocity_lag = 0.005;
  inhand::plant::HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand), p);
  for (int i = 0; i < plant.finger_count(); ++i)
    plant.set_joint_positions(i, hand.grasp_configuration[i]);
  std::vector<inhand::plant::PlantFinger::JointVector> cmd;
  for (const auto& f : hand.fingers)
    cmd.emplace_back(inhand::plant::PlantFinger::JointVector::Constant(f.dof(), 0.1));

  const long before = g_allocations.load();
  double sink = 0.0;
  for (int ms = 0; ms < 200; ++ms) {
    if (ms == 100) plant.set_frozen(true);
    if (ms == 150) plant.set_frozen(false);
    for (int i = 0; i < plant.finger_count(); ++i) {
      cmd[static_cast<std::size_t>(i)] *= -1.0;
      plant.set_joint_velocity_command(i, cmd[static_cast<std::size_t>(i)]);
    }
    plant.step(1e-3);
    plant.sample_sensors();
    sink +=
        plant.measured_object_pose().position.x() + plant.object_twist()(0) + plant.total_energy();
    for (int i = 0; i < plant.finger_count(); ++i) {
      sink += plant.tactile(i).normal_force + plant.contact(i).slip_distance;
      sink += plant.joint_positions(i)(0) + plant.fingertip_pose(i).position.x();
    }
  }
  const long after = g_allocations.load();
  EXPECT_EQ(after - before, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

}  // namespace
