// Internal: the state and steps of MonoSlam (one file per stage: mono_slam_features.cpp,
// mono_slam_initializer.cpp, mono_slam_tracking.cpp, mono_slam_local_mapping.cpp,
// mono_slam_loop_closing.cpp; mono_slam.cpp: bookkeeping and the public API).
#pragma once

#include "unav_localization/mono_slam.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <deque>
#include <functional>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>
#include <optional>
#include <random>
#include <set>
#include <stdexcept>
#include "unav_localization/inertial_init.hpp"
#include "unav_localization/sim3.hpp"
#include "unav_localization/slam_optimizer.hpp"
#include "unav_localization/two_view.hpp"

namespace unav::localization {

namespace slam_internal {
constexpr int kThHigh = 100;  // descriptor distance accepted when projection already constrains
constexpr int kThLow = 50;    // descriptor distance accepted for matching by appearance only
constexpr double kChi2Mono = 5.991;
// A map's steps to metres (IMU or DVL): at 1, 2.5 and 7.5 x the window (ORB-SLAM3: 2, 5, 15 s),
// over the most recent keyframes, 6 at least.
constexpr double kMetricStageSpan[] = {1.0, 2.5, 7.5};
constexpr std::size_t kMetricInitKeyframes = 60;
constexpr std::size_t kMinMetricInitKeyframes = 6;
constexpr double kImuHistoryS = 60.0;   // IMU samples kept at most (a map that never initialises)
constexpr double kDvlHistoryS = 120.0;  // DVL readings kept at most
using Clock = std::chrono::steady_clock;
inline double Ms(Clock::time_point a) { return std::chrono::duration<double, std::milli>(Clock::now() - a).count(); }

// The two smallest descriptor distances seen, for best-match plus ratio tests.
struct BestTwo {
  int best = 256, second = 256, index = -1, best_level = -1, second_level = -1;
  void Add(int d, int i, int level = -1) {
    if (d < best) {
      second = best;
      second_level = best_level;
      best = d;
      index = i;
      best_level = level;
    } else if (d < second) {
      second = d;
      second_level = level;
    }
  }
};
}  // namespace slam_internal

struct MonoSlam::Impl {
  struct Frame {
    int index = -1;
    double stamp = 0;
    Features f;
    std::vector<int> points;  ///< feature -> map point (-1)
    std::vector<bool> outlier;
    Eigen::Isometry3d T_cw = Eigen::Isometry3d::Identity();
  };
  struct TrajEntry {
    double stamp;
    int ref_kf;
    Eigen::Isometry3d T_cr;
  };

  MonoSlamOptions opt;
  PinholeCamera cam;
  cv::Mat K, D;
  std::unique_ptr<OrbExtractor> orb, orb_init;
  std::shared_ptr<const BowVocabulary> voc;
  std::vector<double> scales, sigma2;
  double log_scale = 0;

