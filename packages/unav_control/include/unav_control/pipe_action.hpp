// The pipe-following action of the paper's DRL planner (section V-B), shared by the environment
// core (unav_sim) and the drl_planner node so that training and deployment read an action the
// same way: a = (a1, a2) in [-1, 1]^2, a1 the direction of a step of step_length_m relative to
// the heading (+-max_step_angle_deg, > 0 to the right), a2 the heading change (+-max_turn_deg,
// > 0 clockwise seen from above, i.e. towards east from north). Depth is held by the caller.
#pragma once

#include <Eigen/Core>
#include <array>

#include "unav_common/config.hpp"
#include "unav_control/mpc.hpp"

namespace unav::control {

/// The action's scale: the environment's and the drl_planner node's parameters embed it
/// (`PipeActionParams action;`, `action.Serialize(a)`: the keys stay at the caller's level), so
/// training and deployment declare it once.
struct PipeActionParams {
  double step_length_m = 1.0;
  double max_step_angle_deg = 60.0;
  double max_turn_deg = 30.0;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("step_length_m", &step_length_m).Above(0.0).Max(5.0).Unit("m").Doc("waypoint distance per action"));
    a->Visit(Field("max_step_angle_deg", &max_step_angle_deg)
                 .Range(0.0, 180.0)
                 .Unit("deg")
                 .Doc("a1 = +-1: step direction this far right/left of the heading"));
    a->Visit(Field("max_turn_deg", &max_turn_deg).Range(0.0, 180.0).Unit("deg").Doc("a2 = +-1: heading change"));
  }
};

/// The waypoint of action `a` (components clamped to [-1, 1]; non-finite ones read as 0) from a
/// vehicle at p_W (NED) with heading `yaw` (rad): position at depth `hold_depth_m`, level, yaw.
PoseSetpoint waypoint_from_action(const Eigen::Vector3d& p_W, double yaw, const std::array<double, 2>& a,
                                  const PipeActionParams& params, double hold_depth_m);

}  // namespace unav::control
