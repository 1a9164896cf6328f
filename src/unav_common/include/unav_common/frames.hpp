// Frames, declared once for the workspace (DESIGN.md section 4, STYLE.md item 8):
//
// World frame `world_ned`: x north, y east, z down (metres; z = depth below the surface).
// Body frame `base_link_frd`: x forward, y right, z down.
// Camera optical frame `<name>_optical`: z forward (optical axis), x right, y down.
// Poses follow Drake's monogram notation: X_WB is the pose of frame B in frame W, so that
// p_W = X_WB * p_B. Attitudes are quaternions; roll/pitch/yaw (ZYX: R = Rz(yaw) Ry(pitch)
// Rx(roll)) only for configuration and display.
#pragma once

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace unav::common {

inline constexpr const char* kWorldFrame = "world_ned";
inline constexpr const char* kBodyFrame = "base_link_frd";
/// Suffix of a camera's optical frame: "<name>_optical".
inline constexpr const char* kOpticalFrameSuffix = "_optical";

/// Rigid transform (rotation + translation in metres).
using Pose = Eigen::Isometry3d;

/// Rotation from roll, pitch, yaw [rad] (ZYX convention, R = Rz(yaw) Ry(pitch) Rx(roll)).
Eigen::Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad);

/// Attitude from roll, pitch, yaw [rad] (ZYX convention).
Eigen::Quaterniond quaternion_from_rpy(double roll_rad, double pitch_rad, double yaw_rad);

/// Roll, pitch, yaw [rad] (ZYX convention) of an attitude; pitch in [-pi/2, pi/2]. For display,
/// configuration and tests only.
Eigen::Vector3d roll_pitch_yaw(const Eigen::Quaterniond& q_WB);

/// Pose from a translation [m] and roll, pitch, yaw [rad] (ZYX).
Pose pose_from_xyz_rpy(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_rad);

/// Rotation from a "camera body" frame (x along the optical axis, y right, z down; FRD-like)
/// to the optical frame convention (z forward, x right, y down): R_CbCo. A camera mounted
/// with rpy = (0, 0, 0) looks along body x; rpy = (0, -90 deg, 0) looks down (image top =
/// body forward).
Eigen::Matrix3d R_camera_body_to_optical();

/// Static transforms between named frames, as tf2's buffer holds /tf_static: each edge is
/// X_PC (frame C in its parent P); lookup() composes edges along the tree in either direction.
/// DDS-free (unav_runtime's StaticTransformListener fills one from /tf_static).
class TransformGraph {
 public:
  /// Sets (or replaces) the edge parent -> child. A frame has one parent (tf2's rule): a second
  /// parent for `child` replaces the first.
  void set(const std::string& parent, const std::string& child, const Pose& X_PC);
  /// X_TS: frame `source` in frame `target` (p_T = X_TS * p_S), through any chain of edges;
  /// nullopt when the frames are not connected (or unknown). lookup(f, f) is the identity.
  std::optional<Pose> lookup(const std::string& target, const std::string& source) const;
  /// Number of edges.
  std::size_t size() const { return parent_of_.size(); }

 private:
  std::map<std::string, std::pair<std::string, Pose>> parent_of_;  ///< child -> (parent, X_PC)
};

}  // namespace unav::common
