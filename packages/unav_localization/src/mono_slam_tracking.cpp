// MonoSlam, tracking: motion model, reference keyframe, local map, pose optimisation, relocalisation.
#include "mono_slam_impl.hpp"
#include "pnp_pose.hpp"

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

auto MonoSlam::Impl::Visible(const MapPoint& p, const Eigen::Isometry3d& T_cw, Eigen::Vector2d* uv, int* level,
                             double* view_cos) const -> bool {
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

auto MonoSlam::Impl::SearchByProjection(Frame* f, const std::vector<int>& pts, double radius_factor, bool count_visible,
                                        int th) -> int {
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
      m.Add(DescriptorDistance(p.descriptor.ptr<uint8_t>(), f->f.desc(i)), i,
            f->f.keypoints[static_cast<size_t>(i)].octave);
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

auto MonoSlam::Impl::Optimize(Frame* f) -> int {
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

auto MonoSlam::Impl::TrackWithMotionModel(const std::optional<Eigen::Isometry3d>& predicted) -> bool {
  if (predicted) {
    cur.T_cw = *predicted;
    ++stats.imu_predicted_frames;
  } else {
    cur.T_cw = velocity * last.T_cw;
  }
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

auto MonoSlam::Impl::TrackReferenceKeyFrame() -> bool {
  const KeyFrame& kf = map->kf(ref_kf);
  ComputeBow(&cur.f);
  const auto m = MatchByAppearance(
      kf.f,
      [&](int i) { return kf.points[static_cast<size_t>(i)] >= 0 && !map->mp(kf.points[static_cast<size_t>(i)]).bad; },
      cur.f, [](int) { return true; }, kThHigh, 0.7);
  if (m.size() < 15) return false;
  for (const auto& [i, j] : m) cur.points[static_cast<size_t>(j)] = kf.points[static_cast<size_t>(i)];
  cur.T_cw = last.T_cw;
  return Optimize(&cur) >= 10;
}

auto MonoSlam::Impl::UpdateLocalMap() -> void {
  std::map<int, int> counts;
  for (int p : cur.points)
    if (p >= 0 && !map->mp(p).bad)
      for (const auto& [k, i] : map->mp(p).obs) ++counts[k];
  std::vector<std::pair<int, int>> ranked;
  ranked.reserve(counts.size());
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

auto MonoSlam::Impl::TrackLocalMap() -> int {
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

auto MonoSlam::Impl::PlausibleRelocalization(std::string* why) const -> bool {
  if (opt.reloc_gate_speed_factor <= 0) return true;
  const int frames = std::max(1, cur.index - last.index);
  const double step = recent_steps.empty() ? 0.0 : *std::max_element(recent_steps.begin(), recent_steps.end());
  const double depth = map->MedianDepth(ref_kf);
  const double radius =
      opt.reloc_gate_speed_factor * step * frames + opt.reloc_gate_min_radius * (depth > 0 ? depth : 1.0);
  const double dist = (CameraCentre(cur.T_cw) - CameraCentre(last.T_cw)).norm();
  const double turn_deg = Eigen::AngleAxisd(cur.T_cw.linear() * last.T_cw.linear().transpose()).angle() * 180.0 / M_PI;
  const double max_turn_deg = std::min(180.0, opt.reloc_gate_deg_per_frame * frames);
  char buf[200];
  if (dist > radius) {
    std::snprintf(
        buf, sizeof buf,
        "; a relocalisation %.3g (map units) from the last tracked pose after %d frame(s) rejected (gate %.3g)", dist,
        frames, radius);
    *why = buf;
    return false;
  }
  if (turn_deg > max_turn_deg) {
    std::snprintf(
        buf, sizeof buf,
        "; a relocalisation turned %.1f deg from the last tracked pose after %d frame(s) rejected (gate %.1f)",
        turn_deg, frames, max_turn_deg);
    *why = buf;
    return false;
  }
  return true;
}

auto MonoSlam::Impl::Relocalize() -> bool {
  reloc_rejection.clear();
  if (!voc) return false;
  ComputeBow(&cur.f);
  const auto cands = db.Query(cur.f.bow, 0.0, {}, 10);
  cv::Mat Kcv;
  cv::eigen2cv(cam.K(), Kcv);
  for (const auto& [kid, score] : cands) {
    const KeyFrame& kf = map->kf(kid);
    if (kf.bad) continue;
    const auto m = MatchByAppearance(
        kf.f,
        [&](int i) {
          return kf.points[static_cast<size_t>(i)] >= 0 && !map->mp(kf.points[static_cast<size_t>(i)]).bad;
        },
        cur.f, [](int) { return true; }, kThHigh, 0.75);
    if (m.size() < 15) continue;
    std::vector<cv::Point3f> obj;
    std::vector<cv::Point2f> img;
    for (const auto& [i, j] : m) {
      const auto& X = map->mp(kf.points[static_cast<size_t>(i)]).X_w;
      obj.emplace_back(static_cast<float>(X.x()), static_cast<float>(X.y()), static_cast<float>(X.z()));
      img.emplace_back(static_cast<float>(cur.f.un[static_cast<size_t>(j)].x()),
                       static_cast<float>(cur.f.un[static_cast<size_t>(j)].y()));
    }
    cv::Mat rvec, tvec;
    std::vector<int> inl;
    if (!cv::solvePnPRansac(obj, img, Kcv, cv::noArray(), rvec, tvec, false, 200, 2.0f, 0.99, inl, cv::SOLVEPNP_EPNP))
      continue;
    if (inl.size() < 10) continue;
    cur.T_cw = detail::FromRvecTvec(rvec, tvec);
    std::fill(cur.points.begin(), cur.points.end(), -1);
    for (int k : inl)
      cur.points[static_cast<size_t>(m[static_cast<size_t>(k)].second)] =
          kf.points[static_cast<size_t>(m[static_cast<size_t>(k)].first)];
    if (Optimize(&cur) < 10) continue;
    const int ref_before = ref_kf;
    ref_kf = kid;
    if (TrackLocalMap() < 50) {
      ref_kf = ref_before;
      continue;
    }
    if (!PlausibleRelocalization(&reloc_rejection)) {
      ++stats.relocalizations_rejected;
      ref_kf = ref_before;
      continue;
    }
    last_reloc_frame = cur.index;
    return true;
  }
  std::fill(cur.points.begin(), cur.points.end(), -1);
  return false;
}

}  // namespace unav::localization