  std::unique_ptr<Map> map = std::make_unique<Map>();
  BowDatabase db;
  bool initialized = false;
  std::unique_ptr<Frame> init_ref;
  std::vector<Eigen::Vector2d> init_prev;  ///< per reference feature: where it was matched last
  cv::Ptr<cv::CLAHE> clahe;                ///< when options.clahe_clip > 0
  bool clahe_on = false;                   ///< the current frames are low-contrast (options.clahe_max_stddev)
  cv::Mat equalized;
  /// Feature-count thresholds scale with the image: 1 at 640x480 and above, sqrt(area ratio)
  /// below (a 320x180 camera holds ~0.43 of the features of a 640x480 one), at least 0.35.
  double resolution_scale() const {
    return std::clamp(std::sqrt(static_cast<double>(cam.width) * cam.height / (640.0 * 480.0)), 0.35, 1.0);
  }
  int scaled(int n) const { return std::max(12, static_cast<int>(std::lround(n * resolution_scale()))); }
  Frame cur, last;
  bool last_tracked = false;
  bool has_velocity = false;
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();
  int frame_index = 0;
  int ref_kf = -1, last_kf_frame = -1, last_reloc_frame = -1000;
  int lost_frames_in_row = 0;
  std::deque<double> recent_steps;  ///< camera-centre motion per frame, last 20 tracked frames
  std::string reloc_rejection;      ///< why the gate rejected this frame's relocalisation ("" if not)
  std::vector<int> local_kfs, local_points;
  std::vector<int> recent_points;
  std::vector<std::pair<std::set<int>, int>> consistent_groups;
  std::string loop_log;  ///< verified loop candidates of the current keyframe (summary message)
  std::vector<TrajEntry> traj;
  std::vector<StampedPose> frozen;  ///< trajectories of earlier maps, in the global frame
  Sim3 G;                           ///< current map's world -> global frame
  int map_number = 0;
  Eigen::Isometry3d last_good_T_wc_global = Eigen::Isometry3d::Identity();
  int last_good_ref_kf = -1;  ///< reference keyframe of the last tracked frame
  SlamStats stats;
  std::mt19937 rng{12345};
  // ------------------------------------------------------------------ inertial (mono_slam_inertial.cpp)
  struct ImuSample {
    double t;
    Eigen::Vector3d gyro, accel;
  };
  bool inertial = false;  ///< EnableInertial was called
  Eigen::Isometry3d T_bc = Eigen::Isometry3d::Identity();
  ImuNoise imu_noise;
  std::deque<ImuSample> imu;  ///< samples from the current map's first keyframe on (bounded)
  /// Samples not used yet: a frame at t admits those stamped before t only, so what the SLAM uses
  /// never depends on whether a sensor's sample stamped t arrived before or after the image (two
  /// DDS topics: either order; lockstep runs repeat exactly).
  std::deque<ImuSample> imu_pending;
  /// 0: the current map is not in metres yet; 1, 2, 3: scaled once, refined once, twice (by the
  /// IMU or the DVL).
  int metric_stage = 0;
  bool map_sets_global_scale = false;    ///< the current map defined global_per_metric
  bool inertial_rejection_said = false;  ///< a rejected initialisation was reported for this map
  double global_per_metric = 0.0;        ///< global units per metre, once a map was scaled (0: not yet)
  void AddImu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel);
  /// The samples over [t0, t1], each held until the next; dt() == 0 when they do not cover it.
  ImuPreintegration PreintegrateImu(double t0, double t1) const;
  /// After a keyframe: scales the map to metres when its keyframes span the window, and again
  /// (a refinement) at 2.5 and 7.5 times the window (ORB-SLAM3: 2 s, then 5 s and 15 s); what it
  /// did ("" when it did nothing).
  std::string TryInertialInit();
  /// Multiplies every length of the current map and its tracking state by s.
  void ScaleMap(double s);
  /// ScaleMap(s) as the current map's step to metres (the IMU's or the DVL's): keeps the global
  /// frame's units (the first metric map defines them), advances metric_stage.
  void ApplyMetricScale(double s);
  /// The current map's good keyframes stamped at or after not_before, oldest first; the last
  /// `count` of them (all when 0).
  std::vector<const KeyFrame*> RecentKeyFrames(double not_before, std::size_t count) const;
  // ------------------------------------------------------------------ DVL (mono_slam_dvl.cpp)
  struct DvlSample {
    double t;
    Eigen::Vector3d v;  ///< velocity of the DVL's origin in its frame [m/s]
    bool valid;
  };
  bool dvl_on = false;  ///< EnableDvl was called
  Eigen::Isometry3d T_dc = Eigen::Isometry3d::Identity();
  std::deque<DvlSample> dvl;          ///< recent readings (bounded)
  std::deque<DvlSample> dvl_pending;  ///< not used yet (as imu_pending)
  /// Before a frame at `stamp`: the pending IMU and DVL samples stamped before it join the used ones.
  void AdmitSensorData(double stamp);
  bool dvl_rejection_said = false;
  void AddDvl(double stamp, const Eigen::Vector3d& v, bool valid);
  /// The DVL origin's displacement over [t0, t1] in the map frame [m]: the readings (linear
  /// between them) rotated by the attitude slerped from R_wd0 to R_wd1; nullopt when the readings
  /// do not cover the interval, a gap is longer than 0.5 s or one is invalid.
  std::optional<Eigen::Vector3d> DvlDisplacement(double t0, double t1, const Eigen::Quaterniond& q_wd0,
                                                 const Eigen::Quaterniond& q_wd1) const;
  /// Consecutive keyframes of `kfs` the DVL covers: their camera poses and the DVL displacement.
  struct DvlStep {
    int kf_i, kf_j;
    Eigen::Isometry3d T_wc_i, T_wc_j;
    Eigen::Vector3d d_w;
  };
  std::vector<DvlStep> DvlSteps(const std::vector<const KeyFrame*>& kfs) const;
  /// After a keyframe: scales the map to metres from the DVL (stages as TryInertialInit).
  std::string TryDvlScale();
  /// Displacement factors between consecutive keyframes of the current map (the last `count`
  /// good ones; all when count is 0) where the DVL covers them; empty unless metric.
  std::vector<BodyDisplacementFactor> DvlFactors(std::size_t count) const;
  /// Gyroscope rotation factors between consecutive keyframes (the last `count` good ones; all
  /// when 0) where the IMU covers them (options.gyro_factors, inertial on); scale-free.
  std::vector<RelativeRotationFactor> GyroFactors(std::size_t count) const;
  /// Visual-inertial bundle adjustment (options.inertial_ba): once the IMU scaled the current
  /// map, each keyframe's velocity, the window's biases and gravity in the map's world.
  bool vi_ready = false;
  InertialStates vi;
  /// Inertial factors between consecutive keyframes (the last `count` good ones; all when 0)
  /// where the IMU covers them; a keyframe without a velocity yet gets the IMU's prediction from
  /// its predecessor's state.
  std::vector<InertialFactor> InertialFactors(std::size_t count);
  /// The visual-inertial states from an inertial-only initialisation over kfs.
  void StartInertialStates(const std::vector<const KeyFrame*>& kfs, const InertialInitResult& r);
  /// With the visual-inertial states: the camera pose (T_cw) at `stamp` predicted by the IMU from
  /// the newest keyframe with a velocity (ORB-SLAM3's tracking prediction); nullopt otherwise.
  std::optional<Eigen::Isometry3d> ImuPredictedPose(double stamp) const;
  /// All of them, for a bundle adjustment over the last `count` keyframes; counted in stats.
  BundleFactors AidingFactors(std::size_t count) {
    BundleFactors f{DvlFactors(count), GyroFactors(count), InertialFactors(count), nullptr};
    if (!f.inertial.empty()) f.states = &vi;
    stats.dvl_factors += static_cast<long>(f.displacements.size());
    stats.gyro_factors += static_cast<long>(f.rotations.size());
    stats.inertial_factors += static_cast<long>(f.inertial.size());
    return f;
  }

