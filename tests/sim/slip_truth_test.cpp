// The force layer's slip flag (FingerOutput::slipping; SlipDetector, contact_observers.hpp)
// against the analytic plant's own stick and slide state (ContactState::slip_distance, the
// bristle anchor's accumulated slide; sim/contact_model.hpp), in closed loop on campaign
// cases (docs/force_layer.md, "Slip against the plant's truth").
//  - On the default ranges (pads of 2 kN/m), from 100 ms after release on, every flagged tick
//    is one on which the plant's contact has slid within the last 100 ms: no flag on a
//    contact that sticks. Before that the released object settles, and a pad's elastic
//    shear is flagged for a few ticks (8-25 in seeds 0-7; docs/force_layer.md, "Slip").
//  - A slide of more than twice slip_distance within 100 ms on a free object (the heavy
//    releases of the wide ranges) is flagged within 50 ms of that 100 ms window's end.
// Seeded: the listed seeds, then INHAND_TEST_SCALE - 1 further blocks of consecutive seeds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <deque>
#include <string>
#include <vector>

#include "campaign/campaign_cases.hpp"
#include "common/test_support.hpp"
#include "inhand/sim/scenario.hpp"

namespace {

namespace ip = inhand::plant;
namespace cp = inhand::examples::campaign;

constexpr double kWindow = 0.1;        ///< s, "has slid within the last ..."
constexpr double kStuck = 1e-6;        ///< m of anchor slide within kWindow: the contact sticks
constexpr double kCatchWithin = 0.05;  ///< s from a long slide's start to its flag
constexpr double kSettle = 0.1;        ///< s after release: the object settling
/// A long slide: more than kFast * slip_distance within kWindow (6 mm/s on average with the
/// default 0.3 mm; the detector flags a steady slide of 3.3 mm/s and more).
constexpr double kFast = 2.0;

struct SlipTally {
  long flagged = 0;         ///< finger-ticks flagged slipping
  long flagged_stuck = 0;   ///< of them, on a contact the plant says stuck over kWindow
  long settling_stuck = 0;  ///< of those, within kSettle of release
  long slides = 0;          ///< slides of more than kFast * slip_distance within kWindow
  long caught = 0;          ///< of them, flagged within kCatchWithin of their start
  std::string first_stuck, first_miss;  ///< the first of each, described
};

void miss(SlipTally& t, std::uint64_t seed, int finger, double start, const char* until) {
  if (t.first_miss.empty())
    t.first_miss = "seed " + std::to_string(seed) + " finger " + std::to_string(finger) +
                   ": a slide from t " + std::to_string(start) + " s " + until +
                   ", not flagged within " + std::to_string(kCatchWithin) + " s";
}

/// Runs campaign case `seed` (wide or default ranges) and tallies its slip flags against the
/// plant. A long slide starts on the first tick whose last kWindow of anchor slide exceeds
/// slip_distance (its start taken kWindow earlier, the latest it can have begun); it ends once
/// the contact has stuck for kWindow.
void tally(std::uint64_t seed, bool wide, SlipTally& t) {
  const cp::Case c = cp::make_case(seed, wide);
  const double slip_distance = c.spec.controller.force_layer.slip_distance;
  struct Finger {
    std::deque<double> slid;  ///< the anchor's accumulated slide, the last kWindow of ticks
    double slide_start = -1;  ///< s, the long slide under way (< 0: none)
    bool caught = false;
  };
  std::vector<Finger> fingers;
  double dt = 0, last_time = 0, released = -1;
  const ip::ScenarioResult r = ip::ScenarioRunner{}.run(c.spec, [&](const ip::TickRecord& rec) {
    dt = rec.time - last_time;
    last_time = rec.time;
    const int n = rec.plant->finger_count();
    fingers.resize(static_cast<std::size_t>(n));
    const bool free = rec.status == inhand::ControllerStatus::ok;
    if (free && released < 0) released = rec.time;
    for (int i = 0; i < n; ++i) {
      Finger& f = fingers[static_cast<std::size_t>(i)];
      const ip::ContactState& cs = rec.plant->contact(i);
      if (!cs.active) {
        if (f.slide_start >= 0 && !f.caught)
          miss(t, seed, i, f.slide_start, "until the contact opened");
        f = Finger{};
        continue;
      }
      f.slid.push_back(cs.slip_distance);
      const auto window_ticks = static_cast<std::size_t>(kWindow / dt + 0.5);
      while (f.slid.size() > window_ticks + 1) f.slid.pop_front();
      // Less than kWindow in contact, or the object held (a held object cannot slip).
      if (f.slid.size() <= window_ticks || !free) continue;
      const double recent = f.slid.back() - f.slid.front();
      const bool flagged = rec.output->fingers[static_cast<std::size_t>(i)].slipping;
      if (flagged) {
        ++t.flagged;
        if (recent < kStuck) {
          ++t.flagged_stuck;
          if (rec.time - released <= kSettle)
            ++t.settling_stuck;
          else if (t.first_stuck.empty())
            t.first_stuck = "seed " + std::to_string(seed) + " finger " + std::to_string(i) +
                            " flagged at t " + std::to_string(rec.time) + " s, stuck";
        }
      }
      if (f.slide_start < 0 && recent > kFast * slip_distance) {
        f.slide_start = rec.time - kWindow;
        f.caught = false;
        ++t.slides;
      }
      if (f.slide_start >= 0) {
        if (flagged && !f.caught && rec.time - f.slide_start <= kWindow + kCatchWithin) {
          f.caught = true;
          ++t.caught;
        }
        if (recent < kStuck) {
          if (!f.caught) miss(t, seed, i, f.slide_start, "until it stuck");
          f.slide_start = -1;
        }
      }
    }
  });
  for (std::size_t i = 0; i < fingers.size(); ++i)
    if (fingers[i].slide_start >= 0 && !fingers[i].caught)
      miss(t, seed, static_cast<int>(i), fingers[i].slide_start, "to the end of the run");
  ASSERT_TRUE(r.failure.empty() || r.failure.find("invalid") == std::string::npos)
      << "seed " << seed << ": " << r.failure;
}

/// The listed seeds, then (scale() - 1) blocks of `block` consecutive seeds from `next`.
std::vector<std::uint64_t> campaign_seeds(std::vector<std::uint64_t> listed, std::uint64_t next,
                                          int block) {
  for (int k = 1; k < inhand_test::scale(); ++k)
    for (int j = 0; j < block; ++j) listed.push_back(next++);
  return listed;
}

TEST(SlipTruth, OnTheDefaultRangesNoContactThatSticksIsFlaggedOnceSettled) {
  SlipTally t;
  for (const std::uint64_t s : campaign_seeds({0, 1, 2, 3, 4, 5, 6, 7}, 1000, 8))
    tally(s, false, t);
  inhand_test::record("flagged_ticks", static_cast<double>(t.flagged));
  EXPECT_GT(t.flagged, 0) << "no slip flagged: the sample tests nothing";
  inhand_test::record("flagged_stuck_while_settling", static_cast<double>(t.settling_stuck));
  EXPECT_EQ(t.flagged_stuck, t.settling_stuck) << t.first_stuck;
}

TEST(SlipTruth, ASlideOfTwiceSlipDistanceInATenthOfASecondIsFlaggedWithinFiftyMilliseconds) {
  SlipTally t;
  for (const std::uint64_t s : campaign_seeds({21, 150, 261, 354, 417}, 6000, 8)) tally(s, true, t);
  inhand_test::record("long_slides", static_cast<double>(t.slides));
  inhand_test::record("caught", static_cast<double>(t.caught));
  EXPECT_GE(t.slides, 5) << "too few long slides: the sample tests nothing";
  EXPECT_EQ(t.caught, t.slides) << t.first_miss;
}

/// The first tick of `c` that raises `flag` after release, and the first on which a contact
/// the controller had is lost (ControllerStatus::contact_lost), in s (-1: none).
struct FirstTicks {
  double warned = -1, lost = -1;
};
FirstTicks first_ticks(const cp::Case& c, inhand::ControllerWarning flag) {
  FirstTicks f;
  ip::ScenarioRunner{}.run(c.spec, [&](const ip::TickRecord& rec) {
    if (rec.stage < 1) return;
    if (f.warned < 0 && inhand::has(rec.output->warnings, flag)) f.warned = rec.time;
    if (f.lost < 0 && rec.status == inhand::ControllerStatus::contact_lost) f.lost = rec.time;
  });
  return f;
}

// beyond_capacity asks the slide at the grip's cap not to slow down (capacity_slide_ratio):
// wide seed 8 (a 330 g cylinder on 1.7 kN/m pads) settles on its pads at release, every
// finger flagged as slipping for 20-40 ms with no anchor sliding, and is held: not
// reported (it was, 37 ms after release, with any slide counted). Wide seed 261 (a 356 g
// cylinder at friction 0.47 on 806 N/m pads) slides out: reported at least 40 ms before
// its first contact is lost (89 ms either way).
TEST(SlipTruth, ASettlingReleaseIsNotBeyondCapacityASlideOutIs) {
  const FirstTicks settles =
      first_ticks(cp::make_case(8, true), inhand::ControllerWarning::beyond_capacity);
  EXPECT_LT(settles.warned, 0.0) << "beyond_capacity at t " << settles.warned << " s";
  EXPECT_LT(settles.lost, 0.0);
  const FirstTicks slides =
      first_ticks(cp::make_case(261, true), inhand::ControllerWarning::beyond_capacity);
  ASSERT_GT(slides.lost, 0.0);
  ASSERT_GT(slides.warned, 0.0);
  EXPECT_GE(slides.lost - slides.warned, 0.04);
}

}  // namespace
