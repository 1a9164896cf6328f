// Similarity transforms Sim(3): x' = s R x + t. Used for monocular maps, whose scale is not
// observable and drifts, and for loop corrections.
#pragma once

#include <random>
#include <vector>

#include <Eigen/Geometry>

namespace unav_localization {

struct Sim3 {
  double s = 1.0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();

  Sim3() = default;
  Sim3(double scale, const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation)
      : s(scale), R(rotation), t(translation) {}
  explicit Sim3(const Eigen::Isometry3d& T) : s(1.0), R(T.linear()), t(T.translation()) {}

  Eigen::Vector3d operator*(const Eigen::Vector3d& x) const { return s * (R * x) + t; }
  Sim3 operator*(const Sim3& o) const { return {s * o.s, R * o.R, s * (R * o.t) + t}; }
  Sim3 inverse() const {
    const Eigen::Matrix3d Rt = R.transpose();
    return {1.0 / s, Rt, -(Rt * t) / s};
  }
  /// The rigid transform with the same rotation and the translation divided by the scale: the
  /// camera pose a Sim(3) world-to-camera correction stands for.
  Eigen::Isometry3d ToIsometryUnscaled() const {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = R;
    T.translation() = t / s;
    return T;
  }
};

/// Closed-form similarity (Umeyama 1991) mapping `from` onto `to` (3xN, N >= 3): to ~ S * from.
/// Returns false when the points are degenerate (collinear, coincident).
bool EstimateSim3(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool fix_scale, Sim3* S);

}  // namespace unav_localization
