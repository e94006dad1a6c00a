// Scenario files and the example helpers: the JSON parser of examples/scenario
// (defaults, every rejection names its key), the shipped paper files against
// inhand::plant::paper_scenario(), expectations, run summaries, trace CSV and atomic
// output files of examples/common.
// Built by tests/scenarios/tests.cmake (it needs nlohmann-json, which the global test
// glob does not link).
#include <dirent.h>
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "common/atomic_file.hpp"
#include "common/controller_instances.hpp"
#include "common/expectations.hpp"
#include "common/scene_svg.hpp"
#include "common/summary_json.hpp"
#include "common/test_support.hpp"
#include "common/trace_csv.hpp"
#include "scenario_json.hpp"

namespace {

namespace ex = inhand::examples;
namespace ip = inhand::plant;
using ex::Json;

const std::string kScenarioDir = INHAND_SCENARIO_DIR;

// A small valid scenario; tests mutate it.
Json base_scenario() {
  return ex::parse_json_text(R"({
    "name": "base",
    "hand": "shadow_like",
    "object": {"shape": "cylinder", "radius": 0.02, "length": 0.1, "mass": 0.05},
    "stages": [
      {"name": "grasp", "kind": "grasp", "duration": 3.0},
      {"name": "hold", "kind": "hold", "release": true, "duration": 2.0},
      {"name": "manipulate", "kind": "manipulate", "settle": 1.0, "segments": [
        {"kind": "reciprocate", "motion": "move", "axis": [1, 0, 0], "amount": 0.005, "duration": 4.0}]}
    ],
    "expect": {"all": {"must_not_drop": true}, "hold": {"max_settle_time": 1.0}}
  })");
}

// The message of the JsonError thrown by parsing `j` ("" if none was thrown).
std::string parse_error(const Json& j) {
  try {
    ex::parse_scenario(j);
  } catch (const ex::JsonError& e) {
    return e.what();
  }
  return "";
}
std::string text_error(const std::string& text) {
  try {
    ex::parse_scenario(ex::parse_json_text(text));
  } catch (const ex::JsonError& e) {
    return e.what();
  }
  return "";
}

std::string read_text(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

// A fresh empty directory under the test's working directory.
std::string fresh_dir(const std::string& name) {
  const std::string d = "scenario_json_check_" + name;
  std::filesystem::remove_all(d);
  std::filesystem::create_directory(d);
  return d;
}
std::vector<std::string> list_dir(const std::string& d) {
  std::vector<std::string> out;
  if (DIR* dir = ::opendir(d.c_str())) {
    while (dirent* e = ::readdir(dir)) {
      const std::string n = e->d_name;
      if (n != "." && n != "..") out.push_back(n);
    }
    ::closedir(dir);
  }
  return out;
}

// ---------------------------------------------------------------------------
// Parsing valid files

TEST(ScenarioJson, OmittedFieldsTakeTheLibraryDefaults) {
  const ex::ScenarioFile f = ex::parse_scenario(base_scenario());
  const ip::PlantParams d = ip::default_plant_params();
  const ip::PlantParams& p = f.spec.plant;
  EXPECT_EQ(p.time_step, d.time_step);
  EXPECT_EQ(p.contact.friction, d.contact.friction);
  EXPECT_EQ(p.contact.normal_stiffness, d.contact.normal_stiffness);
  EXPECT_EQ(p.contact.tangential_damping, d.contact.tangential_damping);
  EXPECT_EQ(p.gravity, d.gravity);
  EXPECT_EQ(p.sensing.normal_force_std, 0.0);
  EXPECT_EQ(p.seed, d.seed);
  const ip::HandController::Config dc{};
  const ip::HandController::Config& c = f.spec.controller;
  EXPECT_EQ(c.control_period, dc.control_period);
  EXPECT_EQ(c.pose_feedback.position_gain, dc.pose_feedback.position_gain);
  EXPECT_EQ(c.pose_feedback.orientation_integral_limit,
            dc.pose_feedback.orientation_integral_limit);
  EXPECT_EQ(c.servo.force.kp, dc.servo.force.kp);
  EXPECT_EQ(c.servo.force.ki, dc.servo.force.ki);
  EXPECT_TRUE(std::isinf(c.servo.motion.output_limit));
  EXPECT_EQ(c.ik.damping.max_damping, dc.ik.damping.max_damping);
  EXPECT_EQ(c.force_planner.nominal_force, dc.force_planner.nominal_force);
  EXPECT_EQ(c.grasp.creep_speed, dc.grasp.creep_speed);
  const ip::MetricsTolerances dt{};
  EXPECT_EQ(f.spec.tolerances.drop_distance, dt.drop_distance);
  EXPECT_EQ(f.hand_preset, "shadow_like");
  EXPECT_EQ(f.spec.hand.fingers.size(), 4u);
  ASSERT_EQ(f.expect.stages.size(), 2u);
}

// Each "hand" value selects its preset (name, fingers, couplings).
TEST(ScenarioJson, HandNamesSelectThePresets) {
  const std::pair<const char*, ip::HandPreset> hands[] = {
      {"shadow_like", ip::shadow_like_hand()},
      {"three_finger", ip::three_finger_hand()},
      {"allegro_like", ip::allegro_like_hand()},
      {"shadow_like_coupled", ip::shadow_like_coupled_hand()}};
  for (const auto& [value, preset] : hands) {
    Json j = base_scenario();
    j["hand"] = value;
    const ex::ScenarioFile f = ex::parse_scenario(j);
    EXPECT_EQ(f.hand_preset, value);
    EXPECT_EQ(f.spec.hand.name, preset.name) << value;
    ASSERT_EQ(f.spec.hand.fingers.size(), preset.fingers.size()) << value;
    for (std::size_t i = 0; i < preset.fingers.size(); ++i)
      EXPECT_EQ(f.spec.hand.fingers[i].actuated_dof(), preset.fingers[i].actuated_dof()) << value;
  }
  EXPECT_EQ(ip::shadow_like_coupled_hand().fingers[0].actuated_dof(), 3);
  EXPECT_EQ(ip::allegro_like_hand().fingers[3].fingertip_radius, 0.012);
}

TEST(ScenarioJson, EveryGivenFieldIsApplied) {
  Json j = base_scenario();
  j["hand"] = "three_finger";
  j["object"] = ex::parse_json_text(
      R"({"shape": "box", "size": [0.02, 0.03, 0.08], "mass": 0.07,
          "pose_offset": {"position": [0.001, -0.002, 0.003], "rpy": [0.1, -0.05, 0.2]}})");
  j["plant"] = ex::parse_json_text(R"({"time_step": 5e-5, "friction": 0.6, "normal_stiffness": 3000,
      "normal_damping": 8, "tangential_stiffness": 2500, "tangential_damping": 4,
      "gravity": [0, 0, -5], "joint_velocity_lag": 0.01, "seed": 42,
      "sensing": {"normal_force_std": 0.01, "normal_force_bias": -0.02, "contact_point_std": 1e-4,
                  "normal_angle_std": 0.02, "object_position_std": 2e-5, "object_rotation_std": 3e-4,
                  "touch_threshold": 0.05}})");
  j["controller"] = ex::parse_json_text(R"({"control_period": 2e-3, "max_tick": 0.02,
      "max_joint_acceleration": 300, "keep_twist_in_reach": true, "at_risk_hold": 0.2,
      "outlier_gates": {"max_object_speed": 0.4, "max_object_angular_speed": 8, "max_force_rate": 200,
                        "contact_stiffness": 5000, "max_rejection_time": 0.003},
      "pose_feedback": {"position_gain": 6, "orientation_gain": 7, "max_linear_speed": 0.04,
                        "max_angular_speed": 0.9, "position_integral_gain": 9,
                        "orientation_integral_gain": 11, "position_integral_limit": 1e-3,
                        "orientation_integral_limit": 0.01, "position_integral_band": 2e-4,
                        "orientation_integral_band": null, "astray_distance": 5e-3,
                        "astray_angle": null, "astray_time": 0.02},
      "servo": {"motion": {"kp": 1.1, "ki": 0.5, "integral_limit": 0.2, "output_limit": null},
                "force": {"kp": 0.03, "ki": 0.25, "integral_limit": 3, "output_limit": 0.1}},
      "ik": {"singular_threshold": 4e-3, "max_damping": 6e-3},
      "force_planner": {"nominal_force": 1.5, "min_force": 0.3, "max_force": 5, "regularisation": 2e-3,
                        "filter_time": 0.03},
      "grasp": {"approach_gain": 3, "approach_speed": 0.02, "creep_speed": 0.004, "tangential_gain": 4,
                "force_tolerance": 0.15, "position_tolerance": 2e-3, "alignment_speed": 0.05,
                "alignment_tolerance": 0.1, "settle_time": 0.2, "slide_force_fraction": 0.5,
                "gravity_tilt": 0.2, "flat_curvature": 20}})");
  j["tolerances"] = ex::parse_json_text(
      R"({"drop_distance": 0.03, "settle_position_tolerance": 1e-3, "settle_orientation_tolerance": 0.02})");
  j["faults"] = ex::parse_json_text(R"([
      {"kind": "tactile_dropout", "stage": "hold", "at": 0.5, "duration": 0.1, "finger": 2,
       "expect": {"max_detection_ticks": 3, "max_reacquire_ticks": 400, "max_force_integral": 0.25}},
      {"kind": "force_spike", "stage": "manipulate", "at": 1.0, "duration": 0.01, "finger": 1, "magnitude": 3},
      {"kind": "pose_outlier", "stage": "manipulate", "vector": [0.01, 0, 0]},
      {"kind": "knock", "stage": "hold", "at": 1.5, "duration": 0.02, "vector": [0, 0, 2]},
      {"kind": "finger_away", "stage": "hold", "finger": 0, "duration": 0}])");
  const ex::ScenarioFile f = ex::parse_scenario(j);
  const ip::ScenarioSpec& s = f.spec;
  EXPECT_EQ(s.hand.fingers.size(), 3u);
  EXPECT_EQ(s.object.shape.kind, ip::ObjectShape::Kind::box);
  EXPECT_TRUE(s.object.shape.half_extents.isApprox(Eigen::Vector3d(0.01, 0.015, 0.04)));
  EXPECT_EQ(s.object.mass, 0.07);
  const ip::HandPreset h = ip::three_finger_hand();
  EXPECT_TRUE(s.object.pose.position.isApprox(h.object_pose.position +
                                              Eigen::Vector3d(0.001, -0.002, 0.003)));
  // Offset rotation about world axes through the object centre.
  const Eigen::Matrix3d R = inhand::rotation_from_euler<double>(Eigen::Vector3d(0.1, -0.05, 0.2)) *
                            h.object_pose.rotation;
  EXPECT_LT((s.object.pose.rotation - R).norm(), 1e-12);
  EXPECT_EQ(s.plant.time_step, 5e-5);
  EXPECT_EQ(s.plant.contact.friction, 0.6);
  EXPECT_EQ(s.plant.contact.normal_stiffness, 3000);
  EXPECT_EQ(s.plant.contact.normal_damping, 8);
  EXPECT_EQ(s.plant.contact.tangential_stiffness, 2500);
  EXPECT_EQ(s.plant.contact.tangential_damping, 4);
  EXPECT_EQ(s.plant.gravity, Eigen::Vector3d(0, 0, -5));
  EXPECT_EQ(s.plant.joint_velocity_lag, 0.01);
  EXPECT_EQ(s.plant.seed, 42u);
  EXPECT_EQ(s.plant.sensing.normal_force_std, 0.01);
  EXPECT_EQ(s.plant.sensing.normal_force_bias, -0.02);
  EXPECT_EQ(s.plant.sensing.contact_point_std, 1e-4);
  EXPECT_EQ(s.plant.sensing.normal_angle_std, 0.02);
  EXPECT_EQ(s.plant.sensing.object_position_std, 2e-5);
  EXPECT_EQ(s.plant.sensing.object_rotation_std, 3e-4);
  EXPECT_EQ(s.plant.sensing.touch_threshold, 0.05);
  const auto& c = s.controller;
  EXPECT_EQ(c.control_period, 2e-3);
  EXPECT_EQ(c.max_tick, 0.02);
  EXPECT_EQ(c.max_joint_acceleration, 300);
  EXPECT_TRUE(c.keep_twist_in_reach);
  EXPECT_EQ(c.at_risk_hold, 0.2);
  EXPECT_EQ(c.outlier_gates.max_object_speed, 0.4);
  EXPECT_EQ(c.outlier_gates.max_object_angular_speed, 8);
  EXPECT_EQ(c.outlier_gates.max_force_rate, 200);
  EXPECT_EQ(c.outlier_gates.contact_stiffness, 5000);
  EXPECT_EQ(c.outlier_gates.max_rejection_time, 0.003);
  using FK = ip::FaultSpec::Kind;
  ASSERT_EQ(s.faults.size(), 5u);
  EXPECT_EQ(s.faults[0].kind, FK::tactile_dropout);
  EXPECT_EQ(s.faults[0].stage, "hold");
  EXPECT_EQ(s.faults[0].at, 0.5);
  EXPECT_EQ(s.faults[0].duration, 0.1);
  EXPECT_EQ(s.faults[0].finger, 2);
  ASSERT_EQ(f.fault_expect.size(), 5u);
  EXPECT_EQ(f.fault_expect[0].max_detection_ticks, 3);
  EXPECT_EQ(f.fault_expect[0].max_reacquire_ticks, 400);
  EXPECT_EQ(f.fault_expect[0].max_force_integral, 0.25);
  EXPECT_FALSE(f.fault_expect[1].max_detection_ticks.has_value());
  EXPECT_EQ(s.faults[1].kind, FK::force_spike);
  EXPECT_EQ(s.faults[1].magnitude, 3);
  EXPECT_EQ(s.faults[2].kind, FK::pose_outlier);
  EXPECT_EQ(s.faults[2].vector, Eigen::Vector3d(0.01, 0, 0));
  EXPECT_EQ(s.faults[2].at, ip::FaultSpec{}.at);  // library defaults
  EXPECT_EQ(s.faults[2].duration, ip::FaultSpec{}.duration);
  EXPECT_EQ(s.faults[3].kind, FK::knock);
  EXPECT_EQ(s.faults[3].vector, Eigen::Vector3d(0, 0, 2));
  EXPECT_EQ(s.faults[4].kind, FK::finger_away);
  EXPECT_EQ(s.faults[4].duration, 0.0);
  EXPECT_EQ(c.pose_feedback.position_gain, 6);
  EXPECT_EQ(c.pose_feedback.orientation_gain, 7);
  EXPECT_EQ(c.pose_feedback.max_linear_speed, 0.04);
  EXPECT_EQ(c.pose_feedback.max_angular_speed, 0.9);
  EXPECT_EQ(c.pose_feedback.position_integral_gain, 9);
  EXPECT_EQ(c.pose_feedback.orientation_integral_gain, 11);
  EXPECT_EQ(c.pose_feedback.position_integral_limit, 1e-3);
  EXPECT_EQ(c.pose_feedback.orientation_integral_limit, 0.01);
  EXPECT_EQ(c.pose_feedback.position_integral_band, 2e-4);
  EXPECT_TRUE(std::isinf(c.pose_feedback.orientation_integral_band));
  EXPECT_EQ(c.pose_feedback.astray_distance, 5e-3);
  EXPECT_TRUE(std::isinf(c.pose_feedback.astray_angle));  // null: never
  EXPECT_EQ(c.pose_feedback.astray_time, 0.02);
  EXPECT_EQ(c.servo.motion.kp, 1.1);
  EXPECT_EQ(c.servo.motion.ki, 0.5);
  EXPECT_EQ(c.servo.motion.integral_limit, 0.2);
  EXPECT_TRUE(std::isinf(c.servo.motion.output_limit));  // null: no limit
  EXPECT_EQ(c.servo.force.kp, 0.03);
  EXPECT_EQ(c.servo.force.ki, 0.25);
  EXPECT_EQ(c.servo.force.integral_limit, 3);
  EXPECT_EQ(c.servo.force.output_limit, 0.1);
  EXPECT_EQ(c.ik.damping.singular_threshold, 4e-3);
  EXPECT_EQ(c.ik.damping.max_damping, 6e-3);
  EXPECT_EQ(c.force_planner.nominal_force, 1.5);
  EXPECT_EQ(c.force_planner.min_force, 0.3);
  EXPECT_EQ(c.force_planner.max_force, 5);
  EXPECT_EQ(c.force_planner.regularisation, 2e-3);
  EXPECT_EQ(c.force_planner.filter_time, 0.03);
  EXPECT_EQ(c.grasp.approach_gain, 3);
  EXPECT_EQ(c.grasp.approach_speed, 0.02);
  EXPECT_EQ(c.grasp.creep_speed, 0.004);
  EXPECT_EQ(c.grasp.tangential_gain, 4);
  EXPECT_EQ(c.grasp.force_tolerance, 0.15);
  EXPECT_EQ(c.grasp.position_tolerance, 2e-3);
  EXPECT_EQ(c.grasp.alignment_speed, 0.05);
  EXPECT_EQ(c.grasp.alignment_tolerance, 0.1);
  EXPECT_EQ(c.grasp.settle_time, 0.2);
  EXPECT_EQ(c.grasp.slide_force_fraction, 0.5);
  EXPECT_EQ(c.grasp.gravity_tilt, 0.2);
  EXPECT_EQ(c.grasp.flat_curvature, 20);
  EXPECT_EQ(s.tolerances.drop_distance, 0.03);
  EXPECT_EQ(s.tolerances.settle_position_tolerance, 1e-3);
  EXPECT_EQ(s.tolerances.settle_orientation_tolerance, 0.02);
}

