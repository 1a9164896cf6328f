// IMU preintegration on the manifold between two keyframes (Forster, Carlone, Dellaert, Scaramuzza,
// "On-Manifold Preintegration for Real-Time Visual-Inertial Odometry", IEEE T-RO 2017, section VI;
// the form ORB-SLAM3 uses): the rotation, velocity and position deltas of the gyroscope and
// accelerometer samples between keyframes i and j, independent of the states at i and j, with
// their 9x9 covariance and their Jacobians with respect to the biases, so that a bias update
// corrects the deltas to first order without integrating the samples again.
//
// Conventions: R_WB rotates body (IMU) vectors into the world; the IMU measures the angular rate
// w_B and the specific force f_B = R_WB^T (a_W - g_W) in the body frame, plus biases and white
// noise; g_W is the world's gravity (NED: (0, 0, +9.81)). The state error order is
// [rotation, velocity, position] (rotation as a right perturbation R Exp(dphi)).
#pragma once

#include <Eigen/Core>

namespace unav::localization {

/// Continuous-time IMU noise of a datasheet (the Kalibr/EuRoC convention).
struct ImuNoise {
  double gyro_noise_density = 1.7e-4;   ///< [rad/s/sqrt(Hz)]
  double accel_noise_density = 2.0e-3;  ///< [m/s^2/sqrt(Hz)]
  double gyro_random_walk = 1.9e-5;     ///< [rad/s^2/sqrt(Hz)]
  double accel_random_walk = 3.0e-3;    ///< [m/s^3/sqrt(Hz)]
};

struct ImuBias {
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero();   ///< [rad/s]
  Eigen::Vector3d accel = Eigen::Vector3d::Zero();  ///< [m/s^2]
};

/// The navigation state an IMU propagates: body pose and velocity in the world.
struct NavState {
  Eigen::Matrix3d R_WB = Eigen::Matrix3d::Identity();
  Eigen::Vector3d p_W = Eigen::Vector3d::Zero();
  Eigen::Vector3d v_W = Eigen::Vector3d::Zero();
};

using Matrix9d = Eigen::Matrix<double, 9, 9>;
using Vector9d = Eigen::Matrix<double, 9, 1>;

class ImuPreintegration {
 public:
  /// Deltas from zero, linearised at `bias` (the estimate at keyframe i).
  explicit ImuPreintegration(const ImuBias& bias = {}, const ImuNoise& noise = {});

  /// One sample held over dt seconds (Euler, as Forster eq. 37). Throws std::invalid_argument on
  /// a non-finite sample or a dt that is not finite and positive.
  void Integrate(const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel, double dt);

  double dt() const { return dt_; }
  const ImuBias& bias() const { return bias_; }
  const Eigen::Matrix3d& delta_R() const { return dR_; }
  const Eigen::Vector3d& delta_v() const { return dv_; }
  const Eigen::Vector3d& delta_p() const { return dp_; }
  /// Covariance of the deltas' errors [dphi, dv, dp] from the white measurement noise.
  const Matrix9d& covariance() const { return cov_; }
  /// Jacobians of the deltas with respect to the gyro and accelerometer biases.
  const Eigen::Matrix3d& dR_dbg() const { return dR_dbg_; }
  const Eigen::Matrix3d& dv_dbg() const { return dv_dbg_; }
  const Eigen::Matrix3d& dv_dba() const { return dv_dba_; }
  const Eigen::Matrix3d& dp_dbg() const { return dp_dbg_; }
  const Eigen::Matrix3d& dp_dba() const { return dp_dba_; }

  /// The deltas corrected to first order for another bias (Forster eq. 44).
  Eigen::Matrix3d CorrectedDeltaR(const ImuBias& b) const;
  Eigen::Vector3d CorrectedDeltaV(const ImuBias& b) const;
  Eigen::Vector3d CorrectedDeltaP(const ImuBias& b) const;

  /// The state at j from the state at i, with bias b and gravity g_W (Forster eq. 33).
  NavState Predict(const NavState& i, const ImuBias& b, const Eigen::Vector3d& g_W) const;
  /// The residual [r_R, r_v, r_p] of states i and j against the deltas (Forster eq. 45): zero
  /// for states the samples agree with; its covariance is covariance().
  Vector9d Residual(const NavState& i, const NavState& j, const ImuBias& b, const Eigen::Vector3d& g_W) const;

  /// Covariance of the bias change over the interval (random walks): diag(sigma_bg^2, sigma_ba^2) dt.
  Eigen::Matrix<double, 6, 6> BiasWalkCovariance() const;

 private:
  ImuBias bias_;
  ImuNoise noise_;
  double dt_ = 0.0;
  Eigen::Matrix3d dR_ = Eigen::Matrix3d::Identity();
  Eigen::Vector3d dv_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d dp_ = Eigen::Vector3d::Zero();
  Matrix9d cov_ = Matrix9d::Zero();
  Eigen::Matrix3d dR_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dv_dba_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dbg_ = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d dp_dba_ = Eigen::Matrix3d::Zero();
};

}  // namespace unav::localization
