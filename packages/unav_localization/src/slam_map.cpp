#include "unav_localization/slam_map.hpp"

#include <algorithm>
#include <cmath>

#include "unav_localization/orb_extractor.hpp"
#include "unav_localization/sim3.hpp"

namespace unav::localization {

void Features::BuildGrid(int width, int height, double cell) {
  cell_px = cell;
  grid_cols = std::max(1, static_cast<int>(std::ceil(width / cell)));
  grid_rows = std::max(1, static_cast<int>(std::ceil(height / cell)));
  grid.assign(static_cast<size_t>(grid_cols) * static_cast<size_t>(grid_rows), {});
  for (size_t i = 0; i < un.size(); ++i) {
    const int cx = static_cast<int>(std::floor(un[i].x() / cell_px)),
              cy = static_cast<int>(std::floor(un[i].y() / cell_px));
    if (cx < 0 || cy < 0 || cx >= grid_cols || cy >= grid_rows) continue;
    grid[static_cast<size_t>(cy) * static_cast<size_t>(grid_cols) + static_cast<size_t>(cx)].push_back(
        static_cast<int>(i));
  }
}

std::vector<int> Features::InArea(const Eigen::Vector2d& uv, double radius, int min_level, int max_level) const {
  std::vector<int> out;
  const int x0 = std::max(0, static_cast<int>(std::floor((uv.x() - radius) / cell_px)));
  const int x1 = std::min(grid_cols - 1, static_cast<int>(std::floor((uv.x() + radius) / cell_px)));
  const int y0 = std::max(0, static_cast<int>(std::floor((uv.y() - radius) / cell_px)));
  const int y1 = std::min(grid_rows - 1, static_cast<int>(std::floor((uv.y() + radius) / cell_px)));
  const double r2 = radius * radius;
  for (int y = y0; y <= y1; ++y)
    for (int x = x0; x <= x1; ++x)
      for (int i : grid[static_cast<size_t>(y) * static_cast<size_t>(grid_cols) + static_cast<size_t>(x)]) {
        const int lvl = keypoints[static_cast<size_t>(i)].octave;
        if (min_level >= 0 && lvl < min_level) continue;
        if (max_level >= 0 && lvl > max_level) continue;
        if ((un[static_cast<size_t>(i)] - uv).squaredNorm() <= r2) out.push_back(i);
      }
  return out;
}

std::vector<int> KeyFrame::BestCovisible(size_t n) const {
  std::vector<std::pair<int, int>> v;
  for (const auto& [id, w] : covisibility) v.emplace_back(w, id);
  std::sort(v.begin(), v.end(),
            [](const auto& a, const auto& b) { return a.first != b.first ? a.first > b.first : a.second < b.second; });
  std::vector<int> out;
  for (size_t i = 0; i < v.size() && i < n; ++i) out.push_back(v[i].second);
  return out;
}

int Map::AddPoint(const Eigen::Vector3d& X_w, int kf_id) {
  auto p = std::make_unique<MapPoint>();
  p->id = static_cast<int>(points.size());
  p->X_w = X_w;
  p->first_kf = p->ref_kf = kf_id;
  points.push_back(std::move(p));
  return points.back()->id;
}

void Map::AddObservation(int point, int kf_id, int feature) {
  mp(point).obs[kf_id] = feature;
  kf(kf_id).points[static_cast<size_t>(feature)] = point;
}

void Map::EraseObservation(int point, int kf_id) {
  MapPoint& p = mp(point);
  const auto it = p.obs.find(kf_id);
  if (it == p.obs.end()) return;
  KeyFrame& k = kf(kf_id);
  if (k.points[static_cast<size_t>(it->second)] == point) k.points[static_cast<size_t>(it->second)] = -1;
  p.obs.erase(it);
  if (p.ref_kf == kf_id && !p.obs.empty()) p.ref_kf = p.obs.begin()->first;
  if (!p.bad && p.obs.size() < 2) ErasePoint(point);  // a monocular point needs two views
}

void Map::ErasePoint(int point) {
  MapPoint& p = mp(point);
  p.bad = true;
  for (const auto& [k, i] : p.obs) {
    KeyFrame& kfr = kf(k);
    if (kfr.points[static_cast<size_t>(i)] == point) kfr.points[static_cast<size_t>(i)] = -1;
  }
  p.obs.clear();
}

void Map::Replace(int from, int into) {
  if (from == into) return;
  MapPoint& a = mp(from);
  MapPoint& b = mp(into);
  if (a.bad || b.bad) return;
  for (const auto& [k, i] : a.obs) {
    KeyFrame& kfr = kf(k);
    if (b.obs.count(k)) {
      if (kfr.points[static_cast<size_t>(i)] == from) kfr.points[static_cast<size_t>(i)] = -1;
    } else {
      b.obs[k] = i;
      kfr.points[static_cast<size_t>(i)] = into;
    }
  }
  b.visible += a.visible;
  b.found += a.found;
  a.obs.clear();
  a.bad = true;
}

void Map::UpdatePoint(int point, const std::vector<double>& level_scales) {
  MapPoint& p = mp(point);
  if (p.bad || p.obs.empty()) return;
  std::vector<const uint8_t*> descs;
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  for (const auto& [k, i] : p.obs) {
    const KeyFrame& kfr = kf(k);
    descs.push_back(kfr.f.desc(i));
    n += (p.X_w - kfr.Center()).normalized();
  }
  p.normal = n.normalized();
  size_t best = 0;
  int best_median = 1 << 30;
  for (size_t a = 0; a < descs.size(); ++a) {
    std::vector<int> d;
    for (size_t b = 0; b < descs.size(); ++b) d.push_back(DescriptorDistance(descs[a], descs[b]));
    std::nth_element(d.begin(), d.begin() + static_cast<long>(d.size() / 2), d.end());
    if (d[d.size() / 2] < best_median) {
      best_median = d[d.size() / 2];
      best = a;
    }
  }
  p.descriptor = cv::Mat(1, 32, CV_8U);
  std::copy(descs[best], descs[best] + 32, p.descriptor.ptr<uint8_t>());
  const KeyFrame& ref = kf(p.ref_kf);
  const auto it = p.obs.find(p.ref_kf);
  if (it == p.obs.end()) return;
  const int level = ref.f.keypoints[static_cast<size_t>(it->second)].octave;
  const double dist = (p.X_w - ref.Center()).norm();
  p.max_distance = dist * level_scales[static_cast<size_t>(level)];
  p.min_distance = p.max_distance / level_scales.back();
}

void Map::UpdateConnections(int kf_id, int min_weight) {
  KeyFrame& k = kf(kf_id);
  std::map<int, int> counts;
  for (int p : k.points) {
    if (p < 0 || mp(p).bad) continue;
    for (const auto& [o, i] : mp(p).obs)
      if (o != kf_id) ++counts[o];
  }
  // Remove this keyframe from its old neighbours, then add the new weights.
  for (const auto& [o, w] : k.covisibility) kf(o).covisibility.erase(kf_id);
  k.covisibility.clear();
  int best = -1, best_w = 0;
  for (const auto& [o, w] : counts) {
    if (kf(o).bad) continue;
    if (w > best_w) {
      best_w = w;
      best = o;
    }
    if (w >= min_weight) {
      k.covisibility[o] = w;
      kf(o).covisibility[kf_id] = w;
    }
  }
  if (k.covisibility.empty() && best >= 0) {
    k.covisibility[best] = best_w;
    kf(best).covisibility[kf_id] = best_w;
  }
  if (k.parent < 0 && kf_id != 0 && best >= 0) {
    k.parent = best;
    kf(best).children.insert(kf_id);
  }
}

int Map::GoodPoints() const {
  int n = 0;
  for (const auto& p : points) n += p->bad ? 0 : 1;
  return n;
}

int Map::GoodKeyFrames() const {
  int n = 0;
  for (const auto& k : keyframes) n += k->bad ? 0 : 1;
  return n;
}

double Map::MedianDepth(int kf_id) const {
  const KeyFrame& k = kf(kf_id);
  std::vector<double> z;
  for (int p : k.points)
    if (p >= 0 && !mp(p).bad) z.push_back((k.T_cw * mp(p).X_w).z());
  if (z.empty()) return 1.0;
  std::nth_element(z.begin(), z.begin() + static_cast<long>(z.size() / 2), z.end());
  return z[z.size() / 2];
}

bool EstimateSim3(const Eigen::Matrix3Xd& from, const Eigen::Matrix3Xd& to, bool fix_scale, Sim3* S) {
  // The common Umeyama with the SLAM's rules (its defaults): >= 3 points, spread > 1e-12 m^2,
  // not collinear; a non-positive scale is written but rejected (as before, bit for bit).
  unav::common::UmeyamaOptions options;
  options.with_scale = !fix_scale;
  const unav::common::UmeyamaResult r = unav::common::Umeyama(from, to, options);
  if (r.status == unav::common::UmeyamaStatus::kOk || r.status == unav::common::UmeyamaStatus::kBadScale) *S = r.S;
  return r.ok();
}

}  // namespace unav::localization
