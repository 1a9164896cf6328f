// Trajectories read straight from a rosbag2 (MCAP or sqlite3), as `evo_ape bag` reads them: a
// topic of nav_msgs/msg/Odometry, geometry_msgs/msg/PoseStamped, PoseWithCovarianceStamped or
// TransformStamped, or a frame pair on /tf and /tf_static written "/tf:PARENT.CHILD". Stamps are
// the messages' header stamps. A tool (not the core): it decodes CDR with the IDL types.
#pragma once

#include <string>

#include "unav_evaluation/trajectory.hpp"

namespace unav::evaluation {

/// Throws TrajectoryError naming the bag and topic: no such topic (listing the ones there), an
/// unsupported type, no transform for the frame pair (listing the pairs seen), no message.
Trajectory read_bag_trajectory(const std::string& bag, const std::string& topic_or_tf);

}  // namespace unav::evaluation
