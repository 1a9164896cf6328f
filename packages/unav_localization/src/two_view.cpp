#include "unav_localization/two_view.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace unav::localization {

namespace {

constexpr double kScoreTh = 5.991;  // chi-square 95 %, 2 dof (ORB-SLAM's score threshold)
constexpr double kLineTh = 3.841;   // chi-square 95 %, 1 dof (a distance to a line)

double HomographyScore(const cv::Mat& H, const std::vector<cv::Point2f>& p1, const std::vector<cv::Point2f>& p2) {
  const cv::Matx33d H12(H), H21 = H12.inv();
  double score = 0;
  auto transfer = [](const cv::Matx33d& M, const cv::Point2f& a, const cv::Point2f& b) {
    const cv::Vec3d x = M * cv::Vec3d(a.x, a.y, 1.0);
    if (std::abs(x[2]) < 1e-12) return 1e9;
    const double dx = x[0] / x[2] - b.x, dy = x[1] / x[2] - b.y;
    return dx * dx + dy * dy;
  };
  for (std::size_t i = 0; i < p1.size(); ++i) {
    const double e2 = transfer(H12, p1[i], p2[i]), e1 = transfer(H21, p2[i], p1[i]);
    if (e2 < kScoreTh) score += kScoreTh - e2;
    if (e1 < kScoreTh) score += kScoreTh - e1;
  }
  return score;
}

double EssentialScore(const cv::Mat& E, const cv::Matx33d& K, const std::vector<cv::Point2f>& p1,
                      const std::vector<cv::Point2f>& p2) {
  const cv::Matx33d Ki = K.inv();
  const cv::Matx33d F = Ki.t() * cv::Matx33d(E) * Ki;  // x2^T F x1 = 0
  double score = 0;
  for (std::size_t i = 0; i < p1.size(); ++i) {
    const cv::Vec3d x1(p1[i].x, p1[i].y, 1.0), x2(p2[i].x, p2[i].y, 1.0);
    const cv::Vec3d l2 = F * x1, l1 = F.t() * x2;
    const double num = x2.dot(l2);
    const double d2 = num * num / (l2[0] * l2[0] + l2[1] * l2[1] + 1e-18);
    const double d1 = num * num / (l1[0] * l1[0] + l1[1] * l1[1] + 1e-18);
    if (d2 < kLineTh) score += kScoreTh - d2;
    if (d1 < kLineTh) score += kScoreTh - d1;
  }
  return score;
}

}  // namespace

double HomographyRatio(const std::vector<TwoViewCandidate>& candidates) {
  double sh = 0, se = 0;
  bool any_h = false, any_e = false;
  for (const auto& c : candidates) {
    if (c.model == TwoViewCandidate::Model::kHomography) {
      sh = c.model_score;
      any_h = true;
    } else {
      se = c.model_score;
      any_e = true;
    }
  }
  if (!any_h) return 0.0;
  if (!any_e) return 1.0;
  return sh + se > 0 ? sh / (sh + se) : 0.0;
}

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
      c.model_score = EssentialScore(E, K, p1, p2);
      out.push_back(std::move(c));
    }
  }
  std::vector<std::uint8_t> mask_h;
  const cv::Mat H = cv::findHomography(p1, p2, cv::RANSAC, options.homography_ransac_px, mask_h);
  if (!H.empty()) {
    std::vector<cv::Mat> Rs, ts, ns;
    cv::decomposeHomographyMat(H, Kcv, Rs, ts, ns);
    const double score = HomographyScore(H, p1, p2);
    for (std::size_t k = 0; k < Rs.size(); ++k) {
      TwoViewCandidate c;
      c.model = TwoViewCandidate::Model::kHomography;
      cv::cv2eigen(Rs[k], c.R);
      cv::cv2eigen(ts[k], c.t);
      if (!(c.t.norm() > 1e-9)) continue;
      c.inliers = mask_h;
      c.model_score = score;
      out.push_back(std::move(c));
    }
  }
  return out;
}

}  // namespace unav::localization
