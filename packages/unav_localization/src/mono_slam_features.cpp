// MonoSlam, features: extraction, bag of words, scale prediction, matching by appearance.
#include "mono_slam_impl.hpp"

namespace unav::localization {

using namespace slam_internal;  // NOLINT(google-build-using-namespace): the SLAM's own constants

auto MonoSlam::Impl::ExtractFeatures(const cv::Mat& gray, const OrbExtractor& extractor, Frame* f) -> void {
  extractor.Extract(gray, &f->f.keypoints, &f->f.descriptors);
  f->f.un.resize(f->f.keypoints.size());
  if (!f->f.keypoints.empty()) {
    std::vector<cv::Point2f> pts, und;
    for (const auto& k : f->f.keypoints) pts.push_back(k.pt);
    if (!D.empty())
      cv::undistortPoints(pts, und, K, D, cv::noArray(), K);
    else
      und = pts;
    for (size_t i = 0; i < und.size(); ++i) f->f.un[i] = Eigen::Vector2d(und[i].x, und[i].y);
  }
  f->f.BuildGrid(cam.width, cam.height, 16.0);
  f->points.assign(f->f.size(), -1);
  f->outlier.assign(f->f.size(), false);
}

auto MonoSlam::Impl::ComputeBow(Features* f) const -> void {
  if (voc && f->bow.empty() && !f->descriptors.empty())
    voc->Transform(f->descriptors, &f->bow, &f->feature_vector, std::max(0, voc->levels() - 1));
}

auto MonoSlam::Impl::PredictLevel(const MapPoint& p, double dist) const -> int {
  const double ratio = p.max_distance / std::max(dist, 1e-9);
  const int level = static_cast<int>(std::ceil(std::log(ratio) / log_scale));
  return std::clamp(level, 0, opt.orb.levels - 1);
}

auto MonoSlam::Impl::MatchByAppearance(const Features& a, const std::function<bool(int)>& use_a, const Features& b,
                                       const std::function<bool(int)>& use_b, int th, double ratio,
                                       const std::function<bool(int, int)>& pair_ok, double off_pair_ratio) const
    -> std::vector<std::pair<int, int>> {
  std::vector<std::pair<int, int>> out;
  std::vector<int> best_for_b(b.size(), -1), best_dist_b(b.size(), 256);
  auto match_sets = [&](const std::vector<int>& ia, const std::vector<int>& ib) {
    for (int i : ia) {
      if (!use_a(i)) continue;
      BestTwo m;
      int off_pair = 256;  // the nearest candidate pair_ok refused
      for (int j : ib) {
        if (!use_b(j)) continue;
        const int d = DescriptorDistance(a.desc(i), b.desc(j));
        if (!pair_ok || pair_ok(i, j))
          m.Add(d, j);
        else
          off_pair = std::min(off_pair, d);
      }
      const int best = m.best, bj = m.index;
      if (bj < 0 || best > th || best >= ratio * m.second) continue;
      if (off_pair_ratio > 0 && best >= off_pair_ratio * off_pair) continue;
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

}  // namespace unav::localization
