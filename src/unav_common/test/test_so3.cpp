#include <cmath>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "unav_common/so3.hpp"

namespace {

using namespace unav::common;  // Skew, ExpSO3, LogSO3, RightJacobian(Inverse)SO3

TEST(SO3, SkewIsTheCrossProduct) {
  const Eigen::Vector3d a(0.3, -1.2, 2.0), b(-0.7, 0.4, 1.1);
  EXPECT_LT((Skew(a) * b - a.cross(b)).norm(), 1e-15);
}

TEST(SO3, ExpIsARotationAboutTheVectorAndLogInvertsIt) {
  // Angles from 0 through the small-angle branch (1e-5) to just below pi.
  for (const double angle : {0.0, 1e-9, 3e-6, 1e-3, 0.5, 2.0, 3.0, M_PI - 1e-6}) {
    const Eigen::Vector3d axis = Eigen::Vector3d(1.0, -2.0, 0.5).normalized();
    const Eigen::Matrix3d R = ExpSO3(angle * axis);
    const Eigen::Matrix3d expected = Eigen::AngleAxisd(angle, axis).toRotationMatrix();
    EXPECT_LT((R - expected).norm(), 1e-13) << angle;
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-14) << angle;
    // Log: 1e-9 near pi as the rotation there fixes the axis only to ~sqrt(eps) / angle.
    EXPECT_LT((LogSO3(R) - angle * axis).norm(), angle > 3.1 ? 1e-7 : 1e-13) << angle;
  }
}

TEST(SO3, LogOfAHalfTurnHasAnglePi) {
  const Eigen::Matrix3d R = Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_NEAR(LogSO3(R).norm(), M_PI, 1e-12);
  EXPECT_NEAR(std::abs(LogSO3(R).z()), M_PI, 1e-12);
}

TEST(SO3, RightJacobianLinearisesTheExponential) {
  // Exp(phi + d) = Exp(phi) Exp(Jr(phi) d) + O(|d|^2): with |d| = 1e-6 the residual is ~1e-12.
  for (const Eigen::Vector3d& phi : {Eigen::Vector3d(0.0, 0.0, 0.0), Eigen::Vector3d(2e-6, -1e-6, 0.0),
                                     Eigen::Vector3d(0.3, -0.2, 0.9), Eigen::Vector3d(-1.5, 1.0, 2.0)}) {
    const Eigen::Vector3d d(1e-6, -0.5e-6, 0.8e-6);
    const Eigen::Matrix3d lhs = ExpSO3(phi + d);
    const Eigen::Matrix3d rhs = ExpSO3(phi) * ExpSO3(RightJacobianSO3(phi) * d);
    EXPECT_LT((lhs - rhs).norm(), 1e-11) << phi.transpose();
    // and its inverse: Log(Exp(phi) Exp(d)) = phi + Jr^-1 d + O(|d|^2)
    const Eigen::Vector3d log = LogSO3(ExpSO3(phi) * ExpSO3(d));
    EXPECT_LT((log - (phi + RightJacobianInverseSO3(phi) * d)).norm(), 1e-11) << phi.transpose();
    EXPECT_LT((RightJacobianInverseSO3(phi) * RightJacobianSO3(phi) - Eigen::Matrix3d::Identity()).norm(), 1e-12);
  }
}

}  // namespace
