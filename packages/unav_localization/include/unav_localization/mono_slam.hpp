// Feature-based monocular SLAM in the spirit of ORB-SLAM: ORB features spread over the image;
// map initialisation from two views (essential matrix or homography, whichever explains more
// triangulated points); tracking with a constant-velocity prediction and projection search, then
// the local map; keyframes; local bundle adjustment (Ceres, Huber loss) with map-point culling;
// loop detection by bag of binary words, Sim(3) loop correction, essential-graph optimisation and
// a global bundle adjustment; relocalisation, and re-initialisation when it fails.
//
// Everything runs in the caller's thread, frame by frame (tracking, then mapping, then loop
// closing on new keyframes), so a run is deterministic: the same images give the same map.
// Monocular scale is arbitrary: the first map's median depth is 1. Compare trajectories with a
// Sim(3) alignment.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "unav_localization/bow_vocabulary.hpp"
#include "unav_localization/imu_preintegration.hpp"
#include "unav_localization/orb_extractor.hpp"
#include "unav_localization/slam_map.hpp"

namespace unav::localization {

struct MonoSlamOptions {
  OrbOptions orb;
  int init_orb_features_factor = 2;    ///< more features while initialising
  double init_min_parallax_deg = 1.0;  ///< triangulated points need this much parallax
  int init_min_points = 60;            ///< triangulated points to accept an initial map
  double init_min_good_ratio = 0.9;    ///< share of the motion's inliers that must reconstruct
  /// Homography ratio S_H / (S_H + S_E) above which the view is taken as planar and only the
  /// homography's motions are tried (ORB-SLAM: 0.40-0.45); below, only the essential matrix's.
  double init_homography_ratio = 0.45;
  /// Two motions reconstruct the views about equally well (a plane's twin solutions): take the
  /// one that turns the camera at most half as much (and 1 deg less), instead of waiting.
  bool init_prefer_smaller_rotation = true;
  int init_max_frames = 30;             ///< a reference frame older than this is replaced
  int min_tracked_inliers = 30;         ///< fewer after pose optimisation: tracking lost
  int keyframe_max_gap = 10;            ///< frames between keyframes at most
  int keyframe_min_gap = 2;             ///< frames between keyframes at least (unless weak)
  double keyframe_tracked_ratio = 0.8;  ///< new keyframe when tracked < ratio x reference's
  int local_ba_keyframes = 10;          ///< keyframes optimised by local BA
  int local_ba_iterations = 10;
  int mapping_neighbours = 10;  ///< keyframes searched for new points
  bool loop_closing = true;
  double loop_min_score_ratio = 1.0;  ///< candidate score >= ratio x weakest covisible score
  int loop_consistency = 2;           ///< consecutive keyframes that must agree
  int loop_min_inliers = 40;          ///< matches after Sim(3) optimisation and guided search
  int loop_min_keyframe_gap = 20;     ///< keyframes between the loop ends at least
  /// A loop whose correction moves the current keyframe further than this share of the path
  /// flown since the loop keyframe is taken for perceptual aliasing (a repetitive seabed) and
  /// rejected: it would mean several times the drift this SLAM shows (< 0.5 % here).
  double loop_max_correction_ratio = 0.08;
  bool global_ba_after_loop = true;
  int global_ba_iterations = 15;
  int relocalize_frames = 10;  ///< frames of relocalisation attempts before re-initialising
  /// Atlas (ORB-SLAM3's multi-map): a map whose tracking was lost for good is kept (maps of 5
  /// keyframes or fewer are not) and each new keyframe looks for its place in them by bag of
  /// words (loop_consistency keyframes agreeing, Sim(3) verified with loop_min_inliers matches). Once found the old map
  /// is merged into the current one: its keyframes and points move into the current map's frame, the matched points are
  /// fused, a global bundle adjustment (global_ba_after_loop) welds them, and the trajectory since the loss is
  /// expressed in the old map's frame, so the output is one trajectory. Needs the vocabulary. Maps merge only when both
  /// are metric or both are not.
  bool merge_maps = true;   ///< off: a lost map is dropped (its trajectory is kept)
  int atlas_max_maps = 10;  ///< maps kept for merging at most (the oldest dropped)
  /// Relocalisation plausibility gate. Video is continuous: a relocalised camera lies within
  /// reloc_gate_speed_factor x (the fastest of the last 20 frame-to-frame motions) x (frames
  /// since the last tracked one), plus reloc_gate_min_radius x the map's median depth, of the
  /// last tracked pose, and has turned by at most reloc_gate_deg_per_frame per frame. A pose
  /// beyond that is taken for perceptual aliasing (a repetitive seabed, a pipe that looks the
  /// same along its length) and rejected. reloc_gate_speed_factor = 0: no gate (a kidnapped
  /// camera may relocalise anywhere in the map).
  double reloc_gate_speed_factor = 3.0;
  double reloc_gate_min_radius = 0.1;
  double reloc_gate_deg_per_frame = 15.0;
  /// Contrast-limited adaptive histogram equalisation before feature extraction (underwater
  /// footage: uneven artificial light, low contrast); clip limit, 0 = off. Tiles of ~40 px.
  double clahe_clip = 0.0;
  /// CLAHE applies to low-contrast frames only: grey-level standard deviation below this (turbid
  /// rendered water: ~12), off again above 1.25x it. A well-contrasted frame (daylight driving:
  /// ~58, a lit pool: ~45) is left alone: there its tiles make features that change from frame
  /// to frame as the scene moves across them (KITTI-like driving lost tracking with it).
  double clahe_max_stddev = 30.0;
  /// orb.features is per 640x480 of image: a larger image gets proportionally more (at most 4x;
  /// 1000 -> 1478 at 1226x370, 3000 at 1280x720); a smaller one keeps orb.features.
  bool features_scale_with_area = true;
  /// With an IMU (MonoSlam::EnableInertial): each map is scaled to metres by an inertial-only
  /// initialisation once its keyframes span this long [s] (ORB-SLAM3: 2 s), at least 6 of them.
  double inertial_init_window_s = 2.0;
  /// With a DVL (MonoSlam::EnableDvl): each map is scaled to metres from the DVL's bottom velocity
  /// integrated between keyframes once they span this long [s] (refined at 2.5x and 7.5x it) and
  /// the vehicle has moved dvl_min_travel_m; it replaces the IMU's scaling when both are on.
  double dvl_init_window_s = 2.0;
  double dvl_min_travel_m = 0.5;
  /// Once a map is metric, the DVL's displacement between consecutive keyframes is a factor of
  /// the local (and the loop's global) bundle adjustment, so the scale does not drift; its
  /// standard deviation: dvl_factor_sigma_m + dvl_factor_sigma_ratio x the displacement.
  bool dvl_factors = true;
  double dvl_factor_sigma_m = 0.01;
  double dvl_factor_sigma_ratio = 0.03;
  /// With an IMU: the gyroscope's rotation between consecutive keyframes (preintegrated, bias
  /// taken as zero) is a factor of the bundle adjustments, in any map (rotation has no scale);
  /// its standard deviation: the preintegration's + gyro_factor_sigma_rad + gyro_bias_sigma x the
  /// interval (an unknown bias).
  bool gyro_factors = true;
  /// With an IMU, once a map is scaled by it: a visual-inertial bundle adjustment (ORB-SLAM3's):
  /// the preintegrated IMU between consecutive keyframes (Forster's residual, its covariance) is a
  /// factor on their poses, their velocities and the IMU biases, which keeps the scale observed
  /// and the gravity direction, instead of the rotation factors alone.
  bool inertial_ba = true;
  /// With the visual-inertial states: each frame's pose is first predicted by the IMU from the
  /// newest keyframe's state (instead of the constant-velocity model), which holds through a gap
  /// in the images or a sudden manoeuvre.
  bool imu_prediction = true;
  double gyro_factor_sigma_rad = 0.002;
  double gyro_bias_sigma = 0.001;  ///< rad/s
  bool IsValid(std::string* msg) const;
};

enum class SlamState { kInitializing, kTracking, kRelocalized, kLost, kInvalidInput };
const char* to_string(SlamState state);

struct SlamFrameSummary {
  SlamState state = SlamState::kInvalidInput;
  int features = 0;
  int inliers = 0;  ///< map points matched after pose optimisation
  bool keyframe = false;
  bool loop_closed = false;
  bool reinitialized = false;
  bool maps_merged = false;  ///< an earlier map was recognised and merged into the current one
  double tracking_ms = 0.0;  ///< features + tracking
  double mapping_ms = 0.0;   ///< keyframe insertion, local BA, loop closing (0 without keyframe)
  Eigen::Isometry3d T_wc = Eigen::Isometry3d::Identity();  ///< current camera pose (tracked or predicted)
  std::string message;
};

struct SlamStats {
  int frames = 0, tracked_frames = 0, lost_frames = 0, keyframes = 0, points = 0;
  int loops = 0, relocalizations = 0, reinitializations = 0, maps = 1;
  int merges = 0;                     ///< earlier maps merged into the current one (maps - merges: maps left apart)
  int relocalizations_rejected = 0;   ///< by the plausibility gate
  int inertial_inits = 0;             ///< maps scaled to metres by the IMU
  int inertial_refinements = 0;       ///< scales refined over a longer span (2 a map at most)
  int inertial_rejections = 0;        ///< initialisations refused (InertialInitResult::ok false)
  double inertial_scale = 0.0;        ///< the last scaling: metres per map unit before it (0: none)
  double inertial_gravity_deg = 0.0;  ///< its gravity's angle from the first keyframe's camera z axis
  int imu_samples_rejected = 0;       ///< non-finite or out of time order
  int dvl_inits = 0;                  ///< maps scaled to metres by the DVL
  int dvl_refinements = 0;            ///< scales refined over a longer span (2 a map at most)
  int dvl_rejections = 0;             ///< scalings refused (too little travel, inconsistent)
  double dvl_scale = 0.0;             ///< the last DVL scaling: metres per map unit before it (0: none)
  int dvl_samples_rejected = 0;       ///< non-finite or out of time order
  long dvl_factors = 0;               ///< displacement factors handed to bundle adjustments
  long gyro_factors = 0;              ///< gyroscope rotation factors handed to bundle adjustments
  long inertial_factors = 0;          ///< preintegrated IMU factors (visual-inertial BA)
  int imu_predicted_frames = 0;       ///< frames tracked from the IMU's predicted pose
  int motion_model_misses = 0;        ///< frames the predicted pose did not track (matched again by appearance)
  /// The output is in metres: a map was scaled by the IMU or the DVL (later maps continue in its
  /// units). Before that, poses are in the first map's units (median depth 1).
  bool metric = false;
};

class MonoSlam {
 public:
  /// distortion: OpenCV plumb_bob coefficients (empty = rectified). vocabulary: needed for loop
  /// closing and relocalisation (null or empty: both off). Throws std::invalid_argument.
  MonoSlam(const PinholeCamera& camera, const std::vector<double>& distortion, const MonoSlamOptions& options,
           std::shared_ptr<const BowVocabulary> vocabulary);
  ~MonoSlam();
  MonoSlam(const MonoSlam&) = delete;
  MonoSlam& operator=(const MonoSlam&) = delete;

