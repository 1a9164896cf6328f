// MonoSlam, two-view initialisation: essential / homography candidates, triangulation, initial map.
#include "mono_slam_impl.hpp"

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

auto MonoSlam::Impl::Triangulate(const Eigen::Matrix<double, 3, 4>& P1, const Eigen::Matrix<double, 3, 4>& P2,
                                 const Eigen::Vector2d& x1, const Eigen::Vector2d& x2, Eigen::Vector3d* X) -> bool {
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

auto MonoSlam::Impl::CheckMotion(const Eigen::Matrix3d& R, const Eigen::Vector3d& t, const Features& f1,
                                 const Features& f2, const std::vector<std::pair<int, int>>& matches,
                                 const std::vector<uchar>& inlier) const -> Reconstruction {
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
    ++rec.inliers;
    const auto& x1 = f1.un[static_cast<size_t>(matches[m].first)];
    const auto& x2 = f2.un[static_cast<size_t>(matches[m].second)];
    Eigen::Vector3d X;
    if (!Triangulate(P1, P2, x1, x2, &X)) continue;
    const Eigen::Vector3d X2 = R * X + t;
    if (X.z() <= 0 || X2.z() <= 0) continue;
    const double cos_par = X.normalized().dot((X - O2).normalized());
    if ((cam.Project(X) - x1).squaredNorm() > 4.0 * kChi2Mono) continue;
    if ((cam.Project(X2) - x2).squaredNorm() > 4.0 * kChi2Mono) continue;
    ++rec.good;
    parallaxes.push_back(std::acos(std::clamp(cos_par, -1.0, 1.0)) * 180.0 / M_PI);
    if (cos_par < 0.99998) rec.points.emplace_back(static_cast<int>(m), X);
  }
  if (!parallaxes.empty()) {
    // The parallax of the k-th most parallax-rich point (k = 50, as ORB-SLAM), not the median:
    // under forward motion (driving, a vehicle flying along a pipe) the points near the focus of
    // expansion have almost none however far the camera moved, and a median waits for ever.
    std::sort(parallaxes.begin(), parallaxes.end(), std::greater<>());
    rec.parallax_deg = parallaxes[std::min<size_t>(50, parallaxes.size() - 1)];
  }
  return rec;
}

