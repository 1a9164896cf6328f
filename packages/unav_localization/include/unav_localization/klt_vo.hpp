// KLT optical-flow visual odometry, two modes.
//
// RGB-D: corners of a keyframe, lifted to 3D with its depth (bilinear), are tracked frame to frame
// with pyramidal Lucas-Kanade (forward-backward checked); each frame's pose relative to the
// keyframe comes from PnP + RANSAC, so error does not accumulate between keyframes. A new keyframe
// is made when too few tracks survive. Metric scale comes from the depth camera.
//
// Monocular: corners are tracked from a reference frame until their median displacement (parallax)
// is large enough; two-view geometry then initialises a map, from the better of an essential-matrix
// solution and a homography solution (seabed scenes are near-planar, where the essential matrix is
// ill-conditioned). Each later frame's pose comes from PnP + RANSAC against the map points it
// tracks; at a keyframe (too few map points tracked, or enough parallax since the last keyframe)
// the corners tracked since they were detected are triangulated from the two estimated poses and
// new corners are detected over the image. The scale is arbitrary: the first map's median depth is
// 1 (compare with ground truth after a Sim(3) alignment). When PnP fails the estimator reports
// kLost and re-initialises from scratch; the new map is expressed so that its reference pose is the
// last good pose and its median depth is the old map's median depth in the last good frame. What
// this preserves: position and attitude continuity at the gap, and the scale as far as the scene
// depth stays the same (a down camera at constant altitude). What it does not: the motion during
// the gap (the pose is held, then resumes from the last good pose), and the scale when the scene
// depth changed while lost.
//
// Frames: camera optical (z forward, x right, y down); poses T_C0C: camera k in the first camera's
// frame (monocular: the first map's reference frame, which is the first frame unless the
// initialisation had to restart from a later one).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace unav::localization {

struct KltVoOptions {
  enum class Mode { kRgbd, kMonocular };
  Mode mode = Mode::kRgbd;  ///< kMonocular: gray images only, arbitrary scale

  int max_features = 400;          ///< corners kept per frame
  double min_corner_distance = 8;  ///< px between corners
  int redetect_below = 150;        ///< RGB-D: re-detect corners when fewer are tracked
  double fb_max_error_px = 1.0;    ///< forward-backward tracking consistency
  double ransac_reprojection_px = 2.0;
  int min_inliers = 12;                          ///< fewer (or under 30% of the tracks): tracking lost for this frame
  double min_depth_m = 0.1, max_depth_m = 30.0;  ///< RGB-D: depths outside are not used
  double max_step_rotation_rad = 0.35;           ///< larger frame-to-frame rotations are rejected as wrong
  double max_step_translation_m = 1.0;           ///< RGB-D: larger frame-to-frame translations are rejected

  // Monocular mode.
  double min_init_parallax_px = 20.0;              ///< median track displacement from the reference frame before
                                                   ///< an initialisation is tried [px]
  int min_init_tracks = 60;                        ///< fewer tracks from the reference frame: new reference frame
  int min_init_points = 50;                        ///< well-triangulated points needed to accept an initialisation
  double keyframe_parallax_px = 25.0;              ///< new keyframe when the median track displacement since the
                                                   ///< last keyframe exceeds this [px]
  int keyframe_min_points = 100;                   ///< new keyframe when fewer map points are tracked
  double min_triangulation_angle_rad = 0.02;       ///< rays meeting at a smaller angle are not mapped
  double max_triangulation_reprojection_px = 2.0;  ///< in both views, for a point to be mapped
  double max_step_translation_depth = 0.5;         ///< frame-to-frame translation limit, in units of the
                                                   ///< median depth of the tracked points (scale-free)
  int grid_cols = 8, grid_rows = 5;                ///< new corners are spread over this grid of image cells

  bool IsValid(std::string* msg) const;
};

/// kInitializing (monocular only): no map yet, waiting for parallax; the pose is the reference
/// frame's. kLost: no estimate for this frame; the pose is a prediction (RGB-D: constant velocity;
/// monocular: the last good pose, held until re-initialisation).
enum class VoStatus { kInitialized, kTracking, kLost, kInvalidInput, kInitializing };
const char* to_string(VoStatus status);

