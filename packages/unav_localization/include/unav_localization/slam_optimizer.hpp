// Ceres optimisations of the monocular SLAM: pose-only tracking refinement, local and global
// bundle adjustment, the Sim(3) between two keyframes at a loop, and the Sim(3) pose graph
// (essential graph) that spreads a loop correction. Residuals are reprojection errors in pixels
// divided by the feature's pyramid scale, under a Huber loss; measurements whose chi-square
// exceeds the 95% gate (2 dof: 5.991) are marked outliers between rounds, as in ORB-SLAM.
#pragma once

#include <map>
#include <vector>

#include "unav_localization/imu_preintegration.hpp"
#include "unav_localization/sim3.hpp"
#include "unav_localization/slam_map.hpp"

namespace unav::localization {

struct PoseObservation {
  Eigen::Vector3d X_w;
  Eigen::Vector2d uv;
  double inv_sigma2 = 1.0;
  bool outlier = false;
};

/// Refines T_cw from 2D-3D matches (4 rounds x 10 iterations, outliers re-classified each
/// round). Returns the number of inliers.
int OptimizePose(const PinholeCamera& cam, std::vector<PoseObservation>* obs, Eigen::Isometry3d* T_cw);

struct BundleAdjustmentSummary {
  int keyframes = 0, fixed_keyframes = 0, points = 0, residuals = 0, outliers_removed = 0;
  double seconds = 0.0;
};

/// A metric displacement of the vehicle's body between two keyframes, measured by another sensor
/// (the DVL's bottom velocity integrated over the keyframes' interval, rotated into the map by the
/// keyframes' attitude): a factor of the bundle adjustment on the body origin's positions,
/// p_j - p_i = d_w, p = T_wc * o_c, whitened by sigma [m] (isotropic). Added only where both
/// keyframes take part in the adjustment; the map must be in metres.
struct BodyDisplacementFactor {
  int kf_i = -1, kf_j = -1;
  Eigen::Vector3d o_c = Eigen::Vector3d::Zero();  ///< the body origin in the camera frame
  Eigen::Vector3d d_w = Eigen::Vector3d::Zero();  ///< p_j - p_i in the map frame [m]
  double sigma = 1.0;
};

/// The body's rotation between two keyframes measured by the gyroscope (its preintegrated delta):
/// a factor on the keyframes' attitudes, Log(dR_b^T R_bi^T R_bj) = 0 with R_b = R_wc R_cb,
/// whitened by sigma [rad] (isotropic). Scale-free: it holds in any map.
struct RelativeRotationFactor {
  int kf_i = -1, kf_j = -1;
  Eigen::Matrix3d R_cb = Eigen::Matrix3d::Identity();  ///< the body's axes in the camera frame
  Eigen::Matrix3d dR_b = Eigen::Matrix3d::Identity();  ///< R_bi^T R_bj measured
  double sigma = 1.0;
};

/// The IMU between two keyframes of a metric map (ORB-SLAM3's inertial edge): Forster's 9-D
/// residual of the preintegrated deltas against both keyframes' body poses (T_wb = T_cw^-1 T_cb)
/// and velocities, with the IMU biases, whitened by the preintegration's covariance. A factor on
/// poses, velocities and biases of InertialStates.
struct InertialFactor {
  int kf_i = -1, kf_j = -1;
  ImuPreintegration pre;
  Eigen::Isometry3d T_cb = Eigen::Isometry3d::Identity();  ///< the body (IMU) in the camera frame
};

/// The states the inertial factors add, read and written back by the adjustment: each
/// keyframe's body velocity [m/s, map world axes] and one bias for the window, held near its prior.
struct InertialStates {
  std::map<int, Eigen::Vector3d> velocities;
  ImuBias bias;
  ImuBias bias_prior;
  double gyro_bias_prior_sigma = 0.01;            ///< [rad/s]
  double accel_bias_prior_sigma = 0.1;            ///< [m/s^2]
  Eigen::Vector3d g_w = Eigen::Vector3d::Zero();  ///< gravity in the map's world [m/s^2]
};

/// What other sensors add to a bundle adjustment (only where both keyframes take part).
struct BundleFactors {
  std::vector<BodyDisplacementFactor> displacements;
  std::vector<RelativeRotationFactor> rotations;
  std::vector<InertialFactor> inertial;  ///< used with `states` only
  InertialStates* states = nullptr;      ///< every inertial factor's keyframes have a velocity here
};

/// Local BA around keyframe `kf_id`: it and its covisible keyframes (up to max_local) are
/// optimised with every point they see; other keyframes that see those points stay fixed, and so
/// does keyframe 0 (gauge). Outlier observations are erased from the map afterwards.
BundleAdjustmentSummary LocalBundleAdjustment(Map* map, const PinholeCamera& cam,
                                              const std::vector<double>& level_sigma2, int kf_id, int max_local,
                                              int iterations, const BundleFactors& factors = {});

/// All keyframes and points, keyframe 0 fixed.
BundleAdjustmentSummary GlobalBundleAdjustment(Map* map, const PinholeCamera& cam,
                                               const std::vector<double>& level_sigma2, int iterations,
                                               const BundleFactors& factors = {});

struct Sim3Match {
  Eigen::Vector3d X1_c1, X2_c2;  ///< the matched points in their keyframes' camera frames
  Eigen::Vector2d uv1, uv2;      ///< their features in keyframe 1 and keyframe 2
  double inv_sigma2_1 = 1.0, inv_sigma2_2 = 1.0;
  bool outlier = false;
};

/// Refines S_12 (camera 2 -> camera 1) by reprojecting each pair into both images. Returns inliers.
int OptimizeSim3(const PinholeCamera& cam, std::vector<Sim3Match>* matches, Sim3* S_12, double chi2_gate);

struct PoseGraphEdge {
  int i = -1, j = -1;
  Sim3 S_ij;  ///< measured camera j -> camera i
};

/// Essential-graph optimisation over keyframe Sim(3) poses S_iw (world -> camera i): minimises
/// the relative-pose errors of the edges, keeping `fixed` keyframes constant. S_iw is indexed by
/// keyframe id; entries of bad keyframes are ignored.
void OptimizePoseGraph(std::vector<Sim3>* S_iw, const std::vector<bool>& active,
                       const std::vector<PoseGraphEdge>& edges, const std::vector<int>& fixed, int iterations);

}  // namespace unav::localization
