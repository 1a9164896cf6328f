// The pipe-following action of the paper's DRL planner (section V-B), shared by the environment
// core (unav_sim) and the drl_planner node so that training and deployment read an action the
// same way: a = (a1, a2) in [-1, 1]^2, a1 the direction of a step of step_length_m relative to
// the heading (+-max_step_angle_deg, > 0 to the right), a2 the heading change (+-max_turn_deg,
// > 0 clockwise seen from above, i.e. towards east from north). Depth is held by the caller.
#pragma once

#include <Eigen/Core>
#include <array>

#include "unav_control/mpc.hpp"

namespace unav::control {

struct PipeActionParams {
  double step_length_m = 1.0;
  double max_step_angle_deg = 60.0;
  double max_turn_deg = 30.0;
};

/// The waypoint of action `a` (components clamped to [-1, 1]; non-finite ones read as 0) from a
/// vehicle at p_W (NED) with heading `yaw` (rad): position at depth `hold_depth_m`, level, yaw.
PoseSetpoint waypoint_from_action(const Eigen::Vector3d& p_W, double yaw, const std::array<double, 2>& a,
                                  const PipeActionParams& params, double hold_depth_m);

}  // namespace unav::control
