// RendererPool: frames in submission order, each the same bit for bit as one Renderer's.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <vector>

#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/renderer_pool.hpp"
#include "unav_scene/world.hpp"

using namespace unav::renderer;

namespace {

// The pipe world seen by a front (with lens distortion and sensor noise) and a down camera.
std::vector<CameraModel> cameras() {
  CameraModel front = CameraModel::from_hfov("front", 160, 120, 80.0 * M_PI / 180.0);
  front.X_BC.linear() = R_camera_body_to_optical();
  front.distortion << -0.05, 0.01, 0, 0, 0;
  front.noise_stddev = 0.02;
  front.shot_noise = 0.01;
  CameraModel down = CameraModel::from_hfov("down", 120, 90, 90.0 * M_PI / 180.0);
  down.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  down.noise_stddev = 0.02;
  return {front, down};
}

RenderOptions options() {
  RenderOptions o;  // every effect on: noise, snow, caustics, lamps, shadows
  o.texture_size = 64;
  return o;
}

World pipe_world() { return load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml"); }

struct Shot {
  Pose X_WB;
  const char* camera;
  double stamp_s;
};
std::vector<Shot> shots() {
  std::vector<Shot> s;
  s.reserve(7);
  for (int i = 0; i < 7; ++i)
    s.push_back({pose_from_xyz_rpy({1.0 + 0.7 * i, 0.2 - 0.1 * i, 8.0}, {0.0, 0.05 * i, 0.1 * i}),
                 i % 3 == 2 ? "down" : "front", 0.1 * i});
  return s;
}

}  // namespace

TEST(RendererPool, FramesComeInOrderAndMatchOneRendererBitForBit) {
  const World world = pipe_world();
  Renderer one(world, cameras(), options());
  one.set_next_sequence(40);
  std::vector<Frame> expected;
  for (const Shot& s : shots()) expected.push_back(one.render(s.X_WB, s.camera, s.stamp_s));

  RendererPool pool(world, cameras(), options(), 2);
  EXPECT_EQ(pool.workers(), 2);
  // On llvmpipe the second worker takes the other EGL display (its own rasterizer threads), and
  // the comparison below is then also one of two displays.
  const auto platforms = pool.platforms();
  std::printf("pool on %s: workers on %s and %s\n", pool.gl_renderer().c_str(), platforms[0].c_str(),
              platforms[1].c_str());
  if (pool.gl_renderer().find("llvmpipe") != std::string::npos) {
    EXPECT_NE(platforms[0], platforms[1]);
  }
  pool.set_next_sequence(40);
  std::vector<Frame> got;
  // More frames than the pool holds in flight (2 per worker): submit() waits, nothing is lost.
  for (const Shot& s : shots()) {
    pool.submit(s.X_WB, s.camera, s.stamp_s);
    if (pool.in_flight() == 3) got.push_back(pool.collect());
  }
  while (pool.in_flight() > 0) got.push_back(pool.collect());
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    SCOPED_TRACE("frame " + std::to_string(i));
    EXPECT_EQ(got[i].sequence, 40 + i);
    EXPECT_EQ(got[i].camera, expected[i].camera);
    EXPECT_EQ(got[i].stamp_s, expected[i].stamp_s);
    EXPECT_TRUE(got[i].X_WC.isApprox(expected[i].X_WC, 0.0));
    // The same frame, not just a similar one: noise included (a function of seed and sequence).
    EXPECT_EQ(got[i].rgb, expected[i].rgb);
    EXPECT_EQ(got[i].depth, expected[i].depth);
    EXPECT_EQ(got[i].seg, expected[i].seg);
  }
  // And the frames differ from one another (the poses move): the comparison above compared images.
  EXPECT_NE(got[0].rgb, got[1].rgb);
}

TEST(RendererPool, ErrorsReachTheCaller) {
  const World world = pipe_world();
  EXPECT_THROW(RendererPool(world, cameras(), options(), 0), ConfigError);
  RenderOptions bad = options();
  bad.shadow_map_size = 0;
  EXPECT_THROW(RendererPool(world, cameras(), bad, 2), ConfigError);  // a worker's Renderer error
  RendererPool pool(world, cameras(), options(), 2);
  EXPECT_THROW(pool.collect(), std::logic_error);  // nothing in flight
  pool.submit(Pose::Identity(), "no_such_camera");
  pool.submit(pose_from_xyz_rpy({2.0, 0.0, 8.0}, {0, 0, 0}), "front");
  EXPECT_THROW(pool.collect(), std::invalid_argument);  // the unknown camera's frame
  const Frame f = pool.collect();                       // the pool goes on
  EXPECT_EQ(f.camera, "front");
  EXPECT_EQ(f.sequence, 1u);
}
