#include "unav_localization/klt_vo.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

#include "pnp_pose.hpp"

namespace unav::localization {

bool KltVoOptions::IsValid(std::string* msg) const {
  auto fail = [&](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (max_features < 10) return fail("max_features must be >= 10, got " + std::to_string(max_features));
  if (!(min_corner_distance > 0)) return fail("min_corner_distance must be > 0");
  if (redetect_below < 0 || redetect_below > max_features) return fail("redetect_below must be in [0, max_features]");
  if (!(fb_max_error_px > 0) || !(ransac_reprojection_px > 0)) return fail("pixel thresholds must be > 0");
  if (min_inliers < 6) return fail("min_inliers must be >= 6, got " + std::to_string(min_inliers));
  if (!(min_depth_m > 0) || !(max_depth_m > min_depth_m)) return fail("need 0 < min_depth_m < max_depth_m");
  if (!(max_step_rotation_rad > 0) || !(max_step_translation_m > 0)) return fail("step limits must be > 0");
  if (mode != Mode::kRgbd && mode != Mode::kMonocular) return fail("mode must be kRgbd or kMonocular");
  if (!(min_init_parallax_px > 0))
    return fail("min_init_parallax_px must be > 0, got " + std::to_string(min_init_parallax_px));
  if (min_init_tracks < 8 || min_init_tracks > max_features)
    return fail("min_init_tracks must be in [8, max_features = " + std::to_string(max_features) + "], got " +
                std::to_string(min_init_tracks));
  if (min_init_points < min_inliers || min_init_points > min_init_tracks)
    return fail("min_init_points must be in [min_inliers = " + std::to_string(min_inliers) +
                ", min_init_tracks = " + std::to_string(min_init_tracks) + "], got " + std::to_string(min_init_points));
  if (!(keyframe_parallax_px > 0))
    return fail("keyframe_parallax_px must be > 0, got " + std::to_string(keyframe_parallax_px));
  if (keyframe_min_points < min_inliers || keyframe_min_points > max_features)
    return fail("keyframe_min_points must be in [min_inliers = " + std::to_string(min_inliers) +
                ", max_features = " + std::to_string(max_features) + "], got " + std::to_string(keyframe_min_points));
  if (!(min_triangulation_angle_rad > 0) || !(min_triangulation_angle_rad < M_PI / 2))
    return fail("min_triangulation_angle_rad must be in (0, pi/2), got " + std::to_string(min_triangulation_angle_rad));
  if (!(max_triangulation_reprojection_px > 0))
    return fail("max_triangulation_reprojection_px must be > 0, got " +
                std::to_string(max_triangulation_reprojection_px));
  if (!(max_step_translation_depth > 0))
    return fail("max_step_translation_depth must be > 0, got " + std::to_string(max_step_translation_depth));
  if (grid_cols < 1 || grid_rows < 1 || grid_cols * grid_rows > max_features)
    return fail("grid_cols and grid_rows must be >= 1 with grid_cols * grid_rows <= max_features, got " +
                std::to_string(grid_cols) + " x " + std::to_string(grid_rows));
  return true;
}

const char* to_string(VoStatus s) {
  switch (s) {
    case VoStatus::kInitialized:
      return "initialized";
    case VoStatus::kTracking:
      return "tracking";
    case VoStatus::kLost:
      return "lost";
    case VoStatus::kInvalidInput:
      return "invalid input";
    case VoStatus::kInitializing:
      return "initializing";
  }
  return "?";
}

KltVo::KltVo(const Eigen::Matrix3d& K, const KltVoOptions& options) : options_(options) {
  std::string msg;
  if (!options.IsValid(&msg)) throw std::invalid_argument("KltVoOptions: " + msg);
  if (!(K(0, 0) > 0) || !(K(1, 1) > 0) || !K.allFinite())
    throw std::invalid_argument("KltVo: intrinsics need fx, fy > 0 and finite values");
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K_(r, c) = K(r, c);
}

void KltVo::detect(const cv::Mat& gray) {
  cv::Mat mask(gray.size(), CV_8UC1, cv::Scalar(255));
  for (const auto& p : prev_pts_)
    cv::circle(mask, p, static_cast<int>(options_.min_corner_distance), cv::Scalar(0), -1);
  std::vector<cv::Point2f> fresh;
  const int want = options_.max_features - static_cast<int>(prev_pts_.size());
  if (want <= 0) return;
  cv::goodFeaturesToTrack(gray, fresh, want, 0.01, options_.min_corner_distance, mask, 5);
  prev_pts_.insert(prev_pts_.end(), fresh.begin(), fresh.end());
}

namespace {

// Bilinear depth at a sub-pixel position; NaN when any neighbour is missing.
float depth_at(const cv::Mat& depth, const cv::Point2f& p) {
  const int u = static_cast<int>(std::floor(p.x)), v = static_cast<int>(std::floor(p.y));
  if (u < 0 || v < 0 || u + 1 >= depth.cols || v + 1 >= depth.rows) return NAN;
  const float a = p.x - static_cast<float>(u), b = p.y - static_cast<float>(v);
  const float d00 = depth.at<float>(v, u), d01 = depth.at<float>(v, u + 1), d10 = depth.at<float>(v + 1, u),
              d11 = depth.at<float>(v + 1, u + 1);
  // Depth edges (pipe against sand) would interpolate to a surface that is not there.
  const float lo = std::min(std::min(d00, d01), std::min(d10, d11)),
              hi = std::max(std::max(d00, d01), std::max(d10, d11));
  if (!(hi - lo < 0.05f * lo)) return NAN;
  return (1 - a) * (1 - b) * d00 + a * (1 - b) * d01 + (1 - a) * b * d10 + a * b * d11;
}

}  // namespace

void KltVo::make_keyframe(const cv::Mat& gray, const cv::Mat& depth) {
  detect(gray);
  kf_points_.clear();
  std::vector<cv::Point2f> pts;
  for (const auto& p : prev_pts_) {
    const float z = depth_at(depth, p);
    if (!std::isfinite(z) || z < options_.min_depth_m || z > options_.max_depth_m) continue;
    kf_points_.emplace_back(static_cast<float>((p.x - K_(0, 2)) * z / K_(0, 0)),
                            static_cast<float>((p.y - K_(1, 2)) * z / K_(1, 1)), z);
    pts.push_back(p);
  }
  prev_pts_ = pts;
  T_C0K_ = T_C0C_;
}

VoSummary KltVo::ProcessFrame(const cv::Mat& gray, const cv::Mat& depth, Eigen::Isometry3d* T_C0C) {
  VoSummary s;
  if (options_.mode != KltVoOptions::Mode::kRgbd) {
    s.message = "KltVo is in monocular mode: call ProcessFrame(gray, T_C0C)";
    if (T_C0C) *T_C0C = T_C0C_;
    return s;
  }
  if (gray.empty() || gray.type() != CV_8UC1 || depth.type() != CV_32FC1 || depth.size() != gray.size()) {
    s.message = "need CV_8UC1 gray and CV_32FC1 depth of the same size";
    if (T_C0C) *T_C0C = T_C0C_;
    return s;
  }
  if (!initialized_) {
    prev_pts_.clear();
    make_keyframe(gray, depth);
    prev_gray_ = gray.clone();
    initialized_ = true;
    s.status = VoStatus::kInitialized;
    s.tracked = static_cast<int>(prev_pts_.size());
    if (T_C0C) *T_C0C = T_C0C_;
    return s;
  }
  // Track the keyframe's corners from the previous frame into this one (forward-backward checked);
  // each keeps the 3D point lifted in the keyframe, so PnP is against the keyframe and errors do not
  // accumulate frame to frame between keyframes.
  std::vector<cv::Point2f> fwd, back;
  std::vector<unsigned char> st1, st2;
  std::vector<float> err;
  if (!prev_pts_.empty()) {
    cv::calcOpticalFlowPyrLK(prev_gray_, gray, prev_pts_, fwd, st1, err, cv::Size(21, 21), 3);
    cv::calcOpticalFlowPyrLK(gray, prev_gray_, fwd, back, st2, err, cv::Size(21, 21), 3);
  }
  std::vector<cv::Point3f> obj;
  std::vector<cv::Point2f> img;
  for (size_t i = 0; i < prev_pts_.size(); ++i) {
    if (!st1[i] || !st2[i] || cv::norm(back[i] - prev_pts_[i]) > options_.fb_max_error_px) continue;
    if (fwd[i].x < 0 || fwd[i].y < 0 || fwd[i].x >= gray.cols || fwd[i].y >= gray.rows) continue;
    obj.push_back(kf_points_[i]);
    img.push_back(fwd[i]);
  }
  s.tracked = static_cast<int>(img.size());
  bool ok = false;
  Eigen::Isometry3d X_cur_kf = Eigen::Isometry3d::Identity();
  if (static_cast<int>(obj.size()) >= options_.min_inliers) {
    // Start from the constant-velocity prediction of this frame in the keyframe: every RANSAC
    // hypothesis and the final refinement iterate from it. From no guess, the solver starts from a
    // homography of these near-planar points (the seabed seen from above), which has a mirrored
    // twin; seen: 277 of 293 tracks "inliers" to a pose 2 m and 35 deg off.
    cv::Mat rvec, tvec;
    detail::ToRvecTvec((T_C0K_.inverse() * (T_C0C_ * last_motion_)).inverse(), &rvec, &tvec);
    std::vector<int> inliers;
    ok =
        cv::solvePnPRansac(obj, img, K_, cv::noArray(), rvec, tvec, true, 200,
                           static_cast<float>(options_.ransac_reprojection_px), 0.999, inliers, cv::SOLVEPNP_ITERATIVE);
    s.inliers = static_cast<int>(inliers.size());
    ok = ok && s.inliers >= options_.min_inliers && 10 * s.inliers >= 3 * static_cast<int>(obj.size());
    if (ok) {
      X_cur_kf = detail::FromRvecTvec(rvec, tvec);
      // Keep only inlier tracks.
      std::vector<cv::Point3f> obj_in;
      std::vector<cv::Point2f> img_in;
      obj_in.reserve(inliers.size());
      img_in.reserve(inliers.size());
      for (int i : inliers) {
        obj_in.push_back(obj[static_cast<size_t>(i)]);
        img_in.push_back(img[static_cast<size_t>(i)]);
      }
      obj.swap(obj_in);
      img.swap(img_in);
    }
  }
  const Eigen::Isometry3d previous = T_C0C_;
  if (ok) {
    // A planar scene can give PnP a mirrored solution with plenty of inliers: reject steps no
    // vehicle makes between two frames.
    const Eigen::Isometry3d step = previous.inverse() * (T_C0K_ * X_cur_kf.inverse());
    const double angle = Eigen::AngleAxisd(step.linear()).angle();
    if (angle > options_.max_step_rotation_rad || step.translation().norm() > options_.max_step_translation_m) {
      ok = false;
      s.inliers = 0;
    }
  }
  if (ok) {
    T_C0C_ = Renormalized(T_C0K_ * X_cur_kf.inverse());
    last_motion_ = Renormalized(previous.inverse() * T_C0C_);
    kf_points_ = obj;
    prev_pts_ = img;
    s.status = VoStatus::kTracking;
  } else {
    T_C0C_ = Renormalized(T_C0C_ * last_motion_);  // constant-velocity prediction
    s.status = VoStatus::kLost;
    s.message = "no consistent PnP solution (" + std::to_string(s.tracked) + " tracks): constant-velocity prediction";
    prev_pts_.clear();
  }
  if (static_cast<int>(prev_pts_.size()) < options_.redetect_below) make_keyframe(gray, depth);
  prev_gray_ = gray.clone();
  if (T_C0C) *T_C0C = T_C0C_;
  return s;
}

Eigen::Isometry3d KltVo::Renormalized(const Eigen::Isometry3d& T) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(T.linear()).normalized().toRotationMatrix();
  out.translation() = T.translation();
  return out;
}

// ---------------------------------------------------------------------------------------------
// Monocular mode.

}  // namespace unav::localization
