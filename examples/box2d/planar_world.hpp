// The planar plant of the Box2D demo: two opposing fingers and one object in a Box2D 2.4
// world (the hand lies in the world x-y plane; rotations about +z, counter-clockwise
// positive, as everywhere in inhand).
//
// Scale (Box2D is tuned for bodies of 0.1 to 10 units): lengths are those of a real hand
// times 100, so 1 Box2D length unit ("u") is 1 cm of the real hand. Time is not scaled
// (seconds). The Box2D mass unit is taken as 100 kg, so that its force unit
// (mass unit * u / s^2) is exactly 1 N and its torque unit 1 N cm; real gravity,
// 9.81 m/s^2, is 981 u/s^2. Every number of this directory, of the demo's traces and of
// its metrics is in these units: lengths u (= cm), forces N, angles rad, time s.
//
// Fingers: a chain of three links on revolute joints, each driven by its Box2D motor as a
// velocity servo (motorSpeed = the commanded joint velocity, up to maxMotorTorque). The
// fingertip is a soft pad: a circle on its own body, held at the end of the distal link
// by two perpendicular wheel-joint springs in series (rotation locked by the wheel
// motors), so it gives way isotropically by f / pad_stiffness. Box2D contacts are rigid;
// without this compliance a velocity-driven finger could press only with whatever torque
// saturates its motor, and the normal force would not be controllable.
// Object: a box or a circle, static while frozen (the grasp stage), dynamic once released;
// set_object_force() pushes it with an external force (a disturbance, the "knock" fault).
//
// Sensing (everything the controller may read; FingerChain models the links and pad):
//   joint angles    b2RevoluteJoint::GetJointAngle (encoders)
//   object pose     the object body's position and angle ("vision")
//   touching        Begin/EndContact between a pad and the object (a counter per finger)
//   contact point   b2WorldManifold of the touching pad-object contact (midpoint of the
//                   manifold points)
//   contact normal  the manifold normal turned into inhand's convention: the OBJECT's
//                   outward unit normal, pointing from the object towards the fingertip
//   normal force    sum of the PostSolve normal impulses of that contact over the last
//                   tick, divided by the tick's duration (N)
// Truth (for metrics and drawings only): slip, i.e. the integral of the tangential
// relative velocity of the pad and object material points at the contact; contacts of a
// non-sensing link with the object; the pads' actual positions.
#pragma once

#include <box2d/box2d.h>

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <stdexcept>

#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/math/pose.hpp"