struct VoSummary {
  VoStatus status = VoStatus::kInvalidInput;
  int tracked = 0;  ///< features tracked into this frame
  int inliers = 0;  ///< PnP inliers (monocular initialisation: well-triangulated points)
  std::string message;
};

class KltVo {
 public:
  /// K: 3x3 pinhole intrinsics of rectified images. Throws std::invalid_argument for bad
  /// options or K.
  KltVo(const Eigen::Matrix3d& K, const KltVoOptions& options = {});

  /// RGB-D mode. gray: CV_8UC1; depth: CV_32FC1 metres along z (same size; non-finite = none). On
  /// kLost the pose is propagated with the last motion (constant velocity) and tracking restarts
  /// from this frame's corners. Never throws; kInvalidInput in monocular mode.
  VoSummary ProcessFrame(const cv::Mat& gray, const cv::Mat& depth, Eigen::Isometry3d* T_C0C);

  /// Monocular mode. gray: CV_8UC1, the same size every frame. Translations are in map units
  /// (see the file comment). Never throws; kInvalidInput in RGB-D mode.
  VoSummary ProcessFrame(const cv::Mat& gray, Eigen::Isometry3d* T_C0C);

  const Eigen::Isometry3d& pose() const { return T_C0C_; }

 private:
  // RGB-D.
  void detect(const cv::Mat& gray);
  void make_keyframe(const cv::Mat& gray, const cv::Mat& depth);

  // Monocular. A track is a corner followed from the frame it was detected in ("birth"); it gets a
  // map point when triangulated at a keyframe.
  struct Track {
    cv::Point2f px;                                           ///< in the previous (after tracking: the current) frame
    cv::Point2f kf_px;                                        ///< in the last keyframe
    cv::Point2f birth_px;                                     ///< in the frame it was detected in
    Eigen::Isometry3d T_C0B = Eigen::Isometry3d::Identity();  ///< pose of that frame
    bool has_point = false;
    Eigen::Vector3d p_C0 = Eigen::Vector3d::Zero();  ///< map point [map units]
  };
  enum class MonoState { kNoReference, kInitializing, kTracking };
  void mono_start_reference(const cv::Mat& gray);
  bool mono_initialize(VoSummary* s);
  bool mono_track(VoSummary* s);
  void mono_keyframe(const cv::Mat& gray);
  void mono_detect(const cv::Mat& gray);
  void track_klt(const cv::Mat& gray, std::vector<Track>* tracks) const;
  double median_depth() const;

  /// T with its rotation projected back onto SO(3) (normalised quaternion). Poses are chained
  /// frame after frame, and Isometry3d::inverse() transposes the rotation: without this, the
  /// rounding error of a chained rotation grew geometrically over a long run with lost frames
  /// (an hour-long soak saw |q| reach 1.07, then 1e68, then NaN poses).
  static Eigen::Isometry3d Renormalized(const Eigen::Isometry3d& T);

  cv::Matx33d K_;
  KltVoOptions options_;
  cv::Mat prev_gray_;
  std::vector<cv::Point2f> prev_pts_;                        ///< current image positions of the keyframe's tracks
  std::vector<cv::Point3f> kf_points_;                       ///< their 3D points in the keyframe camera frame
  Eigen::Isometry3d T_C0K_ = Eigen::Isometry3d::Identity();  ///< keyframe pose
  Eigen::Isometry3d T_C0C_ = Eigen::Isometry3d::Identity();
  Eigen::Isometry3d last_motion_ = Eigen::Isometry3d::Identity();  ///< T_{k-1,k}
  bool initialized_ = false;

  MonoState mono_state_ = MonoState::kNoReference;
  std::vector<Track> tracks_;
  Eigen::Isometry3d T_C0R_ = Eigen::Isometry3d::Identity();  ///< pose given to the next map's reference frame
  double map_median_depth_ = 1.0;  ///< median depth of the next map's initial points [map units]
  bool ever_initialized_ = false;
};

}  // namespace unav::localization
