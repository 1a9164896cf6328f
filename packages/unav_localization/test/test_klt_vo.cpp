// KLT RGB-D VO on a sequence rendered by our renderer (llvmpipe) with known motion: the down
// camera 2 m above the textured sand of the pipe-inspection world.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "unav_localization/klt_vo.hpp"
#include "unav_renderer/camera.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/world.hpp"

using unav_localization::KltVo;
using unav_localization::VoStatus;

TEST(KltVo, RgbdTracksARenderedSequenceWithKnownMotion) {
  unav_renderer::World world = unav_renderer::load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  unav_renderer::CameraModel cam = unav_renderer::CameraModel::from_hfov("down", 320, 180, 90.0 * M_PI / 180.0);
  unav_renderer::RenderOptions ro;
  ro.noise = false;
  ro.marine_snow = false;      // particles move independently of the scene
  ro.lamps = false;            // the lamp pool moves with the camera: a moving brightness pattern
  ro.forward_scatter = false;
  unav_renderer::Renderer renderer(world, {cam}, ro);
  KltVo vo(cam.K());
  // 60 frames: 3 m north at 5 cm per frame, yawing 0.3 rad in total, sinking 0.3 m.
  const int n = 60;
  Eigen::Isometry3d X_WC0 = Eigen::Isometry3d::Identity(), last_est = Eigen::Isometry3d::Identity();
  int lost = 0;
  double path = 0.0;
  Eigen::Vector3d prev_p = Eigen::Vector3d::Zero();
  for (int k = 0; k < n; ++k) {
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.translation() = Eigen::Vector3d(-2.0 + 0.05 * k, 1.5, 7.8 + 0.005 * k);
    X_WB.linear() = Eigen::AngleAxisd(0.005 * k, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const unav_renderer::Frame f = renderer.render(X_WB, "down", 0.1 * k);
    cv::Mat rgb(f.height, f.width, CV_8UC3, const_cast<uint8_t*>(f.rgb.data())), gray;
    cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
    cv::Mat depth(f.height, f.width, CV_32FC1, const_cast<float*>(f.depth.data()));
    Eigen::Isometry3d T_C0C;
    const auto s = vo.ProcessFrame(gray, depth, &T_C0C);
    if (k == 0) {
      EXPECT_EQ(s.status, VoStatus::kInitialized);
      X_WC0 = f.X_WC;
    } else if (s.status != VoStatus::kTracking) {
      ++lost;
    }
    const Eigen::Vector3d p = (X_WC0.inverse() * f.X_WC).translation();
    if (k > 0) path += (p - prev_p).norm();
    prev_p = p;
    last_est = T_C0C;
    if (k == n - 1) {
      const Eigen::Isometry3d gt = X_WC0.inverse() * f.X_WC;
      const double err = (gt.translation() - T_C0C.translation()).norm();
      const double rot = Eigen::AngleAxisd(gt.linear().transpose() * T_C0C.linear()).angle();
      std::printf("KLT RGB-D VO: path %.3f m, final position error %.4f m (%.2f%%), rotation error %.5f rad\n", path,
                  err, 100 * err / path, rot);
      // Bound: 2% of the distance travelled and 0.02 rad after 60 frames, a usual figure for
      // RGB-D VO; seen here: 0.55% and 0.007 rad. The remaining drift comes from KLT on the 1-D
      // sand ripples (aperture) and keyframe hand-overs, not from depth (exact, noise-free).
      EXPECT_LT(err, 0.02 * path);
      EXPECT_LT(rot, 0.02);
    }
  }
  // A rare frame without a consistent PnP solution is bridged by constant-velocity prediction
  // (seen: 1 of 60); the pose bounds above still hold through it.
  EXPECT_LE(lost, 2);
}

TEST(KltVo, BadInputIsRejectedNotCrashing) {
  Eigen::Matrix3d K;
  K << 100, 0, 50, 0, 100, 40, 0, 0, 1;
  unav_localization::KltVoOptions bad;
  bad.min_inliers = 2;
  EXPECT_THROW(KltVo(K, bad), std::invalid_argument);
  EXPECT_THROW(KltVo(Eigen::Matrix3d::Zero()), std::invalid_argument);
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
