// Two-view relative motion candidates, shared by the monocular initialisations of MonoSlam and
// KltVo: the essential matrix (general 3-D scenes; RANSAC + cheirality-checked recoverPose) and
// the up to four decompositions of a homography (a plane, e.g. the seabed). Each estimator then
// scores the candidates with its own triangulation checks and picks one.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core.hpp>

namespace unav::localization {

struct TwoViewOptions {
  double essential_ransac_px = 1.0;  ///< epipolar RANSAC threshold
  double essential_confidence = 0.999;
  int essential_max_iterations = 1000;
  double homography_ransac_px = 1.5;  ///< reprojection RANSAC threshold
};

/// One motion hypothesis: x_2 = R x_1 + t for points x_1 of view 1 (t as OpenCV returns it:
/// unit length from the essential matrix, scaled by 1 / plane distance from a homography).
struct TwoViewCandidate {
  enum class Model { kEssential, kHomography };
  Model model = Model::kEssential;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t = Eigen::Vector3d::Zero();
  /// RANSAC inliers of the model, one per correspondence (essential: after recoverPose's
  /// cheirality check).
  std::vector<std::uint8_t> inliers;
  /// ORB-SLAM's model score of this candidate's model over all correspondences (1 px noise):
  /// homography: sum over both transfer directions of (5.991 - e^2) where e^2 < 5.991;
  /// essential: sum over both epipolar distances of (5.991 - d^2) where d^2 < 3.841.
  double model_score = 0.0;
};

/// ORB-SLAM's homography ratio S_H / (S_H + S_E) of a candidate set (0 when there is no
/// homography candidate, 1 when there is no essential one). Above ~0.45 the scene is (nearly)
/// planar or the motion a rotation: the essential matrix is then ill-conditioned (RANSAC finds
/// a wrong motion with a good fit: seen as a wrong ~8 deg pitch with the rippled seabed ahead),
/// and the homography's decompositions should be used.
double HomographyRatio(const std::vector<TwoViewCandidate>& candidates);

/// The candidates for pixel correspondences p1[i] <-> p2[i] of a camera with matrix K:
/// the essential-matrix motion first (absent when RANSAC or recoverPose finds none), then the
/// homography decompositions with a non-zero translation (a pure rotation gives no depth).
std::vector<TwoViewCandidate> TwoViewCandidates(const std::vector<cv::Point2f>& p1, const std::vector<cv::Point2f>& p2,
                                                const cv::Matx33d& K, const TwoViewOptions& options = {});

}  // namespace unav::localization
