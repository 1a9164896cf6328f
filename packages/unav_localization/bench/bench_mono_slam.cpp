// bench_mono_slam: frame rate of the monocular ORB SLAM at 640 x 480 on one core (OpenCV and
// Ceres limited to one thread), and of the monocular KLT VO on the same frames.
//   bench_mono_slam [DATASET_DIR]   (a TUM folder with camera.yaml, and imu.txt + manifest.json
//                                    for the inertial rows; default: renders 300 frames of the down
//                                    camera swaying 1.4 m over the pipe-inspection seabed, with its
//                                    IMU in closed form)
// Prints per-frame tracking time (features + tracking) and the time with mapping (keyframe
// insertion, local BA, loop closing) as percentiles and frames per second, monocular and
// monocular-inertial (visual-inertial BA, IMU prediction).
// Machine-readable: BENCH slam/<part>_mean_ms and slam/<part>_p50_ms, part: orb_tracking,
// orb_tracking_mapping, orb_mapping_per_keyframe, orb_vi_tracking, orb_vi_tracking_mapping,
// klt_vo_mono.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <numeric>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"
#include "unav_localization/image_sequence.hpp"
#include "unav_localization/klt_vo.hpp"
#include "unav_localization/mono_slam.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/world.hpp"

namespace ul = unav::localization;

namespace {

void Report(const char* what, const std::string& id, std::vector<double> ms, const char* unit = "frames/s") {
  std::sort(ms.begin(), ms.end());
  const double mean = std::accumulate(ms.begin(), ms.end(), 0.0) / static_cast<double>(ms.size());
  auto pct = [&](double q) {
    return ms[std::min(ms.size() - 1, static_cast<size_t>(q * static_cast<double>(ms.size())))];
  };
  std::printf("  %-30s mean %7.2f ms  p50 %7.2f  p90 %7.2f  p99 %7.2f  max %7.2f  -> %6.1f %s\n", what, mean, pct(0.5),
              pct(0.9), pct(0.99), ms.back(), 1000.0 / mean, unit);
  unav::common::print_bench("slam/" + id + "_mean_ms", mean, "ms");
  unav::common::print_bench("slam/" + id + "_p50_ms", pct(0.5), "ms");
}

}  // namespace

