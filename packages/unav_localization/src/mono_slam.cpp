#include "unav_localization/mono_slam.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <functional>
#include <cmath>
#include <random>
#include <set>
#include <stdexcept>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_localization/sim3.hpp"
#include "unav_localization/slam_optimizer.hpp"

namespace unav_localization {

namespace {
constexpr int kThHigh = 100;  // descriptor distance accepted when projection already constrains
constexpr int kThLow = 50;    // descriptor distance accepted for matching by appearance only
constexpr double kChi2Mono = 5.991;
using Clock = std::chrono::steady_clock;
double Ms(Clock::time_point a) { return std::chrono::duration<double, std::milli>(Clock::now() - a).count(); }

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
}  // namespace

bool MonoSlamOptions::IsValid(std::string* msg) const {
  auto fail = [msg](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (!orb.IsValid(msg)) return false;
  if (init_orb_features_factor < 1 || init_orb_features_factor > 5)
    return fail("init_orb_features_factor must be in [1, 5], got " + std::to_string(init_orb_features_factor));
  if (!(init_min_parallax_deg > 0 && init_min_parallax_deg < 30))
    return fail("init_min_parallax_deg must be in (0, 30), got " + std::to_string(init_min_parallax_deg));
  if (init_min_points < 20) return fail("init_min_points must be >= 20, got " + std::to_string(init_min_points));
  if (init_max_frames < 2) return fail("init_max_frames must be >= 2, got " + std::to_string(init_max_frames));
  if (min_tracked_inliers < 10) return fail("min_tracked_inliers must be >= 10, got " + std::to_string(min_tracked_inliers));
  if (keyframe_min_gap < 0 || keyframe_max_gap < 1 || keyframe_min_gap > keyframe_max_gap)
    return fail("keyframe gaps must satisfy 0 <= keyframe_min_gap <= keyframe_max_gap, >= 1; got " +
                std::to_string(keyframe_min_gap) + ", " + std::to_string(keyframe_max_gap));
  if (!(keyframe_tracked_ratio > 0 && keyframe_tracked_ratio < 1))
    return fail("keyframe_tracked_ratio must be in (0, 1), got " + std::to_string(keyframe_tracked_ratio));
  if (local_ba_keyframes < 2) return fail("local_ba_keyframes must be >= 2, got " + std::to_string(local_ba_keyframes));
  if (local_ba_iterations < 1) return fail("local_ba_iterations must be >= 1, got " + std::to_string(local_ba_iterations));
  if (mapping_neighbours < 1) return fail("mapping_neighbours must be >= 1, got " + std::to_string(mapping_neighbours));
  if (loop_consistency < 0) return fail("loop_consistency must be >= 0, got " + std::to_string(loop_consistency));
  if (loop_min_inliers < 20) return fail("loop_min_inliers must be >= 20, got " + std::to_string(loop_min_inliers));
  if (!(loop_max_correction_ratio > 0)) return fail("loop_max_correction_ratio must be > 0, got " + std::to_string(loop_max_correction_ratio));
  if (loop_min_keyframe_gap < 5) return fail("loop_min_keyframe_gap must be >= 5, got " + std::to_string(loop_min_keyframe_gap));
  if (global_ba_iterations < 1) return fail("global_ba_iterations must be >= 1, got " + std::to_string(global_ba_iterations));
  if (relocalize_frames < 0) return fail("relocalize_frames must be >= 0, got " + std::to_string(relocalize_frames));
  return true;
}

const char* to_string(SlamState state) {
  switch (state) {
    case SlamState::kInitializing: return "initializing";
    case SlamState::kTracking: return "tracking";
    case SlamState::kRelocalized: return "relocalized";
    case SlamState::kLost: return "lost";
    case SlamState::kInvalidInput: return "invalid_input";
  }
  return "?";
}

struct MonoSlam::Impl {
  struct Frame {
    int index = -1;
    double stamp = 0;
    Features f;
    std::vector<int> points;     ///< feature -> map point (-1)
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
  Frame cur, last;
  bool last_tracked = false;
  bool has_velocity = false;
  Eigen::Isometry3d velocity = Eigen::Isometry3d::Identity();
  int frame_index = 0;
  int ref_kf = -1, last_kf_frame = -1, last_reloc_frame = -1000;
  int lost_frames_in_row = 0;
  std::vector<int> local_kfs, local_points;
  std::vector<int> recent_points;
  std::vector<std::pair<std::set<int>, int>> consistent_groups;
  std::string loop_log;  ///< verified loop candidates of the current keyframe (summary message)
  std::vector<TrajEntry> traj;
  std::vector<StampedPose> frozen;  ///< trajectories of earlier maps, in the global frame
  Sim3 G;                          ///< current map's world -> global frame
  int map_number = 0;
  Eigen::Isometry3d last_good_T_wc_global = Eigen::Isometry3d::Identity();
  int last_good_ref_kf = -1;  ///< reference keyframe of the last tracked frame
  SlamStats stats;
  std::mt19937 rng{12345};

  // ---------------------------------------------------------------- features
  void ExtractFeatures(const cv::Mat& gray, const OrbExtractor& extractor, Frame* f) {
    extractor.Extract(gray, &f->f.keypoints, &f->f.descriptors);
    f->f.un.resize(f->f.keypoints.size());
    if (!f->f.keypoints.empty()) {
      std::vector<cv::Point2f> pts, und;
      for (const auto& k : f->f.keypoints) pts.push_back(k.pt);
      if (!D.empty()) cv::undistortPoints(pts, und, K, D, cv::noArray(), K);
      else und = pts;
      for (size_t i = 0; i < und.size(); ++i) f->f.un[i] = Eigen::Vector2d(und[i].x, und[i].y);
    }
    f->f.BuildGrid(cam.width, cam.height, 16.0);
    f->points.assign(f->f.size(), -1);
    f->outlier.assign(f->f.size(), false);
  }
  void ComputeBow(Features* f) const {
    if (voc && f->bow.empty() && !f->descriptors.empty()) voc->Transform(f->descriptors, &f->bow, &f->feature_vector, std::max(0, voc->levels() - 1));
  }
  double InvSigma2(const Features& f, int i) const { return 1.0 / sigma2[static_cast<size_t>(f.keypoints[static_cast<size_t>(i)].octave)]; }

  int PredictLevel(const MapPoint& p, double dist) const {
    const double ratio = p.max_distance / std::max(dist, 1e-9);
    const int level = static_cast<int>(std::ceil(std::log(ratio) / log_scale));
    return std::clamp(level, 0, opt.orb.levels - 1);
  }

  // Matches features of a (filtered) to features of b (filtered) by appearance: within the same
  // vocabulary node when both have feature vectors, else all pairs. Best distance <= th and a
  // ratio test against the second best.
  std::vector<std::pair<int, int>> MatchByAppearance(const Features& a, const std::function<bool(int)>& use_a, const Features& b,
                                                     const std::function<bool(int)>& use_b, int th, double ratio) const {
    std::vector<std::pair<int, int>> out;
    std::vector<int> best_for_b(b.size(), -1), best_dist_b(b.size(), 256);
    auto match_sets = [&](const std::vector<int>& ia, const std::vector<int>& ib) {
      for (int i : ia) {
        if (!use_a(i)) continue;
        BestTwo m;
        for (int j : ib)
          if (use_b(j)) m.Add(DescriptorDistance(a.desc(i), b.desc(j)), j);
        const int best = m.best, bj = m.index;
        if (bj < 0 || best > th || best >= ratio * m.second) continue;
        if (best < best_dist_b[static_cast<size_t>(bj)]) {
          best_dist_b[static_cast<size_t>(bj)] = best;
          best_for_b[static_cast<size_t>(bj)] = i;
        }
      }
    };
    if (!a.feature_vector.empty() && !b.feature_vector.empty()) {
      auto ita = a.feature_vector.begin();
      auto itb = b.feature_vector.begin();
      while (ita != a.feature_vector.end() && itb != b.feature_vector.end()) {
        if (ita->first == itb->first) {
          match_sets(ita->second, itb->second);
          ++ita;
          ++itb;
        } else if (ita->first < itb->first) {
          ++ita;
        } else {
          ++itb;
        }
      }
    } else {
      std::vector<int> ia(a.size()), ib(b.size());
      for (size_t i = 0; i < ia.size(); ++i) ia[i] = static_cast<int>(i);
      for (size_t j = 0; j < ib.size(); ++j) ib[j] = static_cast<int>(j);
      match_sets(ia, ib);
    }
    for (size_t j = 0; j < b.size(); ++j)
      if (best_for_b[j] >= 0) out.emplace_back(best_for_b[j], static_cast<int>(j));
    return out;
  }

  // --------------------------------------------------------------- initialisation
  struct Reconstruction {
    Eigen::Matrix3d R;
    Eigen::Vector3d t;
    std::vector<std::pair<int, Eigen::Vector3d>> points;  ///< match index -> X in camera 1
    double parallax_deg = 0;
  };

  static bool Triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2, const Eigen::Vector2d& x1,
                          const Eigen::Vector2d& x2, Eigen::Vector3d* X) {
    Eigen::Matrix4d A;
    A.row(0) = x1.x() * P1.row(2) - P1.row(0);
    A.row(1) = x1.y() * P1.row(2) - P1.row(1);
    A.row(2) = x2.x() * P2.row(2) - P2.row(0);
    A.row(3) = x2.y() * P2.row(2) - P2.row(1);
    Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
    const Eigen::Vector4d h = svd.matrixV().col(3);
    if (std::abs(h(3)) < 1e-12) return false;
    *X = h.head<3>() / h(3);
    return X->allFinite();
  }

  // Triangulates the matched pairs for motion (R, t) of camera 2 w.r.t. camera 1 and keeps the
  // points in front of both cameras that reproject within the gate.
  Reconstruction CheckMotion(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Features& f1, const Features& f2,
                             const std::vector<std::pair<int, int>>& matches, const std::vector<uchar>& inlier) const {
    Reconstruction rec;
    rec.R = R;
    rec.t = t;
    Eigen::Matrix<double, 3, 4> P1, P2;
    const Eigen::Matrix3d Km = cam.K();
    P1 << Km, Eigen::Vector3d::Zero();
    P2 << Km * R, Km * t;
    const Eigen::Vector3d O2 = -R.transpose() * t;
    std::vector<double> parallaxes;
    for (size_t m = 0; m < matches.size(); ++m) {
      if (!inlier[m]) continue;
      const auto& x1 = f1.un[static_cast<size_t>(matches[m].first)];
      const auto& x2 = f2.un[static_cast<size_t>(matches[m].second)];
      Eigen::Vector3d X;
      if (!Triangulate(P1, P2, x1, x2, &X)) continue;
      const Eigen::Vector3d X2 = R * X + t;
      if (X.z() <= 0 || X2.z() <= 0) continue;
      const double cos_par = X.normalized().dot((X - O2).normalized());
      if ((cam.Project(X) - x1).squaredNorm() > 4.0 * kChi2Mono) continue;
      if ((cam.Project(X2) - x2).squaredNorm() > 4.0 * kChi2Mono) continue;
      parallaxes.push_back(std::acos(std::clamp(cos_par, -1.0, 1.0)) * 180.0 / M_PI);
      if (cos_par < 0.99998) rec.points.emplace_back(static_cast<int>(m), X);
    }
    if (!parallaxes.empty()) {
      std::sort(parallaxes.begin(), parallaxes.end());
      rec.parallax_deg = parallaxes[parallaxes.size() / 2];
    }
    return rec;
  }

  SlamFrameSummary TryInitialize(SlamFrameSummary s) {
    s.state = SlamState::kInitializing;
    if (!init_ref || static_cast<int>(cur.f.size()) < 100 || cur.index - init_ref->index > opt.init_max_frames) {
      if (static_cast<int>(cur.f.size()) >= 100) init_ref = std::make_unique<Frame>(cur);
      else init_ref.reset();
      s.message = "waiting for a reference frame with enough features";
      return s;
    }
    // Window search around the same pixel: the camera moved little.
    std::vector<std::pair<int, int>> matches;
    std::vector<int> taken(cur.f.size(), -1), taken_dist(cur.f.size(), 256);
    for (size_t i = 0; i < init_ref->f.size(); ++i) {
      if (init_ref->f.keypoints[i].octave > 1) continue;
      const auto cands = cur.f.InArea(init_ref->f.un[i], 0.15 * cam.width, 0, 2);
      BestTwo m;
      for (int j : cands) m.Add(DescriptorDistance(init_ref->f.desc(static_cast<int>(i)), cur.f.desc(j)), j);
      const int best = m.best, bj = m.index;
      if (bj < 0 || best > kThLow || best > 0.9 * m.second) continue;
      if (best < taken_dist[static_cast<size_t>(bj)]) {
        taken_dist[static_cast<size_t>(bj)] = best;
        taken[static_cast<size_t>(bj)] = static_cast<int>(i);
      }
    }
    for (size_t j = 0; j < taken.size(); ++j)
      if (taken[j] >= 0) matches.emplace_back(taken[j], static_cast<int>(j));
    s.inliers = static_cast<int>(matches.size());
    if (static_cast<int>(matches.size()) < opt.init_min_points) {
      if (matches.size() < 40) init_ref = std::make_unique<Frame>(cur);  // lost the reference view
      s.message = "initialisation: " + std::to_string(matches.size()) + " matches";
      return s;
    }
    std::vector<cv::Point2f> p1, p2;
    double median_flow = 0;
    {
      std::vector<double> flow;
      for (const auto& [i, j] : matches) {
        p1.emplace_back(static_cast<float>(init_ref->f.un[static_cast<size_t>(i)].x()), static_cast<float>(init_ref->f.un[static_cast<size_t>(i)].y()));
        p2.emplace_back(static_cast<float>(cur.f.un[static_cast<size_t>(j)].x()), static_cast<float>(cur.f.un[static_cast<size_t>(j)].y()));
        flow.push_back(cv::norm(p1.back() - p2.back()));
      }
      std::sort(flow.begin(), flow.end());
      median_flow = flow[flow.size() / 2];
    }
    if (median_flow < 0.03 * cam.width) {
      s.message = "initialisation: waiting for parallax";
      return s;
    }
    cv::Mat Kcv;
    cv::eigen2cv(cam.K(), Kcv);
    std::vector<Reconstruction> candidates;
    std::vector<uchar> maskE;
    const cv::Mat E = cv::findEssentialMat(p1, p2, Kcv, cv::RANSAC, 0.999, 1.0, maskE);
    if (E.rows == 3 && E.cols == 3) {
      cv::Mat Rc, tc;
      cv::recoverPose(E, p1, p2, Kcv, Rc, tc, maskE);
      Eigen::Matrix3d R;
      Eigen::Vector3d t;
      cv::cv2eigen(Rc, R);
      cv::cv2eigen(tc, t);
      candidates.push_back(CheckMotion(R, t.normalized(), init_ref->f, cur.f, matches, maskE));
    }
    std::vector<uchar> maskH;
    const cv::Mat H = cv::findHomography(p1, p2, cv::RANSAC, 1.5, maskH);
    if (!H.empty()) {
      std::vector<cv::Mat> Rs, ts, ns;
      cv::decomposeHomographyMat(H, Kcv, Rs, ts, ns);
      for (size_t k = 0; k < Rs.size(); ++k) {
        Eigen::Matrix3d R;
        Eigen::Vector3d t;
        cv::cv2eigen(Rs[k], R);
        cv::cv2eigen(ts[k], t);
        if (t.norm() < 1e-9) continue;
        candidates.push_back(CheckMotion(R, t.normalized(), init_ref->f, cur.f, matches, maskH));
      }
    }
    std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) { return a.points.size() > b.points.size(); });
    if (candidates.empty() || static_cast<int>(candidates[0].points.size()) < opt.init_min_points ||
        candidates[0].parallax_deg < opt.init_min_parallax_deg) {
      s.message = "initialisation: not enough parallax or points";
      return s;
    }
    // A second, different motion explaining almost as many points: ambiguous, wait.
    for (size_t k = 1; k < candidates.size(); ++k) {
      const double dR = Eigen::AngleAxisd(candidates[k].R.transpose() * candidates[0].R).angle();
      const double dt = std::acos(std::clamp(candidates[k].t.dot(candidates[0].t), -1.0, 1.0));
      if ((dR > 0.05 || dt > 0.2) && candidates[k].points.size() > 0.75 * candidates[0].points.size()) {
        s.message = "initialisation: ambiguous two-view motion";
        return s;
      }
    }
    CreateInitialMap(candidates[0], matches);
    if (!initialized) {
      s.message = "initialisation: map rejected after bundle adjustment";
      return s;
    }
    s.state = SlamState::kTracking;
    s.keyframe = true;
    s.inliers = static_cast<int>(std::count_if(cur.points.begin(), cur.points.end(), [](int p) { return p >= 0; }));
    s.message = "map initialised with " + std::to_string(map->GoodPoints()) + " points";
    return s;
  }

