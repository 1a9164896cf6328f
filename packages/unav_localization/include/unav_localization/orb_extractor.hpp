// ORB features spread evenly over the image: OpenCV's ORB (FAST corners on a scale pyramid,
// oriented BRIEF) detects several times the wanted number of corners with a low FAST threshold,
// then a grid keeps the strongest of each cell first, so weak-texture regions (sand, water) still
// contribute and one bright rock cannot take every feature.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>

namespace unav::localization {

struct OrbOptions {
  int features = 1000;        ///< features kept per image
  double scale_factor = 1.2;  ///< pyramid scale between levels
  int levels = 8;             ///< pyramid levels
  int fast_threshold = 12;    ///< FAST threshold (intensity units); low, the grid selects
  int cell_px = 32;           ///< grid cell size at level 0 [px]
  int edge_px = 19;           ///< border without features (ORB patch radius + margin) [px]
  bool IsValid(std::string* msg) const;
};

class OrbExtractor {
 public:
  /// Throws std::invalid_argument for invalid options.
  explicit OrbExtractor(const OrbOptions& options = {});

  /// gray: CV_8UC1. keypoints in level-0 pixels with octave set; descriptors: CV_8U, 32 bytes
  /// per row. An empty or non-gray image gives no features.
  void Extract(const cv::Mat& gray, std::vector<cv::KeyPoint>* keypoints, cv::Mat* descriptors) const;

  const OrbOptions& options() const { return options_; }
  /// Scale of pyramid level l (scale_factor^l) and the variance of a keypoint's position there.
  double scale(int level) const { return scales_[static_cast<size_t>(level)]; }
  double sigma2(int level) const { return scales_[static_cast<size_t>(level)] * scales_[static_cast<size_t>(level)]; }

 private:
  OrbOptions options_;
  cv::Ptr<cv::ORB> orb_;
  std::vector<double> scales_;
};

/// Hamming distance between two 32-byte ORB descriptors.
int DescriptorDistance(const uint8_t* a, const uint8_t* b);
inline int DescriptorDistance(const cv::Mat& a, const cv::Mat& b) {
  return DescriptorDistance(a.ptr<uint8_t>(), b.ptr<uint8_t>());
}

}  // namespace unav::localization