  // ---------------------------------------------------------------- features
  void ExtractFeatures(const cv::Mat& gray, const OrbExtractor& extractor, Frame* f);
  void ComputeBow(Features* f) const;
  double InvSigma2(const Features& f, int i) const {
    return 1.0 / sigma2[static_cast<size_t>(f.keypoints[static_cast<size_t>(i)].octave)];
  }

  int PredictLevel(const MapPoint& p, double dist) const;

  // Matches features of a (filtered) to features of b (filtered) by appearance: within the same
  // vocabulary node when both have feature vectors, else all pairs. Best distance <= th and a
  // ratio test against the second best. `pair_ok` (optional) admits a pair before it competes
  // (e.g. the epipolar constraint: the ratio test then runs among geometrically possible pairs,
  // which a repetitive texture — a facade, a road, a pipe — otherwise fails); `off_pair_ratio`
  // (> 0) still asks the match to beat the nearest refused candidate by that ratio (a look-alike
  // elsewhere in the image: sand ripples).
  std::vector<std::pair<int, int>> MatchByAppearance(const Features& a, const std::function<bool(int)>& use_a,
                                                     const Features& b, const std::function<bool(int)>& use_b, int th,
                                                     double ratio,
                                                     const std::function<bool(int, int)>& pair_ok = nullptr,
                                                     double off_pair_ratio = 0.0) const;

  // --------------------------------------------------------------- initialisation
  struct Reconstruction {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<std::pair<int, Eigen::Vector3d>> points;  ///< match index -> X in camera 1
    double parallax_deg = 0;
    int inliers = 0;  ///< the model's RANSAC inliers
    int good = 0;     ///< inliers in front of both cameras and reprojected well (any parallax)
  };

