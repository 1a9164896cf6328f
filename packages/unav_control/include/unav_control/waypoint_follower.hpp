// Waypoint follower: a path (list of poses in NED) -> pose setpoints for the MPC, one waypoint at
// a time, advancing when the vehicle is within an acceptance radius. Yaw follows the path
// direction (heading of the segment leading to the target) or the waypoints' own attitude.
#pragma once

#include <string>
#include <vector>

#include "unav_control/mpc.hpp"

namespace unav::control {

enum class YawMode {
  kPathDirection,  ///< yaw = heading of the segment into the target waypoint (level attitude)
  kWaypoint,       ///< the waypoint's own attitude
};

struct WaypointFollowerOptions {
  double acceptance_radius = 0.3;  ///< m, > 0: distance at which a waypoint counts as reached
  YawMode yaw_mode = YawMode::kPathDirection;
  /// Segments shorter than this horizontally keep the previous yaw (vertical moves), m, >= 0.
  double min_heading_segment = 0.05;
  bool IsValid(std::string* msg) const;
};

struct WaypointUpdate {
  PoseSetpoint setpoint;        ///< what the MPC should track now
  int target_index = 0;         ///< waypoint being approached
  double distance = 0.0;        ///< to the target, m
  double progress = 0.0;        ///< fraction of the path length covered, [0, 1]
  bool finished = false;        ///< the last waypoint has been reached (setpoint holds it)
};

class WaypointFollower {
 public:
  /// Throws physics::ConfigError for invalid options.
  explicit WaypointFollower(const WaypointFollowerOptions& options = WaypointFollowerOptions{});

  /// Replaces the path and restarts at its first waypoint. Returns false (keeping the old path)
  /// with a message naming the offending waypoint for an empty path, NaN/Inf or a non-unit
  /// quaternion.
  bool SetPath(const std::vector<PoseSetpoint>& path, std::string* msg = nullptr);
  /// Advances past every waypoint within the acceptance radius of p_W (NED, m) and returns the
  /// setpoint to track. Without a path: finished, setpoint = p_W (hold). Never throws.
  WaypointUpdate Update(const Eigen::Vector3d& p_W);

  const std::vector<PoseSetpoint>& path() const { return path_; }
  int target_index() const { return target_; }
  bool finished() const { return finished_; }

 private:
  PoseSetpoint SetpointFor(int index) const;
  WaypointFollowerOptions options_;
  std::vector<PoseSetpoint> path_;
  std::vector<double> cumulative_;  // path length up to each waypoint, m
  std::vector<double> yaw_;         // path-direction yaw per waypoint, rad
  int target_ = 0;
  bool finished_ = true;
};

/// Poses `height` metres above a line of points (e.g. a pipeline on the seabed, NED), with yaw
/// along the line: the inspection path for WaypointFollower.
std::vector<PoseSetpoint> path_above(const std::vector<Eigen::Vector3d>& points_W, double height);

}  // namespace unav::control
