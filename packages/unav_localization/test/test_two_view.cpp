// The shared two-view candidates recover a known relative motion: a general 3-D scene through
// the essential matrix, a plane (the seabed seen from above) through a homography decomposition.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Geometry>

#include "unav_localization/two_view.hpp"

namespace ul = unav::localization;

namespace {

const cv::Matx33d kK(500.0, 0.0, 320.0, 0.0, 500.0, 240.0, 0.0, 0.0, 1.0);

cv::Point2f project(const Eigen::Vector3d& p) {
  return {static_cast<float>(kK(0, 0) * p.x() / p.z() + kK(0, 2)),
          static_cast<float>(kK(1, 1) * p.y() / p.z() + kK(1, 2))};
}

// Correspondences of `points` (in view 1) seen from view 2 at x_2 = R x_1 + t.
void views(const std::vector<Eigen::Vector3d>& points, const Eigen::Matrix3d& R, const Eigen::Vector3d& t,
           std::vector<cv::Point2f>* p1, std::vector<cv::Point2f>* p2) {
  for (const auto& p : points) {
    p1->push_back(project(p));
    p2->push_back(project(R * p + t));
  }
}

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::acos(std::clamp(a.normalized().dot(b.normalized()), -1.0, 1.0));
}

}  // namespace

TEST(TwoView, EssentialCandidateRecoversAGeneralMotion) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-2.0, 2.0), z(3.0, 8.0);
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(200);
  for (int i = 0; i < 200; ++i) pts.emplace_back(xy(rng), xy(rng), z(rng));
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.08, Eigen::Vector3d(0.2, 1.0, 0.1).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(-0.4, 0.05, 0.1);
  std::vector<cv::Point2f> p1, p2;
  views(pts, R, t, &p1, &p2);
  const auto candidates = ul::TwoViewCandidates(p1, p2, kK);
  ASSERT_FALSE(candidates.empty());
  const auto& e = candidates.front();
  ASSERT_EQ(e.model, ul::TwoViewCandidate::Model::kEssential);
  // Noise-free pixels rounded to float (~1e-5 px): the motion is exact to well under 1e-3.
  EXPECT_LT(Eigen::AngleAxisd(e.R.transpose() * R).angle(), 1e-3);
  EXPECT_NEAR(e.t.norm(), 1.0, 1e-9);  // essential translation: unit length
  EXPECT_LT(angle_between(e.t, t), 1e-3);
  int inliers = 0;
  for (auto m : e.inliers) inliers += m != 0;
  EXPECT_GE(inliers, 195);
}

TEST(TwoView, HomographyCandidatesContainThePlaneMotion) {
  // The seabed 4 m below a down-looking camera (optical z = depth), the camera moving forward.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> xy(-3.0, 3.0);
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(150);
  for (int i = 0; i < 150; ++i) pts.emplace_back(xy(rng), xy(rng), 4.0);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d t(0.0, -0.5, 0.0);
  std::vector<cv::Point2f> p1, p2;
  views(pts, R, t, &p1, &p2);
  const auto candidates = ul::TwoViewCandidates(p1, p2, kK);
  double best = 1e9;
  int homographies = 0;
  for (const auto& c : candidates) {
    if (c.model != ul::TwoViewCandidate::Model::kHomography) continue;
    ++homographies;
    EXPECT_GT(c.t.norm(), 1e-9);
    best = std::min(best, Eigen::AngleAxisd(c.R.transpose() * R).angle() + angle_between(c.t, t));
  }
  EXPECT_GE(homographies, 2);  // up to four decompositions, the physically valid pair at least
  EXPECT_LT(best, 1e-3);
}

// ORB-SLAM's model selection score S_H / (S_H + S_E): a plane is explained by the homography as
// well as by the essential matrix (~0.5, above the 0.45 threshold); a 3-D scene only in part by
// a homography (well below). Correspondences with 0.5 px noise.
TEST(TwoView, HomographyRatioTellsAPlaneFromA3DScene) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> xy(-2.5, 2.5), depth(3.0, 8.0);
  std::normal_distribution<float> noise(0.0f, 0.5f);
  const Eigen::Matrix3d R = Eigen::AngleAxisd(0.03, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const Eigen::Vector3d t(0.1, -0.4, 0.2);
  auto ratio = [&](bool plane) {
    std::vector<Eigen::Vector3d> pts;
    pts.reserve(200);
    for (int i = 0; i < 200; ++i) pts.emplace_back(xy(rng), xy(rng), plane ? 4.0 : depth(rng));
    std::vector<cv::Point2f> p1, p2;
    views(pts, R, t, &p1, &p2);
    for (auto& p : p2) p += cv::Point2f(noise(rng), noise(rng));
    return ul::HomographyRatio(ul::TwoViewCandidates(p1, p2, kK));
  };
  const double plane = ratio(true), scene = ratio(false);
  std::printf("homography ratio: plane %.3f, 3-D scene %.3f\n", plane, scene);
  EXPECT_GT(plane, 0.45);
  EXPECT_LT(plane, 0.6);  // both models fit every point: about one half
  EXPECT_LT(scene, 0.3);
  EXPECT_EQ(ul::HomographyRatio({}), 0.0);
}

TEST(TwoView, TooFewOrMismatchedCorrespondencesGiveNoCandidate) {
  std::vector<cv::Point2f> a(4, cv::Point2f(1, 2)), b(4, cv::Point2f(3, 4));
  EXPECT_TRUE(ul::TwoViewCandidates(a, b, kK).empty());
  a.resize(10);
  EXPECT_TRUE(ul::TwoViewCandidates(a, b, kK).empty());
}
