// MuJoCo loads the shipped URDF hands (models/urdf/*.urdf) and its forward kinematics
// agrees with the finger chains inhand::urdf reads from the same files: the fingertip
// sphere centre (inhand's ws.fingertip.position; MuJoCo's geom_xpos of the tip link's
// collision sphere) and the tip link orientation, at random joint configurations within
// the limits. Units: metres, radians.
//
// Loading (MuJoCo 2.2.2, src/xml/xml_urdf.cc): the URDF importer reads a <mujoco>
// element inside <robot> (its <compiler>, <option>, <size>); urdfdom ignores it. Its
// defaults fuse every body without a joint into its parent (fusestatic), which would
// remove the palm, base and tip link bodies, and the links here carry no <inertial>, so
// the moving bodies would be massless, which MuJoCo's compiler refuses. The test
// therefore hands MuJoCo each file with kMujocoSection inserted after <robot ...>, from
// memory (a virtual file system): fusestatic off, and a lower bound on mass and inertia
// (irrelevant to kinematics). The files themselves are left unchanged.
//
// Frames: MuJoCo makes the root link (palm) a body under the world body (at the world
// origin); inhand's chains are in the root link frame of the finger spec, so MuJoCo's
// positions are expressed in that body's frame before comparing.
// Mimic joints: MuJoCo 2.2.2's URDF importer ignores <mimic> (no equality constraint
// is made; every joint is an independent hinge), so the Shadow-like J1 joints take
// independent random values in both, as in the KDL comparison of tests/urdf.
#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Core>
#include <algorithm>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "common/test_support.hpp"
#include "common/urdf_hand_models.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/urdf.hpp"
#include "mujoco_model.hpp"