  int NewKeyFrame(const Frame& f) {
    auto kf = std::make_unique<KeyFrame>();
    kf->id = static_cast<int>(map->keyframes.size());
    kf->frame_index = f.index;
    kf->stamp = f.stamp;
    kf->T_cw = f.T_cw;
    kf->f = f.f;
    kf->points.assign(f.f.size(), -1);
    ComputeBow(&kf->f);
    map->keyframes.push_back(std::move(kf));
    return map->keyframes.back()->id;
  }

  void CreateInitialMap(const Reconstruction& rec, const std::vector<std::pair<int, int>>& matches) {
    map = std::make_unique<Map>();
    db = BowDatabase();
    recent_points.clear();
    consistent_groups.clear();
    init_ref->T_cw = Eigen::Isometry3d::Identity();
    cur.T_cw = Eigen::Isometry3d::Identity();
    cur.T_cw.linear() = rec.R;
    cur.T_cw.translation() = rec.t;
    const int k0 = NewKeyFrame(*init_ref);
    const int k1 = NewKeyFrame(cur);
    for (const auto& [m, X] : rec.points) {
      const int p = map->AddPoint(X, k0);
      map->AddObservation(p, k0, matches[static_cast<size_t>(m)].first);
      map->AddObservation(p, k1, matches[static_cast<size_t>(m)].second);
      map->UpdatePoint(p, scales);
    }
    map->UpdateConnections(k0);
    map->UpdateConnections(k1);
    GlobalBundleAdjustment(map.get(), cam, sigma2, 20);
    const double median = map->MedianDepth(k0);
    int tracked = 0;
    for (int p : map->kf(k1).points) tracked += p >= 0 && !map->mp(p).bad ? 1 : 0;
    if (!(median > 0) || tracked < opt.init_min_points * 3 / 4) {
      map = std::make_unique<Map>();
      init_ref.reset();
      return;
    }
    // Scale: median depth of the first keyframe = 1.
    map->kf(k1).T_cw.translation() /= median;
    for (auto& p : map->points) {
      p->X_w /= median;
      if (!p->bad) map->UpdatePoint(p->id, scales);
    }
    if (voc) {
      db.Add(k0, map->kf(k0).f.bow);
      db.Add(k1, map->kf(k1).f.bow);
    }
    initialized = true;
    cur.T_cw = map->kf(k1).T_cw;
    cur.points = map->kf(k1).points;
    cur.outlier.assign(cur.f.size(), false);
    // The reference frame's pose joins the trajectory too.
    traj.push_back({init_ref->stamp, k0, Eigen::Isometry3d::Identity()});
    ref_kf = k1;
    last_kf_frame = cur.index;
    has_velocity = false;
    local_kfs = {k0, k1};
    for (const auto& p : map->points)
      if (!p->bad) recent_points.push_back(p->id);
    init_ref.reset();
  }

