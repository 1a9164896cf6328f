// Pings per second of the sonar simulation on worlds/pipe_inspection: forward-looking sonar at
// 256 beams x 512 bins and 512 x 1024 (130 x 20 deg, Oculus M750d-like), side-scan at 1024 bins a
// side; median raster (GL passes + readback) and accumulation (CPU) times. With --gallery DIR
// also writes the README's sonar gallery: FLS fans over the pipe in clear and turbid water (the
// sonar does not care), the front camera's view in both, and a side-scan waterfall along the pipe.
//   bench_unav_sonar [pings=30] [--gallery DIR] [world.yaml]
// Machine-readable: BENCH sonar/<sonar>_pings_per_s, sonar/<sonar>_raster_ms,
// sonar/<sonar>_accumulate_ms (sonar: fls_256x512, fls_256x512_sidelobes, fls_512x1024,
// sidescan_1024).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "unav_common/bench.hpp"
#include "unav_common/resources.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/sonar_renderer.hpp"
#include "unav_scene/sonar.hpp"

using namespace unav::renderer;
using Clock = std::chrono::steady_clock;

namespace {

constexpr double kDeg = M_PI / 180.0;

// Fly along the first leg of the pipe at 2.5 m altitude, 0.1 m per ping.
Pose pose_at(int i) { return pose_from_xyz_rpy({-3.0 + 0.1 * i, 0.3, 7.5}, {0.0, 0.0, 0.05}); }

SonarModel fls(int beams, int bins) {
  SonarModel m = sonar_preset("oculus_m750d_lf");
  m.name = "fls_" + std::to_string(beams) + "x" + std::to_string(bins);
  m.beams = beams;
  m.bins = bins;
  m.min_range_m = 0.3;
  m.max_range_m = 20.0;
  m.X_BH = pose_from_xyz_rpy({0.25, 0.0, -0.12}, {0.0, -15.0 * kDeg, 0.0});
  return m;
}

SonarModel side_scan(int bins) {
  SonarModel m = sonar_preset("sidescan_900k");
  m.name = "sidescan_" + std::to_string(bins);
  m.bins = bins;
  m.max_range_m = 20.0;
  m.X_BH = pose_from_xyz_rpy({0.0, 0.0, 0.15}, {0.0, 0.0, 0.0});
  return m;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v[v.size() / 2];
}

}  // namespace