namespace {

using Chain = inhand::FingerChain<double, 3, inhand::Dynamic>;
using RowMatrix3d = Eigen::Matrix<double, 3, 3, Eigen::RowMajor>;

constexpr const char* kMujocoSection =
    "<mujoco><compiler fusestatic=\"false\" boundmass=\"1e-6\" boundinertia=\"1e-12\"/>"
    "</mujoco>";

/// `xml` with kMujocoSection right after the <robot ...> start tag ("" if none).
std::string with_mujoco_section(const std::string& xml) {
  const std::size_t robot = xml.find("<robot");
  if (robot == std::string::npos) return "";
  const std::size_t end = xml.find('>', robot);
  if (end == std::string::npos) return "";
  return xml.substr(0, end + 1) + kMujocoSection + xml.substr(end + 1);
}

struct VfsDeleter {
  void operator()(mjVFS* vfs) const noexcept {
    mj_deleteVFS(vfs);
    delete vfs;
  }
};

/// Compiles the URDF document `xml` with MuJoCo from memory; null with `error` set on
/// failure.
inhand::mujoco_demo::ModelPtr load_urdf_string(const std::string& xml, std::string& error) {
  std::unique_ptr<mjVFS, VfsDeleter> vfs(new mjVFS);
  mj_defaultVFS(vfs.get());
  const char* name = "hand.urdf";
  if (xml.empty() || mj_makeEmptyFileVFS(vfs.get(), name, static_cast<int>(xml.size())) != 0) {
    error = "cannot make the in-memory file";
    return nullptr;
  }
  std::memcpy(vfs->filedata[mj_findFileVFS(vfs.get(), name)], xml.data(), xml.size());
  char message[1000] = "";
  inhand::mujoco_demo::ModelPtr m(mj_loadXML(name, vfs.get(), message, sizeof(message)));
  error = message;
  return m;
}

/// The first sphere geom of body `body`, or -1.
int first_sphere_geom(const mjModel* m, int body) {
  for (int i = 0; i < m->body_geomnum[body]; ++i) {
    const int g = m->body_geomadr[body] + i;
    if (m->geom_type[g] == mjGEOM_SPHERE) return g;
  }
  return -1;
}

// Per model and finger: scaled(1000) random configurations within the joint limits,
// set in qpos through the URDF joint names; fingertip sphere centre and tip link
// orientation in the palm frame after mj_kinematics. Bound 1e-9 m (and 1e-9 on the
// rotation matrix entries); the largest differences are recorded per model.
TEST(MujocoUrdf, ForwardKinematicsAgreesWithTheUrdfReader) {
  constexpr double kBound = 1e-9;
  auto rng = inhand_test::make_rng(20260714);
  for (const inhand_test::UrdfHandModel& model : inhand_test::urdf_hand_models()) {
    SCOPED_TRACE(model.file);
    const std::string path = inhand_test::urdf_model_path(model.file);
    const auto hand = inhand::urdf::read_fingers_file(path, model.specs);
    ASSERT_TRUE(hand.ok()) << hand.error;
    std::string text, error;
    ASSERT_TRUE(inhand::urdf::detail::read_text_file(path, text, error)) << error;
    const std::string xml = with_mujoco_section(text);
    ASSERT_FALSE(xml.empty()) << "no <robot> element in " << path;
    // urdfdom ignores the MuJoCo section.
    const auto same = inhand::urdf::read_fingers_string(xml, model.specs);
    ASSERT_TRUE(same.ok()) << same.error;
    const inhand::mujoco_demo::ModelPtr m = load_urdf_string(xml, error);
    ASSERT_NE(m, nullptr) << error;
    EXPECT_EQ(m->neq, 0);  // <mimic> is not imported
    const inhand::mujoco_demo::DataPtr d = inhand::mujoco_demo::make_data(m.get());
    double worst_position = 0, worst_rotation = 0;
    for (std::size_t f = 0; f < model.specs.size(); ++f) {
      const inhand::urdf::FingerSpec& spec = model.specs[f];
      SCOPED_TRACE(spec.name);
      const Chain& chain = hand.fingers[f];
      const int root = mj_name2id(m.get(), mjOBJ_BODY, spec.root_link.c_str());
      const int tip = mj_name2id(m.get(), mjOBJ_BODY, spec.tip_link.c_str());
      ASSERT_GE(root, 0);
      ASSERT_GE(tip, 0);
      const int sphere = first_sphere_geom(m.get(), tip);
      ASSERT_GE(sphere, 0);
      EXPECT_EQ(m->geom_size[3 * sphere], chain.fingertip_radius);
      std::vector<int> qpos_address;
      for (const std::string& name : hand.joint_names[f]) {
        const int j = mj_name2id(m.get(), mjOBJ_JOINT, name.c_str());
        ASSERT_GE(j, 0) << name;
        ASSERT_EQ(m->jnt_type[j], mjJNT_HINGE) << name;
        qpos_address.push_back(m->jnt_qposadr[j]);
      }
      ASSERT_EQ(static_cast<int>(qpos_address.size()), chain.dof());
      inhand::FingerKinematics<Chain> ws(chain);
      for (int k = 0; k < inhand_test::scaled(1000); ++k) {
        const Chain::JointVector q = inhand_test::random_joint_angles(chain, rng);
        for (int i = 0; i < chain.dof(); ++i)
          d->qpos[qpos_address[static_cast<std::size_t>(i)]] = q(i);
        mj_kinematics(m.get(), d.get());
        inhand::forward_kinematics(chain, q, ws);
        const Eigen::Map<const Eigen::Vector3d> root_position(d->xpos + 3 * root);
        const Eigen::Map<const RowMatrix3d> root_rotation(d->xmat + 9 * root);
        const Eigen::Map<const Eigen::Vector3d> centre(d->geom_xpos + 3 * sphere);
        const Eigen::Map<const RowMatrix3d> tip_rotation(d->xmat + 9 * tip);
        const Eigen::Vector3d centre_in_root = root_rotation.transpose() * (centre - root_position);
        const Eigen::Matrix3d tip_in_root = root_rotation.transpose() * tip_rotation;
        const double position_error = (ws.fingertip.position - centre_in_root).norm();
        const double rotation_error = (ws.fingertip.rotation - tip_in_root).cwiseAbs().maxCoeff();
        worst_position = std::max(worst_position, position_error);
        worst_rotation = std::max(worst_rotation, rotation_error);
        ASSERT_LE(position_error, kBound) << "q " << q.transpose();
        ASSERT_LE(rotation_error, kBound) << "q " << q.transpose();
      }
    }
    const std::string hand_name = model.file.substr(0, model.file.find('.'));
    inhand_test::record(hand_name + "_max_tip_distance_m", worst_position);
    inhand_test::record(hand_name + "_max_rotation_entry_error", worst_rotation);
  }
}

}  // namespace
