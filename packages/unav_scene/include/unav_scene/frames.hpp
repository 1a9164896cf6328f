// Frames and poses used by the renderer and the world API.
//
// World frame `world_ned`: x north, y east, z down (metres; z = depth below the surface).
// Body frame `base_link_frd`: x forward, y right, z down.
// Camera optical frame `<name>_optical`: z forward (optical axis), x right, y down.
// Poses follow Drake's monogram notation: X_WB is the pose of frame B in frame W, so that
// p_W = X_WB * p_B.
#pragma once

#include <Eigen/Geometry>

namespace unav_renderer {

/// Rigid transform (rotation + translation in metres).
using Pose = Eigen::Isometry3d;

/// Rotation from roll, pitch, yaw [rad] (ZYX convention, R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad);

/// Pose from a translation [m] and roll, pitch, yaw [rad] (ZYX).
Pose pose_from_xyz_rpy(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_rad);

/// Rotation from a "camera body" frame (x along the optical axis, y right, z down; FRD-like)
/// to the optical frame convention (z forward, x right, y down): R_CbCo. A camera mounted
/// with rpy = (0, 0, 0) looks along body x; rpy = (0, -90 deg, 0) looks down (image top =
/// body forward).
Eigen::Matrix3d R_camera_body_to_optical();

}  // namespace unav_renderer