namespace inhand::box2d_demo {

constexpr int kFingers = 2;
constexpr int kLinks = 3;
using Vec2 = Eigen::Vector2d;
using JointVector = Eigen::Matrix<double, kLinks, 1>;
using Chain = FingerChain<double, 2, kLinks>;

/// Lengths of a real hand times this are Box2D units (1 u = 1 cm).
constexpr double kLengthScale = 100.0;
/// Real gravity in Box2D units (u/s^2).
constexpr double kGravity = 9.81 * kLengthScale;

/// One finger: a serial chain of kLinks links (see the file comment for the units).
struct FingerSpec {
  Vec2 base = Vec2::Zero();                            ///< u, position of joint 0 (world)
  double base_angle = 0.0;                             ///< rad, direction of link 0 at q = 0
  std::array<double, kLinks> length{{4.5, 3.5, 2.5}};  ///< u, joint i -> i+1; last: -> pad centre
  JointVector q_open = JointVector::Zero();            ///< rad, start configuration
  JointVector lower = JointVector::Constant(-1.8);     ///< rad, joint limits (Box2D enforces them)
  JointVector upper = JointVector::Constant(1.8);
  /// Side the finger comes from: the object's expected outward normal at its contact,
  /// in the object frame (hand knowledge, not object knowledge).
  Vec2 approach_normal = -Vec2::UnitX();
};

struct HandSpec {
  std::array<FingerSpec, kFingers> fingers{};
  double link_width = 0.8;     ///< u
  double link_density = 4e-5;  ///< mass units / u^2 (a 4.5 x 0.8 link: 14 g)
  double link_friction = 0.5;
  double max_joint_velocity = 3.0;  ///< rad/s, the controller's joint-velocity limit
  double max_motor_torque = 40.0;   ///< N cm, Box2D motor limit
  double pad_radius = 1.0;          ///< u
  double pad_density = 1.6e-5;      ///< mass units / u^2 (5 g)
  double pad_friction = 1.0;
  double pad_stiffness = 10.0;  ///< N/u in each direction (1 N per mm)
  double pad_damping = 0.05;    ///< N s/u
  double pad_travel = 0.4;      ///< u, pad deflection limit in each direction
};

enum class ObjectShape { box, circle };
inline const char* to_string(ObjectShape s) noexcept {
  return s == ObjectShape::box ? "box" : "circle";
}

/// The object: unknown to the controller (only its pose is sensed).
struct ObjectSpec {
  ObjectShape shape = ObjectShape::box;
  Vec2 half_extents = Vec2(2.2, 2.8);  ///< u, box
  double radius = 2.6;                 ///< u, circle
  double density = 2e-5;               ///< mass units / u^2
  double friction = 0.8;
  Vec2 position = Vec2::Zero();  ///< u, initial centre
  double angle = 0.0;            ///< rad, initial orientation
  /// Characteristic size: the box's smaller side, the circle's diameter (u).
  double size() const noexcept {
    return shape == ObjectShape::box ? 2.0 * std::min(half_extents.x(), half_extents.y())
                                     : 2.0 * radius;
  }
};

struct WorldParams {
  double gravity = 0.0;  ///< u/s^2 along -y; 0: the hand works in a horizontal plane
  int substeps = 2;      ///< Box2D steps per control tick (fixed)
  int velocity_iterations = 10;
  int position_iterations = 4;
};

/// What a tactile sensor reports for one finger.
struct TactileReading {
  bool touching = false;
  Vec2 contact_point = Vec2::Zero();  ///< u, world
  Vec2 normal = Vec2::UnitX();        ///< object's outward unit normal (towards the pad)
  double normal_force = 0.0;          ///< N, mean over the last tick
};

/// The controller's model of finger i: the same links as the Box2D bodies; the
/// fingertip centre is the pad's rest position.
inline Chain finger_chain(const HandSpec& hand, int i) {
  const FingerSpec& f = hand.fingers[static_cast<std::size_t>(i)];
  Chain c;
  c.base.position = f.base;
  c.base.rotation = so2_exp<double>(f.base_angle);
  for (int j = 0; j < kLinks; ++j) {
    c.joints[j].parent_to_joint = Pose<double, 2>{};
    if (j > 0)
      c.joints[j].parent_to_joint.position = Vec2(f.length[static_cast<std::size_t>(j - 1)], 0.0);
    c.joints[j].axis = Eigen::Vector3d::UnitZ();
    c.joints[j].lower = f.lower(j);
    c.joints[j].upper = f.upper(j);
    c.joints[j].max_velocity = hand.max_joint_velocity;
  }
  c.joint_to_tip.position = Vec2(f.length[kLinks - 1], 0.0);
  c.fingertip_radius = hand.pad_radius;
  return c;
}

class PlanarWorld {
 public:
  PlanarWorld(const HandSpec& hand, const ObjectSpec& object, const WorldParams& params)
      : hand_(hand), object_spec_(object), params_(params) {
    if (params.substeps < 1) throw std::invalid_argument("substeps must be >= 1");
    world_ = std::make_unique<b2World>(b2Vec2(0.0f, static_cast<float>(-params.gravity)));
    world_->SetAllowSleeping(false);
    // Bodies move a few cm/s: no tunnelling, and no TOI sub-steps, whose contacts
    // would skip PostSolve and so the force sensing.
    world_->SetContinuousPhysics(false);
    world_->SetContactListener(&tracker_);
    b2BodyDef ground_def;
    ground_ = world_->CreateBody(&ground_def);
    for (int i = 0; i < kFingers; ++i) build_finger(i);
    build_object();
  }
  PlanarWorld(const PlanarWorld&) = delete;
  PlanarWorld& operator=(const PlanarWorld&) = delete;

