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

void TransformGraph::set(const std::string& parent, const std::string& child, const Pose& X_PC) {
  parent_of_[child] = {parent, X_PC};
}

std::optional<Pose> TransformGraph::lookup(const std::string& target, const std::string& source) const {
  // X_RF of every ancestor R of `frame` (the frame itself first), walking up to its root.
  const auto chain = [this](const std::string& frame) {
    std::vector<std::pair<std::string, Pose>> up{{frame, Pose::Identity()}};
    Pose X = Pose::Identity();
    for (auto it = parent_of_.find(frame); it != parent_of_.end() && up.size() <= parent_of_.size();
         it = parent_of_.find(it->second.first)) {
      X = it->second.second * X;
      up.emplace_back(it->second.first, X);
    }
    return up;
  };
  const auto from_source = chain(source);  // (A, X_AS)
  const auto from_target = chain(target);  // (A, X_AT)
  for (const auto& [a, X_AT] : from_target)
    for (const auto& [b, X_BS] : from_source)
      if (a == b) return X_AT.inverse() * X_BS;  // first common ancestor
  return std::nullopt;
}

}  // namespace unav::common
