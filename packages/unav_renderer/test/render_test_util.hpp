// Helpers shared by the renderer's image tests (one test executable).
#pragma once

#include "unav_renderer/renderer.hpp"

namespace unav::renderer::test {

// Exact optics: no blur, snow, caustics, noise, lamps, auto exposure, material effects; linear
// 8-bit output.
inline RenderOptions exact_options() {
  RenderOptions o;
  o.forward_scatter = false;
  o.marine_snow = false;
  o.caustics = false;
  o.noise = false;
  o.lamps = false;
  o.auto_exposure = false;
  o.srgb_output = false;
  o.texture_size = 64;
  o.materials = false;  // Lambertian, flat, clean (test_materials.cpp tests them)
  return o;
}

// Water only: no seabed, the sun straight down.
inline World empty_world() {
  World w;
  w.name = "test";
  w.file = "<test world>";
  w.seabed.enabled = false;
  w.sun.direction_W = {0, 0, 1};
  return w;
}

// A horizontal plane `size_m` square at `depth_m` (seabed class, untextured albedo 0.5).
inline Object floor_object(double depth_m, double size_m) {
  Object f;
  f.name = "floor";
  f.shape = "plane";
  f.size_m = {size_m, size_m, 1.0};
  f.X_WO = pose_from_xyz_rpy({0.0, 0.0, depth_m}, {0.0, 0.0, 0.0});
  f.seg_class = SegClass::kSeabed;
  return f;
}

// A forward camera "cam" (optical axis = body x) with a centred principal point.
inline CameraModel forward_camera(int w, int h, double f) {
  CameraModel c;
  c.name = "cam";
  c.width = w;
  c.height = h;
  c.fx = c.fy = f;
  c.cx = 0.5 * (w - 1);
  c.cy = 0.5 * (h - 1);
  c.X_BC.linear() = R_camera_body_to_optical();
  return c;
}

// A level body at p_W (world_ned).
inline Pose body_at(const Eigen::Vector3d& p_W) { return pose_from_xyz_rpy(p_W, Eigen::Vector3d::Zero()); }

}  // namespace unav::renderer::test
