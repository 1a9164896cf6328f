// KLT VO (RGB-D and monocular) on a sequence rendered by our renderer with known motion (KltPath
// in slam_flights.hpp, rendered by the fixture render_slam_sequences): the down camera 2 m above
// the textured sand of the pipe-inspection world.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include <opencv2/imgproc.hpp>

#include "slam_sequences.hpp"
#include "unav_localization/klt_vo.hpp"

using unav::localization::KltVo;
using unav::localization::KltVoOptions;
using unav::localization::VoStatus;

namespace {

// The gray images and ground-truth camera poses T_C0C (optical frame, relative to frame 0) of a
// sequence over the pipe-inspection sand: 5 cm north per frame, yawing 0.005 rad and sinking 5 mm
// per frame (the RGB-D test uses the first 60). Rendered once for all tests.
struct Sequence {
  Eigen::Matrix3d K;
  std::vector<cv::Mat> gray;
  std::vector<cv::Mat> depth;  ///< metres (CV_32FC1)
  std::vector<Eigen::Isometry3d> T_C0C;
  double median_depth0_m = 0.0;  ///< median of frame 0's depth image
};

// 320 x 180, 90 deg, no noise, snow, lamps (their pool moves with the camera: a moving
// brightness pattern) or forward scatter. Caustics stay on: a light pattern drifting over the
// seabed, which biases the corners it makes (their tracks follow the light); most of the RGB-D
// test's remaining error comes from it (seen 0.044 m at the end with caustics, 0.018 m without).
const Sequence& rendered_sequence() {
  static const Sequence seq = [] {
    auto r = unav::localization::testing::load_sequence("klt");
    Sequence s;
    s.K = r.K;
    s.gray = std::move(r.images);
    s.depth = std::move(r.depth);
    for (const auto& X_WC : r.X_WC) s.T_C0C.push_back(r.X_WC.front().inverse() * X_WC);
    std::vector<float> z(s.depth.front().begin<float>(), s.depth.front().end<float>());
    std::nth_element(z.begin(), z.begin() + static_cast<std::ptrdiff_t>(z.size() / 2), z.end());
    s.median_depth0_m = z[z.size() / 2];
    return s;
  }();
  return seq;
}

// Sim(3) (Umeyama, with scale) alignment of estimated to true positions; returns the position
// RMSE after alignment [m], the scale that was applied and the aligned error of the last position.
double aligned_rmse(const std::vector<Eigen::Vector3d>& est, const std::vector<Eigen::Vector3d>& gt, double* scale,
                    double* final_error = nullptr) {
  Eigen::Matrix3Xd src(3, est.size()), dst(3, gt.size());
  for (size_t i = 0; i < est.size(); ++i) {
    src.col(static_cast<Eigen::Index>(i)) = est[i];
    dst.col(static_cast<Eigen::Index>(i)) = gt[i];
  }
  const Eigen::Matrix4d S = Eigen::umeyama(src, dst, true);
  if (scale) *scale = S.block<3, 1>(0, 0).norm();
  const Eigen::Matrix3Xd aligned = (S.topLeftCorner<3, 3>() * src).colwise() + S.topRightCorner<3, 1>();
  if (final_error) *final_error = (aligned - dst).col(aligned.cols() - 1).norm();
  return std::sqrt((aligned - dst).colwise().squaredNorm().mean());
}

double path_length(const std::vector<Eigen::Vector3d>& p) {
  double l = 0.0;
  for (size_t i = 1; i < p.size(); ++i) l += (p[i] - p[i - 1]).norm();
  return l;
}

KltVoOptions monocular() {
  KltVoOptions o;
  o.mode = KltVoOptions::Mode::kMonocular;
  return o;
}

// The image with 2 % of its pixels moved by one grey level (seeded): what a renderer change that
// re-rounds a texture does. Tracking must not hinge on it.
cv::Mat perturbed(const cv::Mat& gray, unsigned seed) {
  cv::Mat out = gray.clone();
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> pick(0, 99), sign(0, 1);
  for (int r = 0; r < out.rows; ++r)
    for (int c = 0; c < out.cols; ++c)
      if (pick(rng) < 2) {
        const int v = out.at<uint8_t>(r, c) + (sign(rng) != 0 ? 1 : -1);
        out.at<uint8_t>(r, c) = static_cast<uint8_t>(std::clamp(v, 0, 255));
      }
  return out;
}

}  // namespace

// Seed 0: the rendered images as they are; seeds 1, 2: perturbed().
class KltVoRgbd : public ::testing::TestWithParam<unsigned> {};

