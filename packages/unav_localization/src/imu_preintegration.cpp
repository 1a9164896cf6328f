#include "unav_localization/imu_preintegration.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include "unav_common/so3.hpp"

namespace unav::localization {

using common::ExpSO3;
using common::LogSO3;
using common::RightJacobianSO3;
using common::Skew;

ImuPreintegration::ImuPreintegration(const ImuBias& bias, const ImuNoise& noise) : bias_(bias), noise_(noise) {
  for (const double v :
       {noise.gyro_noise_density, noise.accel_noise_density, noise.gyro_random_walk, noise.accel_random_walk})
    if (!std::isfinite(v) || v < 0.0) throw std::invalid_argument("ImuNoise: densities must be finite and >= 0");
  if (!bias.gyro.allFinite() || !bias.accel.allFinite()) throw std::invalid_argument("ImuBias: not finite");
}

void ImuPreintegration::Integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt) {
  if (!(std::isfinite(dt) && dt > 0.0))
    throw std::invalid_argument("ImuPreintegration: dt = " + std::to_string(dt) + " must be finite and > 0");
  if (!gyro.allFinite() || !accel.allFinite())
    throw std::invalid_argument("ImuPreintegration: a gyro or accelerometer sample is not finite");
  const Eigen::Vector3d w = gyro - bias_.gyro;
  const Eigen::Vector3d a = accel - bias_.accel;
  const Eigen::Matrix3d a_x = Skew(a);
  const double dt2 = dt * dt;
  const Eigen::Matrix3d dR_step = ExpSO3(w * dt);
  const Eigen::Matrix3d Jr = RightJacobianSO3(w * dt);

  // Error propagation (Forster eq. 59-62) with the deltas before this sample: A on the error
  // state [dphi, dv, dp], B on the gyro and accelerometer noise.
  Matrix9d A = Matrix9d::Identity();
  A.block<3, 3>(0, 0) = dR_step.transpose();
  A.block<3, 3>(3, 0) = -dR_ * a_x * dt;
  A.block<3, 3>(6, 0) = -0.5 * dR_ * a_x * dt2;
  A.block<3, 3>(6, 3) = Eigen::Matrix3d::Identity() * dt;
  Eigen::Matrix<double, 9, 3> Bg = Eigen::Matrix<double, 9, 3>::Zero();
  Eigen::Matrix<double, 9, 3> Ba = Eigen::Matrix<double, 9, 3>::Zero();
  Bg.block<3, 3>(0, 0) = Jr * dt;
  Ba.block<3, 3>(3, 0) = dR_ * dt;
  Ba.block<3, 3>(6, 0) = 0.5 * dR_ * dt2;
  // Discrete noise of a sample averaged over dt: density^2 / dt.
  const double var_g = noise_.gyro_noise_density * noise_.gyro_noise_density / dt;
  const double var_a = noise_.accel_noise_density * noise_.accel_noise_density / dt;
  cov_ = A * cov_ * A.transpose() + var_g * Bg * Bg.transpose() + var_a * Ba * Ba.transpose();

  // Bias Jacobians (Forster appendix B), each from the others' values before this sample.
  dp_dba_ += dv_dba_ * dt - 0.5 * dR_ * dt2;
  dp_dbg_ += dv_dbg_ * dt - 0.5 * dR_ * a_x * dR_dbg_ * dt2;
  dv_dba_ -= dR_ * dt;
  dv_dbg_ -= dR_ * a_x * dR_dbg_ * dt;
  dR_dbg_ = dR_step.transpose() * dR_dbg_ - Jr * dt;

  // The deltas themselves: position first, it uses the velocity and rotation before the sample.
  dp_ += dv_ * dt + 0.5 * dR_ * a * dt2;
  dv_ += dR_ * a * dt;
  dR_ = dR_ * dR_step;
  dt_ += dt;
}

Eigen::Matrix3d ImuPreintegration::CorrectedDeltaR(const ImuBias& b) const {
  return dR_ * ExpSO3(dR_dbg_ * (b.gyro - bias_.gyro));
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaV(const ImuBias& b) const {
  return dv_ + dv_dbg_ * (b.gyro - bias_.gyro) + dv_dba_ * (b.accel - bias_.accel);
}

Eigen::Vector3d ImuPreintegration::CorrectedDeltaP(const ImuBias& b) const {
  return dp_ + dp_dbg_ * (b.gyro - bias_.gyro) + dp_dba_ * (b.accel - bias_.accel);
}

NavState ImuPreintegration::Predict(const NavState& i, const ImuBias& b, const Eigen::Vector3d& g_W) const {
  NavState j;
  j.R_WB = i.R_WB * CorrectedDeltaR(b);
  j.v_W = i.v_W + g_W * dt_ + i.R_WB * CorrectedDeltaV(b);
  j.p_W = i.p_W + i.v_W * dt_ + 0.5 * g_W * dt_ * dt_ + i.R_WB * CorrectedDeltaP(b);
  return j;
}

Vector9d ImuPreintegration::Residual(const NavState& i, const NavState& j, const ImuBias& b,
                                     const Eigen::Vector3d& g_W) const {
  const Eigen::Matrix3d Rt = i.R_WB.transpose();
  Vector9d r;
  r.segment<3>(0) = LogSO3(CorrectedDeltaR(b).transpose() * Rt * j.R_WB);
  r.segment<3>(3) = Rt * (j.v_W - i.v_W - g_W * dt_) - CorrectedDeltaV(b);
  r.segment<3>(6) = Rt * (j.p_W - i.p_W - i.v_W * dt_ - 0.5 * g_W * dt_ * dt_) - CorrectedDeltaP(b);
  return r;
}

Eigen::Matrix<double, 6, 6> ImuPreintegration::BiasWalkCovariance() const {
  Eigen::Matrix<double, 6, 6> C = Eigen::Matrix<double, 6, 6>::Zero();
  C.topLeftCorner<3, 3>().diagonal().setConstant(noise_.gyro_random_walk * noise_.gyro_random_walk * dt_);
  C.bottomRightCorner<3, 3>().diagonal().setConstant(noise_.accel_random_walk * noise_.accel_random_walk * dt_);
  return C;
}

}  // namespace unav::localization
