// The rotation group SO(3) as estimators use it (Forster et al. 2017, "On-Manifold Preintegration
// for Real-Time Visual-Inertial Odometry", section III): the hat operator, the exponential and
// logarithm maps and the right Jacobian with its inverse. Rotation vectors are in radians.
#pragma once

#include <Eigen/Core>

namespace unav::common {

/// [a]x: the skew-symmetric matrix with [a]x b = a x b.
Eigen::Matrix3d Skew(const Eigen::Vector3d& a);
/// Exp(phi): the rotation by |phi| about phi / |phi| (Rodrigues; first order below 1e-10 rad).
Eigen::Matrix3d ExpSO3(const Eigen::Vector3d& phi);
/// Log(R): the rotation vector of R, angle in [0, pi]. R must be a rotation (orthonormal, det +1).
Eigen::Vector3d LogSO3(const Eigen::Matrix3d& R);
/// Right Jacobian Jr(phi): Exp(phi + d) ~ Exp(phi) Exp(Jr(phi) d) for small d.
Eigen::Matrix3d RightJacobianSO3(const Eigen::Vector3d& phi);
/// Jr(phi)^-1: Log(Exp(phi) Exp(d)) ~ phi + Jr(phi)^-1 d for small d.
Eigen::Matrix3d RightJacobianInverseSO3(const Eigen::Vector3d& phi);

}  // namespace unav::common
