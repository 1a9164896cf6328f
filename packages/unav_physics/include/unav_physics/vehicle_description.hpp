// The vehicle for 3-D views (RViz, Foxglove): a URDF of a vehicle file (its body, every thruster
// with its thrust axis) and of the camera and sonar mounts on it, in the frames the rest of the
// workspace uses: base_link_frd (FRD body) and <camera>_optical / <sonar>_head children, the
// very transforms the renderer and the sonar node publish on /tf_static (one source: the mount
// in the camera / sonar YAML). Published latched on /robot_description by the robot_description
// node (launch files), as robot_state_publisher does in ROS 2.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "unav_physics/vehicle.hpp"

namespace unav::physics {

/// A fixed frame on the body: child name and its pose in base_link_frd.
struct MountedFrame {
  std::string name;
  Eigen::Isometry3d X_B = Eigen::Isometry3d::Identity();
};

/// URDF 1.0 text: link base_link_frd (a box spanning the thrusters, vehicle.height tall), a link
/// thruster_<name> per thruster (a cylinder of the propeller's diameter along the thrust
/// direction, its joint at the thruster's position with the link's z axis along
/// direction_B), and a link per mounted frame on a fixed joint (origin = X_B).
std::string vehicle_urdf(const VehicleParams& vehicle, const std::vector<MountedFrame>& mounts);

/// URDF's rpy of a rotation (fixed axes x, y, z: R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Vector3d urdf_rpy(const Eigen::Matrix3d& R);

}  // namespace unav::physics