int main(int argc, char** argv) {
  cv::setNumThreads(1);
  std::vector<cv::Mat> frames;
  std::vector<double> stamps;
  ul::PinholeCamera cam;
  std::string source;
  std::vector<ul::ImuSample> imu;  // for the inertial rows (none: not run)
  Eigen::Isometry3d X_BC = Eigen::Isometry3d::Identity();
  if (argc > 1) {
    const auto cf = ul::LoadCameraFile(std::string(argv[1]) + "/camera.yaml");
    cam = cf.camera;
    for (const auto& im : ul::ListImages(argv[1])) {
      cv::Mat gray;
      cv::cvtColor(cv::imread(im.path, cv::IMREAD_COLOR), gray, cv::COLOR_BGR2GRAY);
      frames.push_back(gray);
      stamps.push_back(im.stamp);
    }
    source = argv[1];
    const std::string imu_path = std::string(argv[1]) + "/imu.txt";
    const auto mount = ul::ReadCameraMount(std::string(argv[1]) + "/manifest.json");
    if (std::filesystem::exists(imu_path) && mount) {
      imu = ul::ReadImuSamples(imu_path);
      X_BC = *mount;
    }
  } else {
    const auto world = unav::scene::load_world(unav::common::find_resource("worlds/pipe_inspection/world.yaml"));
    const auto model = unav::scene::CameraModel::from_hfov("down", 640, 480, 90.0 * M_PI / 180.0);
    unav::renderer::Renderer renderer(world, {model}, {});
    for (int k = 0; k < 300; ++k) {
      Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
      const double t = 0.1 * k;
      X.translation() = Eigen::Vector3d(-1.0 + 0.6 * t, 0.3 * std::sin(0.5 * t), 8.35);
      X.linear() = Eigen::AngleAxisd(0.1 * std::sin(0.4 * t), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      const auto f = renderer.render(X, "down", 0.1 * k);
      cv::Mat rgb(f.height, f.width, CV_8UC3, const_cast<uint8_t*>(f.rgb.data())), gray;
      cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
      frames.push_back(gray);
      stamps.push_back(0.1 * k);
    }
    cam = ul::PinholeCamera::FromK(model.K(), 640, 480);
    source = "300 rendered frames (pipe_inspection seabed, 6 cm/frame, 1.4 m range)";
    // Its ideal 200 Hz IMU (the camera at the body origin; gravity +z, NED-like as the physics).
    for (double t = 0.0; t <= 30.0; t += 0.005) {
      const double tm = t + 0.0025;
      const Eigen::Vector3d a(0.0, -0.075 * std::sin(0.5 * tm), 0.0);
      const Eigen::Matrix3d R =
          Eigen::AngleAxisd(0.1 * std::sin(0.4 * tm), Eigen::Vector3d::UnitZ()).toRotationMatrix();
      imu.push_back(
          {t, Eigen::Vector3d(0.0, 0.0, 0.04 * std::cos(0.4 * tm)), R.transpose() * (a - Eigen::Vector3d(0, 0, 9.81))});
    }
  }
  std::printf("bench_mono_slam: %zu frames of %dx%d from %s, one thread\n", frames.size(), cam.width, cam.height,
              source.c_str());

  std::shared_ptr<const ul::BowVocabulary> voc;
  const std::string voc_path = unav::common::find_resource("config/vocabulary/orb_vocabulary.bin");
  if (std::filesystem::exists(voc_path)) voc = std::make_shared<ul::BowVocabulary>(ul::BowVocabulary::Load(voc_path));
  ul::MonoSlam slam(cam, {}, {}, voc);
  std::vector<double> track, total, kf_mapping;
  for (size_t k = 0; k < frames.size(); ++k) {
    const auto s = slam.Track(frames[k], stamps[k]);
    track.push_back(s.tracking_ms);
    total.push_back(s.tracking_ms + s.mapping_ms);
    if (s.keyframe && s.mapping_ms > 0) kf_mapping.push_back(s.mapping_ms);
  }
  const auto st = slam.stats();
  std::printf("orb_slam: %d tracked, %d lost, %d keyframes, %d points, %d loops\n", st.tracked_frames, st.lost_frames,
              st.keyframes, st.points, st.loops);
  Report("tracking (ORB + pose)", "orb_tracking", track);
  Report("tracking + mapping", "orb_tracking_mapping", total);
  if (!kf_mapping.empty()) Report("mapping per keyframe", "orb_mapping_per_keyframe", kf_mapping, "keyframes/s");

  if (!imu.empty()) {
    ul::MonoSlam vi(cam, {}, {}, voc);
    vi.EnableInertial(X_BC, ul::ImuNoise{});
    std::vector<double> vi_track, vi_total;
    size_t next = 0;
    for (size_t k = 0; k < frames.size(); ++k) {
      for (; next < imu.size() && imu[next].stamp <= stamps[k]; ++next)
        vi.AddImu(imu[next].stamp, imu[next].gyro, imu[next].accel);
      const auto s = vi.Track(frames[k], stamps[k]);
      vi_track.push_back(s.tracking_ms);
      vi_total.push_back(s.tracking_ms + s.mapping_ms);
    }
    const auto vs = vi.stats();
    std::printf(
        "orb_slam inertial: %d tracked, %d lost, %d inertial initialisation(s), %d refinement(s), %ld inertial "
        "factors, %d frames from the IMU's prediction\n",
        vs.tracked_frames, vs.lost_frames, vs.inertial_inits, vs.inertial_refinements, vs.inertial_factors,
        vs.imu_predicted_frames);
    Report("inertial tracking", "orb_vi_tracking", vi_track);
    Report("inertial tracking + mapping", "orb_vi_tracking_mapping", vi_total);
  }

  ul::KltVoOptions ko;
  ko.mode = ul::KltVoOptions::Mode::kMonocular;
  ul::KltVo klt(cam.K(), ko);
  std::vector<double> klt_ms;
  for (const auto& f : frames) {
    Eigen::Isometry3d T;
    const auto t0 = std::chrono::steady_clock::now();
    klt.ProcessFrame(f, &T);
    klt_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  Report("klt_vo monocular", "klt_vo_mono", klt_ms);
  return 0;
}