  const HandSpec& hand() const noexcept { return hand_; }
  const ObjectSpec& object_spec() const noexcept { return object_spec_; }
  const WorldParams& params() const noexcept { return params_; }

  /// Frozen: a static body (the grasp stage). Released: dynamic.
  void set_object_frozen(bool frozen) {
    const b2BodyType type = frozen ? b2_staticBody : b2_dynamicBody;
    if (object_->GetType() == type) return;
    object_->SetType(type);
    // SetType destroys the body's contacts, and Box2D 2.4 would find them again only
    // at the end of the next step's solve: the pads would pass one step through the
    // object with no contact (a false contact loss and an impact). Re-enabling the body
    // makes the next step create its contacts first; a step of zero duration runs only
    // that collision pass (b2World::Step solves nothing when dt = 0), so the tactile
    // sensing read before the next tick still reports the contacts (Begin/EndContact
    // both fire here, on the same tick).
    object_->SetEnabled(false);
    object_->SetEnabled(true);
    world_->Step(0.0f, params_.velocity_iterations, params_.position_iterations);
  }
  bool object_frozen() const noexcept { return object_->GetType() == b2_staticBody; }

  /// Joint-velocity command (rad/s) of one finger: its motors' speeds.
  void set_joint_velocity(int finger, const JointVector& qdot) noexcept {
    for (int j = 0; j < kLinks; ++j) joint(finger, j)->SetMotorSpeed(static_cast<float>(qdot(j)));
  }

  /// External force (N, world) on the object's centre, applied in every Box2D step
  /// until changed (a disturbance: the "knock" fault). Ignored while the object is frozen.
  void set_object_force(const Vec2& f) noexcept { object_force_ = f; }
  const Vec2& object_force() const noexcept { return object_force_; }

  /// Advances by dt (one control tick) in params.substeps fixed Box2D steps.
  void step(double dt) {
    const double h = dt / params_.substeps;
    tracker_.impulse.fill(0.0);
    for (int s = 0; s < params_.substeps; ++s) {
      // Box2D clears applied forces after every step: apply it again each substep.
      if (!object_force_.isZero(0.0) && !object_frozen())
        object_->ApplyForceToCenter(to_b2(object_force_), true);
      world_->Step(static_cast<float>(h), params_.velocity_iterations, params_.position_iterations);
      accumulate_slip(h);
    }
    for (int i = 0; i < kFingers; ++i)
      force_[static_cast<std::size_t>(i)] = tracker_.impulse[static_cast<std::size_t>(i)] / dt;
    time_ += dt;
  }
  double time() const noexcept { return time_; }

  // ---- sensing -------------------------------------------------------------------
  JointVector joint_angles(int finger) const noexcept {
    JointVector q;
    for (int j = 0; j < kLinks; ++j) q(j) = static_cast<double>(joint(finger, j)->GetJointAngle());
    return q;
  }
  Pose<double, 2> object_pose() const noexcept { return body_pose(object_); }

  TactileReading tactile(int finger) const noexcept {
    TactileReading r;
    r.touching = tracker_.touching[static_cast<std::size_t>(finger)] > 0;
    if (!r.touching) return r;
    b2WorldManifold wm;
    bool object_is_a = false;
    const b2Contact* c = pad_contact(finger, wm, object_is_a);
    if (c == nullptr) {  // cannot happen while the counter is positive; report no contact
      r.touching = false;
      return r;
    }
    const int points = c->GetManifold()->pointCount;
    Vec2 p = Vec2::Zero();
    for (int k = 0; k < points; ++k) p += Vec2(wm.points[k].x, wm.points[k].y);
    r.contact_point = p / static_cast<double>(points);
    // b2WorldManifold::normal points from fixture A to fixture B.
    const Vec2 n(wm.normal.x, wm.normal.y);
    r.normal = (object_is_a ? n : Vec2(-n)).normalized();
    r.normal_force = force_[static_cast<std::size_t>(finger)];
    return r;
  }