int main(int argc, char** argv) {
  int pings = 30;
  std::string gallery, world_path;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--gallery" && i + 1 < argc) {
      gallery = argv[++i];
    } else if (a.find(".yaml") != std::string::npos) {
      world_path = a;
    } else {
      pings = std::max(1, std::atoi(a.c_str()));
    }
  }
  if (world_path.empty()) world_path = std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml";
  World world = load_world(world_path);
  SonarModel lobes = fls(256, 512);  // the same fan with its side lobes (-30 dB, 6 dB/octave)
  lobes.name += "_sidelobes";
  lobes.sidelobes = true;
  const std::vector<SonarModel> models = {fls(256, 512), lobes, fls(512, 1024), side_scan(1024)};
  SonarRenderer sr(world, models);
  std::printf("sonar benchmark: %s, %s (EGL %s), %d pings each\n", world_path.c_str(),
              sr.context().gl_renderer().c_str(), sr.context().platform().c_str(), pings);
  std::printf("%-18s %10s %12s %14s %10s\n", "sonar", "pings/s", "raster ms", "accumulate ms", "ms/ping");
  for (const auto& m : models) {
    for (int i = 0; i < 3; ++i) sr.ping(pose_at(i), m.name);  // warm-up (shader JIT)
    std::vector<double> raster, acc, total;
    const auto t0 = Clock::now();
    for (int i = 0; i < pings; ++i) {
      const auto a = Clock::now();
      const SonarPing p = sr.ping(pose_at(i), m.name, 0.1 * i);
      total.push_back(std::chrono::duration<double, std::milli>(Clock::now() - a).count());
      raster.push_back(sr.last_timings().raster_ms);
      acc.push_back(sr.last_timings().accumulate_ms);
      if (p.image.empty()) return 1;
    }
    const double s = std::chrono::duration<double>(Clock::now() - t0).count();
    std::printf("%-18s %10.1f %12.2f %14.2f %10.2f\n", m.name.c_str(), pings / s, median(raster), median(acc),
                median(total));
    unav::common::print_bench("sonar/" + m.name + "_pings_per_s", pings / s, "pings_per_s");
    unav::common::print_bench("sonar/" + m.name + "_raster_ms", median(raster), "ms");
    unav::common::print_bench("sonar/" + m.name + "_accumulate_ms", median(acc), "ms");
  }
  if (gallery.empty()) return 0;

  // Gallery, with the vehicle's own sonars (config/sensors/bluerov2_sonars.yaml: their codings and
  // gains as the demo publishes them): the FLS over the pipe in clear (Jerlov I) and turbid (coastal
  // 9C) water beside the front camera, a side-scan waterfall, the profiler's height map.
  std::filesystem::create_directories(gallery);
  const std::string sonars_file = std::string(UNAV_REPO_ROOT) + "/config/sensors/bluerov2_sonars.yaml";
  const SonarModel vfls = load_sonar(sonars_file, "fls"), vss = load_sonar(sonars_file, "sidescan"),
                   profiler = load_sonar(sonars_file, "profiler");
  SonarRenderer vehicle(world, {vfls, vss, profiler});
  const Pose X_WB = pose_from_xyz_rpy({-3.0, 0.0, 7.6}, {0.0, 0.0, 0.0});
  std::vector<CameraModel> cams = default_cameras();
  for (const char* water : {"I", "9C"}) {
    World w = world;
    w.water = jerlov_preset(water);
    vehicle.set_world(w);
    const SonarPing p = vehicle.ping(X_WB, "fls");
    const FanImage fan = fan_image(p, 640);
    write_png_mono(fan.pixels, fan.width, fan.height, gallery + "/sonar_fls_" + water + ".png");
    Renderer cam(w, cams);
    write_png_rgb(cam.render(X_WB, "front"), gallery + "/sonar_front_camera_" + water + ".png");
  }
  vehicle.set_world(world);
  Waterfall wf(vss.bins, 300);
  for (int i = 0; i < 300; ++i) {
    // Along the pipe, 7 m to port of its first leg: the pipe and its shadow fall to starboard.
    const Pose X = pose_from_xyz_rpy({-4.0 + 0.08 * i, -7.0, 7.0}, {0.0, 0.0, 0.0});
    wf.add(vehicle.ping(X, "sidescan", 0.1 * i));
  }
  write_png_mono(wf.pixels(), wf.width(), wf.height(), gallery + "/sonar_sidescan_waterfall.png");
  // The profiler 2 m over the pipe's first leg, 5 cm between pings: its detected points as a height
  // map of the strip under the track (rows along track, north up; columns across, 2.5 cm each;
  // grey = height above the 10 m seabed, from -0.2 m black to 0.6 m white; no return: black). The
  // pipe is a ridge, rocks are knobs.
  const int rows = 200, cols = 240;
  std::vector<std::uint8_t> height(static_cast<std::size_t>(rows) * cols, 0);
  for (int i = 0; i < rows; ++i) {
    const double north = 8.0 - 0.05 * i;  // the first row is the northernmost
    const SonarPing p = vehicle.ping(pose_from_xyz_rpy({north, 0.0, 7.85}, {0.0, 0.0, 0.0}), "profiler", 0.1 * i);
    for (const ProfilePoint& q : detect_profile(p, profiler.detection_db)) {
      const Eigen::Vector3d p_W = p.X_WS * q.p_S;
      const int c = static_cast<int>(std::floor((p_W.y() + 3.0) / 0.025));
      if (c < 0 || c >= cols) continue;
      const double h = world.seabed.depth_m - p_W.z();
      height[static_cast<std::size_t>(i) * cols + static_cast<std::size_t>(c)] =
          static_cast<std::uint8_t>(std::clamp((h + 0.2) / 0.8 * 255.0, 1.0, 255.0));
    }
  }
  write_png_mono(height, cols, rows, gallery + "/sonar_profiler_heightmap.png");
  std::printf("gallery written to %s\n", gallery.c_str());
  return 0;
}