  /// gray: CV_8UC1 of the camera's size; stamp [s], increasing. Never throws.
  SlamFrameSummary Track(const cv::Mat& gray, double stamp);
  /// Monocular-inertial mode: IMU samples (AddImu) scale every map to metres (its trajectory and
  /// points) once its keyframes span options.inertial_init_window_s (InertialOnlyInit), so the
  /// trajectory comes out metric and a re-initialised map continues at the right scale. T_bc: the
  /// camera in the IMU's body frame (metric). Throws std::invalid_argument on a non-rigid T_bc.
  void EnableInertial(const Eigen::Isometry3d& T_bc, const ImuNoise& noise);
  /// One IMU sample (angular rate [rad/s], specific force [m/s^2], body frame) at stamp [s], on the
  /// images' clock, in time order. An image at t uses the samples stamped before t only (one
  /// stamped t is used from the next image on), so the result does not depend on whether it
  /// arrived before or after the image. Non-finite or out-of-order samples are dropped and
  /// counted. Never throws.
  void AddImu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel);
  /// DVL-aided mode: the DVL's bottom-relative velocity (the velocity of the DVL frame's origin
  /// in its own axes) scales every map to metres (options.dvl_init_window_s) and, once metric,
  /// constrains the bundle adjustments with the displacement between keyframes
  /// (options.dvl_factors), so the trajectory comes out metric and keeps its scale. T_dc: the
  /// camera in the DVL's frame (metric). Throws std::invalid_argument on a non-rigid T_dc.
  void EnableDvl(const Eigen::Isometry3d& T_dc);
  /// One DVL reading at stamp [s] on the images' clock, in time order; valid false (no bottom
  /// lock) interrupts the integration there; used as the IMU's (before the image's stamp only).
  /// Non-finite or out-of-order readings are dropped and
  /// counted. Never throws.
  void AddDvl(double stamp, const Eigen::Vector3d& velocity, bool valid);

  struct StampedPose {
    double stamp;
    Eigen::Isometry3d T_wc;
    int map;  ///< which map (re-initialisation starts a new one, joined at the last good pose)
  };
  /// Every tracked frame's pose, expressed through its reference keyframe, so loop corrections
  /// and bundle adjustment move the whole history. Frames before initialisation are absent.
  std::vector<StampedPose> Trajectory() const;
  /// The last `last` poses of Trajectory() (all when 0), computed for those only: O(last).
  std::vector<StampedPose> Trajectory(std::size_t last) const;
  std::vector<StampedPose> KeyFrameTrajectory() const;
  SlamStats stats() const;
  /// stats().metric without counting the map (for every frame).
  bool metric() const;
  const Map& map() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace unav::localization