  // ---- truth (metrics, drawings) --------------------------------------------------
  double slip_distance(int finger) const noexcept {
    return slip_[static_cast<std::size_t>(finger)];
  }
  /// Ticks on which a non-sensing link touched the object (should stay 0).
  int link_contacts() const noexcept { return tracker_.link_touching; }
  /// World positions of the joints 0..kLinks-1 and the pad-rest point at the distal end.
  std::array<Vec2, kLinks + 1> finger_points(int finger) const noexcept {
    std::array<Vec2, kLinks + 1> p{};
    const FingerSpec& f = hand_.fingers[static_cast<std::size_t>(finger)];
    for (int j = 0; j < kLinks; ++j) {
      const b2Body* b = link(finger, j);
      p[static_cast<std::size_t>(j)] = to_vec(b->GetPosition());
      if (j == kLinks - 1)
        p[kLinks] =
            to_vec(b->GetWorldPoint(b2Vec2(static_cast<float>(f.length[kLinks - 1]), 0.0f)));
    }
    return p;
  }
  Vec2 pad_centre(int finger) const noexcept {
    return to_vec(pads_[static_cast<std::size_t>(finger)]->GetPosition());
  }
  Vec2 object_velocity() const noexcept { return to_vec(object_->GetLinearVelocity()); }

 private:
  // Fixture tags (b2FixtureUserData::pointer): which body a contact involves.
  static constexpr std::uintptr_t kObjectTag = 100;
  static constexpr std::uintptr_t kPadTag = 1;    // + finger
  static constexpr std::uintptr_t kLinkTag = 10;  // + finger
  static constexpr uint16 kObjectCategory = 0x0001, kPadCategory = 0x0002, kLinkCategory = 0x0004;

  struct ContactTracker : b2ContactListener {
    std::array<int, kFingers> touching{};
    std::array<double, kFingers> impulse{};  ///< N s over the current tick
    int link_touching = 0;
    /// Finger whose pad touches the object in `c`, or -1.
    static int pad_finger(b2Contact* c) noexcept {
      const std::uintptr_t a = c->GetFixtureA()->GetUserData().pointer;
      const std::uintptr_t b = c->GetFixtureB()->GetUserData().pointer;
      const std::uintptr_t other = a == kObjectTag ? b : (b == kObjectTag ? a : 0);
      if (other >= kPadTag && other < kPadTag + kFingers) return static_cast<int>(other - kPadTag);
      return -1;
    }
    static bool link_object(b2Contact* c) noexcept {
      const std::uintptr_t a = c->GetFixtureA()->GetUserData().pointer;
      const std::uintptr_t b = c->GetFixtureB()->GetUserData().pointer;
      const std::uintptr_t other = a == kObjectTag ? b : (b == kObjectTag ? a : 0);
      return other >= kLinkTag && other < kLinkTag + kFingers;
    }
    void BeginContact(b2Contact* c) override {
      const int f = pad_finger(c);
      if (f >= 0) ++touching[static_cast<std::size_t>(f)];
      if (link_object(c)) ++link_touching;
    }
    void EndContact(b2Contact* c) override {
      const int f = pad_finger(c);
      if (f >= 0) --touching[static_cast<std::size_t>(f)];
    }
    void PostSolve(b2Contact* c, const b2ContactImpulse* imp) override {
      const int f = pad_finger(c);
      if (f < 0) return;
      for (int k = 0; k < imp->count; ++k)
        impulse[static_cast<std::size_t>(f)] += imp->normalImpulses[k];
    }
  };

  static Vec2 to_vec(const b2Vec2& v) noexcept { return Vec2(v.x, v.y); }
  static b2Vec2 to_b2(const Vec2& v) noexcept {
    return b2Vec2(static_cast<float>(v.x()), static_cast<float>(v.y()));
  }
  static Pose<double, 2> body_pose(const b2Body* b) noexcept {
    Pose<double, 2> p;
    p.position = to_vec(b->GetPosition());
    p.rotation = so2_exp<double>(static_cast<double>(b->GetAngle()));
    return p;
  }