  // --------------------------------------------------------------------- tracking
  bool Visible(const MapPoint& p, const Eigen::Isometry3d& T_cw, Eigen::Vector2d* uv, int* level, double* view_cos) const {
    const Eigen::Vector3d pc = T_cw * p.X_w;
    if (pc.z() <= 0) return false;
    *uv = cam.Project(pc);
    if (uv->x() < 0 || uv->y() < 0 || uv->x() >= cam.width || uv->y() >= cam.height) return false;
    const Eigen::Vector3d O = T_cw.inverse().translation();
    const Eigen::Vector3d ray = p.X_w - O;
    const double dist = ray.norm();
    if (dist < 0.8 * p.min_distance || dist > 1.2 * p.max_distance) return false;
    *view_cos = ray.dot(p.normal) / dist;
    if (*view_cos < 0.5) return false;
    *level = PredictLevel(p, dist);
    return true;
  }

  // Searches each point's projection for the best unmatched feature. Returns new matches.
  int SearchByProjection(Frame* f, const std::vector<int>& pts, double radius_factor, bool count_visible, int th) {
    int n = 0;
    for (int pid : pts) {
      MapPoint& p = map->mp(pid);
      if (p.bad || p.last_seen_frame == f->index) continue;
      Eigen::Vector2d uv;
      int level;
      double vc;
      if (!Visible(p, f->T_cw, &uv, &level, &vc)) continue;
      if (count_visible) ++p.visible;
      const double r = radius_factor * (vc > 0.998 ? 2.5 : 4.0) * scales[static_cast<size_t>(level)];
      const auto cands = f->f.InArea(uv, r, std::max(0, level - 1), level + 1);
      BestTwo m;
      for (int i : cands) {
        const int q = f->points[static_cast<size_t>(i)];
        if (q >= 0 && !map->mp(q).bad && !f->outlier[static_cast<size_t>(i)]) continue;
        m.Add(DescriptorDistance(p.descriptor.ptr<uint8_t>(), f->f.desc(i)), i, f->f.keypoints[static_cast<size_t>(i)].octave);
      }
      const int best = m.best, bi = m.index, best_level = m.best_level, second_level = m.second_level, second = m.second;
      if (bi < 0 || best > th) continue;
      if (best_level == second_level && best > 0.8 * second) continue;
      f->points[static_cast<size_t>(bi)] = pid;
      f->outlier[static_cast<size_t>(bi)] = false;
      p.last_seen_frame = f->index;
      ++n;
    }
    return n;
  }

