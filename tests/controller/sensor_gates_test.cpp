// Properties of the sensor gates (controller/sensor_gates.hpp): a force spike is rejected
// and the last accepted reading held; a real jump is followed once the reading has been
// held for max_rejection_time (at least one tick), at any tick length and with jitter; a change the
// finger's own press or withdrawal explains (the credit) is accepted at any tick length, with its
// sign; credit and time add up over rejected ticks; a new touch is accepted as it comes; the pose
// gate's speed bounds. float and double.
#include "inhand/controller/sensor_gates.hpp"

#include <gtest/gtest.h>

#include <limits>
#include <string>

namespace {

using inhand::ForceGate;
using inhand::OutlierGates;
using inhand::PoseGate;

template <typename S>
class SensorGates : public ::testing::Test {
 protected:
  static OutlierGates<S> gates() {
    OutlierGates<S> g;
    g.max_force_rate = S(200);  // N/s: 0.2 N per 1 ms tick
    g.contact_stiffness = S(1e4);
    g.max_rejection_time = S(3e-3);  // s: 3 ticks at 1 kHz
    return g;
  }
};
using Scalars = ::testing::Types<float, double>;
TYPED_TEST_SUITE(SensorGates, Scalars, );

TYPED_TEST(SensorGates, SpikeOnAStillFingerIsRejectedAndTheReadingHeld) {
  using S = TypeParam;
  const OutlierGates<S> g = this->gates();
  ForceGate<S> gate;
  EXPECT_FALSE(gate.update(g, true, S(1), S(0), S(1e-3)));     // first touch: accepted
  EXPECT_FALSE(gate.update(g, true, S(1.15), S(0), S(1e-3)));  // 0.15 N <= 0.2 N
  EXPECT_TRUE(gate.update(g, true, S(4.15), S(0), S(1e-3)));   // +3 N spike
  EXPECT_EQ(gate.force(), S(1.15));
  EXPECT_FALSE(gate.update(g, true, S(1.2), S(0), S(1e-3)));  // back: within 2 ticks' bound
  EXPECT_EQ(gate.force(), S(1.2));
}

// The hold is max_rejection_time (3 ms) rounded to whole ticks, at least one: held while
// the time since the last accepted reading is below max(3 ms, dt) + dt / 2; 0: never held.
TYPED_TEST(SensorGates, ARealJumpIsFollowedAfterTheHoldTimeAtAnyRate) {
  using S = TypeParam;
  const OutlierGates<S> g = this->gates();
  struct Rate {
    S dt;
    int held;
  };
  for (const Rate r : {Rate{S(5e-4), 6}, Rate{S(1e-3), 3}, Rate{S(2e-3), 1}, Rate{S(1e-2), 1}}) {
    ForceGate<S> gate;
    gate.update(g, true, S(1), S(0), r.dt);
    PoseGate<S, 3> pose_gate;
    typename PoseGate<S, 3>::PoseT p{};
    OutlierGates<S> pg = g;
    pg.max_object_speed = S(0.2);
    pose_gate.update(pg, p, r.dt, true);
    p.position.x() = S(0.01);  // the object knocked 1 cm
    for (int k = 0; k < r.held; ++k) {
      EXPECT_TRUE(gate.update(g, true, S(5), S(0), r.dt)) << r.dt << " " << k;
      EXPECT_EQ(gate.force(), S(1));
      EXPECT_TRUE(pose_gate.update(pg, p, r.dt, false).outlier) << r.dt << " " << k;
    }
    EXPECT_FALSE(gate.update(g, true, S(5), S(0), r.dt)) << r.dt;
    EXPECT_EQ(gate.force(), S(5));
    EXPECT_FALSE(pose_gate.update(pg, p, r.dt, false).outlier) << r.dt;
    EXPECT_EQ(pose_gate.pose().position.x(), S(0.01));
  }
}

// Ticks of 2.0, 0.5 and 2.0 ms: the hold is counted in time, not ticks -- held at 2.0 and
// 2.5 ms, followed at 4.5 ms (past 3 ms + 1 ms), where a count of 3 ticks would hold on.
TYPED_TEST(SensorGates, TheHoldIsCountedInTimeUnderJitter) {
  using S = TypeParam;
  const OutlierGates<S> g = this->gates();
  ForceGate<S> gate;
  gate.update(g, true, S(1), S(0), S(1e-3));
  EXPECT_TRUE(gate.update(g, true, S(5), S(0), S(2e-3)));
  EXPECT_TRUE(gate.update(g, true, S(5), S(0), S(5e-4)));
  EXPECT_FALSE(gate.update(g, true, S(5), S(0), S(2e-3)));
  EXPECT_EQ(gate.force(), S(5));
}

// max_rejection_time 0: a reading beyond the bound is accepted at once, at any rate.
TYPED_TEST(SensorGates, AZeroHoldNeverHoldsAReading) {
  using S = TypeParam;
  OutlierGates<S> g = this->gates();
  g.max_rejection_time = S(0);
  for (const S dt : {S(5e-4), S(1e-3), S(2e-2)}) {
    ForceGate<S> gate;
    gate.update(g, true, S(1), S(0), dt);
    EXPECT_FALSE(gate.update(g, true, S(5), S(0), dt)) << dt;
    EXPECT_EQ(gate.force(), S(5));
  }
}

TYPED_TEST(SensorGates, TheFingersOwnPressIsCreditedAtAnyTickLength) {
  using S = TypeParam;
  const OutlierGates<S> g = this->gates();  // held for at least one tick at every rate
  for (const S dt : {S(5e-4), S(1e-3), S(1e-2), S(2e-2)}) {
    ForceGate<S> gate;
    gate.update(g, true, S(1), S(0), dt);
    // The fingertip stepped 0.4 mm into a 1e4 N/m contact: +4 N explained, whatever
    // the rate bound allows over dt (0.1 to 4 N).
    const S credit = g.contact_stiffness * S(4e-4);
    EXPECT_FALSE(gate.update(g, true, S(5), credit, dt)) << dt;
    EXPECT_EQ(gate.force(), S(5));
    // Withdrawn by as much: the fall is explained too.
    EXPECT_FALSE(gate.update(g, true, S(1), -credit, dt)) << dt;
    // The same step does not explain a change of the other sign, nor a larger one.
    if (g.max_force_rate * dt < S(3)) {
      EXPECT_TRUE(gate.update(g, true, S(1) - S(3), credit, dt)) << dt;
      EXPECT_EQ(gate.force(), S(1));
      ForceGate<S> other;
      other.update(g, true, S(1), S(0), dt);
      EXPECT_TRUE(other.update(g, true, S(1) + credit + S(3), credit, dt)) << dt;
    }
  }
}

TYPED_TEST(SensorGates, CreditAndTimeAddUpOverRejectedTicks) {
  using S = TypeParam;
  OutlierGates<S> g = this->gates();
  g.max_rejection_time = S(0.01);
  ForceGate<S> gate;
  gate.update(g, true, S(1), S(0), S(1e-3));
  // A spike on a still finger, then a press of 1 N per tick: after the spike is rejected
  // the gate compares with the last accepted 1 N over the credit summed since.
  EXPECT_TRUE(gate.update(g, true, S(9), S(0), S(1e-3)));
  EXPECT_TRUE(gate.update(g, true, S(9), S(1), S(1e-3)));     // 8 N > 1 N + 0.4 N
  EXPECT_FALSE(gate.update(g, true, S(3.5), S(1), S(1e-3)));  // 2.5 N <= 2 N + 0.6 N
  EXPECT_EQ(gate.force(), S(3.5));
}

TYPED_TEST(SensorGates, ANewTouchIsAcceptedAsItComes) {
  using S = TypeParam;
  const OutlierGates<S> g = this->gates();
  ForceGate<S> gate;
  gate.update(g, true, S(1), S(0), S(1e-3));
  EXPECT_FALSE(gate.update(g, false, S(0), S(0), S(1e-3)));
  EXPECT_FALSE(gate.update(g, true, S(8), S(0), S(1e-3)));
  EXPECT_EQ(gate.force(), S(8));
}

TYPED_TEST(SensorGates, TheDefaultsGateNothing) {
  using S = TypeParam;
  const OutlierGates<S> g;
  EXPECT_TRUE(g.validate().ok());
  ForceGate<S> gate;
  gate.update(g, true, S(1), S(0), S(1e-3));
  EXPECT_FALSE(gate.update(g, true, S(1e4), S(0), S(1e-3)));
  PoseGate<S, 3> pose_gate;
  typename PoseGate<S, 3>::PoseT p{};
  pose_gate.update(g, p, S(1e-3), true);
  p.position.x() = S(1);
  EXPECT_FALSE(pose_gate.update(g, p, S(1e-3), false).outlier);
}

TYPED_TEST(SensorGates, ThePoseGateBoundsTheObjectsSpeed) {
  using S = TypeParam;
  OutlierGates<S> g = this->gates();
  g.max_object_speed = S(0.2);  // m/s: 0.2 mm per 1 ms tick
  g.max_object_angular_speed = S(5);
  PoseGate<S, 3> gate;
  typename PoseGate<S, 3>::PoseT p{};
  EXPECT_FALSE(gate.update(g, p, S(1e-3), true).outlier);
  p.position.x() = S(1.5e-4);
  EXPECT_FALSE(gate.update(g, p, S(1e-3), false).outlier);
  typename PoseGate<S, 3>::PoseT jump = p;
  jump.position.x() = S(0.01);  // a 1 cm vision outlier
  const auto step = gate.update(g, jump, S(1e-3), false);
  EXPECT_TRUE(step.outlier);
  EXPECT_EQ(step.pose.position.x(), p.position.x());
}

TYPED_TEST(SensorGates, ValidationNamesTheField) {
  using S = TypeParam;
  OutlierGates<S> g;
  g.contact_stiffness = S(-1);
  EXPECT_EQ(std::string(g.validate().field), "outlier_gates.contact_stiffness");
  g.contact_stiffness = std::numeric_limits<S>::infinity();
  EXPECT_EQ(std::string(g.validate().field), "outlier_gates.contact_stiffness");
  g.contact_stiffness = S(0);
  EXPECT_TRUE(g.validate().ok());
  for (const S bad :
       {S(-1e-3), std::numeric_limits<S>::infinity(), std::numeric_limits<S>::quiet_NaN()}) {
    g.max_rejection_time = bad;
    EXPECT_EQ(std::string(g.validate().field), "outlier_gates.max_rejection_time") << bad;
  }
  g.max_rejection_time = S(0);
  EXPECT_TRUE(g.validate().ok());
}

}  // namespace