TEST_P(KltVoRgbd, TracksARenderedSequenceWithKnownMotion) {
  // The shared sequence's first 60 frames: 3 m north, yawing 0.3 rad in total, sinking 0.3 m.
  const Sequence& seq = rendered_sequence();
  KltVo vo(seq.K);
  const int n = 60;
  int lost = 0;
  double path = 0.0;
  for (int k = 0; k < n; ++k) {
    const size_t i = static_cast<size_t>(k);
    const cv::Mat gray =
        GetParam() == 0 ? seq.gray[i] : perturbed(seq.gray[i], GetParam() * 1000u + static_cast<unsigned>(k));
    Eigen::Isometry3d T_C0C;
    const auto s = vo.ProcessFrame(gray, seq.depth[i], &T_C0C);
    if (k == 0) {
      EXPECT_EQ(s.status, VoStatus::kInitialized);
    } else if (s.status != VoStatus::kTracking) {
      ++lost;
      std::printf("frame %d: %s (%s)\n", k, to_string(s.status), s.message.c_str());
    }
    if (k > 0) path += (seq.T_C0C[i].translation() - seq.T_C0C[i - 1].translation()).norm();
    if (k == n - 1) {
      const Eigen::Isometry3d& gt = seq.T_C0C[i];
      const double err = (gt.translation() - T_C0C.translation()).norm();
      const double rot = Eigen::AngleAxisd(gt.linear().transpose() * T_C0C.linear()).angle();
      std::printf("KLT RGB-D VO, seed %u: path %.3f m, final position error %.4f m (%.2f%%), rotation error %.5f rad\n",
                  GetParam(), path, err, 100 * err / path, rot);
      // Bound: 2% of the distance travelled and 0.02 rad after 60 frames, a usual figure for
      // RGB-D VO; seen over 11 runs (clean and perturbed): 0.22-1.48 % and 0.003-0.015 rad. The
      // error comes from the caustics (above) and from KLT on the 1-D sand ripples (aperture) and
      // keyframe hand-overs, not from depth (exact, noise-free).
      EXPECT_LT(err, 0.02 * path);
      EXPECT_LT(rot, 0.02);
    }
  }
  // PnP starts from the constant-velocity prediction: from no guess it started from a homography
  // of the near-planar seabed and took its mirrored twin on 1-3 frames of 60 (a pose 2 m and
  // 0.6 rad off with 95 % "inliers", rejected as lost), and which frames did so changed when 2 %
  // of the pixels moved by a grey level. Seen since: 0 lost in 11 runs.
  EXPECT_EQ(lost, 0);
}

INSTANTIATE_TEST_SUITE_P(CleanAndPerturbed, KltVoRgbd, ::testing::Values(0u, 1u, 2u));

TEST(KltVo, BadInputIsRejectedNotCrashing) {
  Eigen::Matrix3d K;
  K << 100, 0, 50, 0, 100, 40, 0, 0, 1;
  unav::localization::KltVoOptions bad;
  bad.min_inliers = 2;
  EXPECT_THROW(KltVo(K, bad), std::invalid_argument);
  EXPECT_THROW(KltVo{Eigen::Matrix3d::Zero()}, std::invalid_argument);
  KltVo vo(K);
  Eigen::Isometry3d T;
  EXPECT_EQ(vo.ProcessFrame(cv::Mat(), cv::Mat(), &T).status, VoStatus::kInvalidInput);
  EXPECT_EQ(vo.ProcessFrame(cv::Mat(80, 100, CV_8UC1), cv::Mat(10, 10, CV_32FC1), &T).status, VoStatus::kInvalidInput);
  // A blank scene: nothing to track is "lost", never a crash, and the pose stays finite.
  const cv::Mat blank(80, 100, CV_8UC1, cv::Scalar(90)), d(80, 100, CV_32FC1, cv::Scalar(2.0f));
  vo.ProcessFrame(blank, d, &T);
  EXPECT_EQ(vo.ProcessFrame(blank, d, &T).status, VoStatus::kLost);
  EXPECT_TRUE(T.matrix().allFinite());
}

