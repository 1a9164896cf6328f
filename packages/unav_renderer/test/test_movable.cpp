// Movable objects (another vehicle of the fleet): drawn, shadowed and labelled where they are put.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/renderer_pool.hpp"

using namespace unav::renderer;
using namespace unav::renderer::test;  // NOLINT(google-build-using-namespace): the shared test scenes

namespace {

// Water over a floor at 8 m, lit by the sun (shadows on), and a vehicle body at `at`, movable or
// not.
World scene_with_body(const Pose& at, bool movable) {
  World w = empty_world();
  w.sun.direction_W = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();  // oblique: the shadow beside the body
  w.objects.push_back(floor_object(8.0, 40.0));
  w.objects.push_back(vehicle_box("rov2", at, movable));
  w.objects.back().material.albedo = {0.8, 0.7, 0.2};
  return w;
}

RenderOptions options() {
  RenderOptions o;
  o.noise = false;
  o.marine_snow = false;
  o.caustics = false;
  o.texture_size = 64;
  return o;
}

// A camera 6 m deep looking forward and 30 deg down, onto the floor and the body.
Pose eye() { return pose_from_xyz_rpy({0.0, 0.0, 6.0}, {0.0, -30.0 * M_PI / 180.0, 0.0}); }

int count_class(const Frame& f, SegClass c) {
  int n = 0;
  for (auto s : f.seg) n += s == static_cast<std::uint8_t>(c) ? 1 : 0;
  return n;
}

}  // namespace

TEST(MovableObjects, MovedObjectRendersAsIfThePlacedThere) {
  // A movable body moved from 4 m ahead to 3 m ahead and 0.8 m to the side gives the frame a world
  // built with the body there gives: the same pixels, labels and depths (its shadow on the floor
  // included: the sun's map is redrawn and the floor's shadow culling learns where it went).
  const Pose start = pose_from_xyz_rpy({4.0, 0.0, 7.0}, {0.0, 0.0, 0.0});
  const Pose moved = pose_from_xyz_rpy({3.0, 0.8, 7.3}, {0.0, 0.1, 0.6});
  const CameraModel cam = forward_camera(160, 120, 120.0);
  Renderer r(scene_with_body(start, true), {cam}, options());
  const Frame before = r.render(eye(), "cam");
  r.set_object_pose("rov2", moved);
  const Frame after = r.render(eye(), "cam");
  Renderer placed(scene_with_body(moved, false), {cam}, options());
  const Frame expected = placed.render(eye(), "cam");
  const int px = count_class(after, SegClass::kVehicle);
  std::printf("vehicle pixels: %d before the move, %d after (placed there: %d)\n",
              count_class(before, SegClass::kVehicle), px, count_class(expected, SegClass::kVehicle));
  EXPECT_GT(px, 100);  // in view, as a vehicle
  EXPECT_NE(before.seg, after.seg);
  EXPECT_EQ(after.seg, expected.seg);
  EXPECT_EQ(after.depth, expected.depth);
  EXPECT_EQ(after.rgb, expected.rgb);

  // Back where it started: the first frame again (nothing of the move is left behind).
  r.set_object_pose("rov2", start);
  EXPECT_EQ(r.render(eye(), "cam").rgb, before.rgb);

  // Two workers: each moves its copy before the frames submitted after the call.
  RendererPool pool(scene_with_body(start, true), {cam}, options(), 2);
  pool.set_object_pose("rov2", moved);
  pool.submit(eye(), "cam");
  pool.submit(eye(), "cam");
  EXPECT_EQ(pool.collect().rgb, expected.rgb);
  EXPECT_EQ(pool.collect().rgb, expected.rgb);
}

TEST(MovableObjects, UnknownOrFixedObjectsAreErrors) {
  const CameraModel cam = forward_camera(32, 24, 30.0);
  Renderer fixed(scene_with_body(Pose::Identity(), false), {cam}, options());
  try {
    fixed.set_object_pose("rov2", Pose::Identity());
    FAIL() << "a fixed object moved";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("rov2"), std::string::npos) << e.what();
  }
  Renderer movable(scene_with_body(Pose::Identity(), true), {cam}, options());
  EXPECT_THROW(movable.set_object_pose("rov3", Pose::Identity()), ConfigError);
  Pose bad = Pose::Identity();
  bad.translation().x() = std::nan("");
  EXPECT_THROW(movable.set_object_pose("rov2", bad), ConfigError);
  RendererPool pool(scene_with_body(Pose::Identity(), true), {cam}, options(), 1);
  EXPECT_THROW(pool.set_object_pose("rov3", Pose::Identity()), ConfigError);
}