  b2RevoluteJoint* joint(int finger, int j) const noexcept {
    return joints_[static_cast<std::size_t>(finger * kLinks + j)];
  }
  b2Body* link(int finger, int j) const noexcept {
    return links_[static_cast<std::size_t>(finger * kLinks + j)];
  }

  /// The touching contact of finger's pad with the object (nullptr if none).
  const b2Contact* pad_contact(int finger, b2WorldManifold& wm, bool& object_is_a) const noexcept {
    for (b2ContactEdge* e = object_->GetContactList(); e != nullptr; e = e->next) {
      b2Contact* c = e->contact;
      if (!c->IsTouching() || ContactTracker::pad_finger(c) != finger) continue;
      c->GetWorldManifold(&wm);
      object_is_a = c->GetFixtureA()->GetBody() == object_;
      return c;
    }
    return nullptr;
  }

  void accumulate_slip(double h) noexcept {
    for (int i = 0; i < kFingers; ++i) {
      b2WorldManifold wm;
      bool object_is_a = false;
      const b2Contact* c = pad_contact(i, wm, object_is_a);
      if (c == nullptr) continue;
      const b2Vec2 p = wm.points[0];
      const Vec2 n = to_vec(wm.normal);
      const Vec2 v =
          to_vec(pads_[static_cast<std::size_t>(i)]->GetLinearVelocityFromWorldPoint(p)) -
          to_vec(object_->GetLinearVelocityFromWorldPoint(p));
      slip_[static_cast<std::size_t>(i)] += (v - v.dot(n) * n).norm() * h;
    }
  }

  void build_finger(int i) {
    const FingerSpec& f = hand_.fingers[static_cast<std::size_t>(i)];
    b2Body* parent = ground_;
    Vec2 p = f.base;
    double angle = f.base_angle;
    for (int j = 0; j < kLinks; ++j) {
      const double len = f.length[static_cast<std::size_t>(j)];
      angle += f.q_open(j);
      b2BodyDef bd;
      bd.type = b2_dynamicBody;
      bd.position = to_b2(p);
      bd.angle = static_cast<float>(angle);
      b2Body* body = world_->CreateBody(&bd);
      b2PolygonShape shape;
      // The distal link ends under the pad; the others reach the next joint.
      shape.SetAsBox(static_cast<float>(len / 2), static_cast<float>(hand_.link_width / 2),
                     b2Vec2(static_cast<float>(len / 2), 0.0f), 0.0f);
      b2FixtureDef fd;
      fd.shape = &shape;
      fd.density = static_cast<float>(hand_.link_density);
      fd.friction = static_cast<float>(hand_.link_friction);
      fd.filter.categoryBits = kLinkCategory;
      fd.filter.maskBits = kObjectCategory;
      fd.userData.pointer = kLinkTag + static_cast<std::uintptr_t>(i);
      body->CreateFixture(&fd);

      b2RevoluteJointDef jd;
      jd.bodyA = parent;
      jd.bodyB = body;
      jd.localAnchorA = parent->GetLocalPoint(to_b2(p));
      jd.localAnchorB = b2Vec2(0.0f, 0.0f);
      // GetJointAngle() = angleB - angleA - referenceAngle must read q, the chain's
      // joint angle: the base link's q = 0 direction is base_angle.
      jd.referenceAngle = static_cast<float>(j == 0 ? f.base_angle : 0.0);
      jd.enableLimit = true;
      jd.lowerAngle = static_cast<float>(f.lower(j));
      jd.upperAngle = static_cast<float>(f.upper(j));
      jd.enableMotor = true;
      jd.motorSpeed = 0.0f;
      jd.maxMotorTorque = static_cast<float>(hand_.max_motor_torque);
      joints_[static_cast<std::size_t>(i * kLinks + j)] =
          static_cast<b2RevoluteJoint*>(world_->CreateJoint(&jd));
      links_[static_cast<std::size_t>(i * kLinks + j)] = body;
      p += len * Vec2(std::cos(angle), std::sin(angle));
      parent = body;
    }
    // Soft pad: carrier on a spring along the distal link, pad on a spring across it.
    const float rot = static_cast<float>(angle);
    b2BodyDef cd;
    cd.type = b2_dynamicBody;
    cd.position = to_b2(p);
    cd.angle = rot;
    b2Body* carrier = world_->CreateBody(&cd);
    b2MassData md;
    md.mass = static_cast<float>(hand_.pad_density * 0.1);  // light, no fixture
    md.center = b2Vec2(0.0f, 0.0f);
    md.I = md.mass * 0.1f;
    carrier->SetMassData(&md);
    b2Body* pad = world_->CreateBody(&cd);
    b2CircleShape circle;
    circle.m_radius = static_cast<float>(hand_.pad_radius);
    b2FixtureDef pf;
    pf.shape = &circle;
    pf.density = static_cast<float>(hand_.pad_density);
    pf.friction = static_cast<float>(hand_.pad_friction);
    pf.filter.categoryBits = kPadCategory;
    pf.filter.maskBits = kObjectCategory;
    pf.userData.pointer = kPadTag + static_cast<std::uintptr_t>(i);
    pad->CreateFixture(&pf);
    add_pad_spring(parent, carrier, p, Vec2(std::cos(angle), std::sin(angle)));
    add_pad_spring(carrier, pad, p, Vec2(-std::sin(angle), std::cos(angle)));
    pads_[static_cast<std::size_t>(i)] = pad;
  }

