// Proof that the per-tick path of a finger allocates nothing: forward_kinematics (with
// and without the chain's plan), point_jacobian, ContactIk::solve (with and without the null-space
// term), ContactIk::pseudo_inverse and HybridServo::update, for fixed-size fingers (planar 2 and 3
// DOF, spatial 3, 4 and 5 DOF) and the run-time bounded finger (Dynamic, MaxDof = 5), float and
// double; and the whole ReactiveController::update() of the Shadow-like hand on the analytic plant
// (grasp, release, hold under gravity, a translation: every force-layer branch; the outlier gates
// on), with bounded and with run-time DOF storage; and the analytic plant's own per-tick calls.
//
// One counter, fed at the bottom of every allocation path, guards the loop: the link of
// this executable wraps the C allocation functions (tests/CMakeLists.txt: the linker's
// --wrap of malloc, calloc, realloc, aligned_alloc and posix_memalign), so every call to
// them from any object linked into the executable is counted while a region is open:
//  - Eigen's heap allocations, which call std::malloc directly (not operator new), in the
//    test's code and in the test instances' library (common/controller_instances.hpp) alike;
//  - every C++ allocation: the replacements of the global operator new below allocate
//    through malloc and posix_memalign, so a new from the executable or from the shared C++
//    library (a std::vector growing, a std::string, new itself) is counted as well.
// The canaries prove that it sees each kind. (An earlier form of this file used Eigen's
// no-malloc assertion, EIGEN_RUNTIME_NO_MALLOC, which sees only the Eigen code compiled
// with the macro in the same file; the wrap sees the shared instances too.)
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <new>
#include <string>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/sim/scenario.hpp"

namespace {

std::atomic<long> g_allocations{0};
std::atomic<bool> g_counting{false};

void count_allocation() noexcept {
  if (g_counting.load(std::memory_order_relaxed))
    g_allocations.fetch_add(1, std::memory_order_relaxed);
}

// Out of line so that GCC does not pair an inlined operator new with free() and
// report a mismatched allocation: both sides are malloc/free by construction.
[[gnu::noinline]] void release(void* p) noexcept { std::free(p); }

void* aligned(std::size_t n, std::align_val_t al) noexcept {
  std::size_t a = static_cast<std::size_t>(al);
  if (a < sizeof(void*)) a = sizeof(void*);
  void* p = nullptr;
  if (posix_memalign(&p, a, n == 0 ? 1 : n) != 0) return nullptr;  // counted by its wrap
  return p;
}

}  // namespace

// The linker's --wrap=f sends every reference to f in the linked objects to __wrap_f, and
// __real_f to the real f.
extern "C" {
void* __real_malloc(std::size_t n);
void* __real_calloc(std::size_t count, std::size_t n);
void* __real_realloc(void* p, std::size_t n);
void* __real_aligned_alloc(std::size_t alignment, std::size_t n);
int __real_posix_memalign(void** p, std::size_t alignment, std::size_t n);

void* __wrap_malloc(std::size_t n) {
  count_allocation();
  return __real_malloc(n);
}
void* __wrap_calloc(std::size_t count, std::size_t n) {
  count_allocation();
  return __real_calloc(count, n);
}
void* __wrap_realloc(void* p, std::size_t n) {
  count_allocation();
  return __real_realloc(p, n);
}
void* __wrap_aligned_alloc(std::size_t alignment, std::size_t n) {
  count_allocation();
  return __real_aligned_alloc(alignment, n);
}
int __wrap_posix_memalign(void** p, std::size_t alignment, std::size_t n) {
  count_allocation();
  return __real_posix_memalign(p, alignment, n);
}
}