  int Optimize(Frame* f) {
    std::vector<PoseObservation> obs;
    std::vector<int> idx;
    for (size_t i = 0; i < f->f.size(); ++i) {
      const int p = f->points[i];
      if (p < 0 || map->mp(p).bad) {
        f->points[i] = -1;
        continue;
      }
      obs.push_back({map->mp(p).X_w, f->f.un[i], InvSigma2(f->f, static_cast<int>(i)), false});
      idx.push_back(static_cast<int>(i));
    }
    if (obs.size() < 6) return 0;
    Eigen::Isometry3d T = f->T_cw;
    const int inliers = OptimizePose(cam, &obs, &T);
    f->T_cw = T;
    for (size_t k = 0; k < obs.size(); ++k) {
      const size_t i = static_cast<size_t>(idx[k]);
      if (obs[k].outlier) {
        map->mp(f->points[i]).last_seen_frame = -1;
        f->points[i] = -1;
      }
      f->outlier[i] = false;
    }
    return inliers;
  }

  bool TrackWithMotionModel() {
    cur.T_cw = velocity * last.T_cw;
    std::vector<int> pts;
    for (size_t i = 0; i < last.points.size(); ++i)
      if (last.points[i] >= 0 && !last.outlier[i]) pts.push_back(last.points[i]);
    int n = SearchByProjection(&cur, pts, 15.0 / 4.0, false, kThHigh);
    if (n < 20) {
      std::fill(cur.points.begin(), cur.points.end(), -1);
      for (int p : pts) map->mp(p).last_seen_frame = -1;
      n = SearchByProjection(&cur, pts, 30.0 / 4.0, false, kThHigh);
    }
    if (n < 20) return false;
    return Optimize(&cur) >= 10;
  }

  bool TrackReferenceKeyFrame() {
    const KeyFrame& kf = map->kf(ref_kf);
    ComputeBow(&cur.f);
    const auto m = MatchByAppearance(
        kf.f, [&](int i) { return kf.points[static_cast<size_t>(i)] >= 0 && !map->mp(kf.points[static_cast<size_t>(i)]).bad; }, cur.f,
        [](int) { return true; }, kThHigh, 0.7);
    if (m.size() < 15) return false;
    for (const auto& [i, j] : m) cur.points[static_cast<size_t>(j)] = kf.points[static_cast<size_t>(i)];
    cur.T_cw = last.T_cw;
    return Optimize(&cur) >= 10;
  }

  void UpdateLocalMap() {
    std::map<int, int> counts;
    for (int p : cur.points)
      if (p >= 0 && !map->mp(p).bad)
        for (const auto& [k, i] : map->mp(p).obs) ++counts[k];
    std::vector<std::pair<int, int>> ranked;
    for (const auto& [k, c] : counts) ranked.emplace_back(c, k);
    std::sort(ranked.rbegin(), ranked.rend());
    std::set<int> kfs;
    for (const auto& [c, k] : ranked) {
      if (kfs.size() >= 40) break;
      kfs.insert(k);
    }
    if (!ranked.empty()) ref_kf = ranked.front().second;
    std::set<int> base = kfs;
    for (int k : base)
      for (int n : map->kf(k).BestCovisible(10)) {
        if (kfs.size() >= 80) break;
        kfs.insert(n);
      }
    local_kfs.assign(kfs.begin(), kfs.end());
    std::set<int> pts;
    for (int k : local_kfs)
      for (int p : map->kf(k).points)
        if (p >= 0 && !map->mp(p).bad) pts.insert(p);
    local_points.assign(pts.begin(), pts.end());
  }

  int TrackLocalMap() {
    UpdateLocalMap();
    for (int p : cur.points)
      if (p >= 0) {
        map->mp(p).last_seen_frame = cur.index;
        ++map->mp(p).visible;
      }
    const bool recent_reloc = cur.index - last_reloc_frame < 2;
    SearchByProjection(&cur, local_points, recent_reloc ? 3.0 : 1.0, true, kThHigh);
    const int inliers = Optimize(&cur);
    for (int p : cur.points)
      if (p >= 0) ++map->mp(p).found;
    return inliers;
  }

