// MonoSlam, loop closing: BoW candidates, Sim(3) RANSAC, correction, essential graph, global BA.
#include "mono_slam_impl.hpp"

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

auto MonoSlam::Impl::ConsistentCandidates(int kid, const Map& other, const BowDatabase& other_db,
                                          const std::set<int>& exclude, CandidateGroups* groups) const
    -> std::vector<int> {
  const KeyFrame& kf = map->kf(kid);
  std::vector<int> out;
  if (!voc || kf.f.bow.empty() || kf.covisibility.empty()) {
    groups->clear();
    return out;
  }
  double min_score = 1.0;
  for (const auto& [n, w] : kf.covisibility)
    min_score = std::min(min_score, BowVocabulary::Score(kf.f.bow, map->kf(n).f.bow));
  const auto hits = other_db.Query(kf.f.bow, min_score * opt.loop_min_score_ratio, exclude, 20);
  CandidateGroups next;
  for (const auto& [c, score] : hits) {
    std::set<int> group{c};
    for (const auto& [n, w] : other.kf(c).covisibility) group.insert(n);
    int count = 0;
    for (const auto& [prev, pc] : *groups) {
      bool shares = false;
      for (int g : group)
        if (prev.count(g)) {
          shares = true;
          break;
        }
      if (shares) count = std::max(count, pc + 1);
    }
    next.emplace_back(group, count);
    if (count >= opt.loop_consistency) out.push_back(c);
  }
  *groups = std::move(next);
  return out;
}

auto MonoSlam::Impl::DetectLoopCandidates(int kid) -> std::vector<int> {
  std::set<int> exclude{kid};
  for (const auto& [n, w] : map->kf(kid).covisibility) exclude.insert(n);
  for (int k = std::max(0, kid - opt.loop_min_keyframe_gap); k < kid; ++k) exclude.insert(k);
  return ConsistentCandidates(kid, *map, db, exclude, &consistent_groups);
}

auto MonoSlam::Impl::ComputeSim3(int kid, const Map& other, int cand, LoopCandidate* lc) -> bool {
  const bool same_map = &other == map.get();
  const KeyFrame& c = map->kf(kid);
  const KeyFrame& m = other.kf(cand);
  const auto has_point = [](const Map& in, const KeyFrame& k) {
    return [&in, &k](int i) {
      return k.points[static_cast<size_t>(i)] >= 0 && !in.mp(k.points[static_cast<size_t>(i)]).bad;
    };
  };
  const auto matches = MatchByAppearance(c.f, has_point(*map, c), m.f, has_point(other, m), kThLow, 0.75);
  if (matches.size() < 20) return false;
  std::vector<Sim3Match> sm;
  for (const auto& [i, j] : matches) {
    Sim3Match s;
    s.X1_c1 = c.T_cw * map->mp(c.points[static_cast<size_t>(i)]).X_w;
    s.X2_c2 = m.T_cw * other.mp(m.points[static_cast<size_t>(j)]).X_w;
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
      const bool ok = p1.z() > 0 && p2.z() > 0 &&
                      (cam.Project(p1) - sm[k].uv1).squaredNorm() * sm[k].inv_sigma2_1 < gate &&
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
  std::vector<int> group = m.BestCovisible(10);
  group.push_back(cand);
  for (int g : group)
    for (int p : other.kf(g).points)
      if (p >= 0 && !other.mp(p).bad) pts.insert(p);
  lc->matches.clear();
  std::vector<int> taken(c.f.size(), -1);
  for (int pid : pts) {
    const MapPoint& p = other.mp(pid);
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
  if (!same_map) {
    // Two maps: nothing relates their frames before this, so no correction can be judged.
    char text[160];
    std::snprintf(text, sizeof(text), "keyframe %d <-> earlier map's %d: scale %.3f, %zu matches", kid, cand, best.s,
                  lc->matches.size());
    loop_log += (loop_log.empty() ? "" : "; ") + std::string(text);
    lc->kf = cand;
    lc->S_cm = best;
    return true;
  }
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
  std::snprintf(text, sizeof(text),
                "keyframe %d <-> %d: scale %.3f, %zu matches, correction %.3f over a path of %.3f (map units)", kid,
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

auto MonoSlam::Impl::CorrectLoop(int kid, const LoopCandidate& lc) -> void {
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
  WeldLoopPoints(kid, lc.kf, lc.matches, connected);
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
  if (opt.global_ba_after_loop)
    GlobalBundleAdjustment(map.get(), cam, sigma2, opt.global_ba_iterations, AidingFactors(0));
  ++stats.loops;
}

auto MonoSlam::Impl::WeldLoopPoints(int kid, int loop_kf, const std::vector<std::pair<int, int>>& matches,
                                    const std::vector<int>& connected) -> void {
  KeyFrame& c = map->kf(kid);
  for (const auto& [i, pid] : matches) {
    if (map->mp(pid).bad) continue;
    const int q = c.points[static_cast<size_t>(i)];
    if (q >= 0 && !map->mp(q).bad)
      map->Replace(q, pid);
    else if (!map->mp(pid).obs.count(kid))
      map->AddObservation(pid, kid, i);
  }
  std::vector<int> loop_points;
  std::set<int> seen;
  std::vector<int> group = map->kf(loop_kf).BestCovisible(10);
  group.push_back(loop_kf);
  for (int g : group)
    for (int p : map->kf(g).points)
      if (p >= 0 && !map->mp(p).bad && seen.insert(p).second) loop_points.push_back(p);
  for (int k : connected) Fuse(k, loop_points);
}

auto MonoSlam::Impl::LoopClosing(int kid) -> bool {
  if (!opt.loop_closing || !voc) return false;
  bool closed = false;
  if (kid > opt.loop_min_keyframe_gap) {
    for (int cand : DetectLoopCandidates(kid)) {
      LoopCandidate lc;
      if (ComputeSim3(kid, *map, cand, &lc)) {
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

}  // namespace unav::localization