TEST(KltVo, MonocularTracksARenderedSequenceUpToSimilarity) {
  const Sequence& seq = rendered_sequence();
  KltVo vo(seq.K, monocular());
  const int n = 60;
  int init_frame = -1, lost = 0;
  std::vector<Eigen::Vector3d> est, gt;
  double ms = 0.0;
  for (int k = 0; k < n; ++k) {
    Eigen::Isometry3d T_C0C;
    const auto t0 = std::chrono::steady_clock::now();
    const auto s = vo.ProcessFrame(seq.gray[static_cast<size_t>(k)], &T_C0C);
    ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    ASSERT_TRUE(T_C0C.matrix().allFinite());
    if (init_frame < 0) {
      if (s.status == VoStatus::kInitialized) {
        init_frame = k;
        std::printf("monocular initialised at frame %d: %s\n", k, s.message.c_str());
      } else {
        EXPECT_EQ(s.status, VoStatus::kInitializing) << "frame " << k << ": " << s.message;
      }
    } else if (s.status != VoStatus::kTracking) {
      ++lost;
      std::printf("frame %d: %s (%s)\n", k, to_string(s.status), s.message.c_str());
    }
    if (s.status == VoStatus::kInitialized || s.status == VoStatus::kTracking) {
      est.push_back(T_C0C.translation());
      gt.push_back(seq.T_C0C[static_cast<size_t>(k)].translation());
    }
  }
  // 20 px median parallax at about 4 px per frame (5 cm at 2 m, f = 160 px): about frame 5.
  ASSERT_GE(init_frame, 1);
  EXPECT_LE(init_frame, 15);
  EXPECT_EQ(lost, 0);
  double scale = 0.0, final_error = 0.0;
  const double rmse = aligned_rmse(est, gt, &scale, &final_error), path = path_length(gt);
  std::printf(
      "KLT monocular VO: %zu poses from frame %d, path %.3f m, Sim(3)-aligned position RMSE %.4f m (%.2f%% of "
      "the path), final error %.4f m (%.2f%%), scale %.3f m per map unit (median depth of frame 0: %.3f m), "
      "%.2f ms per frame\n",
      est.size(), init_frame, path, rmse, 100 * rmse / path, final_error, 100 * final_error / path, scale,
      seq.median_depth0_m, ms / n);
  // Bound: 2% of the distance travelled, the figure usually quoted for monocular VO after Sim(3)
  // alignment (the RGB-D test's bound, with the scale given away to the alignment). Seen: 0.19%
  // RMSE, 0.33% at the last frame, initialised at frame 6 from the homography. The error left is
  // scale drift from map points triangulated from estimated poses.
  EXPECT_LT(rmse, 0.02 * path);
  // The first map's median depth is 1 map unit, so the scale is the reference frame's (frame 0's)
  // median depth, up to the scale drift the alignment averages over and the depths of the corners
  // versus of all pixels: 5% (seen: 1.1%).
  EXPECT_NEAR(scale / seq.median_depth0_m, 1.0, 0.05);
}

TEST(KltVo, MonocularRecoversAfterTheTextureIsGone) {
  const Sequence& seq = rendered_sequence();
  KltVo vo(seq.K, monocular());
  // Frames 30-34 are a uniform gray image (the camera blinded, e.g. by silt); the motion goes on.
  const cv::Mat blank(seq.gray[0].size(), CV_8UC1, cv::Scalar(90));
  int first_lost = -1, recovered = -1;
  Eigen::Isometry3d last_good = Eigen::Isometry3d::Identity();
  std::vector<Eigen::Vector3d> est_before, gt_before, est_after, gt_after;
  for (int k = 0; k < static_cast<int>(seq.gray.size()); ++k) {
    const bool blind = k >= 30 && k < 35;
    Eigen::Isometry3d T_C0C;
    const auto s = vo.ProcessFrame(blind ? blank : seq.gray[static_cast<size_t>(k)], &T_C0C);
    ASSERT_TRUE(T_C0C.matrix().allFinite());
    if (blind) {
      EXPECT_EQ(s.status, VoStatus::kLost) << "frame " << k;
      // No estimate while blind: the last good pose is held.
      EXPECT_TRUE(T_C0C.isApprox(last_good, 1e-12));
    }
    if (s.status == VoStatus::kLost && first_lost < 0) first_lost = k;
    if (first_lost >= 0 && recovered < 0 && s.status == VoStatus::kInitialized) {
      std::printf("re-initialised at frame %d: %s\n", k, s.message.c_str());
    }
    if (first_lost >= 0 && recovered < 0 && s.status == VoStatus::kTracking) recovered = k;
    if (s.status == VoStatus::kInitialized || s.status == VoStatus::kTracking) {
      last_good = T_C0C;
      (first_lost < 0 ? est_before : est_after).push_back(T_C0C.translation());
      (first_lost < 0 ? gt_before : gt_after).push_back(seq.T_C0C[static_cast<size_t>(k)].translation());
    }
  }
  EXPECT_EQ(first_lost, 30);
  ASSERT_GT(recovered, 35);
  // The texture is back at frame 35; re-initialising needs the same parallax as at the start.
  EXPECT_LE(recovered, 50);
  ASSERT_GE(est_after.size(), 10u);
  double scale_before = 0.0, scale_after = 0.0;
  const double rmse_before = aligned_rmse(est_before, gt_before, &scale_before);
  const double rmse_after = aligned_rmse(est_after, gt_after, &scale_after);
  std::printf(
      "lost at frame %d, tracking again at frame %d; before: RMSE %.4f m, scale %.3f; after: RMSE %.4f m, "
      "scale %.3f\n",
      first_lost, recovered, rmse_before, scale_before, rmse_after, scale_after);
  // The new map keeps the old map's median depth: the camera's altitude changed by 3 cm of 2 m
  // while blind, so the scale should carry over to within a few percent; 10% leaves room for the
  // scale drift of each map (seen: 1.4%; re-initialised at frame 40, tracking at 41).
  EXPECT_NEAR(scale_after / scale_before, 1.0, 0.1);
  EXPECT_LT(rmse_after, 0.02 * path_length(gt_after));
}