TEST(ScenarioJson, ForceLayerGravityDirectionIsAppliedAndChecked) {
  Json j = base_scenario();
  j["controller"] = ex::parse_json_text(
      R"({"force_layer": {"release_load": 3, "gravity_direction": [0, -9.81, 0]}})");
  const ex::ScenarioFile f = ex::parse_scenario(j);
  EXPECT_EQ(f.spec.controller.force_layer.release_load, 3.0);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d(0, -9.81, 0));
  j["controller"]["force_layer"]["gravity_direction"] = ex::parse_json_text("[0, 1]");
  const std::string short_msg = parse_error(j);
  EXPECT_NE(short_msg.find("controller.force_layer.gravity_direction"), std::string::npos)
      << short_msg;
  j["controller"]["force_layer"]["gravity_direction"] = ex::parse_json_text("[0, 0, 1e9]");
  const std::string range_msg = parse_error(j);
  EXPECT_NE(range_msg.find("controller.force_layer.gravity_direction"), std::string::npos)
      << range_msg;
  j["controller"]["force_layer"]["gravity_direction"] = "world";
  const std::string word_msg = parse_error(j);
  EXPECT_NE(word_msg.find("controller.force_layer.gravity_direction: must be one of plant"),
            std::string::npos)
      << word_msg;
}

// Left out or "plant", the controller is told the plant's gravity (the analytic plant's
// here; MuJoCo's model's through the adapter); a vector, [0, 0, 0] included, is kept.
TEST(ScenarioJson, GravityDirectionDefaultsToThePlants) {
  Json j = base_scenario();
  j["plant"] = {{"gravity", {3.0, 0.0, -4.0}}};
  ex::ScenarioFile f = ex::parse_scenario(j);
  EXPECT_TRUE(f.gravity_from_plant);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d(3, 0, -4));
  j["controller"] = {{"force_layer", {{"gravity_direction", "plant"}}}};
  f = ex::parse_scenario(j);
  EXPECT_TRUE(f.gravity_from_plant);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d(3, 0, -4));
  j["controller"]["force_layer"]["gravity_direction"] = {0.0, 0.0, 0.0};
  f = ex::parse_scenario(j);
  EXPECT_FALSE(f.gravity_from_plant);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d::Zero());
  j["controller"]["force_layer"]["gravity_direction"] = {0.0, 1.0, 0.0};
  f = ex::parse_scenario(j);
  EXPECT_FALSE(f.gravity_from_plant);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d(0, 1, 0));

  Json m = base_scenario();
  m["hand"] = "three_finger";
  m.erase("object");
  m["plant"] = {{"engine", "mujoco"}};
  f = ex::parse_scenario(m);
  EXPECT_TRUE(f.mujoco.gravity_from_model);
  EXPECT_EQ(f.spec.controller.force_layer.gravity_direction, Eigen::Vector3d::Zero());
  m["controller"] = {{"force_layer", {{"gravity_direction", {0.0, 0.0, 0.0}}}}};
  f = ex::parse_scenario(m);
  EXPECT_FALSE(f.gravity_from_plant);
  EXPECT_FALSE(f.mujoco.gravity_from_model);
}