  bool Relocalize() {
    if (!voc) return false;
    ComputeBow(&cur.f);
    const auto cands = db.Query(cur.f.bow, 0.0, {}, 10);
    cv::Mat Kcv;
    cv::eigen2cv(cam.K(), Kcv);
    for (const auto& [kid, score] : cands) {
      const KeyFrame& kf = map->kf(kid);
      if (kf.bad) continue;
      const auto m = MatchByAppearance(
          kf.f, [&](int i) { return kf.points[static_cast<size_t>(i)] >= 0 && !map->mp(kf.points[static_cast<size_t>(i)]).bad; }, cur.f,
          [](int) { return true; }, kThHigh, 0.75);
      if (m.size() < 15) continue;
      std::vector<cv::Point3f> obj;
      std::vector<cv::Point2f> img;
      for (const auto& [i, j] : m) {
        const auto& X = map->mp(kf.points[static_cast<size_t>(i)]).X_w;
        obj.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()));
        img.emplace_back(static_cast<float>(cur.f.un[static_cast<size_t>(j)].x()), static_cast<float>(cur.f.un[static_cast<size_t>(j)].y()));
      }
      cv::Mat rvec, tvec;
      std::vector<int> inl;
      if (!cv::solvePnPRansac(obj, img, Kcv, cv::noArray(), rvec, tvec, false, 200, 2.0f, 0.99, inl, cv::SOLVEPNP_EPNP)) continue;
      if (inl.size() < 10) continue;
      cv::Mat Rc;
      cv::Rodrigues(rvec, Rc);
      Eigen::Matrix3d R;
      Eigen::Vector3d t;
      cv::cv2eigen(Rc, R);
      cv::cv2eigen(tvec, t);
      cur.T_cw.linear() = R;
      cur.T_cw.translation() = t;
      std::fill(cur.points.begin(), cur.points.end(), -1);
      for (int k : inl) cur.points[static_cast<size_t>(m[static_cast<size_t>(k)].second)] = kf.points[static_cast<size_t>(m[static_cast<size_t>(k)].first)];
      if (Optimize(&cur) < 10) continue;
      ref_kf = kid;
      last_reloc_frame = cur.index;
      if (TrackLocalMap() >= 50) return true;
    }
    std::fill(cur.points.begin(), cur.points.end(), -1);
    return false;
  }

  // --------------------------------------------------------------------- mapping
  bool NeedKeyFrame(int inliers) const {
    const int gap = cur.index - last_kf_frame;
    if (gap < opt.keyframe_min_gap || inliers <= 15) return false;
    const int min_obs = map->keyframes.size() <= 2 ? 2 : 3;
    int ref_matches = 0;
    for (int p : map->kf(ref_kf).points)
      if (p >= 0 && !map->mp(p).bad && static_cast<int>(map->mp(p).obs.size()) >= min_obs) ++ref_matches;
    return inliers < opt.keyframe_tracked_ratio * ref_matches || gap >= opt.keyframe_max_gap;
  }

  void Fuse(int kf_id, const std::vector<int>& pts) {
    KeyFrame& kf = map->kf(kf_id);
    for (int pid : pts) {
      if (pid < 0 || map->mp(pid).bad) continue;
      MapPoint& p = map->mp(pid);
      if (p.obs.count(kf_id)) continue;
      Eigen::Vector2d uv;
      int level;
      double vc;
      if (!Visible(p, kf.T_cw, &uv, &level, &vc)) continue;
      const auto cands = kf.f.InArea(uv, 3.0 * scales[static_cast<size_t>(level)], std::max(0, level - 1), level + 1);
      int best = 256, bi = -1;
      for (int i : cands) {
        const double e2 = (kf.f.un[static_cast<size_t>(i)] - uv).squaredNorm() * InvSigma2(kf.f, i);
        if (e2 > kChi2Mono) continue;
        const int d = DescriptorDistance(p.descriptor.ptr<uint8_t>(), kf.f.desc(i));
        if (d < best) {
          best = d;
          bi = i;
        }
      }
      if (bi < 0 || best > kThLow) continue;
      const int q = kf.points[static_cast<size_t>(bi)];
      if (q >= 0 && !map->mp(q).bad) {
        if (map->mp(q).obs.size() >= p.obs.size()) map->Replace(pid, q);
        else map->Replace(q, pid);
      } else {
        map->AddObservation(pid, kf_id, bi);
      }
    }
  }

  void CullRecentPoints(int kf_id) {
    std::vector<int> keep;
    for (int pid : recent_points) {
      MapPoint& p = map->mp(pid);
      if (p.bad) continue;
      if (p.FoundRatio() < 0.25) {
        map->ErasePoint(pid);
      } else if (kf_id - p.first_kf >= 2 && p.obs.size() <= 2) {
        map->ErasePoint(pid);
      } else if (kf_id - p.first_kf < 3) {
        keep.push_back(pid);
      }
    }
    recent_points = std::move(keep);
  }

  void CreateNewMapPoints(int kf_id) {
    KeyFrame& k1 = map->kf(kf_id);
    const Eigen::Matrix3d Km = cam.K();
    const Eigen::Vector3d O1 = k1.Center();
    for (int nid : k1.BestCovisible(static_cast<size_t>(opt.mapping_neighbours))) {
      KeyFrame& k2 = map->kf(nid);
      if (k2.bad) continue;
      const Eigen::Vector3d O2 = k2.Center();
      if ((O2 - O1).norm() / map->MedianDepth(nid) < 0.01) continue;
      // Fundamental matrix F12: x1^T F12 x2 = 0.
      const Eigen::Isometry3d T12 = k1.T_cw * k2.T_cw.inverse();
      Eigen::Matrix3d tx;
      const Eigen::Vector3d t = T12.translation();
      tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
      const Eigen::Matrix3d F12 = Km.transpose().inverse() * tx * T12.linear() * Km.inverse();
      const Eigen::Vector2d ep2 = cam.Project(k2.T_cw * O1);  // epipole of camera 1 in image 2
      const auto matches = MatchByAppearance(
          k1.f, [&](int i) { return k1.points[static_cast<size_t>(i)] < 0; }, k2.f, [&](int j) { return k2.points[static_cast<size_t>(j)] < 0; },
          kThLow, 0.6);
      Eigen::Matrix<double, 3, 4> P1, P2;
      P1 << Km * k1.T_cw.linear(), Km * k1.T_cw.translation();
      P2 << Km * k2.T_cw.linear(), Km * k2.T_cw.translation();
      for (const auto& [i, j] : matches) {
        if (k1.points[static_cast<size_t>(i)] >= 0 || k2.points[static_cast<size_t>(j)] >= 0) continue;
        const auto& x1 = k1.f.un[static_cast<size_t>(i)];
        const auto& x2 = k2.f.un[static_cast<size_t>(j)];
        const int l1 = k1.f.keypoints[static_cast<size_t>(i)].octave, l2 = k2.f.keypoints[static_cast<size_t>(j)].octave;
        if ((x2 - ep2).norm() < 10 * scales[static_cast<size_t>(l2)]) continue;
        // Epipolar line in image 2: l = F12^T x1.
        const Eigen::Vector3d line = F12.transpose() * Eigen::Vector3d(x1.x(), x1.y(), 1.0);
        const double num = line.dot(Eigen::Vector3d(x2.x(), x2.y(), 1.0));
        const double den = line.head<2>().squaredNorm();
        if (den < 1e-12 || num * num / den > 3.84 * sigma2[static_cast<size_t>(l2)]) continue;
        const Eigen::Vector3d r1 = k1.T_cw.linear().transpose() * cam.Unproject(x1);
        const Eigen::Vector3d r2 = k2.T_cw.linear().transpose() * cam.Unproject(x2);
        const double cos_par = r1.normalized().dot(r2.normalized());
        if (cos_par > 0.9998 || cos_par < 0) continue;
        Eigen::Vector3d X;
        if (!Triangulate(P1, P2, x1, x2, &X)) continue;
        const Eigen::Vector3d c1 = k1.T_cw * X, c2 = k2.T_cw * X;
        if (c1.z() <= 0 || c2.z() <= 0) continue;
        if ((cam.Project(c1) - x1).squaredNorm() / sigma2[static_cast<size_t>(l1)] > kChi2Mono) continue;
        if ((cam.Project(c2) - x2).squaredNorm() / sigma2[static_cast<size_t>(l2)] > kChi2Mono) continue;
        const double d1 = (X - O1).norm(), d2 = (X - O2).norm();
        const double ratio_dist = d2 / d1, ratio_oct = scales[static_cast<size_t>(l1)] / scales[static_cast<size_t>(l2)];
        if (ratio_dist * 1.5 * opt.orb.scale_factor < ratio_oct || ratio_dist > ratio_oct * 1.5 * opt.orb.scale_factor) continue;
        const int p = map->AddPoint(X, kf_id);
        map->AddObservation(p, kf_id, i);
        map->AddObservation(p, nid, j);
        map->UpdatePoint(p, scales);
        recent_points.push_back(p);
      }
    }
  }

  void SearchInNeighbors(int kf_id) {
    std::set<int> targets;
    for (int n : map->kf(kf_id).BestCovisible(static_cast<size_t>(opt.mapping_neighbours))) {
      if (map->kf(n).bad) continue;
      targets.insert(n);
      for (int n2 : map->kf(n).BestCovisible(5))
        if (n2 != kf_id && !map->kf(n2).bad) targets.insert(n2);
    }
    const std::vector<int> mine = map->kf(kf_id).points;
    for (int t : targets) Fuse(t, mine);
    std::vector<int> theirs;
    std::set<int> seen;
    for (int t : targets)
      for (int p : map->kf(t).points)
        if (p >= 0 && !map->mp(p).bad && seen.insert(p).second) theirs.push_back(p);
    Fuse(kf_id, theirs);
    for (int p : map->kf(kf_id).points)
      if (p >= 0 && !map->mp(p).bad) map->UpdatePoint(p, scales);
    map->UpdateConnections(kf_id);
    for (int t : targets) map->UpdateConnections(t);
  }

  void InsertKeyFrame() {
    const int kid = NewKeyFrame(cur);
    for (size_t i = 0; i < cur.points.size(); ++i) {
      const int p = cur.points[i];
      if (p < 0 || map->mp(p).bad) continue;
      map->AddObservation(p, kid, static_cast<int>(i));
      map->UpdatePoint(p, scales);
    }
    map->UpdateConnections(kid);
    ref_kf = kid;
    last_kf_frame = cur.index;
    // Local mapping.
    CullRecentPoints(kid);
    CreateNewMapPoints(kid);
    SearchInNeighbors(kid);
    if (map->keyframes.size() > 2) LocalBundleAdjustment(map.get(), cam, sigma2, kid, opt.local_ba_keyframes, opt.local_ba_iterations);
  }

  // ------------------------------------------------------------------ loop closing
  struct LoopCandidate {
    int kf;
    Sim3 S_cm;
    std::vector<std::pair<int, int>> matches;  ///< current feature -> loop map point
  };

  std::vector<int> DetectLoopCandidates(int kid) {
    KeyFrame& kf = map->kf(kid);
    std::vector<int> out;
    if (!voc || kf.f.bow.empty()) return out;
    double min_score = 1.0;
    for (const auto& [n, w] : kf.covisibility) min_score = std::min(min_score, BowVocabulary::Score(kf.f.bow, map->kf(n).f.bow));
    std::set<int> exclude{kid};
    for (const auto& [n, w] : kf.covisibility) exclude.insert(n);
    for (int k = std::max(0, kid - opt.loop_min_keyframe_gap); k < kid; ++k) exclude.insert(k);
    const auto hits = db.Query(kf.f.bow, min_score * opt.loop_min_score_ratio, exclude, 20);
    std::vector<std::pair<std::set<int>, int>> groups;
    for (const auto& [c, score] : hits) {
      std::set<int> group{c};
      for (const auto& [n, w] : map->kf(c).covisibility) group.insert(n);
      int count = 0;
      for (const auto& [prev, pc] : consistent_groups) {
        bool shares = false;
        for (int g : group)
          if (prev.count(g)) {
            shares = true;
            break;
          }
        if (shares) count = std::max(count, pc + 1);
      }
      groups.emplace_back(group, count);
      if (count >= opt.loop_consistency) out.push_back(c);
    }
    consistent_groups = std::move(groups);
    return out;
  }

  bool ComputeSim3(int kid, int cand, LoopCandidate* lc) {
    const KeyFrame& c = map->kf(kid);
    const KeyFrame& m = map->kf(cand);
    const auto has_point = [&](const KeyFrame& k) {
      return [&](int i) { return k.points[static_cast<size_t>(i)] >= 0 && !map->mp(k.points[static_cast<size_t>(i)]).bad; };
    };
    const auto matches = MatchByAppearance(c.f, has_point(c), m.f, has_point(m), kThLow, 0.75);
    if (matches.size() < 20) return false;
    std::vector<Sim3Match> sm;
    for (const auto& [i, j] : matches) {
      Sim3Match s;
      s.X1_c1 = c.T_cw * map->mp(c.points[static_cast<size_t>(i)]).X_w;
      s.X2_c2 = m.T_cw * map->mp(m.points[static_cast<size_t>(j)]).X_w;
      s.uv1 = c.f.un[static_cast<size_t>(i)];
      s.uv2 = m.f.un[static_cast<size_t>(j)];
      s.inv_sigma2_1 = InvSigma2(c.f, i);
      s.inv_sigma2_2 = InvSigma2(m.f, j);
      sm.push_back(s);
    }
    // RANSAC over 3-point samples.
    const double gate = 9.210;
    auto count_inliers = [&](const Sim3& S, std::vector<bool>* in) {
      int n = 0;
      const Sim3 Si = S.inverse();
      for (size_t k = 0; k < sm.size(); ++k) {
        const Eigen::Vector3d p1 = S * sm[k].X2_c2, p2 = Si * sm[k].X1_c1;
        const bool ok = p1.z() > 0 && p2.z() > 0 && (cam.Project(p1) - sm[k].uv1).squaredNorm() * sm[k].inv_sigma2_1 < gate &&
                        (cam.Project(p2) - sm[k].uv2).squaredNorm() * sm[k].inv_sigma2_2 < gate;
        (*in)[k] = ok;
        n += ok ? 1 : 0;
      }
      return n;
    };
    Sim3 best;
    int best_n = 0;
    std::vector<bool> in(sm.size()), best_in;
    std::uniform_int_distribution<size_t> pick(0, sm.size() - 1);
    for (int it = 0; it < 300; ++it) {
      size_t a = pick(rng), b = pick(rng), d = pick(rng);
      if (a == b || b == d || a == d) continue;
      Eigen::Matrix3Xd from(3, 3), to(3, 3);
      from << sm[a].X2_c2, sm[b].X2_c2, sm[d].X2_c2;
      to << sm[a].X1_c1, sm[b].X1_c1, sm[d].X1_c1;
      Sim3 S;
      if (!EstimateSim3(from, to, false, &S)) continue;
      const int n = count_inliers(S, &in);
      if (n > best_n) {
        best_n = n;
        best = S;
        best_in = in;
      }
    }
    if (best_n < 20) return false;
    for (size_t k = 0; k < sm.size(); ++k) sm[k].outlier = !best_in[k];
    if (OptimizeSim3(cam, &sm, &best, 10.0) < 20) return false;
    // Guided search: the loop keyframe's neighbourhood projected into the current keyframe.
    const Sim3 S_cw = best * Sim3(m.T_cw);
    const Eigen::Isometry3d T_cw_loop = S_cw.ToIsometryUnscaled();
    std::set<int> pts;
    std::vector<int> group = map->kf(cand).BestCovisible(10);
    group.push_back(cand);
    for (int g : group)
      for (int p : map->kf(g).points)
        if (p >= 0 && !map->mp(p).bad) pts.insert(p);
    lc->matches.clear();
    std::vector<int> taken(c.f.size(), -1);
    for (int pid : pts) {
      const MapPoint& p = map->mp(pid);
      // The loop side's points seen from the current keyframe placed by the Sim(3) (in the loop
      // side's units, like the points' distance ranges).
      const Eigen::Vector3d pc = T_cw_loop * p.X_w;
      if (pc.z() <= 0) continue;
      const Eigen::Vector2d uv = cam.Project(pc);
      if (uv.x() < 0 || uv.y() < 0 || uv.x() >= cam.width || uv.y() >= cam.height) continue;
      const double dist = (p.X_w - T_cw_loop.inverse().translation()).norm();
      if (dist < 0.8 * p.min_distance || dist > 1.2 * p.max_distance) continue;
      const int level = PredictLevel(p, dist);
      const auto cands = c.f.InArea(uv, 10.0 * scales[static_cast<size_t>(level)], std::max(0, level - 1), level + 1);
      int bd = 256, bi = -1;
      for (int i : cands) {
        const int d = DescriptorDistance(p.descriptor.ptr<uint8_t>(), c.f.desc(i));
        if (d < bd) {
          bd = d;
          bi = i;
        }
      }
      if (bi < 0 || bd > kThLow || taken[static_cast<size_t>(bi)] >= 0) continue;
      taken[static_cast<size_t>(bi)] = pid;
      lc->matches.emplace_back(bi, pid);
    }
    if (static_cast<int>(lc->matches.size()) < opt.loop_min_inliers) return false;
    // Plausibility: the correction against the path flown between the loop ends.
    double path = 0;
    int prev = -1;
    for (int k = cand; k <= kid; ++k) {
      if (map->kf(k).bad) continue;
      if (prev >= 0) path += (map->kf(k).Center() - map->kf(prev).Center()).norm();
      prev = k;
    }
    const double correction = (T_cw_loop.inverse().translation() - c.Center()).norm();
    char text[200];
    std::snprintf(text, sizeof(text), "keyframe %d <-> %d: scale %.3f, %zu matches, correction %.3f over a path of %.3f (map units)", kid,
                  cand, best.s, lc->matches.size(), correction, path);
    loop_log += (loop_log.empty() ? "" : "; ") + std::string(text);
    if (correction > opt.loop_max_correction_ratio * path) {
      loop_log += " rejected (aliasing)";
      return false;
    }
    lc->kf = cand;
    lc->S_cm = best;
    return true;
  }

  void CorrectLoop(int kid, const LoopCandidate& lc) {
    const size_t n = map->keyframes.size();
    std::vector<Sim3> S_before(n), S_corr(n);
    std::vector<bool> active(n), corrected(n, false);
    for (size_t k = 0; k < n; ++k) {
      active[k] = !map->keyframes[k]->bad;
      S_before[k] = S_corr[k] = Sim3(map->keyframes[k]->T_cw);
    }
    KeyFrame& c = map->kf(kid);
    const Sim3 S_cw = lc.S_cm * Sim3(map->kf(lc.kf).T_cw);
    std::vector<int> connected{kid};
    for (const auto& [k, w] : c.covisibility) connected.push_back(k);
    std::map<int, std::set<int>> prev_connections;
    for (int k : connected) {
      const Eigen::Isometry3d T_ic = map->kf(k).T_cw * c.T_cw.inverse();
      S_corr[static_cast<size_t>(k)] = k == kid ? S_cw : Sim3(T_ic) * S_cw;
      corrected[static_cast<size_t>(k)] = true;
      for (const auto& [o, w] : map->kf(k).covisibility) prev_connections[k].insert(o);
    }
    // Move the points the connected keyframes see, then the keyframes.
    std::set<int> moved;
    for (int k : connected)
      for (int p : map->kf(k).points) {
        if (p < 0 || map->mp(p).bad || !moved.insert(p).second) continue;
        MapPoint& mp = map->mp(p);
        mp.X_w = S_corr[static_cast<size_t>(k)].inverse() * (S_before[static_cast<size_t>(k)] * mp.X_w);
        mp.ref_kf = k;
      }
    for (int k : connected) map->kf(k).T_cw = S_corr[static_cast<size_t>(k)].ToIsometryUnscaled();
    for (int p : moved) map->UpdatePoint(p, scales);
    // The current keyframe's matches become the loop's points.
    for (const auto& [i, pid] : lc.matches) {
      if (map->mp(pid).bad) continue;
      const int q = c.points[static_cast<size_t>(i)];
      if (q >= 0 && !map->mp(q).bad) map->Replace(q, pid);
      else if (!map->mp(pid).obs.count(kid)) map->AddObservation(pid, kid, i);
    }
    std::vector<int> loop_points;
    {
      std::set<int> s;
      std::vector<int> group = map->kf(lc.kf).BestCovisible(10);
      group.push_back(lc.kf);
      for (int g : group)
        for (int p : map->kf(g).points)
          if (p >= 0 && !map->mp(p).bad && s.insert(p).second) loop_points.push_back(p);
    }
    for (int k : connected) Fuse(k, loop_points);
    std::vector<PoseGraphEdge> edges;
    std::set<std::pair<int, int>> have;
    auto add_edge = [&](int i, int j, const Sim3& Si, const Sim3& Sj) {
      if (i == j || !have.insert({std::min(i, j), std::max(i, j)}).second) return;
      edges.push_back({i, j, Si * Sj.inverse()});
    };
    for (int k : connected) {
      map->UpdateConnections(k);
      for (const auto& [o, w] : map->kf(k).covisibility) {
        if (prev_connections[k].count(o) || std::find(connected.begin(), connected.end(), o) != connected.end()) continue;
        add_edge(k, o, S_corr[static_cast<size_t>(k)], S_corr[static_cast<size_t>(o)]);  // new loop links
      }
    }
    c.loop_edges.insert(lc.kf);
    map->kf(lc.kf).loop_edges.insert(kid);
    add_edge(kid, lc.kf, S_corr[static_cast<size_t>(kid)], S_corr[static_cast<size_t>(lc.kf)]);
    for (size_t k = 0; k < n; ++k) {
      if (!active[k]) continue;
      const KeyFrame& kf = *map->keyframes[k];
      const int ki = static_cast<int>(k);
      if (kf.parent >= 0) add_edge(ki, kf.parent, S_before[k], S_before[static_cast<size_t>(kf.parent)]);
      for (int l : kf.loop_edges) add_edge(ki, l, S_corr[k], S_corr[static_cast<size_t>(l)]);
      for (const auto& [o, w] : kf.covisibility)
        if (w >= 100) add_edge(ki, o, S_before[k], S_before[static_cast<size_t>(o)]);
    }
    std::vector<Sim3> S = S_corr;
    OptimizePoseGraph(&S, active, edges, {lc.kf}, 20);
    for (size_t k = 0; k < n; ++k)
      if (active[k]) map->keyframes[k]->T_cw = S[k].ToIsometryUnscaled();
    for (auto& p : map->points) {
      if (p->bad) continue;
      const size_t r = static_cast<size_t>(p->ref_kf >= 0 ? p->ref_kf : p->first_kf);
      p->X_w = S[r].inverse() * (S_corr[r] * p->X_w);
    }
    for (auto& p : map->points)
      if (!p->bad) map->UpdatePoint(p->id, scales);
    if (opt.global_ba_after_loop) GlobalBundleAdjustment(map.get(), cam, sigma2, opt.global_ba_iterations);
    ++stats.loops;
  }

  bool LoopClosing(int kid) {
    if (!opt.loop_closing || !voc) return false;
    bool closed = false;
    if (kid > opt.loop_min_keyframe_gap) {
      for (int cand : DetectLoopCandidates(kid)) {
        LoopCandidate lc;
        if (ComputeSim3(kid, cand, &lc)) {
          CorrectLoop(kid, lc);
          consistent_groups.clear();
          closed = true;
          break;
        }
      }
    }
    db.Add(kid, map->kf(kid).f.bow);
    return closed;
  }

  // ----------------------------------------------------------------- bookkeeping
  Eigen::Isometry3d ToGlobal(const Eigen::Isometry3d& T_wc) const {
    Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
    out.linear() = G.R * T_wc.linear();
    out.translation() = G * T_wc.translation();
    return out;
  }

  std::vector<StampedPose> CurrentTrajectory() const {
    std::vector<StampedPose> out;
    for (const auto& e : traj) {
      const Eigen::Isometry3d T_cw = e.T_cr * map->kf(e.ref_kf).T_cw;
      out.push_back({e.stamp, ToGlobal(T_cw.inverse()), map_number});
    }
    return out;
  }

  void ResetForReinitialization() {
    if (initialized) {
      auto t = CurrentTrajectory();
      frozen.insert(frozen.end(), t.begin(), t.end());
      // The next map continues from the last good pose at the last map's depth scale.
      // (No mapping runs while lost, so that keyframe's depth is as it was at the last good frame.)
      const double median_depth_global = G.s * map->MedianDepth(last_good_ref_kf);
      G = Sim3(median_depth_global, last_good_T_wc_global.linear(), last_good_T_wc_global.translation());
      ++map_number;
      ++stats.reinitializations;
      ++stats.maps;
    }
    map = std::make_unique<Map>();
    db = BowDatabase();
    traj.clear();
    initialized = false;
    init_ref.reset();
    has_velocity = false;
    last_tracked = false;
    ref_kf = -1;
    local_kfs.clear();
    local_points.clear();
    recent_points.clear();
    consistent_groups.clear();
    lost_frames_in_row = 0;
  }

  SlamFrameSummary Track(const cv::Mat& gray, double stamp) {
    const auto t0 = Clock::now();
    SlamFrameSummary s;
    if (gray.empty() || gray.type() != CV_8UC1 || gray.cols != cam.width || gray.rows != cam.height || !std::isfinite(stamp)) {
      s.message = "expected a CV_8UC1 image of " + std::to_string(cam.width) + "x" + std::to_string(cam.height) + " and a finite stamp";
      return s;
    }
    ++stats.frames;
    cur = Frame();
    cur.index = frame_index++;
    cur.stamp = stamp;
    ExtractFeatures(gray, initialized ? *orb : *orb_init, &cur);
    s.features = static_cast<int>(cur.f.size());
    if (!initialized) {
      s = TryInitialize(s);
      if (initialized) {
        traj.push_back({cur.stamp, ref_kf, cur.T_cw * map->kf(ref_kf).T_cw.inverse()});
        last = cur;
        last_tracked = true;
        s.T_wc = ToGlobal(cur.T_cw.inverse());
        UpdateGoodPose();
        ++stats.tracked_frames;
      }
      s.tracking_ms = Ms(t0);
      return s;
    }
    bool ok = false;
    if (last_tracked) {
      if (has_velocity) ok = TrackWithMotionModel();
      if (!ok) {
        std::fill(cur.points.begin(), cur.points.end(), -1);
        ok = TrackReferenceKeyFrame();
      }
      if (ok) {
        s.inliers = TrackLocalMap();
        const bool recent_reloc = cur.index - last_reloc_frame < 10;
        ok = s.inliers >= (recent_reloc ? 50 : opt.min_tracked_inliers);
      }
      s.state = ok ? SlamState::kTracking : SlamState::kLost;
    } else {
      ok = Relocalize();
      if (ok) {
        s.inliers = static_cast<int>(std::count_if(cur.points.begin(), cur.points.end(), [](int p) { return p >= 0; }));
        s.state = SlamState::kRelocalized;
        ++stats.relocalizations;
      }
    }
    if (!ok) {
      ++stats.lost_frames;
      ++lost_frames_in_row;
      s.state = SlamState::kLost;
      const bool young = map->GoodKeyFrames() <= 5;
      if (young || lost_frames_in_row > opt.relocalize_frames || !voc) {
        s.message = "tracking lost; re-initialising a new map";
        ResetForReinitialization();
        s.reinitialized = true;
      } else {
        s.message = "tracking lost; relocalising (" + std::to_string(lost_frames_in_row) + "/" + std::to_string(opt.relocalize_frames) + ")";
        last_tracked = false;
      }
      const Eigen::Isometry3d pred = has_velocity ? velocity * last.T_cw : last.T_cw;
      s.T_wc = ToGlobal(pred.inverse());
      s.tracking_ms = Ms(t0);
      return s;
    }
    lost_frames_in_row = 0;
    ++stats.tracked_frames;
    velocity = cur.T_cw * last.T_cw.inverse();
    has_velocity = last_tracked;
    s.tracking_ms = Ms(t0);
    if (NeedKeyFrame(s.inliers)) {
      const auto t1 = Clock::now();
      InsertKeyFrame();
      s.keyframe = true;
      loop_log.clear();
      s.loop_closed = LoopClosing(ref_kf);
      if (!loop_log.empty()) s.message = (s.loop_closed ? "loop closed: " : "loop candidates: ") + loop_log;
      if (s.loop_closed) {
        // The current frame moves with its keyframe.
        cur.T_cw = map->kf(ref_kf).T_cw;
        has_velocity = false;
      }
      s.mapping_ms = Ms(t1);
    }
    traj.push_back({cur.stamp, ref_kf, cur.T_cw * map->kf(ref_kf).T_cw.inverse()});
    last = cur;
    last_tracked = true;
    UpdateGoodPose();
    s.T_wc = ToGlobal(cur.T_cw.inverse());
    return s;
  }

  void UpdateGoodPose() {
    last_good_T_wc_global = ToGlobal(cur.T_cw.inverse());
    last_good_ref_kf = ref_kf;
  }
};