  void add_pad_spring(b2Body* a, b2Body* b, const Vec2& anchor, const Vec2& axis) {
    b2WheelJointDef wd;
    wd.Initialize(a, b, to_b2(anchor), to_b2(axis));
    wd.stiffness = static_cast<float>(hand_.pad_stiffness);
    wd.damping = static_cast<float>(hand_.pad_damping);
    wd.enableLimit = true;
    wd.lowerTranslation = static_cast<float>(-hand_.pad_travel);
    wd.upperTranslation = static_cast<float>(hand_.pad_travel);
    wd.enableMotor = true;  // locks the relative rotation (the pad does not spin)
    wd.motorSpeed = 0.0f;
    wd.maxMotorTorque = 1e3f;
    world_->CreateJoint(&wd);
  }

  void build_object() {
    b2BodyDef bd;
    bd.type = b2_staticBody;  // frozen until released
    bd.position = to_b2(object_spec_.position);
    bd.angle = static_cast<float>(object_spec_.angle);
    object_ = world_->CreateBody(&bd);
    b2PolygonShape box;
    b2CircleShape circle;
    b2FixtureDef fd;
    if (object_spec_.shape == ObjectShape::box) {
      box.SetAsBox(static_cast<float>(object_spec_.half_extents.x()),
                   static_cast<float>(object_spec_.half_extents.y()));
      fd.shape = &box;
    } else {
      circle.m_radius = static_cast<float>(object_spec_.radius);
      fd.shape = &circle;
    }
    fd.density = static_cast<float>(object_spec_.density);
    fd.friction = static_cast<float>(object_spec_.friction);
    fd.filter.categoryBits = kObjectCategory;
    fd.filter.maskBits = kPadCategory | kLinkCategory;
    fd.userData.pointer = kObjectTag;
    object_->CreateFixture(&fd);
  }

  HandSpec hand_;
  ObjectSpec object_spec_;
  WorldParams params_;
  ContactTracker tracker_{};
  std::unique_ptr<b2World> world_;
  b2Body* ground_ = nullptr;
  b2Body* object_ = nullptr;
  std::array<b2Body*, kFingers * kLinks> links_{};
  std::array<b2RevoluteJoint*, kFingers * kLinks> joints_{};
  std::array<b2Body*, kFingers> pads_{};
  std::array<double, kFingers> force_{};
  std::array<double, kFingers> slip_{};
  Vec2 object_force_ = Vec2::Zero();
  double time_ = 0.0;
};

}  // namespace inhand::box2d_demo
