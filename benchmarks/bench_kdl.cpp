// The same per-finger work done with Orocos KDL, in the same binary as the inhand
// benchmarks so that every ratio comes from one run on one machine state.
//
// Each finger is translated into an equivalent KDL::Chain (the mapping of
// tests/kinematics/kdl_agreement_test.cpp; the set-up checks that KDL's fingertip
// frame and contact-point Jacobian agree with inhand's to 1e-9). Per finger and tick:
//   KDL::ChainFkSolverPos_recursive::JntToCart   fingertip frame
//   KDL::ChainJntToJacSolver::JntToJac            6 x n Jacobian of the tip frame,
//     then Jacobian::changeRefPoint                 moved to the contact point
//   KDL::ChainIkSolverVel_pinv::CartToJnt          joint velocities for the twist
//     (v_contact ; 0): KDL's velocity IK solves the 6-D problem, so a KDL user of
//     fingers asks for the contact velocity with zero angular velocity (with zero
//     angular velocity the tip and the contact point move alike). KDL's weighted
//     solver ChainIkSolverVel_wdls is not used: the Debian build aborts on chains
//     with fewer than 6 joints.
// kdl/kinematics/<finger>: JntToCart + JntToJac + changeRefPoint (vs kinematics/...)
// kdl/finger/<finger>:     the above + CartToJnt (vs finger/...)
// kdl/hand/<hand>:         kdl/finger summed over every finger of the hand, on the
//                          same sensed states as controller/<hand>
// Allocations are counted but not required to be zero here.
#include <kdl/chain.hpp>
#include <kdl/chainfksolverpos_recursive.hpp>
#include <kdl/chainiksolvervel_pinv.hpp>
#include <kdl/chainjnttojacsolver.hpp>
#include <memory>

#include "bench_support.hpp"

namespace inhand_bench {
namespace {

KDL::Vector to_kdl(const Eigen::Vector3d& v) { return KDL::Vector(v.x(), v.y(), v.z()); }
KDL::Frame to_kdl(const inhand::Pose<double, 3>& p) {
  const Eigen::Matrix3d& R = p.rotation;
  return KDL::Frame(KDL::Rotation(R(0, 0), R(0, 1), R(0, 2), R(1, 0), R(1, 1), R(1, 2), R(2, 0),
                                  R(2, 1), R(2, 2)),
                    to_kdl(p.position));
}

/// Segment 0 places the base; segment i holds joint i (origin and axis in the previous
/// segment's tip frame) and ends at the joint frame (times joint_to_tip for the last).
KDL::Chain to_kdl_chain(const RefChain<3>& chain) {
  KDL::Chain k;
  k.addSegment(KDL::Segment("base", KDL::Joint(KDL::Joint::None), to_kdl(chain.base)));
  for (int i = 0; i < chain.dof(); ++i) {
    const auto& j = chain.joints[i];
    const inhand::Pose<double, 3>& p = j.parent_to_joint;
    const Eigen::Vector3d axis_in_parent = p.rotation * j.axis;
    const inhand::Pose<double, 3> tip = i + 1 == chain.dof() ? p * chain.joint_to_tip : p;
    const std::string name = "joint" + std::to_string(i);
    k.addSegment(KDL::Segment(
        name, KDL::Joint(name, to_kdl(p.position), to_kdl(axis_in_parent), KDL::Joint::RotAxis),
        to_kdl(tip)));
  }
  return k;
}

/// One finger's KDL pipeline over its own copy of the sensed states.
class KdlFinger {
 public:
  KdlFinger(const RefChain<3>& chain, const std::vector<FingerSample<3>>& samples)
      : chain_(to_kdl_chain(chain)),
        fk_(chain_),
        jac_solver_(chain_),
        pinv_(chain_),
        jacobian_(chain_.getNrOfJoints()),
        qdot_(chain_.getNrOfJoints()) {
    const unsigned n = chain_.getNrOfJoints();
    inhand::FingerKinematics<RefChain<3>> ws(chain);
    typename RefChain<3>::Jacobian J(3, chain.dof());
    for (const FingerSample<3>& s : samples) {
      KDL::JntArray q(n);
      for (unsigned i = 0; i < n; ++i) q(i) = s.q(static_cast<Eigen::Index>(i));
      q_.push_back(q);
      contact_.push_back(to_kdl(s.contact));
      twist_.push_back(KDL::Twist(to_kdl(s.velocity), KDL::Vector::Zero()));
      // The chain is equivalent: same fingertip, same contact-point Jacobian.
      inhand::forward_kinematics(chain, s.q, ws);
      inhand::point_jacobian(ws, s.contact, J);
      run(q_.size() - 1);
      double err =
          (Eigen::Vector3d(tip_.p.x(), tip_.p.y(), tip_.p.z()) - ws.fingertip.position).norm();
      for (int c = 0; c < chain.dof(); ++c)
        for (int r = 0; r < 3; ++r)
          err = std::max(
              err,
              std::abs(jacobian_(static_cast<unsigned>(r), static_cast<unsigned>(c)) - J(r, c)));
      if (!(err < 1e-9)) throw std::runtime_error("KDL chain disagrees with the inhand chain");
    }
  }
  KdlFinger(const KdlFinger&) = delete;
  KdlFinger& operator=(const KdlFinger&) = delete;

