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

// A primitive `shape` (box, plane, ...) of `size_m`, level at `xyz_m` (world_ned), untextured.
inline Object shape_object(const std::string& name, const std::string& shape, const Eigen::Vector3d& size_m,
                           const Eigen::Vector3d& xyz_m, SegClass seg_class) {
  Object o;
  o.name = name;
  o.shape = shape;
  o.size_m = size_m;
  o.X_WO = pose_from_xyz_rpy(xyz_m, Eigen::Vector3d::Zero());
  o.seg_class = seg_class;
  return o;
}

// A horizontal plane `size_m` square at `depth_m` (seabed class, untextured albedo 0.5).
inline Object floor_object(double depth_m, double size_m) {
  return shape_object("floor", "plane", {size_m, size_m, 1.0}, {0.0, 0.0, depth_m}, SegClass::kSeabed);
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

// Centroid (u, v) of the pixels of segmentation class `id`; `count` says how many there are.
inline Eigen::Vector2d seg_centroid(const Frame& f, int id, int* count) {
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  *count = 0;
  for (int v = 0; v < f.height; ++v)
    for (int u = 0; u < f.width; ++u)
      if (f.seg[static_cast<std::size_t>(v) * f.width + u] == id) {
        sum += Eigen::Vector2d(u, v);
        ++*count;
      }
  return *count > 0 ? Eigen::Vector2d(sum / *count) : sum;
}

// A vehicle-sized box (BlueROV2 Heavy's frame, 0.457 x 0.575 x 0.254 m; class vehicle) at X_WO.
inline Object vehicle_box(const std::string& name, const Pose& X_WO, bool movable) {
  Object o;
  o.name = name;
  o.shape = "box";
  o.size_m = {0.457, 0.575, 0.254};
  o.X_WO = X_WO;
  o.seg_class = SegClass::kVehicle;
  o.movable = movable;
  return o;
}

// A level body at p_W (world_ned).
inline Pose body_at(const Eigen::Vector3d& p_W) { return pose_from_xyz_rpy(p_W, Eigen::Vector3d::Zero()); }

}  // namespace unav::renderer::test
