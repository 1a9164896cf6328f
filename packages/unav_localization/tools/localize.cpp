// unav_localize: runs an estimator offline over a folder of images (also `unav localize`).
//
//   unav_localize --images DIR --camera FILE [--method orb_slam|klt_mono|klt_rgbd]
//                 [--vocabulary FILE] [--output FILE] [--groundtruth FILE] [--max-frames N]
//                 [--imu FILE] [--dvl FILE] [--camera-mount "x y z qx qy qz qw"]
//
// orb_slam with --imu (our imu.txt or EuRoC's imu0/data.csv) and/or --dvl (our nav/dvl.csv): the
// monocular-inertial and DVL-aided modes of the orb_slam node, so the trajectory is metric; they
// need the camera's mount on the body (--camera-mount, or DIR/manifest.json as unav datagen and
// the dataset recorder write it), and report APE after SE(3) alignment too.
//
// DIR: a TUM RGB-D dataset folder (rgb.txt; depth.txt for klt_rgbd), as our dataset_recorder
// writes it, or a folder of images. Writes the camera trajectory (optical frame, TUM format) and,
// when ground truth is given or DIR holds groundtruth.txt, prints APE/RPE after Sim(3)
// alignment (SE(3) for klt_rgbd, which has metric scale). Exit codes: 0 ok, 2 bad input.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>

#include <CLI/CLI.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_common/errors.hpp"
#include "unav_common/resources.hpp"
#include "unav_evaluation/report.hpp"
#include "unav_evaluation/trajectory.hpp"
#include "unav_localization/image_sequence.hpp"
#include "unav_localization/klt_vo.hpp"
#include "unav_localization/mono_slam.hpp"

namespace ul = unav::localization;
namespace ue = unav::evaluation;

namespace {

double Percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<size_t>(q * static_cast<double>(v.size())))];
}

std::map<double, std::string> ReadDepthList(const std::string& dir) {
  std::map<double, std::string> out;
  std::ifstream f(dir + "/depth.txt");
  if (!f) throw ul::InputError(dir + "/depth.txt: cannot be read (klt_rgbd needs the depth images)");
  std::string line;
  while (std::getline(f, line)) {
    if (line.empty() || line[0] == '#') continue;
    std::istringstream is(line);
    double t;
    std::string rel;
    if (is >> t >> rel) out[t] = dir + "/" + rel;
  }
  return out;
}

