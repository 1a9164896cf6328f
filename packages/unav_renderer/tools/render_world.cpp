// Render one frame per camera of a world to PNG (gallery, quick looks):
//   unav_render_world WORLD.yaml CAMERAS.yaml OUT_PREFIX [--water NAME|FILE.yaml]
//       [--pose N E D YAW_DEG] [--camera NAME] [--no-snow] [--no-noise] [--no-shadows] [--no-materials] [--samples N]
//       [--lod PX]
// Writes OUT_PREFIX_<camera>.png and prints timings.
#include <cstdlib>
#include <cstring>
#include <iostream>

#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;

int main(int argc, char** argv) {
  if (argc < 4) {
    std::cerr << "usage: unav_render_world WORLD.yaml CAMERAS.yaml OUT_PREFIX [--water NAME|FILE] "
                 "[--pose N E D YAW_DEG] [--camera NAME] [--no-snow] [--no-noise] [--no-shadows] [--no-materials] "
                 "[--samples N] [--lod PX]\n";
    return 2;
  }
  try {
    World world = load_world(argv[1]);
    auto cams = load_cameras(argv[2]);
    RenderOptions opt;
    Eigen::Vector4d pose(0.0, 0.0, world.seabed.depth_m - 2.0, 0.0);
    std::string only;
    for (int i = 4; i < argc; ++i) {
      const std::string a = argv[i];
      if (a == "--water" && i + 1 < argc) {
        const std::string w = argv[++i];
        world.water = w.find(".yaml") != std::string::npos ? load_water_file(w) : jerlov_preset(w);
      } else if (a == "--pose" && i + 4 < argc) {
        for (int k = 0; k < 4; ++k) pose[k] = std::atof(argv[++i]);
      } else if (a == "--camera" && i + 1 < argc) {
        only = argv[++i];
      } else if (a == "--no-snow") {
        opt.marine_snow = false;
      } else if (a == "--no-materials") {
        opt.materials = false;
      } else if (a == "--no-shadows") {
        opt.shadows = false;
      } else if (a == "--no-noise") {
        opt.noise = false;
      } else if (a == "--lod" && i + 1 < argc) {
        opt.terrain_lod_px = std::atof(argv[++i]);
      } else if (a == "--samples" && i + 1 < argc) {
        opt.lamp_scatter_samples = std::atoi(argv[++i]);
      } else {
        std::cerr << "unknown argument " << a << "\n";
        return 2;
      }
    }
    Renderer r(world, cams, opt);
    std::cout << "GL: " << r.context().gl_renderer() << " via " << r.context().platform() << ", triangles "
              << r.triangle_count() << "\n";
    const Pose X_WB = pose_from_xyz_rpy(pose.head<3>(), {0.0, 0.0, pose[3] * M_PI / 180.0});
    for (const auto& name : r.camera_names()) {
      if (!only.empty() && name != only) continue;
      r.render(X_WB, name, 0.0);
      const Frame f = r.render(X_WB, name, 0.0);
      const std::string path = std::string(argv[3]) + "_" + name + ".png";
      write_png_rgb(f, path);
      std::cout << path << " " << f.width << "x" << f.height << " render " << r.last_timings().render_ms
                << " ms, readback " << r.last_timings().readback_ms << " ms\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "error: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