TEST(ScenarioJson, SegmentsBecomeWorldFrameDisplacements) {
  Json j = base_scenario();
  j["stages"][2]["segments"] = ex::parse_json_text(R"([
    {"kind": "hold", "duration": 0.5},
    {"kind": "move", "axis": [0, 3, 4], "amount": 0.01, "duration": 1.0},
    {"kind": "rotate", "axis": [0, 0, -2], "amount": 0.3, "duration": 2.0},
    {"kind": "reciprocate", "motion": "rotate", "axis": [1, 0, 0], "amount": -0.2, "duration": 4.0, "cycles": 2}
  ])");
  const ex::ScenarioFile f = ex::parse_scenario(j);
  const auto& segs = f.spec.stages[2].segments;
  ASSERT_EQ(segs.size(), 4u);
  EXPECT_EQ(segs[0].kind, inhand::SegmentKind::hold);
  EXPECT_EQ(segs[0].duration, 0.5);
  EXPECT_TRUE(segs[0].displacement.isZero());
  EXPECT_EQ(segs[1].kind, inhand::SegmentKind::move);
  EXPECT_LT((segs[1].displacement.head<3>() - Eigen::Vector3d(0, 0.006, 0.008)).norm(), 1e-15);
  EXPECT_TRUE(segs[1].displacement.tail<3>().isZero());
  EXPECT_EQ(segs[2].kind, inhand::SegmentKind::rotate);
  EXPECT_LT((segs[2].displacement.tail<3>() - Eigen::Vector3d(0, 0, -0.3)).norm(), 1e-15);
  EXPECT_EQ(segs[3].kind, inhand::SegmentKind::reciprocate);
  EXPECT_EQ(segs[3].cycles, 2);
  EXPECT_EQ(segs[3].duration, 4.0);
  EXPECT_LT((segs[3].displacement.tail<3>() - Eigen::Vector3d(-0.2, 0, 0)).norm(), 1e-15);
}

TEST(ScenarioJson, CommentsAreAllowed) {
  const std::string text = R"({
    // a line comment
    "name": "c", /* a block comment */
    "object": {"shape": "sphere", "radius": 0.03},
    "stages": [{"kind": "grasp"}]
  })";
  EXPECT_EQ(text_error(text), "");
  const ex::ScenarioFile f = ex::parse_scenario(ex::parse_json_text(text));
  EXPECT_EQ(f.spec.stages[0].name, "stage0");  // unnamed stages are numbered
  EXPECT_EQ(f.spec.object.shape.radius, 0.03);
}

