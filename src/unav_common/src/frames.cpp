#include "unav_common/frames.hpp"

#include <algorithm>
#include <cmath>

namespace unav::common {

Eigen::Matrix3d rotation_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return (Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
          Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

Eigen::Quaterniond quaternion_from_rpy(double roll_rad, double pitch_rad, double yaw_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitY()) *
                            Eigen::AngleAxisd(roll_rad, Eigen::Vector3d::UnitX()));
}

Eigen::Vector3d roll_pitch_yaw(const Eigen::Quaterniond& q_WB) {
  const Eigen::Matrix3d R = q_WB.normalized().toRotationMatrix();
  const double pitch = std::asin(std::clamp(-R(2, 0), -1.0, 1.0));
  return {std::atan2(R(2, 1), R(2, 2)), pitch, std::atan2(R(1, 0), R(0, 0))};
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
  R.col(0) = Eigen::Vector3d::UnitY();  // optical x = right
  R.col(1) = Eigen::Vector3d::UnitZ();  // optical y = down
  R.col(2) = Eigen::Vector3d::UnitX();  // optical z = forward
  return R;
}

}  // namespace unav::common
