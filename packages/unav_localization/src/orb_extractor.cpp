#include "unav_localization/orb_extractor.hpp"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace unav::localization {

bool OrbOptions::IsValid(std::string* msg) const {
  auto fail = [msg](const std::string& m) {
    if (msg) *msg = m;
    return false;
  };
  if (features < 50) return fail("orb.features must be >= 50, got " + std::to_string(features));
  if (!(scale_factor > 1.0 && scale_factor < 2.0))
    return fail("orb.scale_factor must be in (1, 2), got " + std::to_string(scale_factor));
  if (levels < 1 || levels > 16) return fail("orb.levels must be in [1, 16], got " + std::to_string(levels));
  if (fast_threshold < 1 || fast_threshold > 100)
    return fail("orb.fast_threshold must be in [1, 100], got " + std::to_string(fast_threshold));
  if (cell_px < 8) return fail("orb.cell_px must be >= 8, got " + std::to_string(cell_px));
  if (edge_px < 16) return fail("orb.edge_px must be >= 16 (the ORB patch), got " + std::to_string(edge_px));
  return true;
}

OrbExtractor::OrbExtractor(const OrbOptions& options) : options_(options) {
  std::string msg;
  if (!options_.IsValid(&msg)) throw std::invalid_argument(msg);
  orb_ = cv::ORB::create(options_.features * 3, static_cast<float>(options_.scale_factor), options_.levels,
                         options_.edge_px, 0, 2, cv::ORB::HARRIS_SCORE, 31, options_.fast_threshold);
  scales_.resize(static_cast<size_t>(options_.levels));
  double s = 1.0;
  for (auto& v : scales_) {
    v = s;
    s *= options_.scale_factor;
  }
}

void OrbExtractor::Extract(const cv::Mat& gray, std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors) const {
  keypoints->clear();
  *descriptors = cv::Mat();
  if (gray.empty() || gray.type() != CV_8UC1) return;
  std::vector<cv::KeyPoint> all;
  orb_->detect(gray, all);
  // Grid selection: round-robin over cells, strongest first within each cell.
  const int cols = std::max(1, gray.cols / options_.cell_px), rows = std::max(1, gray.rows / options_.cell_px);
  std::vector<std::vector<cv::KeyPoint>> cells(static_cast<size_t>(cols * rows));
  for (const auto& k : all) {
    const int cx = std::min(cols - 1, static_cast<int>(k.pt.x) * cols / gray.cols);
    const int cy = std::min(rows - 1, static_cast<int>(k.pt.y) * rows / gray.rows);
    cells[static_cast<size_t>(cy) * static_cast<size_t>(cols) + static_cast<size_t>(cx)].push_back(k);
  }
  for (auto& c : cells)
    std::sort(c.begin(), c.end(), [](const cv::KeyPoint& a, const cv::KeyPoint& b) { return a.response > b.response; });
  std::vector<cv::KeyPoint> kept;
  kept.reserve(static_cast<size_t>(options_.features));
  for (size_t round = 0; kept.size() < static_cast<size_t>(options_.features); ++round) {
    bool any = false;
    for (const auto& c : cells) {
      if (round >= c.size()) continue;
      any = true;
      kept.push_back(c[round]);
      if (kept.size() >= static_cast<size_t>(options_.features)) break;
    }
    if (!any) break;
  }
  orb_->compute(gray, kept, *descriptors);
  *keypoints = std::move(kept);
}

int DescriptorDistance(const uint8_t* a, const uint8_t* b) {
  int d = 0;
  for (int i = 0; i < 4; ++i) {
    uint64_t x, y;
    std::memcpy(&x, a + static_cast<std::ptrdiff_t>(8) * i, 8);
    std::memcpy(&y, b + static_cast<std::ptrdiff_t>(8) * i, 8);
    d += __builtin_popcountll(x ^ y);
  }
  return d;
}

}  // namespace unav::localization
