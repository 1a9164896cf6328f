// The CTest fixture of the SLAM and VO tests: renders every sequence they run on (slam_flights.hpp)
// with our renderer (EGL; llvmpipe here) into the folder given, one file each
// (slam_sequences.hpp). The only test of this package that links the renderer.
//   render_slam_sequences OUT_DIR
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "slam_flights.hpp"
#include "slam_sequences.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_scene/camera.hpp"
#include "unav_scene/world.hpp"

namespace ut = unav::localization::testing;

namespace {

const std::string kRoot = UNAV_REPO_ROOT;

// Read once for every sequence.
const unav::scene::World& PipeWorld() {
  static const unav::scene::World world = unav::scene::load_world(kRoot + "/worlds/pipe_inspection/world.yaml");
  return world;
}

enum class Keep { kGray, kGrayDepth, kRgb, kRgbDepth };

// Renders camera "down" of `renderer` along X_WB (frame k at t = 0.1 k).
ut::RenderedSequence Fly(unav::renderer::Renderer& renderer, const Eigen::Matrix3d& K,
                         const std::vector<Eigen::Isometry3d>& X_WB, Keep keep) {
  ut::RenderedSequence s;
  s.K = K;
  for (std::size_t k = 0; k < X_WB.size(); ++k) {
    const double t = 0.1 * static_cast<double>(k);
    const unav::renderer::Frame f = renderer.render(X_WB[k], "down", t);
    const cv::Mat rgb(f.height, f.width, CV_8UC3, const_cast<uint8_t*>(f.rgb.data()));
    if (keep == Keep::kGray || keep == Keep::kGrayDepth) {
      cv::Mat gray;
      cv::cvtColor(rgb, gray, cv::COLOR_RGB2GRAY);
      s.images.push_back(gray);
    } else {
      s.images.push_back(rgb.clone());
    }
    if (keep == Keep::kGrayDepth || keep == Keep::kRgbDepth)
      s.depth.push_back(cv::Mat(f.height, f.width, CV_32FC1, const_cast<float*>(f.depth.data())).clone());
    s.stamps.push_back(t);
    s.X_WB.push_back(X_WB[k]);
    s.X_WC.push_back(f.X_WC);
  }
  return s;
}

// The monocular SLAM tests' camera: 640 x 480 unless told, 90 deg, looking down the body z axis
// unless X_BC says otherwise; Lambertian, flat, clean images (the ones these tests were written
// against: see test_mono_slam.cpp).
ut::RenderedSequence Mono(const std::vector<Eigen::Isometry3d>& X_WB, int width = 640, int height = 480,
                          double noise = 0.0, const Eigen::Isometry3d& X_BC = Eigen::Isometry3d::Identity()) {
  unav::scene::CameraModel cam = unav::scene::CameraModel::from_hfov("down", width, height, 90.0 * M_PI / 180.0);
  cam.noise_stddev = noise;
  cam.X_BC = X_BC;
  unav::renderer::RenderOptions ro;
  ro.noise = noise > 0.0;
  ro.marine_snow = false;  // particles move on their own: not part of the static scene
  ro.materials = false;
  unav::renderer::Renderer renderer(PipeWorld(), {cam}, ro);
  return Fly(renderer, cam.K(), X_WB, Keep::kGray);
}

// The KLT VO tests' 320 x 180 camera 2 m above the sand, gray + depth. No lamps (their pool moves
// with the camera: a moving brightness pattern), no forward scatter; caustics stay on.
ut::RenderedSequence Klt() {
  unav::scene::CameraModel cam = unav::scene::CameraModel::from_hfov("down", 320, 180, 90.0 * M_PI / 180.0);
  unav::renderer::RenderOptions ro;
  ro.noise = false;
  ro.marine_snow = false;
  ro.lamps = false;
  ro.forward_scatter = false;
  unav::renderer::Renderer renderer(PipeWorld(), {cam}, ro);
  return Fly(renderer, cam.K(), ut::KltPath(), Keep::kGrayDepth);
}

// The node tests' down camera as the vSLAM config has it (RGB as published; depth for klt_vo).
ut::RenderedSequence Node(const std::vector<Eigen::Isometry3d>& X_WB, Keep keep) {
  const auto cams = unav::scene::load_cameras(kRoot + "/config/sensors/bluerov2_down_vslam.yaml");
  unav::renderer::RenderOptions ro;
  ro.marine_snow = false;
  unav::renderer::Renderer renderer(PipeWorld(), cams, ro);
  return Fly(renderer, cams[0].K(), X_WB, keep);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: render_slam_sequences OUT_DIR\n");
    return 2;
  }
  const std::string dir = argv[1];
  try {
    std::filesystem::create_directories(dir);
    auto write = [&](const std::string& name, const ut::RenderedSequence& s) {
      ut::save_sequence(s, dir + "/" + name + ".seq");
      std::printf("%s: %zu frames %dx%d\n", name.c_str(), s.size(), s.images[0].cols, s.images[0].rows);
    };
    write("straight", Mono(ut::StraightPath()));
    write("straight_320x180_noise", Mono(ut::StraightPath(), 320, 180, 0.008));
    for (const ut::ForwardCase& c : ut::kForwardCases)
      write("forward_" + std::to_string(c.pitch_deg),
            Mono(ut::ForwardPath(c.step_m), 640, 480, 0.0, ut::ForwardMount(c.pitch_deg)));
    write("square", Mono(ut::SquarePath()));
    write("weave", Mono(ut::WeaveFlight::Path()));
    write("klt", Klt());
    write("orb_node", Node(ut::NodePath(50, 0.06, 0.2, 0.05), Keep::kRgb));
    write("klt_node", Node(ut::NodePath(40, 0.05, 0.15, 0.0), Keep::kRgbDepth));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "render_slam_sequences: %s\n", e.what());
    return 1;
  }
  return 0;
}