// The camera's ground-truth trajectory: a TUM file (camera poses), or EuRoC's
// state_groundtruth_estimate0/data.csv (body poses "t_ns, p x y z, q w x y z") composed with the
// camera's mount (`mount`, else the camera file's T_BS).
ue::Trajectory ReadGroundTruth(const std::string& path, const std::string& camera_path,
                               const std::optional<Eigen::Isometry3d>& mount) {
  if (path.size() < 4 || path.substr(path.size() - 4) != ".csv") return ue::read_tum(path);
  const std::optional<Eigen::Isometry3d> X_BC = mount ? mount : ul::ReadCameraMount(camera_path);
  if (!X_BC) throw ul::InputError(path + ": EuRoC body poses need the camera's mount (T_BS of the --camera file)");
  ue::Trajectory out;
  std::ifstream f(path);
  if (!f) throw ul::InputError(path + ": cannot be read");
  std::string line;
  for (int n = 1; std::getline(f, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream is(line);
    double v[8];
    for (double& x : v)
      if (!(is >> x) || !std::isfinite(x))
        throw ul::InputError(path + ":" + std::to_string(n) + ": expected t_ns, x, y, z, qw, qx, qy, qz");
    Eigen::Isometry3d X_WB = Eigen::Isometry3d::Identity();
    X_WB.linear() = Eigen::Quaterniond(v[4], v[5], v[6], v[7]).normalized().toRotationMatrix();
    X_WB.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    out.push_back(v[0] * 1e-9, X_WB * *X_BC);
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Runs a visual localization estimator offline over a folder of images"};
  std::string images, camera_path, method = "orb_slam", vocabulary, output, groundtruth;
  int max_frames = 0;
  double fps = 10.0;
  bool quiet = false, verbose = false, no_loops = false, no_merge = false, no_vi_ba = false, no_imu_pred = false;
  double clahe = 3.0;
  int features = 1000;
  std::string imu_path, dvl_path, mount_text;
  app.add_option("--images", images, "image folder (TUM RGB-D dataset folder or .png/.jpg files)")->required();
  app.add_option("--camera", camera_path, "camera YAML (dataset camera.yaml or ROS camera_info YAML)")->required();
  app.add_option("--method", method, "orb_slam | klt_mono | klt_rgbd")
      ->check(CLI::IsMember({"orb_slam", "klt_mono", "klt_rgbd"}));
  app.add_option("--vocabulary", vocabulary,
                 "bag-of-words vocabulary (default: unav_resources config/vocabulary/orb_vocabulary.bin)");
  app.add_option("--output", output, "TUM trajectory to write (default: <method>_trajectory.txt)");
  app.add_option("--groundtruth", groundtruth,
                 "TUM ground truth of the camera (default: DIR/groundtruth.txt if present)");
  app.add_option("--max-frames", max_frames, "process at most N frames (0: all)")->check(CLI::NonNegativeNumber);
  app.add_option("--fps", fps, "frame rate for images not named by time")->check(CLI::PositiveNumber);
  app.add_flag("--quiet", quiet, "no per-frame lines");
  app.add_flag("--verbose", verbose,
               "orb_slam: a line for every frame (features, inliers, keyframe), not only for events");
  app.add_flag("--no-loop-closing", no_loops, "orb_slam: do not detect loops");
  app.add_flag("--no-map-merging", no_merge, "orb_slam: do not keep lost maps to merge them later (atlas)");
  app.add_flag("--no-imu-prediction", no_imu_pred,
               "orb_slam with --imu: predict each frame's pose by constant velocity, not by the IMU");
  app.add_flag("--no-inertial-ba", no_vi_ba,
               "orb_slam with --imu: scale by the inertial initialisation only, no visual-inertial bundle adjustment");
  app.add_option("--features", features, "orb_slam: ORB features per 640x480 of image (more on a larger image)")
      ->check(CLI::Range(100, 10000));
  app.add_option("--clahe", clahe,
                 "orb_slam: CLAHE clip limit before feature extraction, on low-contrast frames (grey std < 30) only "
                 "(default 3; 0 = off)")
      ->check(CLI::Range(0.0, 40.0));
  app.add_option("--imu", imu_path, "orb_slam: IMU log (imu.txt: t wx wy wz ax ay az; or EuRoC imu0/data.csv)");
  app.add_option("--dvl", dvl_path, "orb_slam: DVL log (nav/dvl.csv: t,valid,vx,vy,vz,... in the body frame)");
  app.add_option("--camera-mount", mount_text,
                 "the camera's optical frame in the body frame, \"x y z qx qy qz qw\" (default: DIR/manifest.json)");
  CLI11_PARSE(app, argc, argv);
  if (output.empty()) output = method + "_trajectory.txt";

  try {
    const ul::CameraFile cam = ul::LoadCameraFile(camera_path);
    const auto seq = ul::ListImages(images, fps);
    std::unique_ptr<ul::MonoSlam> slam;
    std::vector<ul::ImuSample> imu;  // aiding logs (orb_slam --imu / --dvl)
    std::vector<ul::DvlSample> dvl;
    std::size_t next_imu = 0, next_dvl = 0;
    std::optional<Eigen::Isometry3d> mount;  // the camera on the body, when aiding
    std::unique_ptr<ul::KltVo> klt;
    std::map<double, std::string> depths;
    double depth_scale = 1.0;
    if (method == "orb_slam") {
      if (vocabulary.empty()) {
        vocabulary = unav::common::resource_or_empty("config/vocabulary/orb_vocabulary.bin");
      }
      std::shared_ptr<const ul::BowVocabulary> voc;
      if (!vocabulary.empty()) {
        try {
          voc = std::make_shared<ul::BowVocabulary>(ul::BowVocabulary::Load(vocabulary));
        } catch (const std::exception& e) {
          std::fprintf(stderr, "unav_localize: %s\n", e.what());
          return 2;
        }
      }
      if (!voc) std::fprintf(stderr, "unav_localize: no vocabulary: loop closing and relocalisation are off\n");
      ul::MonoSlamOptions o;
      o.loop_closing = !no_loops;
      o.merge_maps = !no_merge;
      o.inertial_ba = !no_vi_ba;
      o.imu_prediction = !no_imu_pred;
      o.orb.features = features;
      o.clahe_clip = clahe;
      slam = std::make_unique<ul::MonoSlam>(cam.camera, cam.distortion, o, voc);
      if (!imu_path.empty() || !dvl_path.empty()) {
        std::optional<Eigen::Isometry3d> X_BC;
        if (!mount_text.empty() && std::filesystem::is_regular_file(mount_text)) {
          X_BC = ul::ReadCameraMount(mount_text);  // a manifest.json or a EuRoC sensor.yaml
        } else if (!mount_text.empty()) {
          std::istringstream is(mount_text);
          double v[7];
          for (double& x : v)
            if (!(is >> x) || !std::isfinite(x))
              throw ul::InputError("--camera-mount '" + mount_text + "': expected 7 finite numbers x y z qx qy qz qw");
          const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
          if (std::abs(q.norm() - 1.0) > 1e-6) throw ul::InputError("--camera-mount: the quaternion must be unit");
          X_BC = Eigen::Isometry3d::Identity();
          X_BC->linear() = q.toRotationMatrix();
          X_BC->translation() = Eigen::Vector3d(v[0], v[1], v[2]);
        } else if (std::filesystem::exists(images + "/manifest.json")) {
          X_BC = ul::ReadCameraMount(images + "/manifest.json");
        } else {
          X_BC = ul::ReadCameraMount(camera_path);  // a EuRoC sensor.yaml's T_BS
        }
        if (!X_BC)
          throw ul::InputError("--imu/--dvl need the camera's mount on the body: --camera-mount, " + images +
                               "/manifest.json with camera.mount_xyz_m and camera.mount_quaternion_xyzw, or a "
                               "EuRoC sensor.yaml with T_BS as --camera");
        mount = *X_BC;
        if (!imu_path.empty()) {
          imu = ul::ReadImuSamples(imu_path);
          slam->EnableInertial(*X_BC, ul::ImuNoise{});
        }
        if (!dvl_path.empty()) {
          dvl = ul::ReadDvlSamples(dvl_path);
          slam->EnableDvl(*X_BC);  // the DVL reports in the body frame
        }
      }
    } else {
      ul::KltVoOptions o;
      o.mode = method == "klt_mono" ? ul::KltVoOptions::Mode::kMonocular : ul::KltVoOptions::Mode::kRgbd;
      klt = std::make_unique<ul::KltVo>(cam.camera.K(), o);
      if (method == "klt_rgbd") {
        depths = ReadDepthList(images);
        depth_scale = cam.depth_scale > 0 ? cam.depth_scale : 1000.0;
      }
    }
    ue::Trajectory est;
    std::vector<double> track_ms, total_ms;
    int n = 0, lost = 0;
    for (const auto& im : seq) {
      if (max_frames > 0 && n >= max_frames) break;
      // Decoded in colour and converted like the nodes convert rgb8 messages (libpng's own
      // grey conversion rounds differently).
      const cv::Mat bgr = cv::imread(im.path, cv::IMREAD_COLOR);
      if (bgr.empty()) throw ul::InputError(im.path + ": cannot be read as an image");
      cv::Mat gray;
      cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
      ++n;
      const auto t0 = std::chrono::steady_clock::now();
      if (slam) {
        // The aiding samples up to this image (MonoSlam uses those stamped before it).
        for (; next_imu < imu.size() && imu[next_imu].stamp <= im.stamp; ++next_imu)
          slam->AddImu(imu[next_imu].stamp, imu[next_imu].gyro, imu[next_imu].accel);
        for (; next_dvl < dvl.size() && dvl[next_dvl].stamp <= im.stamp; ++next_dvl)
          slam->AddDvl(dvl[next_dvl].stamp, dvl[next_dvl].velocity, dvl[next_dvl].valid);
        const auto s = slam->Track(gray, im.stamp);
        track_ms.push_back(s.tracking_ms);
        total_ms.push_back(s.tracking_ms + s.mapping_ms);
        if (s.state == ul::SlamState::kLost) ++lost;
        if (verbose)
          std::printf("%.3f %s%s%s%s features %d inliers %d %s\n", im.stamp, ul::to_string(s.state),
                      s.keyframe ? " keyframe" : "", s.loop_closed ? " loop closed" : "",
                      s.reinitialized ? " re-initialised" : "", s.features, s.inliers, s.message.c_str());
        else if (!quiet &&
                 (s.state != ul::SlamState::kTracking || s.loop_closed || s.reinitialized || !s.message.empty()))
          std::printf("%.3f %s%s%s %s\n", im.stamp, ul::to_string(s.state), s.loop_closed ? " loop closed" : "",
                      s.reinitialized ? " re-initialised" : "", s.message.c_str());
      } else {
        Eigen::Isometry3d T;
        ul::VoSummary s;
        if (method == "klt_mono") {
          s = klt->ProcessFrame(gray, &T);
        } else {
          const auto it = depths.lower_bound(im.stamp - 1e-4);
          if (it == depths.end() || std::abs(it->first - im.stamp) > 1e-3)
            throw ul::InputError(im.path + ": no depth image with its stamp");
          cv::Mat d16 = cv::imread(it->second, cv::IMREAD_ANYDEPTH), depth;
          if (d16.empty()) throw ul::InputError(it->second + ": cannot be read as a depth image");
          d16.convertTo(depth, CV_32F, 1.0 / depth_scale);
          depth.setTo(std::numeric_limits<float>::quiet_NaN(), d16 == 0);
          s = klt->ProcessFrame(gray, depth, &T);
        }
        const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
        track_ms.push_back(ms);
        total_ms.push_back(ms);
        if (s.status == ul::VoStatus::kLost) ++lost;
        if (!quiet && s.status != ul::VoStatus::kTracking)
          std::printf("%.3f %s %s\n", im.stamp, ul::to_string(s.status), s.message.c_str());
        if (s.status == ul::VoStatus::kTracking || s.status == ul::VoStatus::kInitialized) est.push_back(im.stamp, T);
      }
    }
    if (slam)
      for (const auto& p : slam->Trajectory()) est.push_back(p.stamp, p.T_wc);
    if (est.empty()) {
      std::fprintf(stderr, "unav_localize: no pose was estimated from %d frames\n", n);
      return 1;
    }
    ue::write_tum(output, est);
    double mean_track = 0, mean_total = 0;
    for (double v : track_ms) mean_track += v / static_cast<double>(track_ms.size());
    for (double v : total_ms) mean_total += v / static_cast<double>(total_ms.size());
    std::printf(
        "%s: %d frames, %zu poses, %d lost; per frame: tracking mean %.2f ms (p50 %.2f, p90 %.2f), with mapping mean "
        "%.2f ms (p99 %.1f) -> %.1f frames/s\n",
        method.c_str(), n, est.size(), lost, mean_track, Percentile(track_ms, 0.5), Percentile(track_ms, 0.9),
        mean_total, Percentile(total_ms, 0.99), 1000.0 / std::max(mean_total, 1e-9));
    if (slam) {
      const auto st = slam->stats();
      std::printf(
          "orb_slam: %d keyframes, %d points, %d loops closed, %d relocalisations, %d re-initialisations, %d maps "
          "merged (%d map(s) in the output)\n",
          st.keyframes, st.points, st.loops, st.relocalizations, st.reinitializations, st.merges, st.maps - st.merges);
      if (!imu_path.empty())
        std::printf(
            "orb_slam inertial: %d initialisation(s), %d refinement(s), %ld inertial factors, %d frames tracked from "
            "the IMU's prediction, %d predicted poses missed (constant-velocity or IMU)\n",
            st.inertial_inits, st.inertial_refinements, st.inertial_factors, st.imu_predicted_frames,
            st.motion_model_misses);
    }
    std::printf("trajectory: %s\n", output.c_str());
    if (groundtruth.empty() && std::filesystem::exists(images + "/groundtruth.txt"))
      groundtruth = images + "/groundtruth.txt";
    const std::string euroc_gt = images + "/../state_groundtruth_estimate0/data.csv";  // images = mav0/cam0
    if (groundtruth.empty() && std::filesystem::exists(euroc_gt)) groundtruth = euroc_gt;
    if (!groundtruth.empty()) {
      const ue::Trajectory gt = ReadGroundTruth(groundtruth, camera_path, mount);
      const auto align = method == "klt_rgbd" ? ue::Alignment::kSE3 : ue::Alignment::kSim3;
      const auto r = ue::evaluate(gt, est, "sequence", method, align);
      std::printf(
          "APE (%s-aligned, %zu poses, scale %.4f): rmse %.4f m, mean %.4f m, max %.4f m; rotation rmse %.4f rad\n",
          align == ue::Alignment::kSE3 ? "SE(3)" : "Sim(3)", r.poses, r.scale, r.ape_m.rmse, r.ape_m.mean, r.ape_m.max,
          r.ape_rad.rmse);
      if (slam && (!imu.empty() || !dvl.empty()) && !slam->metric()) {
        std::printf("not metric: the aiding sensors did not scale the map (no SE(3) figure)\n");
      } else if (slam && (!imu.empty() || !dvl.empty())) {  // metric: no scale fitted
        const auto m = ue::evaluate(gt, est, "sequence", method, ue::Alignment::kSE3);
        std::printf("APE (SE(3)-aligned, %zu poses, metric as estimated): rmse %.4f m, mean %.4f m, max %.4f m\n",
                    m.poses, m.ape_m.rmse, m.ape_m.mean, m.ape_m.max);
      }
      std::printf("RPE (1 frame): rmse %.4f m, rotation rmse %.5f rad; ground-truth path %.2f m\n", r.rpe_m.rmse,
                  r.rpe_rad.rmse, gt.path_length());
    }
  } catch (const ul::InputError& e) {
    std::fprintf(stderr, "unav_localize: %s\n", e.what());
    return 2;
  } catch (const ue::TrajectoryError& e) {
    std::fprintf(stderr, "unav_localize: %s\n", e.what());
    return 2;
  } catch (const unav::ConfigError& e) {
    std::fprintf(stderr, "unav_localize: %s\n", e.what());
    return 2;
  } catch (const std::invalid_argument& e) {
    std::fprintf(stderr, "unav_localize: %s\n", e.what());
    return 2;
  }
  return 0;
}
