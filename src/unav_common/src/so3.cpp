#include "unav_common/so3.hpp"

#include <algorithm>
#include <cmath>

#include <Eigen/Geometry>

namespace unav::common {

namespace {
// Below this angle the closed forms lose precision (1 - cos(a) ~ a^2 / 2 cancels); their Taylor
// expansions to second order are exact to double precision there.
constexpr double kSmallAngle = 1e-5;
}  // namespace

Eigen::Matrix3d Skew(const Eigen::Vector3d& a) {
  Eigen::Matrix3d s;
  s << 0.0, -a.z(), a.y(), a.z(), 0.0, -a.x(), -a.y(), a.x(), 0.0;
  return s;
}

Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& phi) {
  const double a = phi.norm();
  const Eigen::Matrix3d W = Skew(phi);
  if (a < kSmallAngle) return Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
  return Eigen::AngleAxisd(a, phi / a).toRotationMatrix();
}

Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R) {
  // Eigen's AngleAxis from a rotation matrix goes through the quaternion, which stays accurate
  // near 0 and near pi (the trace formula does not).
  const Eigen::AngleAxisd aa(Eigen::Quaterniond(R).normalized());
  double angle = aa.angle();
  Eigen::Vector3d axis = aa.axis();
  if (angle > M_PI) {  // AngleAxis gives [0, 2 pi): the same rotation the other way round
    angle = 2.0 * M_PI - angle;
    axis = -axis;
  }
  return angle * axis;
}

Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi) {
  const double a = phi.norm();
  const Eigen::Matrix3d W = Skew(phi);
  if (a < kSmallAngle) return Eigen::Matrix3d::Identity() - 0.5 * W + W * W / 6.0;
  const double a2 = a * a;
  return Eigen::Matrix3d::Identity() - (1.0 - std::cos(a)) / a2 * W + (a - std::sin(a)) / (a2 * a) * W * W;
}

Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& phi) {
  const double a = phi.norm();
  const Eigen::Matrix3d W = Skew(phi);
  if (a < kSmallAngle) return Eigen::Matrix3d::Identity() + 0.5 * W + W * W / 12.0;
  const double a2 = a * a;
  return Eigen::Matrix3d::Identity() + 0.5 * W + (1.0 / a2 - (1.0 + std::cos(a)) / (2.0 * a * std::sin(a))) * W * W;
}

}  // namespace unav::common