// The shipped paper files are exactly the experiments paper_scenario() builds.
TEST(ScenarioJson, PaperFilesMatchPaperScenario) {
  int checked = 0;
  for (const auto object : {ip::PaperObject::cylinder, ip::PaperObject::slender_box}) {
    for (const auto task : {ip::PaperTask::translate, ip::PaperTask::rotate}) {
      for (int axis = 0; axis < 3; ++axis) {
        const ip::ScenarioSpec want = ip::paper_scenario(object, task, axis);
        SCOPED_TRACE(want.name);
        const ex::ScenarioFile f =
            ex::load_scenario(kScenarioDir + "/paper/" + want.name + ".json");
        const ip::ScenarioSpec& got = f.spec;
        EXPECT_EQ(got.name, want.name);
        EXPECT_EQ(got.hand.name, want.hand.name);
        EXPECT_EQ(got.object.shape.kind, want.object.shape.kind);
        EXPECT_NEAR(got.object.shape.radius, want.object.shape.radius, 1e-15);
        EXPECT_NEAR(got.object.shape.half_length, want.object.shape.half_length, 1e-15);
        EXPECT_LT((got.object.shape.half_extents - want.object.shape.half_extents).norm(), 1e-15);
        EXPECT_EQ(got.object.mass, want.object.mass);
        EXPECT_LT((got.object.pose.position - want.object.pose.position).norm(), 1e-15);
        EXPECT_LT((got.object.pose.rotation - want.object.pose.rotation).norm(), 1e-15);
        ASSERT_EQ(got.stages.size(), want.stages.size());
        for (std::size_t i = 0; i < want.stages.size(); ++i) {
          const ip::StageSpec& a = got.stages[i];
          const ip::StageSpec& b = want.stages[i];
          EXPECT_EQ(a.name, b.name);
          EXPECT_EQ(a.kind, b.kind);
          EXPECT_EQ(a.release, b.release);
          if (b.kind == ip::StageKind::manipulate) {
            EXPECT_EQ(a.settle, b.settle);
          } else {
            EXPECT_EQ(a.duration, b.duration);
          }
          ASSERT_EQ(a.segments.size(), b.segments.size());
          for (std::size_t k = 0; k < b.segments.size(); ++k) {
            EXPECT_EQ(a.segments[k].kind, b.segments[k].kind);
            EXPECT_EQ(a.segments[k].duration, b.segments[k].duration);
            EXPECT_EQ(a.segments[k].cycles, b.segments[k].cycles);
            EXPECT_LT((a.segments[k].displacement - b.segments[k].displacement).norm(), 1e-15);
          }
        }
        // Library defaults for everything the files leave out.
        EXPECT_EQ(got.plant.contact.friction, want.plant.contact.friction);
        EXPECT_EQ(got.plant.time_step, want.plant.time_step);
        EXPECT_EQ(got.controller.control_period, want.controller.control_period);
        EXPECT_EQ(got.tolerances.settle_position_tolerance,
                  want.tolerances.settle_position_tolerance);
        // The bounds the reproduction must meet.
        const auto* manip = &f.expect.stages[0];
        for (const auto& e : f.expect.stages)
          if (e.stage == "manipulate") manip = &e;
        ASSERT_EQ(manip->stage, "manipulate");
        EXPECT_EQ(manip->max_relative_force_error.value_or(-1), 0.5);
        if (task == ip::PaperTask::translate) {
          EXPECT_EQ(manip->max_rms_position_error.value_or(-1), 5e-4);
          EXPECT_EQ(manip->max_final_position_error.value_or(-1), 2e-4);
        } else {
          EXPECT_EQ(manip->max_rms_orientation_error.value_or(-1), 0.01);
          EXPECT_EQ(manip->max_final_orientation_error.value_or(-1), 0.005);
        }
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 12);
}

// README.md's scenario-file example parses, every value it shows is the library
// default, and it is the paper's cylinder translated along X.
TEST(ScenarioJson, ReadmeExampleShowsTheDefaults) {
  const std::string readme = read_text(INHAND_README);
  const std::string begin = "<!-- scenario-example:begin -->",
                    end = "<!-- scenario-example:end -->";
  const std::size_t b = readme.find(begin), e = readme.find(end);
  ASSERT_NE(b, std::string::npos);
  ASSERT_NE(e, std::string::npos);
  std::string block = readme.substr(b + begin.size(), e - b - begin.size());
  const std::size_t open = block.find("```jsonc\n"), close = block.rfind("```");
  ASSERT_NE(open, std::string::npos);
  ASSERT_NE(close, std::string::npos);
  block = block.substr(open + 9, close - open - 9);
  const ex::ScenarioFile f = ex::parse_scenario(ex::parse_json_text(block));
  const ip::ScenarioSpec want =
      ip::paper_scenario(ip::PaperObject::cylinder, ip::PaperTask::translate, 0);
  const ip::ScenarioSpec& got = f.spec;
  EXPECT_EQ(got.name, want.name);
  EXPECT_EQ(got.object.shape.radius, want.object.shape.radius);
  EXPECT_EQ(got.object.shape.half_length, want.object.shape.half_length);
  EXPECT_EQ(got.object.mass, want.object.mass);
  EXPECT_LT((got.object.pose.rotation - want.object.pose.rotation).norm(), 1e-15);
  ASSERT_EQ(got.stages.size(), 3u);
  EXPECT_LT((got.stages[2].segments.at(0).displacement - want.stages[2].segments.at(0).displacement)
                .norm(),
            1e-15);
  // Plant defaults.
  EXPECT_EQ(f.engine, "analytic");
  const ip::PlantParams d = ip::default_plant_params();
  const ip::PlantParams& p = got.plant;
  EXPECT_EQ(p.time_step, d.time_step);
  EXPECT_EQ(p.contact.friction, d.contact.friction);
  EXPECT_EQ(p.contact.normal_stiffness, d.contact.normal_stiffness);
  EXPECT_EQ(p.contact.normal_damping, d.contact.normal_damping);
  EXPECT_EQ(p.contact.tangential_stiffness, d.contact.tangential_stiffness);
  EXPECT_EQ(p.contact.tangential_damping, d.contact.tangential_damping);
  EXPECT_EQ(p.gravity, d.gravity);
  EXPECT_EQ(p.joint_velocity_lag, d.joint_velocity_lag);
  EXPECT_EQ(p.command_delay, d.command_delay);
  EXPECT_EQ(p.sensing.normal_force_gain_error, d.sensing.normal_force_gain_error);
  EXPECT_EQ(p.sensing.normal_force_relative_std, d.sensing.normal_force_relative_std);
  EXPECT_EQ(p.sensing.normal_force_std, d.sensing.normal_force_std);
  EXPECT_EQ(p.sensing.normal_force_bias, d.sensing.normal_force_bias);
  EXPECT_EQ(p.sensing.contact_point_std, d.sensing.contact_point_std);
  EXPECT_EQ(p.sensing.normal_angle_std, d.sensing.normal_angle_std);
  EXPECT_EQ(p.sensing.object_position_std, d.sensing.object_position_std);
  EXPECT_EQ(p.sensing.object_rotation_std, d.sensing.object_rotation_std);
  EXPECT_EQ(p.sensing.touch_threshold, d.sensing.touch_threshold);
  EXPECT_EQ(p.seed, d.seed);
  // Controller defaults.
  const ip::HandController::Config dc{};
  const ip::HandController::Config& c = got.controller;
  EXPECT_EQ(c.control_period, dc.control_period);
  EXPECT_EQ(c.max_tick, dc.max_tick);
  EXPECT_EQ(c.max_joint_acceleration, dc.max_joint_acceleration);
  EXPECT_EQ(c.keep_twist_in_reach, dc.keep_twist_in_reach);
  EXPECT_EQ(c.at_risk_hold, dc.at_risk_hold);
  {
    const inhand::ForceLayerParams<double>& fa = c.force_layer;
    const inhand::ForceLayerParams<double>& fb = dc.force_layer;
    const double got_fl[] = {
        fa.bandwidth,        fa.integral_corner, fa.min_stiffness,   fa.max_stiffness,
        fa.stiffness_window, fa.min_excitation,  fa.min_fit,         fa.max_integral_velocity,
        fa.slip_distance,    fa.grip_rise_rate,  fa.friction_margin, fa.grip_decay_time,
        fa.release_grip,     fa.rigid_tolerance, fa.contact_damping, fa.capacity_time,
        fa.servo_stiffness,  fa.servo_damping,   fa.release_load,    fa.capacity_slide_ratio};
    const double want_fl[] = {
        fb.bandwidth,        fb.integral_corner, fb.min_stiffness,   fb.max_stiffness,
        fb.stiffness_window, fb.min_excitation,  fb.min_fit,         fb.max_integral_velocity,
        fb.slip_distance,    fb.grip_rise_rate,  fb.friction_margin, fb.grip_decay_time,
        fb.release_grip,     fb.rigid_tolerance, fb.contact_damping, fb.capacity_time,
        fb.servo_stiffness,  fb.servo_damping,   fb.release_load,    fb.capacity_slide_ratio};
    for (std::size_t k = 0; k < 20; ++k)
      EXPECT_EQ(got_fl[k], want_fl[k]) << "force_layer field " << k;
    EXPECT_EQ(fa.hold_release_grip, fb.hold_release_grip);
    EXPECT_TRUE(f.gravity_from_plant);  // "plant": the plant's gravity, told
    EXPECT_EQ(fa.gravity_direction, got.plant.gravity);
  }
  EXPECT_EQ(c.outlier_gates.max_object_speed, dc.outlier_gates.max_object_speed);
  EXPECT_EQ(c.outlier_gates.max_object_angular_speed, dc.outlier_gates.max_object_angular_speed);
  EXPECT_EQ(c.outlier_gates.max_force_rate, dc.outlier_gates.max_force_rate);
  EXPECT_EQ(c.outlier_gates.contact_stiffness, dc.outlier_gates.contact_stiffness);
  EXPECT_EQ(c.outlier_gates.max_rejection_time, dc.outlier_gates.max_rejection_time);
  EXPECT_TRUE(got.faults.empty());
  EXPECT_EQ(c.pose_feedback.position_gain, dc.pose_feedback.position_gain);
  EXPECT_EQ(c.pose_feedback.orientation_gain, dc.pose_feedback.orientation_gain);
  EXPECT_EQ(c.pose_feedback.position_integral_gain, dc.pose_feedback.position_integral_gain);
  EXPECT_EQ(c.pose_feedback.orientation_integral_gain, dc.pose_feedback.orientation_integral_gain);
  EXPECT_EQ(c.pose_feedback.position_integral_limit, dc.pose_feedback.position_integral_limit);
  EXPECT_EQ(c.pose_feedback.orientation_integral_limit,
            dc.pose_feedback.orientation_integral_limit);
  EXPECT_EQ(c.pose_feedback.position_integral_band, dc.pose_feedback.position_integral_band);
  EXPECT_EQ(c.pose_feedback.orientation_integral_band, dc.pose_feedback.orientation_integral_band);
  EXPECT_EQ(c.pose_feedback.astray_distance, dc.pose_feedback.astray_distance);
  EXPECT_EQ(c.pose_feedback.astray_angle, dc.pose_feedback.astray_angle);
  EXPECT_EQ(c.pose_feedback.astray_time, dc.pose_feedback.astray_time);
  EXPECT_EQ(c.pose_feedback.max_linear_speed, dc.pose_feedback.max_linear_speed);
  EXPECT_EQ(c.pose_feedback.max_angular_speed, dc.pose_feedback.max_angular_speed);
  for (const auto* pair : {&c.servo.motion, &c.servo.force}) {
    const auto& def = pair == &c.servo.motion ? dc.servo.motion : dc.servo.force;
    EXPECT_EQ(pair->kp, def.kp);
    EXPECT_EQ(pair->ki, def.ki);
    EXPECT_EQ(pair->integral_limit, def.integral_limit);
    EXPECT_EQ(pair->output_limit, def.output_limit);
  }
  EXPECT_EQ(c.ik.damping.singular_threshold, dc.ik.damping.singular_threshold);
  EXPECT_EQ(c.ik.damping.max_damping, dc.ik.damping.max_damping);
  EXPECT_EQ(c.force_planner.nominal_force, dc.force_planner.nominal_force);
  EXPECT_EQ(c.force_planner.min_force, dc.force_planner.min_force);
  EXPECT_EQ(c.force_planner.max_force, dc.force_planner.max_force);
  EXPECT_EQ(c.force_planner.regularisation, dc.force_planner.regularisation);
  EXPECT_EQ(c.force_planner.filter_time, dc.force_planner.filter_time);
  EXPECT_EQ(c.grasp.approach_gain, dc.grasp.approach_gain);
  EXPECT_EQ(c.grasp.approach_speed, dc.grasp.approach_speed);
  EXPECT_EQ(c.grasp.creep_speed, dc.grasp.creep_speed);
  EXPECT_EQ(c.grasp.tangential_gain, dc.grasp.tangential_gain);
  EXPECT_EQ(c.grasp.force_tolerance, dc.grasp.force_tolerance);
  EXPECT_EQ(c.grasp.position_tolerance, dc.grasp.position_tolerance);
  EXPECT_EQ(c.grasp.alignment_speed, dc.grasp.alignment_speed);
  EXPECT_EQ(c.grasp.alignment_tolerance, dc.grasp.alignment_tolerance);
  EXPECT_EQ(c.grasp.settle_time, dc.grasp.settle_time);
  EXPECT_EQ(c.grasp.slide_force_fraction, dc.grasp.slide_force_fraction);
  EXPECT_EQ(c.grasp.gravity_tilt, dc.grasp.gravity_tilt);
  EXPECT_EQ(c.grasp.flat_curvature, dc.grasp.flat_curvature);
  const ip::MetricsTolerances dt{};
  EXPECT_EQ(got.tolerances.drop_distance, dt.drop_distance);
  EXPECT_EQ(got.tolerances.settle_position_tolerance, dt.settle_position_tolerance);
  EXPECT_EQ(got.tolerances.settle_orientation_tolerance, dt.settle_orientation_tolerance);
  EXPECT_EQ(got.stages[0].duration, want.stages[0].duration);
  EXPECT_EQ(got.stages[1].duration, want.stages[1].duration);
  EXPECT_EQ(got.stages[2].settle, want.stages[2].settle);
}

// ---------------------------------------------------------------------------
// Rejections: each names the offending key

struct BadCase {
  const char* what;
  std::function<void(Json&)> mutate;
  std::vector<const char*> message_contains;
};

TEST(ScenarioJson, RejectsBadValuesNamingTheKey) {
  const std::vector<BadCase> cases = {
      {"unknown top-level key", [](Json& j) { j["stagez"] = 1; }, {"stagez", "unknown key"}},
      {"unknown nested key",
       [](Json& j) { j["object"]["masss"] = 0.05; },
       {"object.masss", "unknown key"}},
      {"key of another shape",
       [](Json& j) {
         j["object"]["size"] = {0.1, 0.1, 0.1};
       },
       {"object.size", "unknown key"}},
      {"unknown plant key",
       [](Json& j) { j["plant"]["frictoin"] = 0.5; },
       {"plant.frictoin", "unknown key"}},
      {"the tick count the hold time replaced",
       [](Json& j) { j["controller"]["outlier_gates"]["max_consecutive_rejections"] = 5; },
       {"controller.outlier_gates.max_consecutive_rejections", "replaced by max_rejection_time"}},
      {"negative hold time",
       [](Json& j) { j["controller"]["outlier_gates"]["max_rejection_time"] = -0.001; },
       {"controller.outlier_gates.max_rejection_time", "must be"}},
      {"wrong type: string for number",
       [](Json& j) { j["object"]["mass"] = "0.05"; },
       {"object.mass", "must be a number", "string"}},
      {"wrong type: bool for number",
       [](Json& j) { j["plant"]["time_step"] = true; },
       {"plant.time_step", "must be a number"}},
      {"wrong type: object for array",
       [](Json& j) { j["stages"] = Json::object(); },
       {"stages", "must be an array"}},
      {"wrong type: number for bool",
       [](Json& j) { j["stages"][1]["release"] = 1; },
       {"stages[1].release", "true or false"}},
      {"wrong type: number for string",
       [](Json& j) { j["name"] = 3; },
       {"name", "must be a string"}},
      {"negative mass",
       [](Json& j) { j["object"]["mass"] = -0.05; },
       {"object.mass", "(0, 100]", "-0.05"}},
      {"zero radius", [](Json& j) { j["object"]["radius"] = 0; }, {"object.radius"}},
      {"NaN as a string",
       [](Json& j) { j["plant"]["friction"] = "NaN"; },
       {"plant.friction", "must be a number"}},
      {"inf as a string",
       [](Json& j) { j["controller"]["control_period"] = "inf"; },
       {"controller.control_period", "must be a number"}},
      {"Infinity as a string",
       [](Json& j) {
         j["plant"]["gravity"] = {0, 0, "-Infinity"};
       },
       {"plant.gravity[2]", "must be a number"}},
      {"huge mass", [](Json& j) { j["object"]["mass"] = 1e300; }, {"object.mass", "1e+300"}},
      {"huge duration", [](Json& j) { j["stages"][1]["duration"] = 1e30; }, {"stages[1].duration"}},
      {"huge seed", [](Json& j) { j["plant"]["seed"] = 1e30; }, {"plant.seed", "integer"}},
      {"fractional cycles",
       [](Json& j) { j["stages"][2]["segments"][0]["cycles"] = 1.5; },
       {"stages[2].segments[0].cycles", "integer"}},
      {"negative segment duration",
       [](Json& j) { j["stages"][2]["segments"][0]["duration"] = -1; },
       {"stages[2].segments[0].duration"}},
      {"zero axis",
       [](Json& j) {
         j["stages"][2]["segments"][0]["axis"] = {0, 0, 0};
       },
       {"stages[2].segments[0].axis", "non-zero"}},
      {"short axis",
       [](Json& j) {
         j["stages"][2]["segments"][0]["axis"] = {1, 0};
       },
       {"stages[2].segments[0].axis", "array of 3 numbers"}},
      {"reciprocate without motion",
       [](Json& j) { j["stages"][2]["segments"][0].erase("motion"); },
       {"stages[2].segments[0].motion", "missing"}},
      {"unknown segment kind",
       [](Json& j) { j["stages"][2]["segments"][0]["kind"] = "spin"; },
       {"stages[2].segments[0].kind", "spin"}},
      {"unknown shape", [](Json& j) { j["object"]["shape"] = "cone"; }, {"object.shape", "cone"}},
      {"unknown hand", [](Json& j) { j["hand"] = "shadow"; }, {"hand", "shadow_like"}},
      {"missing object", [](Json& j) { j.erase("object"); }, {"object", "missing"}},
      {"missing stages", [](Json& j) { j.erase("stages"); }, {"stages", "missing"}},
      {"no stages", [](Json& j) { j["stages"] = Json::array(); }, {"stages", "at least one"}},
      {"first stage not a grasp",
       [](Json& j) { j["stages"].erase(0); },
       {"stages[0].kind", "grasp"}},
      {"duplicate stage name",
       [](Json& j) { j["stages"][2]["name"] = "hold"; },
       {"stages[2].name", "duplicate"}},
      {"reserved stage name",
       [](Json& j) { j["stages"][1]["name"] = "all"; },
       {"stages[1].name", "reserved"}},
      {"key meaningless for the stage kind",
       [](Json& j) { j["stages"][1]["settle"] = 1.0; },
       {"stages[1].settle", "unknown key"}},
      {"release on a grasp",
       [](Json& j) { j["stages"][0]["release"] = true; },
       {"stages[0].release", "unknown key"}},
      {"expect names no stage",
       [](Json& j) { j["expect"]["hodl"] = Json::object(); },
       {"expect.hodl", "no stage"}},
      {"unknown expectation",
       [](Json& j) { j["expect"]["hold"]["max_rms_error"] = 1; },
       {"expect.hold.max_rms_error", "unknown key"}},
      {"contradictory expectation",
       [](Json& j) {
         j["expect"]["hold"] = {{"must_drop", true}, {"must_not_drop", true}};
       },
       {"expect.hold", "must_drop"}},
      {"negative expectation",
       [](Json& j) { j["expect"]["hold"]["max_settle_time"] = -1; },
       {"expect.hold.max_settle_time"}},
      {"negative warning lead",
       [](Json& j) { j["expect"]["hold"]["min_warning_lead"] = -0.01; },
       {"expect.hold.min_warning_lead"}},
      {"time step too large for the stiffness",
       [](Json& j) {
         j["plant"]["time_step"] = 1e-3;
         j["plant"]["normal_stiffness"] = 1e6;
       },
       {"plant.time_step", "too large"}},
      {"creep faster than approach",
       [](Json& j) {
         j["controller"]["grasp"] = {{"creep_speed", 0.05}};
       },
       {"controller.grasp.creep_speed"}},
      {"nominal force above max",
       [](Json& j) {
         j["controller"]["force_planner"] = {{"nominal_force", 7.0}};
       },
       {"controller.force_planner.nominal_force"}},
      {"control period below the plant step",
       [](Json& j) { j["controller"]["control_period"] = 5e-5; },
       {"controller.control_period", "plant.time_step"}},
      {"stage shorter than a tick",
       [](Json& j) { j["stages"][1]["duration"] = 1e-4; },
       {"stages[1]", "control period"}},
      {"document not an object", [](Json& j) { j = Json::array(); }, {"must be an object"}},
      {"fault in no stage",
       [](Json& j) {
         j["faults"] = {{{"kind", "knock"}, {"stage", "rotate"}}};
       },
       {"faults[0].stage", "rotate"}},
      {"fault finger out of range",
       [](Json& j) {
         j["faults"] = {{{"kind", "tactile_dropout"}, {"finger", 4}}};
       },
       {"faults[0].finger", "[0, 3]"}},
      {"fault key of another kind",
       [](Json& j) {
         j["faults"] = {{{"kind", "tactile_dropout"}, {"magnitude", 1.0}}};
       },
       {"faults[0].magnitude", "unknown key"}},
      {"unknown fault expectation",
       [](Json& j) {
         j["faults"] = {{{"kind", "knock"}, {"expect", {{"max_detection_time", 1}}}}};
       },
       {"faults[0].expect.max_detection_time", "unknown key"}},
      {"negative fault detection bound",
       [](Json& j) {
         j["faults"] = {{{"kind", "knock"}, {"expect", {{"max_detection_ticks", -1}}}}};
       },
       {"faults[0].expect.max_detection_ticks"}},
      {"unknown fault kind",
       [](Json& j) {
         j["faults"] = {{{"kind", "earthquake"}}};
       },
       {"faults[0].kind"}},
      {"negative fault time",
       [](Json& j) {
         j["faults"] = {{{"kind", "knock"}, {"at", -1}}};
       },
       {"faults[0].at"}},
      {"string gate",
       [](Json& j) {
         j["controller"]["outlier_gates"] = {{"max_force_rate", "inf"}};
       },
       {"controller.outlier_gates.max_force_rate", "must be a number"}},
  };
  for (const BadCase& c : cases) {
    SCOPED_TRACE(c.what);
    Json j = base_scenario();
    c.mutate(j);
    const std::string msg = parse_error(j);
    ASSERT_FALSE(msg.empty()) << "accepted";
    for (const char* s : c.message_contains)
      EXPECT_NE(msg.find(s), std::string::npos) << "message: " << msg;
  }
}

// The fault bounds of a scenario file are checked against what the run reported:
// late, never and within the bound.
TEST(ScenarioJson, FaultExpectationsAreChecked) {
  ex::FaultExpectation e;
  e.max_detection_ticks = 2;
  e.max_reacquire_ticks = 100;
  e.max_force_integral = 0.5;
  ip::FaultReport r;
  r.kind = ip::FaultSpec::Kind::tactile_dropout;
  r.detection_ticks = 2;
  r.reacquire_ticks = 100;
  r.max_force_integral = 0.5;
  EXPECT_TRUE(ex::check_fault_expectations({e}, {r}).empty());
  ip::FaultReport late = r;
  late.detection_ticks = 3;
  std::vector<std::string> v = ex::check_fault_expectations({e}, {late});
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NE(v[0].find("detection after 3 ticks exceeds 2"), std::string::npos) << v[0];
  ip::FaultReport never = r;
  never.detection_ticks = -1;
  never.reacquire_ticks = -1;
  never.max_force_integral = 0.51;
  v = ex::check_fault_expectations({e}, {never});
  ASSERT_EQ(v.size(), 3u);
  EXPECT_NE(v[0].find("detection never happened"), std::string::npos) << v[0];
  EXPECT_NE(v[1].find("reacquisition never happened"), std::string::npos) << v[1];
  EXPECT_NE(v[2].find("force integral"), std::string::npos) << v[2];
  // No bounds: nothing to violate.
  EXPECT_TRUE(ex::check_fault_expectations({ex::FaultExpectation{}}, {never}).empty());
}

TEST(ScenarioJson, RejectsMalformedText) {
  const std::string good = base_scenario().dump(2);
  // Syntax error: the message names where parsing stopped (between two keys of
  // "object": the object) and the line.
  std::string msg = text_error(
      R"({"name": "x", "object": {"shape": "cylinder", "radius": 0.02,, "length": 0.1}})");
  EXPECT_EQ(msg.rfind("object: malformed JSON", 0), 0u) << msg;
  EXPECT_NE(msg.find("line 1"), std::string::npos) << msg;
  // Inside a value the key is named.
  msg = text_error(R"({"name": "x", "object": {"shape": "cylinder", "radius": .02}})");
  EXPECT_EQ(msg.rfind("object.radius: malformed JSON", 0), 0u) << msg;
  msg = text_error(R"({"name": "x", "stages": [{"kind": "grasp"}, {"kind": hold}]})");
  EXPECT_EQ(msg.rfind("stages[1].kind: malformed JSON", 0), 0u) << msg;
  // NaN and Infinity literals are not JSON.
  msg = text_error(R"({"name": "x", "plant": {"friction": NaN}})");
  EXPECT_NE(msg.find("plant.friction"), std::string::npos) << msg;
  msg = text_error(R"({"name": "x", "plant": {"gravity": [0, 0, -Infinity]}})");
  EXPECT_NE(msg.find("plant.gravity[2]"), std::string::npos) << msg;
  // A number too large for a double.
  msg = text_error(R"({"name": "x", "object": {"mass": 1e400}})");
  EXPECT_NE(msg.find("object.mass"), std::string::npos) << msg;
  EXPECT_NE(msg.find("overflow"), std::string::npos) << msg;
  // Duplicate keys would silently drop one value.
  msg = text_error(R"({"name": "x", "object": {"mass": 0.05, "mass": 0.06}})");
  EXPECT_NE(msg.find("object.mass"), std::string::npos) << msg;
  EXPECT_NE(msg.find("duplicate"), std::string::npos) << msg;
  // Empty input and trailing garbage.
  EXPECT_NE(text_error("").find("malformed JSON"), std::string::npos);
  EXPECT_NE(text_error(good + "x").find("malformed JSON"), std::string::npos);
}

// Every truncation of a valid file is rejected with a JsonError (never accepted,
// never another exception); seeded sweep over cut positions.
TEST(ScenarioJson, RejectsEveryTruncation) {
  const std::string text = read_text(kScenarioDir + "/paper/cylinder_rotate_x.json");
  ASSERT_GT(text.size(), 200u);
  // Cut positions: all of the first 64 bytes, then a seeded sample.
  std::vector<std::size_t> cuts;
  for (std::size_t i = 0; i < 64; ++i) cuts.push_back(i);
  auto rng = inhand_test::make_rng(20240611);
  std::uniform_int_distribution<std::size_t> pos(0, text.size() - 3);  // keeps the last "}\n" cut
  for (int i = 0; i < inhand_test::scaled(200); ++i) cuts.push_back(pos(rng));
  for (std::size_t cut : cuts) {
    const std::string t = text.substr(0, cut);
    try {
      ex::parse_scenario(ex::parse_json_text(t));
      ADD_FAILURE() << "truncation at " << cut << " accepted";
    } catch (const ex::JsonError& e) {
      EXPECT_NE(std::string(e.what()).find("malformed JSON"), std::string::npos)
          << cut << ": " << e.what();
    }
  }
}

// Random damage to valid values: a JsonError naming the damaged key, or (when the
// damage happens to be valid) a spec that the plant and controller accept.
TEST(ScenarioJson, RandomDamageIsRejectedOrValid) {
  const Json good = ex::load_json_file(kScenarioDir + "/examples/three_finger_cylinder_noisy.json");
  // Collect the paths of all leaves (numbers, strings, booleans).
  std::vector<Json::json_pointer> leaves;
  std::function<void(const Json&, const Json::json_pointer&)> walk =
      [&](const Json& j, const Json::json_pointer& p) {
        if (j.is_object()) {
          for (auto it = j.begin(); it != j.end(); ++it) walk(*it, p / it.key());
        } else if (j.is_array()) {
          for (std::size_t i = 0; i < j.size(); ++i) walk(j[i], p / i);
        } else {
          leaves.push_back(p);
        }
      };
  walk(good, Json::json_pointer());
  ASSERT_GT(leaves.size(), 30u);
  const std::vector<Json> damage = {"NaN",  "inf",  -1.0,    0.0,           1e300,
                                    -1e300, 1e-300, nullptr, Json::array(), Json::object(),
                                    true,   3,      "",      2.5,           -0.5};
  auto rng = inhand_test::make_rng(77);
  int rejected = 0, accepted = 0;
  for (int i = 0; i < inhand_test::scaled(400); ++i) {
    const Json::json_pointer& p =
        leaves[std::uniform_int_distribution<std::size_t>(0, leaves.size() - 1)(rng)];
    const Json& v = damage[std::uniform_int_distribution<std::size_t>(0, damage.size() - 1)(rng)];
    Json j = good;
    j[p] = v;
    try {
      const ex::ScenarioFile f = ex::parse_scenario(j);
      ++accepted;
      EXPECT_TRUE(ip::HandPlant::validate(f.spec.hand.fingers, f.spec.object, f.spec.plant).ok())
          << p.to_string();
    } catch (const ex::JsonError& e) {
      ++rejected;
      // The message starts with the path of the damaged value, of an enclosing value
      // (e.g. the whole axis array), or of a sibling in the same object (a cross-field
      // check there); or it is one of the document-wide cross-field checks (a renamed
      // stage leaves its "expect" entry without a stage).
      std::string leaf, parent;
      for (std::size_t k = 0; k < p.to_string().size();) {
        const std::size_t next = p.to_string().find('/', k + 1);
        const std::string token = p.to_string().substr(
            k + 1, next == std::string::npos ? std::string::npos : next - k - 1);
        parent = leaf;
        if (!token.empty() && std::isdigit(static_cast<unsigned char>(token[0])))
          leaf += "[" + token + "]";
        else
          leaf += (leaf.empty() ? "" : ".") + token;
        if (next == std::string::npos) break;
        k = next;
      }
      const std::string msg = e.what();
      const std::string where = msg.substr(0, msg.find(": "));
      const bool ok = leaf.rfind(where, 0) == 0 ||
                      (!parent.empty() && where.rfind(parent, 0) == 0) ||
                      where == "plant.time_step" || where == "controller.control_period" ||
                      (where.rfind("expect.", 0) == 0 && leaf.size() > 5 &&
                       leaf.substr(leaf.size() - 5) == ".name");
      EXPECT_TRUE(ok) << leaf << " = " << v.dump() << ": " << msg;
    }
  }
  inhand_test::record("rejected", rejected);
  inhand_test::record("accepted", accepted);
  EXPECT_GT(rejected, accepted);  // most damage is invalid
}

TEST(ScenarioJson, LoadScenarioPrefixesTheFileName) {
  try {
    ex::load_scenario("/nonexistent/scenario.json");
    FAIL() << "no error";
  } catch (const ex::JsonError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/scenario.json"), std::string::npos);
  }
}

void expect_contains(const std::string& message, const std::string& part) {
  EXPECT_NE(message.find(part), std::string::npos) << "message: " << message;
}

// plant.engine "mujoco": the MuJoCo settings are read with their defaults (those of
// examples/mujoco's MujocoSetup, held equal by tests/mujoco/mujoco_scenario_file.cpp), the
// object is the model's (its mass alone may be given), the hand is the three-finger one,
// and the analytic plant's keys are refused there.
TEST(ScenarioJson, MujocoEngineSettings) {
  Json j = base_scenario();
  j["hand"] = "three_finger";
  j.erase("object");
  j["plant"] = {{"engine", "mujoco"}};
  ex::ScenarioFile f = ex::parse_scenario(j);
  EXPECT_EQ(f.engine, "mujoco");
  EXPECT_EQ(f.mujoco.model, "three_finger_cylinder.xml");
  EXPECT_EQ(f.mujoco.position_gain, 30.0);
  EXPECT_EQ(f.mujoco.friction, 0.0);
  EXPECT_EQ(f.mujoco.torsional_friction, 0.0);
  EXPECT_EQ(f.mujoco.touch_threshold, 0.02);
  EXPECT_EQ(f.mujoco.object_mass, 0.0);
  EXPECT_EQ(f.spec.object.pose.position, f.spec.hand.object_pose.position);

  j["plant"] = {{"engine", "mujoco"}, {"model", "/tmp/other.xml"},   {"position_gain", 50.0},
                {"friction", 0.5},    {"torsional_friction", 0.002}, {"touch_threshold", 0.05}};
  j["object"] = {{"mass", 0.2}};
  f = ex::parse_scenario(j);
  EXPECT_EQ(f.mujoco.model, "/tmp/other.xml");
  EXPECT_EQ(f.mujoco.position_gain, 50.0);
  EXPECT_EQ(f.mujoco.friction, 0.5);
  EXPECT_EQ(f.mujoco.torsional_friction, 0.002);
  EXPECT_EQ(f.mujoco.touch_threshold, 0.05);
  EXPECT_EQ(f.mujoco.object_mass, 0.2);

  EXPECT_EQ(ex::parse_scenario(base_scenario()).engine, "analytic");

  auto error_with = [](const std::function<void(Json&)>& change) {
    Json k = base_scenario();
    k["hand"] = "three_finger";
    k.erase("object");
    k["plant"] = {{"engine", "mujoco"}};
    change(k);
    return parse_error(k);
  };
  expect_contains(error_with([](Json& k) { k["hand"] = "allegro_like"; }),
                  "hand: plant.engine \"mujoco\" has the three_finger and shadow_like hands");
  {  // the Shadow-like hand's default model is its cylinder scene
    Json k = base_scenario();
    k.erase("object");
    k["plant"] = {{"engine", "mujoco"}};
    EXPECT_EQ(ex::parse_scenario(k).mujoco.model, "shadow_like_cylinder.xml");
  }
  expect_contains(error_with([](Json& k) {
                    k["object"] = {{"shape", "box"}};
                  }),
                  "object.shape: the object of plant.engine \"mujoco\" is the model's");
  expect_contains(error_with([](Json& k) {
                    k["object"] = {{"mass", -1.0}};
                  }),
                  "object.mass: must be a number in");
  expect_contains(error_with([](Json& k) { k["plant"]["normal_stiffness"] = 1000.0; }),
                  "plant.normal_stiffness: unknown key");
  expect_contains(error_with([](Json& k) { k["plant"]["friction"] = -0.1; }),
                  "plant.friction: must be a number in");
  expect_contains(error_with([](Json& k) { k["plant"]["torsional_friction"] = 2.0; }),
                  "plant.torsional_friction: must be a number in");
  expect_contains(error_with([](Json& k) { k["plant"]["model"] = ""; }),
                  "plant.model: must have 1 to 4096 characters");
  expect_contains(error_with([](Json& k) { k["plant"]["engine"] = "bullet"; }),
                  "plant.engine: must be one of");
  // The analytic plant refuses the MuJoCo settings.
  Json k = base_scenario();
  k["plant"] = {{"position_gain", 30.0}};
  expect_contains(parse_error(k), "plant.position_gain: unknown key");
}

// Every shipped MuJoCo scenario file parses (whether or not this build runs them).
TEST(ScenarioJson, MujocoFilesParse) {
  int count = 0;
  for (const auto& e : std::filesystem::directory_iterator(kScenarioDir + "/mujoco")) {
    SCOPED_TRACE(e.path().string());
    const ex::ScenarioFile f = ex::load_scenario(e.path().string());
    EXPECT_EQ(f.engine, "mujoco");
    EXPECT_TRUE(f.hand_preset == "three_finger" || f.hand_preset == "shadow_like") << f.hand_preset;
    ++count;
  }
  EXPECT_GE(count, 22);
}

// ---------------------------------------------------------------------------
// Expectations

ip::StageMetrics stage(const std::string& name, ip::StageKind kind) {
  ip::StageMetrics m;
  m.name = name;
  m.kind = kind;
  m.fingers.resize(2);
  return m;
}

// run_size() is what the runner's bounds compare: the ticks and plant steps a run takes
// when its grasp runs to the timeout, and exactly those of every later stage.
TEST(ScenarioJson, RunSizeBoundsTheRunnersWork) {
  Json j = base_scenario();
  j["stages"][1]["duration"] = 0.2;
  j["stages"][2]["settle"] = 0.1;
  j["stages"][2]["segments"][0]["duration"] = 0.2;
  j["plant"]["time_step"] = 2.5e-5;
  const ip::ScenarioSpec spec = ex::parse_scenario(j).spec;
  const ex::RunSize size = ex::run_size(spec);
  EXPECT_DOUBLE_EQ(size.simulated_time, 3.5);
  EXPECT_EQ(size.control_ticks, 3500.0);
  EXPECT_EQ(size.plant_steps, 140000.0);

  std::vector<long> ticks(spec.stages.size(), 0);
  std::int64_t steps = 0;
  const ip::ScenarioResult r = ip::ScenarioRunner().run(spec, [&](const ip::TickRecord& rec) {
    ++ticks[static_cast<std::size_t>(rec.stage)];
    steps = rec.plant->step_count();
  });
  ASSERT_TRUE(r.failure.empty()) << r.failure;
  EXPECT_GT(ticks[0], 0);
  EXPECT_LT(ticks[0], 3000);  // the grasp completed before its timeout
  EXPECT_EQ(ticks[1], 200);
  EXPECT_EQ(ticks[2], 300);
  const long run_ticks = ticks[0] + ticks[1] + ticks[2];
  EXPECT_EQ(steps, 40 * run_ticks);
  EXPECT_EQ(size.control_ticks - static_cast<double>(run_ticks), 3000.0 - ticks[0]);

  // Counts beyond any integer type stay finite and exact enough to compare.
  j["plant"]["time_step"] = 1e-12;
  EXPECT_DOUBLE_EQ(ex::run_size(ex::parse_scenario(j).spec).plant_steps, 3.5e12);
  j["plant"]["time_step"] = 1e-300;
  j["controller"]["control_period"] = 1e-300;
  j["controller"]["max_tick"] = 1e-300;
  const ex::RunSize huge = ex::run_size(ex::parse_scenario(j).spec);
  EXPECT_DOUBLE_EQ(huge.control_ticks, 3.5e300);
  EXPECT_DOUBLE_EQ(huge.plant_steps, 3.5e300);
}

TEST(Expectations, ReportsEachViolatedBound) {
  const Json e = ex::parse_json_text(R"({
    "all": {"must_not_drop": true, "max_contact_losses": 0},
    "hold": {"max_settle_time": 1.0, "max_slip": 1e-3},
    "manipulate": {"max_rms_position_error": 5e-4, "max_final_position_error": 2e-4,
                   "max_rms_orientation_error": 0.01, "max_final_orientation_error": 0.005,
                   "max_relative_force_error": 0.5, "must_complete": true}
  })");
  const ex::Expectations ex_ = ex::parse_expectations(e, "expect", {"grasp", "hold", "manipulate"});
  std::vector<ip::StageMetrics> ms = {stage("grasp", ip::StageKind::grasp),
                                      stage("hold", ip::StageKind::hold),
                                      stage("manipulate", ip::StageKind::manipulate)};
  ms[1].settle_time = 1.0;  // bounds are inclusive
  ms[2].rms_position_error = 5e-4;
  EXPECT_TRUE(ex::check_expectations(ex_, ms).empty());

  ms[1].settle_time = std::numeric_limits<double>::infinity();  // never settled
  ms[1].fingers[1].slip_distance = 2e-3;
  ms[2].rms_position_error = 6e-4;
  ms[2].final_orientation_error = 0.0051;
  ms[2].max_relative_force_error = 0.7;
  ms[2].completed = false;
  ms[0].dropped = true;
  ms[2].contact_losses = 2;
  const std::vector<std::string> v = ex::check_expectations(ex_, ms);
  const std::vector<std::string> want = {"'grasp': the object was dropped",
                                         "'manipulate': contact_losses = 2",
                                         "settle_time = inf",
                                         "'hold': slip",
                                         "rms_position_error = 0.0006 m",
                                         "final_orientation_error",
                                         "max_relative_force_error = 0.7",
                                         "'manipulate': did not complete"};
  EXPECT_EQ(v.size(), want.size());
  for (const std::string& w : want) {
    bool found = false;
    for (const std::string& s : v) found = found || s.find(w) != std::string::npos;
    EXPECT_TRUE(found) << "missing: " << w;
  }
}

TEST(Expectations, MustDropAndStagesThatDidNotRun) {
  const ex::Expectations e = ex::parse_expectations(
      ex::parse_json_text(R"({"hold": {"must_drop": true}, "manipulate": {"max_settle_time": 1}})"),
      "expect");
  std::vector<ip::StageMetrics> ms = {stage("grasp", ip::StageKind::grasp),
                                      stage("hold", ip::StageKind::hold)};
  std::vector<std::string> v = ex::check_expectations(e, ms);
  ASSERT_EQ(v.size(), 2u);
  EXPECT_NE(v[0].find("expected to drop"), std::string::npos);
  EXPECT_NE(v[1].find("'manipulate': did not run"), std::string::npos);
  ms[1].dropped = true;
  v = ex::check_expectations(e, ms);
  ASSERT_EQ(v.size(), 1u);
}

TEST(Expectations, MinWarningLeadAsksForTheWarningBeforeTheFirstContactLost) {
  const ex::Expectations e = ex::parse_expectations(
      ex::parse_json_text(R"({"hold": {"min_warning_lead": 0.05}})"), "expect");
  std::vector<ip::StageMetrics> ms = {stage("grasp", ip::StageKind::grasp),
                                      stage("hold", ip::StageKind::hold)};
  std::vector<ex::StageWarningTimes> w = {{"grasp", -1.0, -1.0}, {"hold", 0.03, 0.10}};
  const auto violations = [&](const std::vector<ex::StageWarningTimes>* times) {
    return ex::check_expectations(e, ms, times);
  };
  EXPECT_TRUE(violations(&w).empty());  // warned 70 ms before the first loss
  w[1].first_beyond_capacity = 0.05;    // 50 ms: the bound is inclusive
  EXPECT_TRUE(violations(&w).empty());
  w[1].first_beyond_capacity = 0.07;
  std::vector<std::string> v = violations(&w);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NE(v[0].find("'hold': beyond_capacity raised 0.03 s before"), std::string::npos) << v[0];
  for (const double late : {-1.0, 0.12}) {  // never, or only after the loss
    w[1].first_beyond_capacity = late;
    v = violations(&w);
    ASSERT_EQ(v.size(), 1u);
    EXPECT_NE(v[0].find("no beyond_capacity or object_astray warning before it"), std::string::npos)
        << v[0];
  }
  // object_astray counts as the warning too, the earlier of the two setting the lead.
  w[1].first_object_astray = 0.04;  // 60 ms before the loss, beyond_capacity never
  EXPECT_TRUE(violations(&w).empty());
  w[1].first_object_astray = 0.08;
  v = violations(&w);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NE(v[0].find("'hold': object_astray raised 0.02 s before"), std::string::npos) << v[0];
  w[1].first_beyond_capacity = 0.03;  // earlier than object_astray: it sets the lead
  EXPECT_TRUE(violations(&w).empty());
  w[1] = {"hold", -1.0, -1.0};  // nothing lost, nothing dropped: no warning needed
  EXPECT_TRUE(violations(&w).empty());
  ms[1].dropped = true;  // dropped without a contact reported lost: warned at all
  v = violations(&w);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NE(v[0].find("dropped with no beyond_capacity or object_astray warning"),
            std::string::npos)
      << v[0];
  w[1].first_beyond_capacity = 0.5;
  EXPECT_TRUE(violations(&w).empty());
  w[1] = {"hold", -1.0, -1.0, 0.5};  // or object_astray
  EXPECT_TRUE(violations(&w).empty());
  // A runner that does not record the warning times cannot check the bound.
  v = violations(nullptr);
  ASSERT_EQ(v.size(), 1u);
  EXPECT_NE(v[0].find("were not recorded"), std::string::npos) << v[0];
}

// ---------------------------------------------------------------------------
// Summary JSON

TEST(SummaryJson, RoundTripsIncludingNeverSettled) {
  ex::RunSummary r;
  r.scenario = "s";
  r.finger_names = {"a", "b"};
  r.expectations_checked = true;
  r.violations = {"stage 'hold': x"};
  r.failure = "grasp stage 'grasp' timed out";
  ip::StageMetrics m = stage("hold", ip::StageKind::hold);
  m.start_time = 1.25;
  m.end_time = 3.25;
  m.rms_position_error = 1.5e-4;
  m.max_orientation_error = 0.02;
  m.settle_time = std::numeric_limits<double>::infinity();
  m.contact_losses = 3;
  m.dropped = true;
  m.completed = false;
  m.fingers[1].slip_distance = 4e-4;
  m.fingers[1].final_measured_force = 1.1;
  r.stages = {m};
  const Json j = ex::summary_json(r);
  EXPECT_FALSE(j["passed"].get<bool>());
  EXPECT_TRUE(j["stages"][0]["settle_time"].is_null());
  const ex::RunSummary back = ex::summary_from_json(ex::parse_json_text(j.dump()));
  EXPECT_EQ(back.scenario, "s");
  EXPECT_EQ(back.violations, r.violations);
  EXPECT_EQ(back.failure, r.failure);
  EXPECT_EQ(back.finger_names, r.finger_names);
  ASSERT_EQ(back.stages.size(), 1u);
  const ip::StageMetrics& b = back.stages[0];
  EXPECT_EQ(b.name, "hold");
  EXPECT_EQ(b.kind, ip::StageKind::hold);
  EXPECT_EQ(b.start_time, 1.25);
  EXPECT_EQ(b.rms_position_error, 1.5e-4);
  EXPECT_EQ(b.max_orientation_error, 0.02);
  EXPECT_TRUE(std::isinf(b.settle_time));
  EXPECT_EQ(b.contact_losses, 3);
  EXPECT_TRUE(b.dropped);
  EXPECT_FALSE(b.completed);
  ASSERT_EQ(b.fingers.size(), 2u);
  EXPECT_EQ(b.fingers[1].slip_distance, 4e-4);
  EXPECT_EQ(b.fingers[1].final_measured_force, 1.1);
  EXPECT_THROW(ex::summary_from_json(Json::object(), "x.json"), ex::JsonError);
}

// ---------------------------------------------------------------------------
// Atomic files and the trace CSV

TEST(AtomicFile, AppearsOnlyOnCommit) {
  const std::string d = fresh_dir("atomic");
  const std::string target = d + "/out.txt";
  {
    ex::AtomicFile f(target);
    f.write("partial");
    EXPECT_EQ(list_dir(d).size(), 1u);  // only the temporary file
    EXPECT_NE(::access(target.c_str(), F_OK), 0);
  }  // destroyed without commit
  EXPECT_TRUE(list_dir(d).empty());
  ex::write_file_atomically(target, "v1\n");
  EXPECT_EQ(read_text(target), "v1\n");
  {
    ex::AtomicFile f(target);
    f.write("v2 partial");
    f.discard();
  }
  EXPECT_EQ(read_text(target), "v1\n");  // the old version is untouched
  ASSERT_EQ(list_dir(d).size(), 1u);
  EXPECT_THROW(ex::AtomicFile(d + "/missing_dir/out.txt"), std::runtime_error);
}

// The rename would replace whatever the target path names: anything but a regular
// file (or nothing) is refused, and stays as it was.
TEST(AtomicFile, RefusesTargetsThatAreNotRegularFiles) {
  const std::string d = fresh_dir("atomic_targets");
  const std::string regular = d + "/regular.txt", fifo = d + "/fifo", link = d + "/link",
                    dangling = d + "/dangling", sub = d + "/sub";
  ex::write_file_atomically(regular, "keep\n");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::filesystem::create_symlink("regular.txt", link);
  std::filesystem::create_symlink("missing.txt", dangling);
  std::filesystem::create_directory(sub);
  const auto refused = [](const std::string& path, const std::string& what) {
    try {
      ex::AtomicFile f(path);
      ADD_FAILURE() << path << " accepted";
    } catch (const ex::OutputTargetError& e) {
      EXPECT_EQ(std::string(e.what()), path + ": is a " + what +
                                           ", not a regular file (outputs are written only to "
                                           "regular files or new paths)");
    }
  };
  refused(fifo, "FIFO");
  refused(link, "symbolic link to regular.txt");
  refused(dangling, "symbolic link to missing.txt");
  refused(sub, "directory");
  refused("/dev/null", "character device");  // only checked: nothing is created in /dev
  EXPECT_NO_THROW(ex::check_output_target(regular));
  EXPECT_NO_THROW(ex::check_output_target(d + "/new.txt"));
  EXPECT_EQ(list_dir(d).size(), 5u);  // no temporary file was left
  EXPECT_EQ(read_text(link), "keep\n");

  // Checked again before the rename: a FIFO that appeared meanwhile is not replaced.
  const std::string later = d + "/later";
  {
    ex::AtomicFile f(later);
    f.write("text");
    ASSERT_EQ(::mkfifo(later.c_str(), 0600), 0);
    EXPECT_THROW(f.commit(), ex::OutputTargetError);
  }
  struct stat st {};
  ASSERT_EQ(::lstat(later.c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode));
  EXPECT_EQ(list_dir(d).size(), 6u);
}

// Outputs committed together appear together or not at all.
TEST(AtomicFile, CommitTogetherIsAllOrNothing) {
  const std::string d = fresh_dir("atomic_together");
  const std::string a = d + "/a.txt", b = d + "/b.txt";
  {
    ex::AtomicFile fa(a), fb(b);
    fa.write("a\n");
    fb.write("b\n");
    ex::commit_together({&fa, nullptr, &fb});
  }
  EXPECT_EQ(read_text(a), "a\n");
  EXPECT_EQ(read_text(b), "b\n");
  std::filesystem::remove(a);
  std::filesystem::remove(b);

  // b's target turns into a directory: checked before any rename, a.txt never appears.
  {
    ex::AtomicFile fa(a), fb(b);
    std::filesystem::create_directory(b);
    EXPECT_THROW(ex::commit_together({&fa, &fb}), ex::OutputTargetError);
  }
  EXPECT_EQ(list_dir(d), std::vector<std::string>{"b.txt"});
  std::filesystem::remove(b);

  // b's rename fails after a's succeeded (its temporary file vanished): a.txt is
  // removed again.
  {
    ex::AtomicFile fa(a), fb(b);
    for (const std::string& n : list_dir(d))
      if (n.rfind(".b.txt.", 0) == 0) std::filesystem::remove(d + "/" + n);
    EXPECT_THROW(ex::commit_together({&fa, &fb}), std::runtime_error);
  }
  EXPECT_TRUE(list_dir(d).empty());
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream ss(line);
  while (std::getline(ss, cell, ',')) out.push_back(cell);
  return out;
}

// ---------------------------------------------------------------------------
// The scene pictures (common/scene_svg.hpp)

// Extent of panel k's silhouette: (width, height), and its centre back in world units.
std::pair<Eigen::Vector2d, Eigen::Vector2d> extent(const std::vector<Eigen::Vector2d>& pts, int k) {
  Eigen::Vector2d lo = pts.front(), hi = pts.front();
  for (const Eigen::Vector2d& p : pts) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Eigen::Vector2d centre = 0.5 * (lo + hi);
  centre.x() -= (2 * k + 1) * ex::kSceneHalfWidth;
  return {hi - lo, centre};
}

// Each shape's silhouette in each view is its orthographic projection: the cylinder and
// box of the presets (object z along world X, Ry(pi/2)) and a sphere, off the origin.
TEST(SceneSvg, SilhouettesAreTheShapesProjections) {
  namespace sd = ex::scene_detail;
  inhand::Pose<double, 3> pose;
  pose.position = Eigen::Vector3d(0.01, -0.02, 0.005);
  pose.rotation = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  struct Case {
    ip::ObjectShape shape;
    Eigen::Vector3d world_half;  // half extents along world x, y, z
  };
  const Case cases[] = {{ip::ObjectShape::cylinder(0.02, 0.05), {0.05, 0.02, 0.02}},
                        {ip::ObjectShape::box(0.01, 0.02, 0.04), {0.04, 0.02, 0.01}},
                        {ip::ObjectShape::sphere(0.03), {0.03, 0.03, 0.03}}};
  for (const Case& c : cases) {
    for (int k = 0; k < 3; ++k) {
      const sd::View& view = sd::views()[static_cast<std::size_t>(k)];
      const auto [size, centre] = extent(sd::silhouette(c.shape, pose, view, k), k);
      SCOPED_TRACE(std::string(view.name) + ", shape " +
                   std::to_string(static_cast<int>(c.shape.kind)));
      // A sphere's outline is a 48-gon: its extent is within cos(pi/48) of the diameter.
      const double tol = c.shape.kind == ip::ObjectShape::Kind::sphere ? 2e-4 : 1e-12;
      EXPECT_NEAR(size.x(), 2 * c.world_half(view.h), tol);
      EXPECT_NEAR(size.y(), 2 * c.world_half(view.v), tol);
      EXPECT_NEAR(centre.x(), pose.position(view.h), tol);
      EXPECT_NEAR(centre.y(), pose.position(view.v), tol);
    }
  }
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Every finger is drawn in each view; a contact (red point and normal) only where the
// finger touches.
TEST(SceneSvg, DrawsEveryFingerAndOnlyTheTouchingContacts) {
  ex::Scene s;
  s.object = ip::ObjectShape::box(0.01, 0.01, 0.04);
  for (int i = 0; i < 2; ++i) {
    ex::Scene::Finger f;
    f.name = i == 0 ? "first" : "thumb";
    const double y = i == 0 ? 0.05 : -0.05;
    f.links = {Eigen::Vector3d(0, y, 0.05), Eigen::Vector3d(0, y, 0.0),
               Eigen::Vector3d(0, 0.5 * y, 0.0)};
    f.tip_radius = 0.01;
    f.touching = i == 0;
    f.contact_point = Eigen::Vector3d(0, 0.01, 0);
    f.normal = Eigen::Vector3d(0.0, 0.8, 0.6);  // seen at a slant in every view
    f.normal_force = 1.0;
    s.fingers.push_back(f);
  }
  const std::string svg = ex::scene_svg(s);
  const std::size_t box_edges = 12;
  EXPECT_EQ(count(svg, "<polyline"), 3 * (box_edges + s.fingers.size()));
  // Per view, a touching finger's contact: a red dot and an arrow of three red lines.
  EXPECT_EQ(count(svg, "#c00000"), 3u * 4u);
  s.fingers[0].touching = false;
  EXPECT_EQ(count(ex::scene_svg(s), "#c00000"), 0u);
  EXPECT_NE(svg.find("fingers: first, thumb"), std::string::npos);
}

TEST(TraceCsv, SpatialRowsMatchTheHeader) {
  const std::string d = fresh_dir("trace3");
  const std::string path = d + "/trace.csv";
  const Eigen::Matrix3d R0 =
      ip::shadow_like_hand().object_pose.rotation;  // Ry(pi/2): Euler-singular
  {
    ex::TraceCsvWriter<3> w(path, {"first", "thumb tip"}, R0);
    ex::TraceRow<3> row;
    row.time = 0.5;
    row.stage = 2;
    row.stage_name = "manipulate";
    row.desired.rotation = inhand::so3_exp<double>(Eigen::Vector3d(-0.2, 0, 0)) * R0;
    row.desired.position = Eigen::Vector3d(0.005, 0, 0);
    row.measured.rotation = R0;
    row.actual.rotation = inhand::so3_exp<double>(Eigen::Vector3d(0, 0, 0.1)) * R0;
    row.fingers.resize(2);
    row.fingers[0].touching = true;
    row.fingers[0].contact_point = Eigen::Vector3d(0.01, 0.02, -0.03);
    row.fingers[0].desired_force = 1.0;
    row.fingers[0].measured_force = 0.9;
    row.fingers[0].servo.motion = Eigen::Vector3d(1e-3, 0, 0);
    row.fingers[0].servo.force = Eigen::Vector3d(0, -2e-3, 0);
    row.fingers[0].servo.total = Eigen::Vector3d(1e-3, -2e-3, 0);
    row.fingers[0].state = inhand::FingerState::in_contact;
    row.fingers[1].state = inhand::FingerState::reacquiring;
    row.fingers[1].ik_status = inhand::IkStatus::damped;
    w.write(row);
    EXPECT_EQ(list_dir(d).size(), 1u);
    EXPECT_NE(::access(path.c_str(), F_OK), 0);  // not before commit
    w.commit();
  }
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  std::getline(in, line);
  const std::vector<std::string> h = split(header), r = split(line);
  // time, stage, name; 3 poses; per finger 17 + stiffness, integral, slip; grip, load, pose
  // integral
  ASSERT_EQ(h.size(), 3u + 18u + 2u * 20u + 2u + 6u + 6u);
  ASSERT_EQ(r.size(), h.size());
  auto col = [&](const std::string& name) {
    for (std::size_t i = 0; i < h.size(); ++i)
      if (h[i] == name) return r[i];
    ADD_FAILURE() << "no column " << name;
    return std::string();
  };
  EXPECT_EQ(col("time"), "0.500000");
  EXPECT_EQ(col("stage"), "2");
  EXPECT_EQ(col("stage_name"), "manipulate");
  EXPECT_EQ(col("des_x"), "0.005");
  // Orientation relative to R0: -0.2 rad about world X reads as roll, even though R0
  // itself sits on the Euler singularity.
  EXPECT_NEAR(std::stod(col("des_roll")), -0.2, 1e-12);
  EXPECT_NEAR(std::stod(col("des_pitch")), 0.0, 1e-12);
  EXPECT_EQ(col("meas_roll"), "0");
  EXPECT_NEAR(std::stod(col("act_yaw")), 0.1, 1e-12);
  EXPECT_EQ(col("first_touching"), "1");
  EXPECT_EQ(col("first_cz"), "-0.03");
  EXPECT_EQ(col("first_fd"), "1");
  EXPECT_EQ(col("first_f"), "0.9");
  EXPECT_EQ(col("first_motion_x"), "0.001");
  EXPECT_EQ(col("first_force_y"), "-0.002");
  EXPECT_EQ(col("first_total_y"), "-0.002");
  EXPECT_EQ(col("first_state"), "in_contact");
  EXPECT_EQ(col("first_ik"), "ok");
  EXPECT_EQ(col("thumb_tip_touching"), "0");  // name made CSV safe
  EXPECT_EQ(col("thumb_tip_cx"), "nan");      // no contact point while not touching
  EXPECT_EQ(col("thumb_tip_state"), "reacquiring");
  EXPECT_EQ(col("thumb_tip_ik"), "damped");
  EXPECT_FALSE(std::getline(in, line));
}

TEST(TraceCsv, PlanarRowsMatchTheHeader) {
  const std::string d = fresh_dir("trace2");
  const std::string path = d + "/trace.csv";
  {
    ex::TraceCsvWriter<2> w(path, {"left", "right"});
    ex::TraceRow<2> row;
    row.stage_name = "hold";
    row.desired.rotation = inhand::so2_exp<double>(0.3);
    row.fingers.resize(2);
    EXPECT_THROW(([&] {
                   ex::TraceRow<2> bad = row;
                   bad.fingers.resize(3);
                   w.write(bad);
                 }()),
                 std::invalid_argument);
    w.write(row);
    w.commit();
  }
  std::ifstream in(path);
  std::string header, line;
  std::getline(in, header);
  std::getline(in, line);
  const std::vector<std::string> h = split(header), r = split(line);
  ASSERT_EQ(h.size(), 3u + 9u + 2u * 16u + 2u + 3u + 3u);
  ASSERT_EQ(r.size(), h.size());
  EXPECT_EQ(h[3], "des_x");
  EXPECT_EQ(h[5], "des_angle");
  EXPECT_NEAR(std::stod(r[5]), 0.3, 1e-12);
  EXPECT_EQ(h[12], "left_touching");
  EXPECT_EQ(h[13], "left_cx");
  EXPECT_EQ(h[14], "left_cy");
  EXPECT_EQ(h[15], "left_fd");
}

}  // namespace
