// The finger chains read from the compiled MJCF hands (examples/mujoco/mujoco_chains.hpp)
// against MuJoCo's own kinematics, and against the presets the models were written from
// (include/inhand/sim/presets.hpp): the three-finger and the Shadow-like hands, each with
// either paper object (models/<hand>_cylinder.xml, models/<hand>_box.xml) or an object the
// preset was not made for (models/three_finger_capsule.xml, models/shadow_like_ellipsoid.xml).
// Units: metres, radians.
#include "mujoco_chains.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <ostream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "common/test_support.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/sim/presets.hpp"
#include "mujoco_model.hpp"

namespace {

using inhand::mujoco_demo::FingerNames;
using inhand::mujoco_demo::MujocoChain;

/// An MJCF hand with its object and the preset it was written from.
struct HandModel {
  const char* name;  ///< the ctest name's suffix and the prefix of the recorded figures
  const char* file;  ///< in models/
  inhand::plant::HandPreset (*preset)();
};

const HandModel kHandModels[] = {
    {"three_finger", "three_finger_cylinder.xml", &inhand::plant::three_finger_hand},
    {"three_finger_box", "three_finger_box.xml", &inhand::plant::three_finger_hand},
    {"shadow_like", "shadow_like_cylinder.xml", &inhand::plant::shadow_like_hand},
    {"shadow_like_box", "shadow_like_box.xml", &inhand::plant::shadow_like_hand},
    {"three_finger_capsule", "three_finger_capsule.xml", &inhand::plant::three_finger_hand},
    {"shadow_like_ellipsoid", "shadow_like_ellipsoid.xml", &inhand::plant::shadow_like_hand},
};

/// The preset's fingers in its order, as the models name them: {"palm", "<finger>_tip"}.
std::vector<FingerNames> finger_names(const inhand::plant::HandPreset& preset) {
  std::vector<FingerNames> names;
  for (const std::string& f : preset.finger_names) names.push_back({"palm", f + "_tip"});
  return names;
}

struct Hand {
  Hand(const std::string& path, std::vector<FingerNames> names)
      : fingers(std::move(names)),
        model(inhand::mujoco_demo::load_model(path)),
        data(inhand::mujoco_demo::make_data(model.get())),
        chains(inhand::mujoco_demo::finger_chains(model.get(), fingers)) {}
  explicit Hand(const HandModel& hand)
      : Hand(inhand::mujoco_demo::model_path(hand.file), finger_names(hand.preset())) {}
  std::vector<FingerNames> fingers;
  inhand::mujoco_demo::ModelPtr model;
  inhand::mujoco_demo::DataPtr data;
  std::vector<MujocoChain> chains;
};

void PrintTo(const HandModel& hand, std::ostream* os) { *os << hand.name; }

class MujocoChains : public ::testing::TestWithParam<HandModel> {};

MujocoChain::JointVector random_angles(inhand_test::Rng& rng, const MujocoChain& c) {
  MujocoChain::JointVector q(c.dof());
  for (int j = 0; j < c.dof(); ++j)
    q(j) = inhand_test::uniform(rng, c.joints[j].lower, c.joints[j].upper);
  return q;
}

// Every chain read from the model is the preset's finger: the same number of joints, limits
// to 1e-12 rad, velocity limits and fingertip radius exactly, and fingertip positions to
// 1e-12 m at random joint angles within the limits.
TEST_P(MujocoChains, ReadFromTheModelAsThePresetStatesThem) {
  const Hand h(GetParam());
  const auto preset = GetParam().preset();
  ASSERT_EQ(h.chains.size(), preset.fingers.size());
  inhand_test::Rng rng = inhand_test::make_rng(20261201);
  double worst = 0.0;
  for (std::size_t i = 0; i < h.chains.size(); ++i) {
    const MujocoChain& c = h.chains[i];
    const auto& p = preset.fingers[i];
    ASSERT_TRUE(c.validate().ok()) << c.validate().field;
    ASSERT_EQ(c.dof(), p.dof());
    EXPECT_DOUBLE_EQ(c.fingertip_radius, p.fingertip_radius);
    for (int j = 0; j < c.dof(); ++j) {
      EXPECT_NEAR(c.joints[j].lower, p.joints[j].lower, 1e-12);
      EXPECT_NEAR(c.joints[j].upper, p.joints[j].upper, 1e-12);
      EXPECT_DOUBLE_EQ(c.joints[j].max_velocity, p.joints[j].max_velocity);
    }
    inhand::FingerKinematics<MujocoChain> wc(c);
    inhand::FingerKinematics<inhand::plant::PlantFinger> wp(p);
    for (int n = 0; n < inhand_test::scaled(50); ++n) {
      const MujocoChain::JointVector q = random_angles(rng, c);
      inhand::forward_kinematics(c, q, wc);
      inhand::forward_kinematics(p, inhand::plant::PlantFinger::JointVector(q), wp);
      worst = std::max(worst, (wc.fingertip.position - wp.fingertip.position).norm());
    }
  }
  inhand_test::record(std::string(GetParam().name) + "_max_tip_distance_to_preset_m", worst);
  EXPECT_LT(worst, 1e-12);
}

/// Largest differences between the chains and MuJoCo over `count` random configurations:
/// fingertip position against geom_xpos, rotation against geom_xmat and the point
/// Jacobian of a point on the fingertip sphere against mj_jac, each within 1e-9.
void expect_agreement(Hand& h, const char* what) {
  const mjModel* m = h.model.get();
  mjData* d = h.data.get();
  inhand_test::Rng rng = inhand_test::make_rng(11);
  std::vector<mjtNum> jacp(static_cast<std::size_t>(3 * m->nv));
  double worst_tip = 0.0, worst_rot = 0.0, worst_jac = 0.0;
  const int count = inhand_test::scaled(200);
  for (int n = 0; n < count; ++n) {
    for (std::size_t i = 0; i < h.chains.size(); ++i) {
      const MujocoChain& c = h.chains[i];
      const std::vector<int> adr = inhand::mujoco_demo::finger_qpos_addresses(m, h.fingers[i]);
      const MujocoChain::JointVector q = random_angles(rng, c);
      for (int j = 0; j < c.dof(); ++j) d->qpos[adr[static_cast<std::size_t>(j)]] = q(j);
      mj_kinematics(m, d);
      mj_comPos(m, d);
      inhand::FingerKinematics<MujocoChain> ws(c);
      inhand::forward_kinematics(c, q, ws);
      const int g = mj_name2id(m, mjOBJ_GEOM, h.fingers[i].tip_geom.c_str());
      const Eigen::Map<const Eigen::Vector3d> tip(d->geom_xpos + 3 * g);
      const Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>> rot(d->geom_xmat +
                                                                               9 * g);
      worst_tip = std::max(worst_tip, (ws.fingertip.position - tip).norm());
      worst_rot = std::max(worst_rot, (ws.fingertip.rotation - rot).cwiseAbs().maxCoeff());
      // A point on the fingertip sphere, as a contact would be.
      const Eigen::Vector3d point =
          tip + c.fingertip_radius * inhand_test::random_unit_vector<double>(rng);
      mj_jac(m, d, jacp.data(), nullptr, point.data(), m->geom_bodyid[g]);
      MujocoChain::Jacobian J(3, c.dof());
      inhand::point_jacobian(ws, point, J);
      for (int j = 0; j < c.dof(); ++j) {
        const int jnt = -1 + [&] {  // the joint whose qpos address is adr[j]
          for (int k = 0; k < m->njnt; ++k)
            if (m->jnt_qposadr[k] == adr[static_cast<std::size_t>(j)]) return k + 1;
          return 0;
        }();
        ASSERT_GE(jnt, 0);
        for (int r = 0; r < 3; ++r)
          worst_jac = std::max(
              worst_jac,
              std::abs(J(r, j) - jacp[static_cast<std::size_t>(r * m->nv + m->jnt_dofadr[jnt])]));
      }
    }
  }
  const std::string w(what);
  inhand_test::record(w + "_configurations", count);
  inhand_test::record(w + "_max_tip_position_error_m", worst_tip);
  inhand_test::record(w + "_max_tip_rotation_error", worst_rot);
  inhand_test::record(w + "_max_jacobian_error_m", worst_jac);
  EXPECT_LT(worst_tip, 1e-9);
  EXPECT_LT(worst_rot, 1e-9);
  EXPECT_LT(worst_jac, 1e-9);
}

TEST_P(MujocoChains, ForwardKinematicsAndJacobianAgreeWithMujoco) {
  Hand h(GetParam());
  expect_agreement(h, GetParam().name);
}

// At the preset's open configuration, with the object held at its nominal pose (the weld
// object_hold on), MuJoCo finds no contact at all: no hand geom touches or penetrates the
// object (geom margins are 0, so any contact is a touch) and no finger touches another.
// Recorded: the smallest hand-object distance, as MuJoCo's collision reports it with a
// 50 mm margin on every geom.
TEST_P(MujocoChains, OpenConfigurationLeavesTheObjectClear) {
  Hand h(GetParam());
  const auto preset = GetParam().preset();
  mjModel* m = h.model.get();
  mjData* d = h.data.get();
  for (std::size_t i = 0; i < h.fingers.size(); ++i) {
    const std::vector<int> adr = inhand::mujoco_demo::finger_qpos_addresses(m, h.fingers[i]);
    ASSERT_EQ(static_cast<Eigen::Index>(adr.size()), preset.open_configuration[i].size());
    for (std::size_t j = 0; j < adr.size(); ++j)
      d->qpos[adr[j]] = preset.open_configuration[i](static_cast<Eigen::Index>(j));
  }
  const int hold = mj_name2id(m, mjOBJ_EQUALITY, "object_hold");
  const int object = mj_name2id(m, mjOBJ_GEOM, "object_geom");
  ASSERT_GE(hold, 0);
  ASSERT_GE(object, 0);
  m->eq_active[hold] = 1;
  mj_forward(m, d);
  std::ostringstream contacts;
  for (int c = 0; c < d->ncon; ++c)
    contacts << " " << mj_id2name(m, mjOBJ_GEOM, d->contact[c].geom1) << "-"
             << mj_id2name(m, mjOBJ_GEOM, d->contact[c].geom2) << " (" << d->contact[c].dist
             << " m)";
  EXPECT_EQ(d->ncon, 0) << "contacts:" << contacts.str();
  for (int g = 0; g < m->ngeom; ++g) m->geom_margin[g] = 0.05;
  mj_forward(m, d);
  double clearance = 0.05;
  for (int c = 0; c < d->ncon; ++c)
    if (d->contact[c].geom1 == object || d->contact[c].geom2 == object)
      clearance = std::min(clearance, static_cast<double>(d->contact[c].dist));
  inhand_test::record(std::string(GetParam().name) + "_open_min_clearance_to_object_m", clearance);
  EXPECT_GT(clearance, 0.0);
}

// gtest numbers the cases (Hands/MujocoChains.<test>/0, 1, 2); ctest names them by the
// printed parameter (mujoco.Hands/MujocoChains.<test>/three_finger, ...).
INSTANTIATE_TEST_SUITE_P(Hands, MujocoChains, ::testing::ValuesIn(kHandModels));

TEST(MujocoChainsTwistedFinger, TurnedFramesOffsetAnchorsAndGeneralAxesAgreeWithMujoco) {
  Hand h(std::string(INHAND_TEST_DATA_DIR) + "/twisted_finger.xml", {{"palm", "tip"}});
  const MujocoChain& c = h.chains[0];
  ASSERT_TRUE(c.validate().ok()) << c.validate().field;
  EXPECT_DOUBLE_EQ(c.joints[0].max_velocity, 3.0);  // no actuator: the default
  EXPECT_DOUBLE_EQ(c.joints[1].max_velocity, 2.0);  // min(|-2|, 2.5), ctrl not clipped
  EXPECT_DOUBLE_EQ(c.fingertip_radius, 0.008);
  expect_agreement(h, "twisted");
}

}  // namespace
