// KLT optical-flow visual odometry, RGB-D mode: corners of a keyframe, lifted to 3D with its depth
// (bilinear), are tracked frame to frame with pyramidal Lucas-Kanade (forward-backward checked);
// each frame's pose relative to the keyframe comes from PnP + RANSAC, so error does not accumulate
// between keyframes. A new keyframe is made when too few tracks survive. Metric scale comes from
// the depth camera.
// Frames: camera optical (z forward, x right, y down); poses T_C0C: camera k in the first
// camera's frame.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace unav_localization {

struct KltVoOptions {
  int max_features = 400;          ///< corners kept per frame
  double min_corner_distance = 8;  ///< px between corners
  int redetect_below = 150;        ///< re-detect corners when fewer are tracked
  double fb_max_error_px = 1.0;    ///< forward-backward tracking consistency
  double ransac_reprojection_px = 2.0;
  int min_inliers = 12;            ///< fewer (or under 30% of the tracks): tracking lost for this frame
  double min_depth_m = 0.1, max_depth_m = 30.0;  ///< depths outside are not used
  double max_step_rotation_rad = 0.35;  ///< larger frame-to-frame rotations are rejected as wrong
  double max_step_translation_m = 1.0;  ///< larger frame-to-frame translations are rejected
  bool IsValid(std::string* msg) const;
};

enum class VoStatus { kInitialized, kTracking, kLost, kInvalidInput };
const char* to_string(VoStatus status);

struct VoSummary {
  VoStatus status = VoStatus::kInvalidInput;
  int tracked = 0;  ///< features tracked into this frame
  int inliers = 0;  ///< PnP inliers
  std::string message;
};

class KltVo {
 public:
  /// K: 3x3 pinhole intrinsics of rectified images. Throws std::invalid_argument for bad
  /// options or K.
  KltVo(const Eigen::Matrix3d& K, const KltVoOptions& options = {});

  /// gray: CV_8UC1; depth: CV_32FC1 metres along z (same size; non-finite = none). On kLost the
  /// pose is propagated with the last motion (constant velocity) and tracking restarts from
  /// this frame's corners. Never throws.
  VoSummary ProcessFrame(const cv::Mat& gray, const cv::Mat& depth, Eigen::Isometry3d* T_C0C);

  const Eigen::Isometry3d& pose() const { return T_C0C_; }

 private:
  void detect(const cv::Mat& gray);
  void make_keyframe(const cv::Mat& gray, const cv::Mat& depth);
  cv::Matx33d K_;
  KltVoOptions options_;
  cv::Mat prev_gray_;
  std::vector<cv::Point2f> prev_pts_;        ///< current image positions of the keyframe's tracks
  std::vector<cv::Point3f> kf_points_;       ///< their 3D points in the keyframe camera frame
  Eigen::Isometry3d T_C0K_ = Eigen::Isometry3d::Identity();  ///< keyframe pose
  Eigen::Isometry3d T_C0C_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  ///< T_{k-1,k}
  bool initialized_ = false;
};

}  // namespace unav_localization
