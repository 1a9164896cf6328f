#include "unav_control/pipe_action.hpp"

#include <algorithm>
#include <cmath>

namespace unav::control {

PoseSetpoint waypoint_from_action(const Eigen::Vector3d& p_W, double yaw, const std::array<double, 2>& a,
                                  const PipeActionParams& params, double hold_depth_m) {
  constexpr double kDeg = M_PI / 180.0;
  auto clean = [](double v) { return std::isfinite(v) ? std::clamp(v, -1.0, 1.0) : 0.0; };
  const double dir = yaw + clean(a[0]) * params.max_step_angle_deg * kDeg;
  Eigen::Vector3d wp = p_W + params.step_length_m * Eigen::Vector3d(std::cos(dir), std::sin(dir), 0.0);
  wp.z() = hold_depth_m;
  return PoseSetpoint::FromPositionYaw(wp, std::remainder(yaw + clean(a[1]) * params.max_turn_deg * kDeg, 2.0 * M_PI));
}

}  // namespace unav::control