TEST(KltVo, MonocularBadInputIsRejectedNotCrashing) {
  Eigen::Matrix3d K;
  K << 100, 0, 50, 0, 100, 40, 0, 0, 1;
  KltVoOptions bad = monocular();
  bad.min_init_points = bad.min_init_tracks + 1;
  EXPECT_THROW(KltVo(K, bad), std::invalid_argument);
  bad = monocular();
  bad.min_triangulation_angle_rad = 0.0;
  EXPECT_THROW(KltVo(K, bad), std::invalid_argument);
  Eigen::Isometry3d T;
  const cv::Mat gray(80, 100, CV_8UC1, cv::Scalar(90)), d(80, 100, CV_32FC1, cv::Scalar(2.0f));
  // The wrong overload for the mode.
  KltVo rgbd(K);
  auto s = rgbd.ProcessFrame(gray, &T);
  EXPECT_EQ(s.status, VoStatus::kInvalidInput);
  EXPECT_NE(s.message.find("RGB-D mode"), std::string::npos) << s.message;
  KltVo vo(K, monocular());
  s = vo.ProcessFrame(gray, d, &T);
  EXPECT_EQ(s.status, VoStatus::kInvalidInput);
  EXPECT_NE(s.message.find("monocular mode"), std::string::npos) << s.message;
  EXPECT_EQ(vo.ProcessFrame(cv::Mat(), &T).status, VoStatus::kInvalidInput);
  EXPECT_EQ(vo.ProcessFrame(cv::Mat(80, 100, CV_32FC1, cv::Scalar(1.0f)), &T).status, VoStatus::kInvalidInput);
  // A blank scene: nothing to initialise from, never a crash, and the pose stays the identity.
  EXPECT_EQ(vo.ProcessFrame(gray, &T).status, VoStatus::kInitializing);
  EXPECT_EQ(vo.ProcessFrame(gray, &T).status, VoStatus::kInitializing);
  EXPECT_TRUE(T.isApprox(Eigen::Isometry3d::Identity()));
  EXPECT_EQ(vo.ProcessFrame(cv::Mat(40, 50, CV_8UC1, cv::Scalar(90)), &T).status, VoStatus::kInvalidInput);
}

