// inhand: reactive in-hand manipulation of unknown objects (umbrella header).
// Conventions for every header: SI units, world frame unless named otherwise,
// roll-pitch-yaw Euler angles R = Rz(psi) Ry(theta) Rx(phi), contact normals point
// OUT of the object (towards the fingertip). See README.md.
#pragma once

#include "inhand/version.hpp"
#include "inhand/math/types.hpp"
#include "inhand/math/status.hpp"
#include "inhand/math/so3.hpp"
#include "inhand/math/pose.hpp"
#include "inhand/math/sin_cos.hpp"
#include "inhand/math/pi_controller.hpp"
#include "inhand/math/damped_least_squares.hpp"
#include "inhand/kinematics/contact_kinematics.hpp"
#include "inhand/kinematics/finger_chain.hpp"
#include "inhand/kinematics/finger_lanes.hpp"
#include "inhand/controller/ik.hpp"
#include "inhand/controller/servo.hpp"
#include "inhand/controller/trajectory.hpp"
#include "inhand/controller/force_planner.hpp"
#include "inhand/controller/grasp.hpp"
#include "inhand/controller/reactive_controller.hpp"