MonoSlam::MonoSlam(const PinholeCamera& camera, const std::vector<double>& distortion, const MonoSlamOptions& options,
                   std::shared_ptr<const BowVocabulary> vocabulary)
    : impl_(std::make_unique<Impl>()) {
  std::string msg;
  if (!options.IsValid(&msg)) throw std::invalid_argument("MonoSlam: " + msg);
  if (!(camera.fx > 0 && camera.fy > 0 && camera.width > 0 && camera.height > 0 && std::isfinite(camera.cx) && std::isfinite(camera.cy)))
    throw std::invalid_argument("MonoSlam: camera needs fx, fy > 0 and a positive image size");
  for (double d : distortion)
    if (!std::isfinite(d)) throw std::invalid_argument("MonoSlam: distortion coefficients must be finite");
  Impl& m = *impl_;
  m.opt = options;
  m.cam = camera;
  cv::eigen2cv(camera.K(), m.K);
  bool any = false;
  for (double d : distortion) any = any || d != 0.0;
  if (any) m.D = cv::Mat(distortion, true).reshape(1, 1);
  m.orb = std::make_unique<OrbExtractor>(options.orb);
  OrbOptions init = options.orb;
  init.features *= options.init_orb_features_factor;
  m.orb_init = std::make_unique<OrbExtractor>(init);
  if (vocabulary && !vocabulary->empty()) m.voc = std::move(vocabulary);
  for (int l = 0; l < options.orb.levels; ++l) {
    m.scales.push_back(m.orb->scale(l));
    m.sigma2.push_back(m.orb->sigma2(l));
  }
  m.log_scale = std::log(options.orb.scale_factor);
}

