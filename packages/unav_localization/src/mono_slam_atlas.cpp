// MonoSlam, atlas: maps lost for good are kept, recognised by bag of words from the current
// map's keyframes, and merged into it (ORB-SLAM3's multi-map Atlas, Elvira et al. 2019).
#include "mono_slam_impl.hpp"

namespace unav::localization {

auto MonoSlam::Impl::StoreCurrentMap() -> void {
  // A map of a few keyframes is a failed start, not a place worth recognising (ORB-SLAM3
  // discards them too).
  if (!opt.merge_maps || !voc || opt.atlas_max_maps == 0 || map->GoodKeyFrames() <= 5) return;
  StoredMap stored;
  stored.map = std::move(map);
  stored.db = std::move(db);
  stored.G = G;
  stored.number = map_number;
  stored.metric = metric_stage > 0;
  stored.traj = std::move(traj);
  atlas.push_back(std::move(stored));
  while (static_cast<int>(atlas.size()) > opt.atlas_max_maps) atlas.pop_front();
}

auto MonoSlam::Impl::MergeMaps(int kid) -> bool {
  if (!opt.merge_maps || !voc || atlas.empty()) return false;
  const bool metric_now = metric_stage > 0;
  for (std::size_t a = 0; a < atlas.size(); ++a) {
    StoredMap& stored = atlas[a];
    // A metric map and one in arbitrary units would need the scale of one to be trusted over
    // the other's: not merged (the aided modes seldom lose track).
    if (stored.metric != metric_now) continue;
    for (int cand : ConsistentCandidates(kid, *stored.map, stored.db, {}, &stored.groups)) {
      LoopCandidate lc;
      if (!ComputeSim3(kid, *stored.map, cand, &lc)) continue;
      // lc.S_cm maps the candidate's camera frame (old units) into kid's (current units), so
      // S_cw: old world -> kid's camera, and A: old world -> current world.
      const Sim3 S_cw = lc.S_cm * Sim3(stored.map->kf(cand).T_cw);
      const Sim3 A = Sim3(map->kf(kid).T_cw).inverse() * S_cw;
      StoredMap old = std::move(stored);
      atlas.erase(atlas.begin() + static_cast<std::ptrdiff_t>(a));
      AbsorbMap(std::move(old), A, kid, lc);
      return true;
    }
  }
  return false;
}

auto MonoSlam::Impl::AbsorbMap(StoredMap&& old, const Sim3& A, int kid, const LoopCandidate& lc) -> void {
  const int kf_off = static_cast<int>(map->keyframes.size());
  const int pt_off = static_cast<int>(map->points.size());
  const auto shift_kf = [kf_off](int id) { return id >= 0 ? id + kf_off : id; };
  const auto shift_set = [kf_off](const std::set<int>& in) {
    std::set<int> out;
    for (int id : in) out.insert(id + kf_off);
    return out;
  };
  const Eigen::Matrix3d R_A = A.R;
  const double s = A.s;
  // An old camera pose T_cw (old world -> camera, old units) seen from the current world:
  // X_c = R_cw R_A^T (X_cur - t_A) / s + t_cw, so in current units R = R_cw R_A^T and
  // t = s t_cw - R t_A.
  for (auto& k : old.map->keyframes) {
    KeyFrame& kf = *k;
    const Eigen::Matrix3d R = kf.T_cw.linear() * R_A.transpose();
    const Eigen::Vector3d t = s * kf.T_cw.translation() - R * A.t;
    kf.T_cw.linear() = R;
    kf.T_cw.translation() = t;
    kf.id += kf_off;
    for (int& p : kf.points)
      if (p >= 0) p += pt_off;
    std::map<int, int> covisibility;
    for (const auto& [n, w] : kf.covisibility) covisibility[n + kf_off] = w;
    kf.covisibility = std::move(covisibility);
    kf.parent = shift_kf(kf.parent);
    kf.children = shift_set(kf.children);
    kf.loop_edges = shift_set(kf.loop_edges);
    if (!kf.bad) db.Add(kf.id, kf.f.bow);
    map->keyframes.push_back(std::move(k));
  }
  std::vector<int> moved;
  for (auto& q : old.map->points) {
    MapPoint& p = *q;
    p.X_w = A * p.X_w;
    p.min_distance *= s;
    p.max_distance *= s;
    p.id += pt_off;
    std::map<int, int> obs;
    for (const auto& [k, i] : p.obs) obs[k + kf_off] = i;
    p.obs = std::move(obs);
    p.first_kf = shift_kf(p.first_kf);
    p.ref_kf = shift_kf(p.ref_kf);
    if (!p.bad) moved.push_back(p.id);
    map->points.push_back(std::move(q));
  }
  for (int p : moved) map->UpdatePoint(p, scales);
  // The old map's frames follow their keyframes from now on (and their corrections).
  for (TrajEntry e : old.traj) {
    e.ref_kf += kf_off;
    e.T_cr.translation() *= s;
    traj.push_back(e);
  }
  std::stable_sort(traj.begin(), traj.end(), [](const TrajEntry& a, const TrajEntry& b) { return a.stamp < b.stamp; });
  frozen.erase(std::remove_if(frozen.begin(), frozen.end(), [&](const StampedPose& p) { return p.map == old.number; }),
               frozen.end());
  // The current map now lives in the old map's global frame: X_g = G_old X_old = G_old A^-1 X_cur.
  G = old.G * A.inverse();
  // Weld: the current keyframe's matches become the old map's points, and the old place's
  // points are fused into the current keyframe's neighbourhood.
  KeyFrame& c = map->kf(kid);
  const int cand = lc.kf + kf_off;
  std::vector<std::pair<int, int>> matches = lc.matches;
  for (auto& m : matches) m.second += pt_off;
  std::vector<int> connected{kid};
  for (const auto& [k, w] : c.covisibility) connected.push_back(k);
  WeldLoopPoints(kid, cand, matches, connected);
  for (int k : connected) map->UpdateConnections(k);
  std::vector<int> old_side = map->kf(cand).BestCovisible(10);
  old_side.push_back(cand);
  for (int k : old_side) map->UpdateConnections(k);
  c.loop_edges.insert(cand);
  map->kf(cand).loop_edges.insert(kid);
  if (opt.global_ba_after_loop)
    GlobalBundleAdjustment(map.get(), cam, sigma2, opt.global_ba_iterations, AidingFactors(0));
  for (auto& p : map->points)
    if (!p->bad) map->UpdatePoint(p->id, scales);
  consistent_groups.clear();
  ++stats.merges;
}

}  // namespace unav::localization