  static bool Triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2,
                          const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, Eigen::Vector3d* X);

  // Triangulates the matched pairs for motion (R, t) of camera 2 w.r.t. camera 1 and keeps the
  // points in front of both cameras that reproject within the gate.
  Reconstruction CheckMotion(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Features& f1, const Features& f2,
                             const std::vector<std::pair<int, int>>& matches, const std::vector<uchar>& inlier) const;

  SlamFrameSummary TryInitialize(SlamFrameSummary s);

  int NewKeyFrame(const Frame& f);

  void CreateInitialMap(const Reconstruction& rec, const std::vector<std::pair<int, int>>& matches);

  // --------------------------------------------------------------------- tracking
  bool Visible(const MapPoint& p, const Eigen::Isometry3d& T_cw, Eigen::Vector2d* uv, int* level,
               double* view_cos) const;

  // Searches each point's projection for the best unmatched feature. Returns new matches.
  int SearchByProjection(Frame* f, const std::vector<int>& pts, double radius_factor, bool count_visible, int th);

  int Optimize(Frame* f);

  /// Projects the last frame's points from a predicted pose: the IMU's when given, else the
  /// constant-velocity model's.
  bool TrackWithMotionModel(const std::optional<Eigen::Isometry3d>& predicted);

  bool TrackReferenceKeyFrame();

  void UpdateLocalMap();

  int TrackLocalMap();

  bool Relocalize();
  /// The relocalisation gate (MonoSlamOptions::reloc_gate_*): cur.T_cw against last.T_cw.
  bool PlausibleRelocalization(std::string* why) const;
  static Eigen::Vector3d CameraCentre(const Eigen::Isometry3d& T_cw) {
    return -(T_cw.linear().transpose() * T_cw.translation());
  }

  // --------------------------------------------------------------------- mapping
  bool NeedKeyFrame(int inliers) const;

  void Fuse(int kf_id, const std::vector<int>& pts);

  void CullRecentPoints(int kf_id);

  void CreateNewMapPoints(int kf_id);

  void SearchInNeighbors(int kf_id);

  void InsertKeyFrame();

  // ------------------------------------------------------------------ loop closing
  struct LoopCandidate {
    int kf;
    Sim3 S_cm;
    std::vector<std::pair<int, int>> matches;  ///< current feature -> loop map point
  };

  /// Groups of keyframes that stayed candidates over consecutive keyframes (loop or merge).
  using CandidateGroups = std::vector<std::pair<std::set<int>, int>>;

  /// Keyframes of `other` (searched in `other_db`, not in `exclude`) that look like keyframe kid
  /// of the current map at least as much as its weakest covisible neighbour (x
  /// loop_min_score_ratio), and whose covisible group was a candidate for loop_consistency
  /// keyframes in a row (`groups`: the previous keyframe's, replaced).
  std::vector<int> ConsistentCandidates(int kid, const Map& other, const BowDatabase& other_db,
                                        const std::set<int>& exclude, CandidateGroups* groups) const;

  std::vector<int> DetectLoopCandidates(int kid);

  /// The Sim(3) from keyframe `cand` of `other` (the current map for a loop, an earlier map for
  /// a merge) to keyframe kid of the current map, verified by RANSAC, optimisation and a guided
  /// search of cand's neighbourhood; for a loop also the plausibility of its correction.
  bool ComputeSim3(int kid, const Map& other, int cand, LoopCandidate* lc);

  void CorrectLoop(int kid, const LoopCandidate& lc);

  /// The matches (kid's feature -> a point of the loop side) become kid's points, and the loop
  /// keyframe's neighbourhood's points are fused into the `connected` keyframes.
  void WeldLoopPoints(int kid, int loop_kf, const std::vector<std::pair<int, int>>& matches,
                      const std::vector<int>& connected);

  bool LoopClosing(int kid);

  // ----------------------------------------------------------------- atlas (mono_slam_atlas.cpp)
  /// A map whose tracking was lost for good, kept for merging.
  struct StoredMap {
    std::unique_ptr<Map> map;
    BowDatabase db;
    Sim3 G;  ///< its world -> global frame
    int number = 0;
    bool metric = false;
    std::vector<TrajEntry> traj;
    CandidateGroups groups;  ///< merge candidates of the current map's last keyframe
  };
  std::deque<StoredMap> atlas;

  /// Keeps the current map in the atlas (at reset, when it is worth keeping).
  void StoreCurrentMap();
  /// After keyframe kid: looks for its place in the stored maps and merges the first found.
  bool MergeMaps(int kid);
  /// Moves stored map `old` into the current map, placed by A (old world -> current world),
  /// and welds it at kid with lc's matches (their point ids are old's).
  void AbsorbMap(StoredMap&& old, const Sim3& A, int kid, const LoopCandidate& lc);

  // ----------------------------------------------------------------- bookkeeping
  Eigen::Isometry3d ToGlobal(const Eigen::Isometry3d& T_wc) const;

  /// The current map's tracked frames from traj[from] on, in the global frame.
  std::vector<StampedPose> CurrentTrajectory(std::size_t from = 0) const;

  void ResetForReinitialization();

  SlamFrameSummary Track(const cv::Mat& gray, double stamp);

  void UpdateGoodPose();
};

}  // namespace unav::localization