  /// FK + Jacobian at the contact point; with `ik` also the velocity IK.
  double run(std::size_t k, bool ik = true) noexcept {
    fk_.JntToCart(q_[k], tip_);
    jac_solver_.JntToJac(q_[k], jacobian_);
    jacobian_.changeRefPoint(contact_[k] - tip_.p);
    if (ik) pinv_.CartToJnt(q_[k], twist_[k], qdot_);
    return qdot_(0) + jacobian_(0, 0);
  }

 private:
  KDL::Chain chain_;
  KDL::ChainFkSolverPos_recursive fk_;
  KDL::ChainJntToJacSolver jac_solver_;
  KDL::ChainIkSolverVel_pinv pinv_;
  KDL::Jacobian jacobian_;
  KDL::JntArray qdot_;
  KDL::Frame tip_;
  std::vector<KDL::JntArray> q_;
  std::vector<KDL::Vector> contact_;
  std::vector<KDL::Twist> twist_;
};

class KdlFingerFixture {
 public:
  static constexpr long kMaintenancePeriod = 0;
  KdlFingerFixture(const HandDef<3>& hand, int finger, bool ik, std::uint64_t seed)
      : finger_(hand.fingers[static_cast<std::size_t>(finger)],
                random_finger_samples<3>(hand, finger, seed)),
        ik_(ik) {}
  [[gnu::noinline]] double tick() noexcept { return finger_.run(next_++ & (kSamples - 1), ik_); }

 private:
  KdlFinger finger_;
  bool ik_;
  std::size_t next_ = 0;
};

class KdlHandFixture {
 public:
  static constexpr long kMaintenancePeriod = 0;
  KdlHandFixture(const HandDef<3>& hand, std::uint64_t seed) {
    const std::vector<HandSample<3>> samples = random_hand_samples<3>(hand, seed);
    for (int i = 0; i < hand.finger_count(); ++i) {
      std::vector<FingerSample<3>> mine;
      for (const HandSample<3>& s : samples) mine.push_back(s.fingers[static_cast<std::size_t>(i)]);
      fingers_.push_back(
          std::make_unique<KdlFinger>(hand.fingers[static_cast<std::size_t>(i)], mine));
    }
  }
  [[gnu::noinline]] double tick() noexcept {
    const std::size_t k = next_++ & (kSamples - 1);
    double sum = 0.0;
    for (const auto& f : fingers_) sum += f->run(k);
    return sum;
  }

 private:
  std::vector<std::unique_ptr<KdlFinger>> fingers_;
  std::size_t next_ = 0;
};

}  // namespace

void register_kdl_benchmarks() {
  const HandDef<3> shadow = shadow4_hand();
  const HandDef<3> three = three_finger_hand();
  const std::uint64_t kFingerSeed = 404;  // the sensed states of finger/...
  add<KdlFingerFixture>("kdl/kinematics/spatial4", false, shadow, 0, false, std::uint64_t{101});
  add<KdlFingerFixture>("kdl/finger/spatial3", false, three, 0, true, kFingerSeed);
  add<KdlFingerFixture>("kdl/finger/spatial4", false, shadow, 0, true, kFingerSeed);
  add<KdlFingerFixture>("kdl/finger/spatial5", false, shadow, shadow.thumb, true, kFingerSeed);
  const std::uint64_t kHandSeed = 505;  // the sensed states of controller/...
  add<KdlHandFixture>("kdl/hand/spatial3x3", false, three, kHandSeed);
  add<KdlHandFixture>("kdl/hand/allegro4", false, allegro4_hand(), kHandSeed);
  add<KdlHandFixture>("kdl/hand/shadow4", false, shadow, kHandSeed);
  add<KdlHandFixture>("kdl/hand/shadow5", false, shadow5_hand(), kHandSeed);
}

}  // namespace inhand_bench