// Replacements of the global allocation functions (all of them, so that an allocation by
// the shared C++ library also goes through the wrapped malloc of this executable).
void* operator new(std::size_t n) {
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n) {
  if (void* p = std::malloc(n == 0 ? 1 : n)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, const std::nothrow_t&) noexcept {
  return std::malloc(n == 0 ? 1 : n);
}
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept {
  return std::malloc(n == 0 ? 1 : n);
}
void* operator new(std::size_t n, std::align_val_t a) {
  if (void* p = aligned(n, a)) return p;
  throw std::bad_alloc();
}
void* operator new[](std::size_t n, std::align_val_t a) {
  if (void* p = aligned(n, a)) return p;
  throw std::bad_alloc();
}
void* operator new(std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return aligned(n, a);
}
void* operator new[](std::size_t n, std::align_val_t a, const std::nothrow_t&) noexcept {
  return aligned(n, a);
}
void operator delete(void* p) noexcept { release(p); }
void operator delete[](void* p) noexcept { release(p); }
void operator delete(void* p, std::size_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t) noexcept { release(p); }
void operator delete(void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, const std::nothrow_t&) noexcept { release(p); }
void operator delete(void* p, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { release(p); }
void operator delete(void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }
void operator delete[](void* p, std::align_val_t, const std::nothrow_t&) noexcept { release(p); }

namespace {

/// While alive: every allocation of the process's thread is counted.
class NoAllocationRegion {
 public:
  NoAllocationRegion() noexcept {
    g_allocations.store(0);
    g_counting.store(true);
  }
  ~NoAllocationRegion() { g_counting.store(false); }
  NoAllocationRegion(const NoAllocationRegion&) = delete;
  NoAllocationRegion& operator=(const NoAllocationRegion&) = delete;
  /// Allocations counted since construction (read while still inside is fine).
  long allocations() const noexcept { return g_allocations.load(); }
};

// Escapes pointers so the optimiser cannot drop an allocation as unused.
void* volatile g_sink = nullptr;

template <typename Chain>
class NoAllocationTest : public ::testing::Test {};

using Fingers =
    ::testing::Types<inhand_test::Planar2<float>, inhand_test::Planar2<double>,
                     inhand_test::Planar3<float>, inhand_test::Planar3<double>,
                     inhand_test::Spatial3<float>, inhand_test::Spatial3<double>,
                     inhand_test::Spatial4<float>, inhand_test::Spatial4<double>,
                     inhand_test::Spatial5<float>, inhand_test::Spatial5<double>,
                     inhand_test::SpatialBounded<float>, inhand_test::SpatialBounded<double>>;
TYPED_TEST_SUITE(NoAllocationTest, Fingers, inhand_test::ChainNames);

// The per-tick path of one finger under both detectors. Inputs are prepared outside
// the region; every 7th tick uses the stretched (singular) pose so the damped branch
// runs, and tight joint-velocity limits make the limited branch run too.
TYPED_TEST(NoAllocationTest, PerTickPathDoesNotAllocate) {
  using Chain = TypeParam;
  using S = typename Chain::Scalar;
  constexpr int Dim = Chain::Dim;
  using V = inhand::Vector<S, Dim>;

  const int dofs_to_check = Chain::Dof == inhand::Dynamic ? 3 : 1;  // bounded: 3, 4, 5 joints
  for (int variant = 0; variant < dofs_to_check; ++variant) {
    const Chain chain = Chain::Dof == inhand::Dynamic ? inhand_test::make_finger<Chain>(3 + variant)
                                                      : inhand_test::make_finger<Chain>();
    const int n = chain.dof();
    auto rng = inhand_test::make_rng(501 + static_cast<unsigned>(variant));
    const int ticks = inhand_test::scaled(500);
    std::vector<typename Chain::JointVector> q;
    std::vector<V> normals, desired_velocity;
    for (int i = 0; i < ticks; ++i) {
      q.push_back(inhand_test::random_joint_angles(chain, rng));
      if (i % 7 == 0) q.back().setZero();
      normals.push_back(inhand_test::random_unit_vector<S, Dim>(rng));
      desired_velocity.push_back(inhand_test::random_vector<S, Dim>(rng, S(-0.05), S(0.05)));
    }
    inhand::FingerKinematics<Chain> ws(chain);
    const inhand::ChainPlan<Chain> plan(chain);
    typename Chain::Jacobian J(Dim, n);
    J.setZero();
    inhand::ContactIk<S, Dim, Chain::Dof, Chain::MaxDof> ik(n);
    using JointVector = typename decltype(ik)::JointVector;
    typename decltype(ik)::PseudoInverse pinv(n, Dim);
    pinv.setZero();
    JointVector limits(n), z(n), qd(n), qd_ns(n);
    limits.setConstant(S(0.8));
    for (int i = 0; i < n; ++i) z(i) = S(0.1) * S(i + 1);
    inhand::HybridServo<S, Dim> servo;
    inhand::ServoCommand<S, Dim> cmd;

    unsigned seen = 0;
    double checksum = 0.0;
    long counted = -1;
    {
      NoAllocationRegion region;
      for (int i = 0; i < ticks; ++i) {
        if (i % 2 == 0) {
          inhand::forward_kinematics(chain, q[static_cast<std::size_t>(i)], ws);
        } else {
          inhand::forward_kinematics(chain, plan, q[static_cast<std::size_t>(i)], ws);
        }
        const V& nrm = normals[static_cast<std::size_t>(i)];
        // Stretched ticks use the fingertip centre, on the link line: exactly singular.
        const V contact = (i % 7 == 0) ? V(ws.fingertip.position)
                                       : inhand::fingertip_surface_point(chain, ws, nrm);
        inhand::point_jacobian(ws, contact, J);
        servo.update(desired_velocity[static_cast<std::size_t>(i)], S(1), S(0.8), nrm, true,
                     S(1e-3), cmd);
        const auto r1 = ik.solve(J, cmd.total, limits, qd);
        const auto r2 = ik.solve(J, cmd.total, limits, z, qd_ns);
        const auto r3 = ik.pseudo_inverse(J, pinv);
        seen |= static_cast<unsigned>(r1.status) | static_cast<unsigned>(r2.status) |
                static_cast<unsigned>(r3.status);
        checksum += static_cast<double>(qd.sum() + qd_ns.sum() + pinv.sum());
      }
      counted = region.allocations();
    }
    EXPECT_EQ(counted, 0) << "operator new called inside the per-tick path (" << n << " joints)";
    EXPECT_TRUE(std::isfinite(checksum));
    EXPECT_TRUE(seen & static_cast<unsigned>(inhand::IkStatus::damped))
        << "damped branch not exercised";
    EXPECT_TRUE(seen & static_cast<unsigned>(inhand::IkStatus::limited))
        << "limited branch not exercised";
    EXPECT_FALSE(seen & static_cast<unsigned>(inhand::IkStatus::invalid_input));
  }
}

// Canary 1: the counter sees a plain new, an aligned new, a nothrow new and a
// std::vector growing inside the region.
/// Runs grasp -> release -> hold -> move on the analytic plant and returns the
/// allocations counted inside controller.update() (the plant's calls are outside).
template <typename Controller>
long whole_tick_allocations(long& ticks) {
  namespace ip = inhand::plant;
  const ip::HandPreset hand = ip::shadow_like_hand();
  ip::HandPlant plant(hand.fingers, ip::paper_cylinder(hand), ip::default_plant_params());
  typename Controller::Config cfg;
  for (std::size_t i = 0; i < hand.fingers.size(); ++i) {
    typename Controller::FingerConfig f;
    const inhand::plant::PlantFinger& src = hand.fingers[i];
    f.chain.base = src.base;
    f.chain.joint_to_tip = src.joint_to_tip;
    f.chain.fingertip_radius = src.fingertip_radius;
    EXPECT_TRUE(f.chain.joints.resize(src.dof()));
    for (int j = 0; j < src.dof(); ++j) f.chain.joints[j] = src.joints[j];
    f.role = static_cast<int>(i) == hand.thumb ? inhand::FingerRole::balancing
                                               : inhand::FingerRole::preset;
    cfg.fingers.push_back(f);
  }
  // The outlier gates on (the fault files' bounds), so that their per-tick work, the
  // force gate's credit for each finger's step, is inside the counted region too.
  cfg.outlier_gates.max_object_speed = 0.2;
  cfg.outlier_gates.max_object_angular_speed = 5.0;
  cfg.outlier_gates.max_force_rate = 200.0;
  Controller c;
  EXPECT_TRUE(c.configure(cfg).ok());
  for (int i = 0; i < plant.finger_count(); ++i)
    plant.set_joint_positions(i, hand.open_configuration[static_cast<std::size_t>(i)]);
  typename Controller::Input in = c.make_input();
  typename Controller::Output out = c.make_output();
  plant.set_frozen(true);
  EXPECT_TRUE(c.start_grasp(ip::model_free_grasp_targets(hand, plant.object_pose())).ok());
  long allocations = 0;
  double t = 0.0;
  auto tick = [&]() {
    plant.sample_sensors();
    t += 1e-3;
    in.time = t;
    in.object_pose = plant.measured_object_pose();
    for (int i = 0; i < plant.finger_count(); ++i) {
      auto& f = in.fingers[static_cast<std::size_t>(i)];
      f.joint_positions = plant.joint_positions(i);
      const ip::TactileReading r = plant.tactile(i);
      f.contact.touching = r.touching;
      if (r.touching) {
        f.contact.contact_point = r.contact_point;
        f.contact.normal = r.normal;
        f.contact.normal_force = r.normal_force;
      }
    }
    inhand::ControllerStatus st;
    {
      NoAllocationRegion region;
      st = c.update(in, out);
      allocations += region.allocations();
    }
    for (int i = 0; i < plant.finger_count(); ++i)
      plant.set_joint_velocity_command(i,
                                       out.fingers[static_cast<std::size_t>(i)].joint_velocities);
    plant.step(1e-3);
    ++ticks;
    return st;
  };
  for (int k = 0; k < 3000 && tick() != inhand::ControllerStatus::grasped; ++k) {
  }
  EXPECT_EQ(c.phase(), Controller::Phase::grasped);
  plant.set_frozen(false);
  typename Controller::Trajectory traj;
  traj.reset(plant.object_pose());
  traj.append(inhand::TrajectorySegment<double, 3>::hold_for(0.5));
  EXPECT_TRUE(c.start_manipulation(traj).ok());
  for (int k = 0; k < 800; ++k) EXPECT_EQ(tick(), inhand::ControllerStatus::ok);
  return allocations;
}

TEST(NoAllocationWholeTick, BoundedAndRunTimeDofShadowLikeHand) {
  long ticks = 0;
  EXPECT_EQ(whole_tick_allocations<inhand::plant::HandController>(ticks), 0);
  EXPECT_GT(ticks, 1000);
  using DynamicDof = inhand::ReactiveController<double, 3, inhand::Dynamic, inhand::Dynamic>;
  ticks = 0;
  EXPECT_EQ(whole_tick_allocations<DynamicDof>(ticks), 0);
  EXPECT_GT(ticks, 1000);
}

// The analytic plant's per-tick calls (commands, step, sensing, ground truth), which a
// scenario runs beside the controller at every tick: no allocation either.
TEST(HandPlantRealtime, TicksDoNotAllocate) {
  const auto hand = inhand::plant::shadow_like_hand();
  inhand::plant::PlantParams p = inhand::plant::default_plant_params();
  p.sensing.normal_force_std = 0.05;
  p.sensing.normal_angle_std = 0.02;
  p.sensing.object_rotation_std = 1e-3;
  p.joint_velocity_lag = 0.005;
  inhand::plant::HandPlant plant(hand.fingers, inhand::plant::paper_cylinder(hand), p);
  for (int i = 0; i < plant.finger_count(); ++i)
    plant.set_joint_positions(i, hand.grasp_configuration[static_cast<std::size_t>(i)]);
  std::vector<inhand::plant::PlantFinger::JointVector> cmd;
  for (const auto& f : hand.fingers)
    cmd.emplace_back(inhand::plant::PlantFinger::JointVector::Constant(f.dof(), 0.1));

  double sink = 0.0;
  long counted = -1;
  {
    NoAllocationRegion region;
    for (int ms = 0; ms < 200; ++ms) {
      if (ms == 100) plant.set_frozen(true);
      if (ms == 150) plant.set_frozen(false);
      for (int i = 0; i < plant.finger_count(); ++i) {
        cmd[static_cast<std::size_t>(i)] *= -1.0;
        plant.set_joint_velocity_command(i, cmd[static_cast<std::size_t>(i)]);
      }
      plant.step(1e-3);
      plant.sample_sensors();
      sink += plant.measured_object_pose().position.x() + plant.object_twist()(0) +
              plant.total_energy();
      for (int i = 0; i < plant.finger_count(); ++i) {
        sink += plant.tactile(i).normal_force + plant.contact(i).slip_distance;
        sink += plant.joint_positions(i)(0) + plant.fingertip_pose(i).position.x();
      }
    }
    counted = region.allocations();
  }
  EXPECT_EQ(counted, 0);
  EXPECT_TRUE(std::isfinite(sink));
}

TEST(NoAllocationCanary, CounterCatchesCppAllocations) {
  struct alignas(64) Wide {
    double v[8];
  };
  {
    NoAllocationRegion region;
    int* p = new int(3);
    g_sink = p;
    EXPECT_EQ(region.allocations(), 1);
    delete p;
  }
  {
    NoAllocationRegion region;
    Wide* w = new Wide();
    g_sink = w;
    int* a = new (std::nothrow) int[4];
    g_sink = a;
    EXPECT_EQ(region.allocations(), 2);
    delete[] a;
    delete w;
  }
  std::vector<int> v;
  long counted = 0;
  {
    NoAllocationRegion region;
    v.push_back(1);
    g_sink = v.data();
    counted = region.allocations();
  }
  EXPECT_GE(counted, 1);
  EXPECT_EQ(v.size(), 1u);
}

// Canary 2: an Eigen dynamic allocation inside the region is counted (Eigen calls
// std::malloc, not operator new), and so are an allocation made inside the shared C++
// library and calloc / realloc; a fixed-size or bounded Eigen object allocates nothing.
TEST(NoAllocationCanary, CounterCatchesEigenAllocations) {
  {
    NoAllocationRegion region;
    Eigen::MatrixXd m(8, 8);
    m.setZero();
    g_sink = m.data();
    EXPECT_GE(region.allocations(), 1);
  }
  {
    NoAllocationRegion region;
    Eigen::Matrix<double, 3, Eigen::Dynamic, 0, 3, 5> bounded(3, 4);
    bounded.setOnes();
    g_sink = bounded.data();
    EXPECT_EQ(region.allocations(), 0);
  }
  {
    // A std::string growing: its allocation is made inside the shared C++ library, whose
    // call of operator new reaches the replacement in this executable.
    std::string text(4, 'x');
    long counted = 0;
    {
      NoAllocationRegion region;
      text.append(200, 'y');
      g_sink = text.data();
      counted = region.allocations();
    }
    EXPECT_GE(counted, 1);
  }
  {
    NoAllocationRegion region;
    void* p = std::calloc(4, 8);
    g_sink = p;
    p = std::realloc(p, 64);
    g_sink = p;
    EXPECT_EQ(region.allocations(), 2);
    std::free(p);
  }
}

}  // namespace
