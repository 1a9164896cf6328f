// KltVo, monocular mode: two-view initialisation (essential matrix / homography), PnP tracking
// of triangulated points, keyframe triangulation, re-initialisation keeping pose and scale.
// The RGB-D mode and the shared parts are in klt_vo.cpp.
#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>
#include <stdexcept>
#include "pnp_pose.hpp"
#include "unav_localization/klt_vo.hpp"
#include "unav_localization/two_view.hpp"

namespace unav::localization {

namespace {

enum class PointCheck { kGood, kLowParallax, kBad };

Eigen::Vector2d normalized(const cv::Matx33d& K, const cv::Point2f& u) {
  return {(u.x - K(0, 2)) / K(0, 0), (u.y - K(1, 2)) / K(1, 1)};
}

// Linear (DLT) triangulation of normalised image points x1, x2; T_21 maps frame 1 into frame 2.
// Returns the point in frame 1 (non-finite when it is at infinity).
Eigen::Vector3d triangulate(const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, const Eigen::Isometry3d& T_21) {
  Eigen::Matrix<double, 3, 4> P1 = Eigen::Matrix<double, 3, 4>::Zero();
  P1.leftCols<3>().setIdentity();
  const Eigen::Matrix<double, 3, 4> P2 = T_21.matrix().topRows<3>();
  Eigen::Matrix4d A;
  A.row(0) = x1.x() * P1.row(2) - P1.row(0);
  A.row(1) = x1.y() * P1.row(2) - P1.row(1);
  A.row(2) = x2.x() * P2.row(2) - P2.row(0);
  A.row(3) = x2.y() * P2.row(2) - P2.row(1);
  const Eigen::Vector4d X = Eigen::JacobiSVD<Eigen::Matrix4d>(A, Eigen::ComputeFullV).matrixV().col(3);
  return X.head<3>() / X[3];
}

// A triangulated point is mapped when the rays meet at a usable angle, it lies in front of both
// cameras and reprojects close to both observations.
PointCheck check_point(const Eigen::Vector3d& p_1, const Eigen::Isometry3d& T_21, const cv::Point2f& u1,
                       const cv::Point2f& u2, const cv::Matx33d& K, const KltVoOptions& o) {
  if (!p_1.allFinite()) return PointCheck::kLowParallax;
  const Eigen::Vector3d c2_1 = T_21.inverse().translation();
  const Eigen::Vector3d r2 = p_1 - c2_1;
  const double cos_angle = p_1.dot(r2) / (p_1.norm() * r2.norm());
  if (!(std::acos(std::clamp(cos_angle, -1.0, 1.0)) >= o.min_triangulation_angle_rad)) return PointCheck::kLowParallax;
  const Eigen::Vector3d p_2 = T_21 * p_1;
  if (!(p_1.z() > 0) || !(p_2.z() > 0)) return PointCheck::kBad;
  auto err = [&](const Eigen::Vector3d& p, const cv::Point2f& u) {
    return std::hypot(K(0, 0) * p.x() / p.z() + K(0, 2) - u.x, K(1, 1) * p.y() / p.z() + K(1, 2) - u.y);
  };
  if (err(p_1, u1) > o.max_triangulation_reprojection_px || err(p_2, u2) > o.max_triangulation_reprojection_px)
    return PointCheck::kBad;
  return PointCheck::kGood;
}

double median(std::vector<double> v) {
  if (v.empty()) return NAN;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

Eigen::Isometry3d to_isometry(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  T.translation() = t;
  return T;
}

// One two-view hypothesis T_CR (reference into current camera) and the points it triangulates.
struct TwoView {
  Eigen::Isometry3d T_CR = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> p_R;
  std::vector<char> good;
  int n_good = 0;
};

TwoView evaluate_two_view(const Eigen::Isometry3d& T_CR, const std::vector<cv::Point2f>& ref,
                          const std::vector<cv::Point2f>& cur, const cv::Matx33d& K, const KltVoOptions& o) {
  TwoView v;
  v.T_CR = T_CR;
  v.p_R.resize(ref.size());
  v.good.assign(ref.size(), 0);
  for (size_t i = 0; i < ref.size(); ++i) {
    v.p_R[i] = triangulate(normalized(K, ref[i]), normalized(K, cur[i]), T_CR);
    v.good[i] = check_point(v.p_R[i], T_CR, ref[i], cur[i], K, o) == PointCheck::kGood;
    v.n_good += v.good[i];
  }
  return v;
}

}  // namespace

void KltVo::track_klt(const cv::Mat& gray, std::vector<Track>* tracks) const {
  if (tracks->empty()) return;
  std::vector<cv::Point2f> p0, fwd, back;
  p0.reserve(tracks->size());
  for (const auto& t : *tracks) p0.push_back(t.px);
  std::vector<unsigned char> st1, st2;
  std::vector<float> err;
  cv::calcOpticalFlowPyrLK(prev_gray_, gray, p0, fwd, st1, err, cv::Size(21, 21), 3);
  cv::calcOpticalFlowPyrLK(gray, prev_gray_, fwd, back, st2, err, cv::Size(21, 21), 3);
  std::vector<Track> kept;
  kept.reserve(tracks->size());
  for (size_t i = 0; i < p0.size(); ++i) {
    if (!st1[i] || !st2[i] || cv::norm(back[i] - p0[i]) > options_.fb_max_error_px) continue;
    if (fwd[i].x < 0 || fwd[i].y < 0 || fwd[i].x >= gray.cols || fwd[i].y >= gray.rows) continue;
    kept.push_back((*tracks)[i]);
    kept.back().px = fwd[i];
  }
  tracks->swap(kept);
}

// New corners, away from the current tracks, spread over a grid: each cell first gets its share of
// the strongest corners, then what is left of the budget goes to the strongest of the rest (a
// textureless cell gives none, so the quality threshold stays relative to the whole image).
void KltVo::mono_detect(const cv::Mat& gray) {
  const int want = options_.max_features - static_cast<int>(tracks_.size());
  if (want <= 0) return;
  cv::Mat mask(gray.size(), CV_8UC1, cv::Scalar(255));
  for (const auto& t : tracks_)
    cv::circle(mask, t.px, static_cast<int>(options_.min_corner_distance), cv::Scalar(0), -1);
  std::vector<cv::Point2f> all;
  cv::goodFeaturesToTrack(gray, all, 4 * want, 0.01, options_.min_corner_distance, mask, 5);
  const int cells = options_.grid_cols * options_.grid_rows;
  const int per_cell = std::max(1, want / cells);
  std::vector<int> count(static_cast<size_t>(cells), 0);
  std::vector<char> taken(all.size(), 0);
  int added = 0;
  auto add = [&](size_t i) {
    Track t;
    t.px = t.kf_px = t.birth_px = all[i];
    t.T_C0B = T_C0C_;
    tracks_.push_back(t);
    taken[i] = 1;
    ++added;
  };
  for (size_t i = 0; i < all.size() && added < want; ++i) {
    const int cx = std::min(options_.grid_cols - 1, static_cast<int>(all[i].x * options_.grid_cols / gray.cols));
    const int cy = std::min(options_.grid_rows - 1, static_cast<int>(all[i].y * options_.grid_rows / gray.rows));
    int& n = count[static_cast<size_t>(cy) * static_cast<size_t>(options_.grid_cols) + static_cast<size_t>(cx)];
    if (n < per_cell) {
      ++n;
      add(i);
    }
  }
  for (size_t i = 0; i < all.size() && added < want; ++i)
    if (!taken[i]) add(i);
}

void KltVo::mono_start_reference(const cv::Mat& gray) {
  tracks_.clear();
  T_C0C_ = T_C0R_;
  mono_detect(gray);
  mono_state_ =
      static_cast<int>(tracks_.size()) >= options_.min_init_tracks ? MonoState::kInitializing : MonoState::kNoReference;
}

double KltVo::median_depth() const {
  const Eigen::Isometry3d T_CC0 = T_C0C_.inverse();
  std::vector<double> z;
  for (const auto& t : tracks_)
    if (t.has_point) z.push_back((T_CC0 * t.p_C0).z());
  return median(z);
}

// Two-view initialisation between the reference frame (birth_px, pose T_C0R_) and this frame (px).
bool KltVo::mono_initialize(VoSummary* s) {
  std::vector<cv::Point2f> ref, cur;
  for (const auto& t : tracks_) {
    ref.push_back(t.birth_px);
    cur.push_back(t.px);
  }
  TwoView best;
  std::string from = "none";
  TwoViewOptions two_view;
  two_view.homography_ransac_px = options_.ransac_reprojection_px;
  const std::vector<TwoViewCandidate> candidates = TwoViewCandidates(ref, cur, K_, two_view);
  // Essential matrix: general 3-D scenes.
  for (const auto& c : candidates) {
    if (c.model != TwoViewCandidate::Model::kEssential) continue;
    best = evaluate_two_view(to_isometry(c.R, c.t), ref, cur, K_, options_);
    from = "essential";
  }
  const int n_essential = best.n_good;
  // Homography: a plane (the seabed). Of its up to four decompositions keep the one that puts the
  // most points in front of both cameras with low reprojection error; it must clearly beat the
  // runner-up (two decompositions can both be physically valid for a plane seen head-on).
  int n_homography = 0;
  TwoView best_h;
  int second = 0;
  bool any_h = false;
  for (const auto& c : candidates) {
    if (c.model != TwoViewCandidate::Model::kHomography) continue;
    any_h = true;
    TwoView v = evaluate_two_view(to_isometry(c.R, c.t), ref, cur, K_, options_);
    if (v.n_good > best_h.n_good) {
      second = best_h.n_good;
      best_h = std::move(v);
    } else {
      second = std::max(second, v.n_good);
    }
  }
  if (any_h) {
    n_homography = best_h.n_good;
    // Ties go to the homography: when one plane explains the tracks as well as a general scene
    // does, the essential matrix is the worse-conditioned model.
    if (4 * second < 3 * best_h.n_good && best_h.n_good >= best.n_good) {
      best = std::move(best_h);
      from = "homography";
    }
  }
  s->inliers = best.n_good;
  s->message = "initialisation from the " + from + " (well-triangulated points: essential " +
               std::to_string(n_essential) + ", homography " + std::to_string(n_homography) + ")";
  if (best.n_good < options_.min_init_points) {
    s->message = "initialisation failed: " + s->message;
    return false;
  }
  // Scale: the median depth of the initial points is map_median_depth_ (1 for the first map).
  std::vector<double> z;
  for (size_t i = 0; i < ref.size(); ++i)
    if (best.good[i]) z.push_back(best.p_R[i].z());
  const double scale = map_median_depth_ / median(z);
  Eigen::Isometry3d T_CR = best.T_CR;
  T_CR.translation() *= scale;
  T_C0C_ = Renormalized(T_C0R_ * T_CR.inverse());
  for (size_t i = 0; i < tracks_.size(); ++i) {
    tracks_[i].T_C0B = T_C0R_;
    if (!best.good[i]) continue;
    tracks_[i].has_point = true;
    tracks_[i].p_C0 = T_C0R_ * (scale * best.p_R[i]);
  }
  last_motion_ = Eigen::Isometry3d::Identity();
  return true;
}

// Pose of this frame from PnP + RANSAC of the tracked map points (tracks_ already tracked into it).
bool KltVo::mono_track(VoSummary* s) {
  std::vector<cv::Point3f> obj;
  std::vector<cv::Point2f> img;
  std::vector<size_t> idx;
  for (size_t i = 0; i < tracks_.size(); ++i) {
    if (!tracks_[i].has_point) continue;
    const Eigen::Vector3d& p = tracks_[i].p_C0;
    obj.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    img.push_back(tracks_[i].px);
    idx.push_back(i);
  }
  if (static_cast<int>(obj.size()) < options_.min_inliers) {
    s->message = "only " + std::to_string(obj.size()) + " map points tracked";
    return false;
  }
  // Initial guess: constant-velocity prediction.
  cv::Mat rvec, tvec;
  detail::ToRvecTvec((T_C0C_ * last_motion_).inverse(), &rvec, &tvec);
  std::vector<int> ransac_inliers;
  bool ok = cv::solvePnPRansac(obj, img, K_, cv::noArray(), rvec, tvec, true, 100,
                               static_cast<float>(options_.ransac_reprojection_px), 0.999, ransac_inliers,
                               cv::SOLVEPNP_ITERATIVE);
  ok = ok && static_cast<int>(ransac_inliers.size()) >= options_.min_inliers;
  std::vector<char> inlier(obj.size(), 0);
  int n_in = 0;
  if (ok) {
    // Refine on the RANSAC inliers, then take the inliers of the refined pose.
    std::vector<cv::Point3f> obj_in;
    std::vector<cv::Point2f> img_in;
    for (int i : ransac_inliers) {
      obj_in.push_back(obj[static_cast<size_t>(i)]);
      img_in.push_back(img[static_cast<size_t>(i)]);
    }
    cv::solvePnPRefineLM(obj_in, img_in, K_, cv::noArray(), rvec, tvec);
    std::vector<cv::Point2f> proj;
    cv::projectPoints(obj, rvec, tvec, K_, cv::noArray(), proj);
    for (size_t i = 0; i < obj.size(); ++i) {
      inlier[i] = cv::norm(proj[i] - img[i]) <= options_.ransac_reprojection_px;
      n_in += inlier[i];
    }
  }
  s->inliers = n_in;
  if (!ok || n_in < options_.min_inliers || 10 * n_in < 3 * static_cast<int>(obj.size())) {
    s->message = "no consistent PnP solution (" + std::to_string(n_in) + " inliers of " + std::to_string(obj.size()) +
                 " map points)";
    return false;
  }
  const Eigen::Isometry3d T_C0C_new = detail::FromRvecTvec(rvec, tvec).inverse();
  // A planar scene can give PnP a mirrored solution with plenty of inliers: reject steps no
  // vehicle makes between two frames (translation in units of the scene depth: scale is arbitrary).
  const Eigen::Isometry3d step = T_C0C_.inverse() * T_C0C_new;
  const double depth = median_depth();
  if (Eigen::AngleAxisd(step.linear()).angle() > options_.max_step_rotation_rad ||
      !(step.translation().norm() <= options_.max_step_translation_depth * depth)) {
    s->inliers = 0;
    s->message = "PnP step too large for one frame";
    return false;
  }
  std::vector<char> drop(tracks_.size(), 0);
  for (size_t k = 0; k < idx.size(); ++k) drop[idx[k]] = !inlier[k];
  std::vector<Track> kept;
  for (size_t i = 0; i < tracks_.size(); ++i)
    if (!drop[i]) kept.push_back(tracks_[i]);
  tracks_.swap(kept);
  last_motion_ = Renormalized(step);
  T_C0C_ = Renormalized(T_C0C_new);
  const double d = median_depth();
  if (std::isfinite(d) && d > 0) map_median_depth_ = d;
  return true;
}

// Keyframe: map the tracks that have enough parallax since they were detected, then add corners.
void KltVo::mono_keyframe(const cv::Mat& gray) {
  const Eigen::Isometry3d T_CC0 = T_C0C_.inverse();
  std::vector<Track> kept;
  kept.reserve(tracks_.size());
  for (auto& t : tracks_) {
    if (!t.has_point) {
      const Eigen::Isometry3d T_CB = T_CC0 * t.T_C0B;
      const Eigen::Vector3d p_B = triangulate(normalized(K_, t.birth_px), normalized(K_, t.px), T_CB);
      const PointCheck c = check_point(p_B, T_CB, t.birth_px, t.px, K_, options_);
      if (c == PointCheck::kBad) continue;
      if (c == PointCheck::kGood) {
        t.has_point = true;
        t.p_C0 = t.T_C0B * p_B;
      }
    }
    t.kf_px = t.px;
    kept.push_back(t);
  }
  tracks_.swap(kept);
  T_C0K_ = T_C0C_;
  mono_detect(gray);
}

VoSummary KltVo::ProcessFrame(const cv::Mat& gray, Eigen::Isometry3d* T_C0C) {
  VoSummary s;
  auto finish = [&]() {
    if (T_C0C) *T_C0C = T_C0C_;
    return s;
  };
  if (options_.mode != KltVoOptions::Mode::kMonocular) {
    s.message = "KltVo is in RGB-D mode: call ProcessFrame(gray, depth, T_C0C)";
    return finish();
  }
  if (gray.empty() || gray.type() != CV_8UC1) {
    s.message = "need a non-empty CV_8UC1 gray image";
    return finish();
  }
  if (!prev_gray_.empty() && gray.size() != prev_gray_.size()) {
    s.message = "image size changed from " + std::to_string(prev_gray_.cols) + "x" + std::to_string(prev_gray_.rows) +
                " to " + std::to_string(gray.cols) + "x" + std::to_string(gray.rows);
    return finish();
  }
  // Until a map exists there is no estimate: "initializing" the first time, "lost" after that.
  const VoStatus waiting = ever_initialized_ ? VoStatus::kLost : VoStatus::kInitializing;
  auto restart = [&](const std::string& why) {
    mono_start_reference(gray);
    s.status = waiting;
    s.message = why + (mono_state_ == MonoState::kInitializing ? "; new reference frame"
                                                               : "; too few corners for a reference frame");
  };
  switch (mono_state_) {
    case MonoState::kNoReference:
      restart(ever_initialized_ ? "re-initialising" : "initialising");
      break;
    case MonoState::kInitializing: {
      track_klt(gray, &tracks_);
      s.tracked = static_cast<int>(tracks_.size());
      if (s.tracked < options_.min_init_tracks) {
        restart("only " + std::to_string(s.tracked) + " tracks left from the reference frame");
        break;
      }
      std::vector<double> d;
      for (const auto& t : tracks_) d.push_back(cv::norm(t.px - t.birth_px));
      const double parallax = median(d);
      if (parallax < options_.min_init_parallax_px) {
        s.status = waiting;
        s.message = "waiting for parallax: " + std::to_string(parallax) + " px";
      } else if (mono_initialize(&s)) {
        mono_keyframe(gray);
        mono_state_ = MonoState::kTracking;
        ever_initialized_ = true;
        s.status = VoStatus::kInitialized;
      } else if (parallax > 3 * options_.min_init_parallax_px) {
        restart(s.message);
      } else {
        s.status = waiting;
      }
      break;
    }
    case MonoState::kTracking: {
      track_klt(gray, &tracks_);
      s.tracked = static_cast<int>(tracks_.size());
      if (mono_track(&s)) {
        s.status = VoStatus::kTracking;
        int points = 0;
        std::vector<double> d;
        for (const auto& t : tracks_) {
          points += t.has_point;
          d.push_back(cv::norm(t.px - t.kf_px));
        }
        if (points < options_.keyframe_min_points || static_cast<int>(tracks_.size()) < options_.redetect_below ||
            median(d) > options_.keyframe_parallax_px)
          mono_keyframe(gray);
      } else {
        // Start a new map whose reference pose is the last good pose, at the last map's depth.
        T_C0R_ = T_C0C_;
        last_motion_ = Eigen::Isometry3d::Identity();
        ever_initialized_ = true;
        const std::string why = s.message;
        restart("tracking lost: " + why);
        s.status = VoStatus::kLost;
      }
      break;
    }
  }
  prev_gray_ = gray.clone();
  return finish();
}

}  // namespace unav::localization