// An exactly planar scene (the flat seabed at its extreme, where the essential matrix is
// degenerate): a seeded random texture on the plane z = 2 m of camera 0, seen by a camera moving
// sideways over it; each image is the texture warped by the plane-induced homography
// H = K (R + t n^T / d) K^-1 (n = z axis, d = 2 m). No renderer needed.
TEST(KltVo, MonocularInitialisesOnAPlaneFromTheHomography) {
  const int w = 320, h = 180, margin = 200;
  const double f = 160.0, d = 2.0;
  Eigen::Matrix3d K;
  K << f, 0, w / 2.0, 0, f, h / 2.0, 0, 0, 1;
  cv::Mat noise(h + 2 * margin, w + 2 * margin, CV_32FC1), texture;
  cv::RNG rng(7);
  rng.fill(noise, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::GaussianBlur(noise, noise, cv::Size(0, 0), 2.0);
  cv::normalize(noise, noise, 0, 255, cv::NORM_MINMAX);
  noise.convertTo(texture, CV_8UC1);
  Eigen::Matrix3d texture_to_C0 = Eigen::Matrix3d::Identity();  // texture pixel -> camera 0 pixel
  texture_to_C0(0, 2) = texture_to_C0(1, 2) = -margin;
  KltVo vo(K, monocular());
  std::vector<Eigen::Vector3d> est, gt;
  int init_frame = -1;
  std::string init_message;
  for (int k = 0; k < 40; ++k) {
    // Camera k in camera 0: 4 cm per frame along x and 1 cm along y, yawing 0.004 rad per frame.
    Eigen::Isometry3d T_C0C = Eigen::Isometry3d::Identity();
    T_C0C.translation() = Eigen::Vector3d(0.04 * k, 0.01 * k, 0.0);
    T_C0C.linear() = Eigen::AngleAxisd(0.004 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Isometry3d T_CC0 = T_C0C.inverse();
    const Eigen::Matrix3d H = K * (T_CC0.linear() + T_CC0.translation() * Eigen::Vector3d::UnitZ().transpose() / d) *
                              K.inverse() * texture_to_C0;
    cv::Matx33d Hcv;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) Hcv(r, c) = H(r, c);
    cv::Mat gray;
    cv::warpPerspective(texture, gray, Hcv, cv::Size(w, h), cv::INTER_LINEAR);
    Eigen::Isometry3d T_est;
    const auto s = vo.ProcessFrame(gray, &T_est);
    if (s.status == VoStatus::kInitialized) {
      init_frame = k;
      init_message = s.message;
    }
    if (init_frame >= 0) {
      EXPECT_NE(s.status, VoStatus::kLost) << "frame " << k << ": " << s.message;
      est.push_back(T_est.translation());
      gt.push_back(T_C0C.translation());
    }
  }
  std::printf("plane: initialised at frame %d: %s\n", init_frame, init_message.c_str());
  ASSERT_GE(init_frame, 1);
  EXPECT_LE(init_frame, 15);
  EXPECT_NE(init_message.find("from the homography"), std::string::npos) << init_message;
  double scale = 0.0;
  const double rmse = aligned_rmse(est, gt, &scale), path = path_length(gt);
  std::printf("plane: path %.3f m, Sim(3)-aligned position RMSE %.4f m (%.2f%%), scale %.3f m per map unit\n", path,
              rmse, 100 * rmse / path, scale);
  // Every point is at depth 2 m in camera 0, the reference frame, so one map unit is 2 m; a perfect
  // plane leaves only KLT error (sub-pixel) and its scale drift, hence the same 2% bounds (seen:
  // scale 0.3% off, RMSE 0.06% of the path; the essential matrix triangulated 109 points well, the
  // homography 357).
  EXPECT_NEAR(scale / d, 1.0, 0.02);
  EXPECT_LT(rmse, 0.02 * path);
}

TEST(KltVo, RgbdPoseStaysARotationThroughAnHourOfLostFrames) {
  // Found by the soak (scripts/soak.sh, 60 min, turbid water): chained poses lost their
  // orthonormality geometrically (|q| 1.07, then 1e68, then NaN odometry) over many lost and
  // re-initialised frames. Here: the rendered sequence back and forth 30 times (2070 frames),
  // every 4th frame blank (lost: constant-velocity prediction, then new corners). The rotation
  // must stay a rotation to rounding: |R^T R - I| < 1e-12 (seen: ~1e-15) and finite.
  const Sequence& seq = rendered_sequence();
  KltVo vo(seq.K);
  const int n = static_cast<int>(seq.gray.size());
  const cv::Mat blank(seq.gray[0].size(), CV_8UC1, cv::Scalar(90));
  double worst = 0.0;
  int lost = 0, frame = 0;
  for (int pass = 0; pass < 30; ++pass)
    for (int j = 0; j < n - 1; ++j, ++frame) {
      const int k = pass % 2 == 0 ? j : n - 1 - j;
      Eigen::Isometry3d T_C0C;
      const auto s = vo.ProcessFrame(frame % 4 == 3 ? blank : seq.gray[k], seq.depth[k], &T_C0C);
      lost += s.status == VoStatus::kLost ? 1 : 0;
      ASSERT_TRUE(T_C0C.matrix().allFinite()) << "frame " << frame;
      worst = std::max(worst, (T_C0C.linear().transpose() * T_C0C.linear() - Eigen::Matrix3d::Identity()).norm());
    }
  std::printf("KLT RGB-D VO: %d frames, %d lost, worst |R^T R - I| %.3g\n", frame, lost, worst);
  EXPECT_GT(lost, 400);
  EXPECT_LT(worst, 1e-12);
}