MonoSlam::~MonoSlam() = default;

SlamFrameSummary MonoSlam::Track(const cv::Mat& gray, double stamp) {
  try {
    return impl_->Track(gray, stamp);
  } catch (const std::exception& e) {
    SlamFrameSummary s;
    s.state = SlamState::kLost;
    s.message = std::string("internal error: ") + e.what();
    return s;
  }
}

std::vector<MonoSlam::StampedPose> MonoSlam::Trajectory() const {
  std::vector<StampedPose> out = impl_->frozen;
  if (impl_->initialized) {
    const auto t = impl_->CurrentTrajectory();
    out.insert(out.end(), t.begin(), t.end());
  }
  std::stable_sort(out.begin(), out.end(), [](const StampedPose& a, const StampedPose& b) { return a.stamp < b.stamp; });
  return out;
}

std::vector<MonoSlam::StampedPose> MonoSlam::KeyFrameTrajectory() const {
  std::vector<StampedPose> out;
  if (!impl_->initialized) return out;
  for (const auto& k : impl_->map->keyframes)
    if (!k->bad) out.push_back({k->stamp, impl_->ToGlobal(k->T_cw.inverse()), impl_->map_number});
  return out;
}

SlamStats MonoSlam::stats() const {
  SlamStats s = impl_->stats;
  s.keyframes = impl_->map->GoodKeyFrames();
  s.points = impl_->map->GoodPoints();
  return s;
}

const Map& MonoSlam::map() const { return *impl_->map; }

}  // namespace unav_localization
