#include "unav_renderer/frames.hpp"

namespace unav_renderer {

Eigen::Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Pose pose_from_xyz_rpy(const Eigen::Vector3d& xyz_m, const Eigen::Vector3d& rpy_rad) {
  Pose X = Pose::Identity();
  X.linear() = rotation_from_rpy(rpy_rad.x(), rpy_rad.y(), rpy_rad.z());
  X.translation() = xyz_m;
  return X;
}

Eigen::Matrix3d R_camera_body_to_optical() {
  // Columns: optical axes expressed in the camera-body frame (x fwd, y right, z down).
  Eigen::Matrix3d R;
  R.col(0) = Eigen::Vector3d::UnitY();   // optical x = right
  R.col(1) = Eigen::Vector3d::UnitZ();   // optical y = down
  R.col(2) = Eigen::Vector3d::UnitX();   // optical z = forward
  return R;
}

}  // namespace unav_renderer
