// Visual-inertial initialisation, inertial-only MAP (Campos et al., "Inertial-Only Optimization
// for Visual-Inertial Initialization", ICRA 2020; ORB-SLAM3's first stage): given the keyframe
// poses of a monocular map (right up to scale and to a rotation of the world) and the IMU
// preintegrated between consecutive keyframes, find the map's metric scale, the gravity direction
// in the map's world, the keyframes' velocities and the IMU biases, by one small Ceres problem over
// the preintegration residuals (weighted by their covariance) with priors on the biases.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "unav_localization/imu_preintegration.hpp"

namespace unav::localization {

struct InertialInitOptions {
  double gravity = 9.81;  ///< [m/s^2]
  /// Prior standard deviations of the biases around zero (ORB-SLAM3 holds the accelerometer bias
  /// near zero during initialisation: a few seconds of motion barely observe it).
  double gyro_bias_prior_std = 0.1;    ///< [rad/s]
  double accel_bias_prior_std = 0.01;  ///< [m/s^2]
  int max_iterations = 100;
  /// Smallest acceptable scale (ORB-SLAM3's 0.1 in LocalMapping::InitializeIMU). With too little
  /// acceleration against the IMU's noise the keyframes' own errors pull the scale towards 0
  /// (regression dilution): a map whose first views are ~1 unit deep and come out at millimetres
  /// was not observed, not measured.
  double min_scale = 0.1;
};

struct InertialInitResult {
  bool ok = false;
  std::string message;  ///< why not, when !ok
  /// Metric length of one map unit: p_metric = scale * p_map.
  double scale = 1.0;
  /// The map's world rotated to gravity: R_wg maps gravity-aligned axes (z along gravity, down)
  /// into the map's world; gravity in the map's world is R_wg * (0, 0, g).
  Eigen::Matrix3d R_wg = Eigen::Matrix3d::Identity();
  Eigen::Vector3d gravity_w = Eigen::Vector3d::Zero();
  ImuBias bias;
  /// Body velocity at each keyframe, metric, in the map world's axes.
  std::vector<Eigen::Vector3d> velocities;
  double final_cost = 0.0;
  int iterations = 0;
};

/// keyframes: map poses of the camera (T_wc, translation in map units), in time order;
/// preintegrations[k] spans keyframe k to k + 1 (so one fewer); T_bc: the camera in the IMU body
/// frame (metric). Needs at least 3 keyframes.
InertialInitResult InertialOnlyInit(const std::vector<Eigen::Isometry3d>& keyframes,
                                    const std::vector<ImuPreintegration>& preintegrations,
                                    const Eigen::Isometry3d& T_bc, const InertialInitOptions& options = {});

}  // namespace unav::localization
