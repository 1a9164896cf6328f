#include "unav_localization/two_view.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace unav::localization {

std::vector<TwoViewCandidate> TwoViewCandidates(const std::vector<cv::Point2f>& p1, const std::vector<cv::Point2f>& p2,
                                                const cv::Matx33d& K, const TwoViewOptions& options) {
  std::vector<TwoViewCandidate> out;
  if (p1.size() < 5 || p1.size() != p2.size()) return out;
  const cv::Mat Kcv(K);
  std::vector<std::uint8_t> mask_e;
  const cv::Mat E = cv::findEssentialMat(p1, p2, Kcv, cv::RANSAC, options.essential_confidence,
                                         options.essential_ransac_px, options.essential_max_iterations, mask_e);
  if (E.rows == 3 && E.cols == 3) {
    cv::Mat R, t;
    if (cv::recoverPose(E, p1, p2, Kcv, R, t, mask_e) > 0) {
      TwoViewCandidate c;
      c.model = TwoViewCandidate::Model::kEssential;
      cv::cv2eigen(R, c.R);
      cv::cv2eigen(t, c.t);
      c.inliers = mask_e;
      out.push_back(std::move(c));
    }
  }
  std::vector<std::uint8_t> mask_h;
  const cv::Mat H = cv::findHomography(p1, p2, cv::RANSAC, options.homography_ransac_px, mask_h);
  if (!H.empty()) {
    std::vector<cv::Mat> Rs, ts, ns;
    cv::decomposeHomographyMat(H, Kcv, Rs, ts, ns);
    for (std::size_t k = 0; k < Rs.size(); ++k) {
      TwoViewCandidate c;
      c.model = TwoViewCandidate::Model::kHomography;
      cv::cv2eigen(Rs[k], c.R);
      cv::cv2eigen(ts[k], c.t);
      if (!(c.t.norm() > 1e-9)) continue;
      c.inliers = mask_h;
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace unav::localization