auto MonoSlam::Impl::TryInitialize(SlamFrameSummary s) -> SlamFrameSummary {
  s.state = SlamState::kInitializing;
  const int min_ref_features = scaled(100), min_points = scaled(opt.init_min_points);
  auto set_reference = [this] {
    init_ref = std::make_unique<Frame>(cur);
    init_prev = cur.f.un;
  };
  if (!init_ref || static_cast<int>(cur.f.size()) < min_ref_features ||
      cur.index - init_ref->index > opt.init_max_frames) {
    if (static_cast<int>(cur.f.size()) >= min_ref_features)
      set_reference();
    else
      init_ref.reset();
    s.message = "waiting for a reference frame with enough features";
    return s;
  }
  // Window search around where each reference feature was matched last (its own pixel at first):
  // the window follows the features frame by frame, so the flow may grow large over the frames
  // it takes to gather parallax (forward motion: ~100 px a frame at the image border).
  std::vector<std::pair<int, int>> matches;
  std::vector<int> taken(cur.f.size(), -1), taken_dist(cur.f.size(), 256);
  for (size_t i = 0; i < init_ref->f.size(); ++i) {
    if (init_ref->f.keypoints[i].octave > 1) continue;
    const auto cands = cur.f.InArea(init_prev[i], 0.15 * cam.width, 0, 2);
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
    if (taken[j] >= 0) {
      matches.emplace_back(taken[j], static_cast<int>(j));
      init_prev[static_cast<size_t>(taken[j])] = cur.f.un[j];
    }
  s.inliers = static_cast<int>(matches.size());
  if (static_cast<int>(matches.size()) < min_points) {
    if (static_cast<int>(matches.size()) < scaled(40)) set_reference();  // lost the reference
    s.message = "initialisation: " + std::to_string(matches.size()) + " matches";
    return s;
  }
  std::vector<cv::Point2f> p1, p2;
  double median_flow = 0;
  {
    std::vector<double> flow;
    for (const auto& [i, j] : matches) {
      p1.emplace_back(static_cast<float>(init_ref->f.un[static_cast<size_t>(i)].x()),
                      static_cast<float>(init_ref->f.un[static_cast<size_t>(i)].y()));
      p2.emplace_back(static_cast<float>(cur.f.un[static_cast<size_t>(j)].x()),
                      static_cast<float>(cur.f.un[static_cast<size_t>(j)].y()));
      flow.push_back(cv::norm(p1.back() - p2.back()));
    }
    std::sort(flow.begin(), flow.end());
    median_flow = flow[flow.size() / 2];
  }
  if (median_flow < 0.005 * cam.width) {  // too little motion to try (the parallax test decides)
    s.message = "initialisation: waiting for parallax (" + std::to_string(matches.size()) + " matches, median flow " +
                std::to_string(static_cast<int>(median_flow)) + " px)";
    return s;
  }
  std::vector<Reconstruction> candidates;
  TwoViewOptions two_view;
  two_view.homography_ransac_px = 1.5;
  const Eigen::Matrix3d Km = cam.K();
  cv::Matx33d K;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K(r, c) = Km(r, c);
  // Model selection as ORB-SLAM: a (nearly) planar view — the seabed — makes the essential
  // matrix ill-conditioned, and RANSAC then returns a wrong motion that fits well (a rippled
  // seabed ahead gave an 8 deg pitch where the camera did not turn); a 3-D scene makes the
  // homography fit only part of it. Only the better model's motions compete.
  const std::vector<TwoViewCandidate> motions = TwoViewCandidates(p1, p2, K, two_view);
  const bool planar = HomographyRatio(motions) > opt.init_homography_ratio;
  for (const TwoViewCandidate& c : motions)
    if ((c.model == TwoViewCandidate::Model::kHomography) == planar)
      candidates.push_back(CheckMotion(c.R, c.t.normalized(), init_ref->f, cur.f, matches, c.inliers));
  // Ranked by the correspondences they reconstruct at all (ORB-SLAM's nGood): a wrong twin of the
  // true motion triangulates far points with a little more parallax, so counting only points
  // with parallax favoured it.
  std::sort(candidates.begin(), candidates.end(), [](const auto& a, const auto& b) {
    return a.good != b.good ? a.good > b.good : a.points.size() > b.points.size();
  });
  if (candidates.empty()) {
    s.message = "initialisation: no two-view motion";
    return s;
  }
  // A second, different motion reconstructing almost as many correspondences. A plane seen from
  // two views has two exact motions: the true one and a twin whose translation is the plane's
  // normal and which turns the camera (the seabed ahead: the twin turned 12 deg over 5 frames
  // where the camera turned < 1 deg). With init_prefer_smaller_rotation the one that turns at
  // least twice as much, and 1 deg more, gives way (a vehicle or a car translates more than it
  // turns between nearby frames); any other ambiguity waits for more frames.
  size_t chosen = 0;
  std::vector<size_t> rivals;
  for (size_t k = 1; k < candidates.size(); ++k) {
    const double dR = Eigen::AngleAxisd(candidates[k].R.transpose() * candidates[0].R).angle();
    const double dt = std::acos(std::clamp(candidates[k].t.dot(candidates[0].t), -1.0, 1.0));
    if ((dR > 0.05 || dt > 0.2) && candidates[k].good > 0.75 * candidates[0].good) rivals.push_back(k);
  }
  if (!rivals.empty()) {
    bool resolved = false;
    if (opt.init_prefer_smaller_rotation && rivals.size() == 1) {
      const double a0 = Eigen::AngleAxisd(candidates[0].R).angle(),
                   a1 = Eigen::AngleAxisd(candidates[rivals[0]].R).angle();
      const double one_deg = M_PI / 180.0;
      if (2 * a1 <= a0 && a0 - a1 >= one_deg) {
        chosen = rivals[0];
        resolved = true;
      } else if (2 * a0 <= a1 && a1 - a0 >= one_deg) {
        resolved = true;
      }
    }
    if (!resolved) {
      s.message = "initialisation: ambiguous two-view motion";
      return s;
    }
  }
  const Reconstruction& best = candidates[chosen];
  // As ORB-SLAM: nearly every inlier of the chosen model must reconstruct (in front of both
  // cameras, reprojecting well); a motion that explains only part of them is a wrong one.
  if (static_cast<int>(best.points.size()) < min_points || best.parallax_deg < opt.init_min_parallax_deg ||
      best.good < opt.init_min_good_ratio * best.inliers) {
    s.message = "initialisation: not enough parallax or points (" + std::to_string(best.points.size()) + " points, " +
                std::to_string(best.good) + " of " + std::to_string(best.inliers) + " inliers good, parallax " +
                std::to_string(best.parallax_deg).substr(0, 4) + " deg)";
    return s;
  }
  CreateInitialMap(best, matches);
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

auto MonoSlam::Impl::NewKeyFrame(const Frame& f) -> int {
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

auto MonoSlam::Impl::CreateInitialMap(const Reconstruction& rec, const std::vector<std::pair<int, int>>& matches)
    -> void {
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

}  // namespace unav::localization
