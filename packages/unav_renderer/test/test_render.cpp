// Renderer tests on Mesa llvmpipe (headless EGL): geometry, projection, image formation.
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include <chrono>
#include <cmath>

#include "../src/pixel_ops.hpp"
#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;
using unav::renderer::test::body_at;
using unav::renderer::test::empty_world;
using unav::renderer::test::exact_options;

namespace {

Object plane(const Eigen::Vector3d& p_W, const Eigen::Vector3d& rpy, double size, SegClass cls,
             const Eigen::Vector3d& albedo = {0.5, 0.5, 0.5}) {
  Object o;
  o.name = "plane";
  o.shape = "plane";
  o.size_m = {size, size, 1.0};
  o.X_WO = pose_from_xyz_rpy(p_W, rpy);
  o.seg_class = cls;
  o.material.texture = "none";
  o.material.albedo = albedo;
  return o;
}

CameraModel down_camera(int w = 96, int h = 72, double hfov_deg = 60.0) {
  CameraModel c = CameraModel::from_hfov("down", w, h, hfov_deg * M_PI / 180.0);
  c.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  return c;
}

CameraModel front_camera(int w, int h, double fx, double fy, double cx, double cy) {
  CameraModel c;
  c.name = "front";
  c.width = w;
  c.height = h;
  c.fx = fx;
  c.fy = fy;
  c.cx = cx;
  c.cy = cy;
  c.X_BC.linear() = R_camera_body_to_optical();
  return c;
}

Eigen::Vector3d mean_rgb(const Frame& f, int u0, int v0, int half) {
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  int n = 0;
  for (int v = v0 - half; v <= v0 + half; ++v)
    for (int u = u0 - half; u <= u0 + half; ++u) {
      const std::size_t i = static_cast<std::size_t>(v) * f.width + u;
      for (int c = 0; c < 3; ++c) s[c] += f.rgb[3 * i + c] / 255.0;
      ++n;
    }
  return s / n;
}

std::uint8_t seg_at(const Frame& f, const Eigen::Vector2d& uv) {
  const int u = static_cast<int>(std::lround(uv.x())), v = static_cast<int>(std::lround(uv.y()));
  return f.seg[static_cast<std::size_t>(v) * f.width + u];
}

Eigen::Vector2d project(const Frame& f, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p_C = f.X_WC.inverse() * p_W;
  return {f.K(0, 0) * p_C.x() / p_C.z() + f.K(0, 2), f.K(1, 1) * p_C.y() / p_C.z() + f.K(1, 2)};
}

}  // namespace

TEST(Render, DepthOfPlaneAtKnownDistance) {
  World w = empty_world();
  w.objects.push_back(plane({0, 0, 10.0}, {0, 0, 0}, 20.0, SegClass::kSeabed));
  Renderer r(w, {down_camera()}, exact_options());
  for (double z : {0.7, 2.5, 7.25}) {
    const Frame f = r.render(body_at({0, 0, 10.0 - z}), "down");
    ASSERT_EQ(f.depth.size(), 96u * 72u);
    // Plane perpendicular to the optical axis: every pixel has depth z. 1 mm tolerance
    // (float32 interpolation of z is ~1e-6 relative).
    for (float d : f.depth) ASSERT_NEAR(d, z, 1e-3);
    for (auto s : f.seg) ASSERT_EQ(s, 1);
  }
  // Looking up where no geometry is: water pixels report +inf and segmentation 0.
  CameraModel up = down_camera();
  up.name = "up";
  up.X_BC.linear() = rotation_from_rpy(0, M_PI / 2, 0) * R_camera_body_to_optical();
  Renderer r2(w, {up}, exact_options());
  const Frame f = r2.render(body_at({30.0, 0, 12.0}), "up");  // beyond the plane edge
  for (std::size_t i = 0; i < f.depth.size(); ++i) {
    ASSERT_TRUE(std::isinf(f.depth[i]));
    ASSERT_EQ(f.seg[i], 0);
  }
}

TEST(Render, PointLandsOnPixelPredictedByK) {
  // Off-centre principal point and fx != fy check the pixel convention (OpenCV: centre of the
  // top-left pixel is (0, 0)). A small square parallel to the image plane projects to a
  // square whose centroid is the projection of its centre; the centroid of its pixels is
  // within 0.5 px (rasterisation of a ~16 px square).
  World w = empty_world();
  const Eigen::Vector3d target_W(6.0, 0.8, -0.5);  // 6 m ahead, right and up of the axis
  w.objects.push_back(plane(target_W, {0, M_PI / 2, 0}, 0.25, SegClass::kOther));
  Renderer r(w, {front_camera(160, 120, 380.0, 372.0, 83.3, 57.6)}, exact_options());
  const Frame f = r.render(Pose::Identity(), "front");
  int n = 0;
  const Eigen::Vector2d centroid = test::seg_centroid(f, 4, &n);
  ASSERT_GT(n, 100);
  const Eigen::Vector2d uv = project(f, target_W);
  EXPECT_NEAR(centroid.x(), uv.x(), 0.5);
  EXPECT_NEAR(centroid.y(), uv.y(), 0.5);
  // Expected from K by hand: u = fx y/x + cx with body/optical axes (x fwd -> z_C).
  EXPECT_NEAR(uv.x(), 380.0 * 0.8 / 6.0 + 83.3, 1e-9);
  EXPECT_NEAR(uv.y(), 372.0 * -0.5 / 6.0 + 57.6, 1e-9);
}

TEST(Render, DistortedPointMatchesOpenCvProjection) {
  World w = empty_world();
  const Eigen::Vector3d target_W(5.0, 1.6, 1.1);
  w.objects.push_back(plane(target_W, {0, M_PI / 2, 0}, 0.2, SegClass::kOther));
  CameraModel c = front_camera(160, 120, 120.0, 120.0, 79.5, 59.5);
  c.distortion << -0.2, 0.05, 0.001, -0.001, 0.0;
  Renderer r(w, {c}, exact_options());
  const Frame f = r.render(Pose::Identity(), "front");
  int n = 0;
  const Eigen::Vector2d centroid = test::seg_centroid(f, 4, &n);
  ASSERT_GT(n, 4);
  const Eigen::Vector3d p_C = f.X_WC.inverse() * target_W;
  std::vector<cv::Point3d> obj{{p_C.x(), p_C.y(), p_C.z()}};
  std::vector<cv::Point2d> img;
  cv::Mat K = (cv::Mat_<double>(3, 3) << c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  cv::Mat D = (cv::Mat_<double>(1, 5) << -0.2, 0.05, 0.001, -0.001, 0.0);
  cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, img);
  // Small square (~5 px): the distortion is locally affine, 0.5 px holds.
  EXPECT_NEAR(centroid.x(), img[0].x, 0.5);
  EXPECT_NEAR(centroid.y(), img[0].y, 0.5);
  // Depth stays metres along the optical axis through the distortion remap.
  const auto i = static_cast<std::size_t>(std::lround(centroid.y())) * f.width + std::lround(centroid.x());
  EXPECT_NEAR(f.depth[i], p_C.z(), 1e-3);
}

TEST(Render, UniformPatchFollowsAttenuationPlusBackscatter) {
  // I_c = J_c exp(-beta_c z) + B_inf_c(d_cam) (1 - exp(-beta_c z)), with J_c = albedo_c E0
  // exp(-K_d,c d_patch) for a patch facing a vertical sun. Values kept in 0.25 .. 0.75 so
  // 8-bit quantisation (0.5/255) is < 0.8 %; half-float intermediates add < 0.1 %: 2 % holds.
  World w = empty_world();
  const double d_patch = 6.0;
  const Eigen::Vector3d albedo(0.8, 0.35, 0.3);
  w.objects.push_back(plane({0, 0, d_patch}, {0, 0, 0}, 30.0, SegClass::kSeabed, albedo));
  w.sun.surface_irradiance = {3.0, 3.0, 3.0};
  WaterModel water;
  water.name = "test";
  water.beta_D = water.beta_B = water.K_d = {0.3, 0.12, 0.06};
  water.B_inf = {0.2, 0.25, 0.3};
  water.veiling_light_gradient = 0.0;
  w.water = water;
  Renderer r(w, {down_camera()}, exact_options());
  for (double z : {1.0, 2.0, 3.5, 5.0}) {
    const double d_cam = d_patch - z;
    const Frame f = r.render(body_at({0, 0, d_cam}), "down");
    const Eigen::Vector3d I = mean_rgb(f, 48, 36, 2);
    const Eigen::Vector3d B = water.veiling_light_at(d_cam, w.sun.surface_irradiance);
    for (int c = 0; c < 3; ++c) {
      const double J = albedo[c] * 3.0 * std::exp(-water.K_d[c] * d_patch);
      const double t = std::exp(-water.beta_D[c] * z);
      const double expected = J * t + B[c] * (1.0 - t);
      EXPECT_NEAR(I[c], expected, 0.02 * expected) << "z " << z << " channel " << c;
    }
  }
}

TEST(Render, JerlovIIAttenuatesRedMoreThanBlueAtFiveMetres) {
  World w = empty_world();
  w.objects.push_back(plane({0, 0, 3.0}, {0, 0, 0}, 30.0, SegClass::kSeabed, {0.6, 0.6, 0.6}));
  w.sun.surface_irradiance = {1.5, 1.5, 1.5};
  w.water = jerlov_preset("II");
  RenderOptions o = exact_options();
  Renderer r(w, {down_camera()}, o);
  const Eigen::Vector3d near = mean_rgb(r.render(body_at({0, 0, 2.5}), "down"), 48, 36, 2);
  const Eigen::Vector3d far = mean_rgb(r.render(body_at({0, 0, -2.0}), "down"), 48, 36, 2);
  // With the full preset (backscatter included) the patch turns blue with range.
  EXPECT_LT(far[0] / far[2], 0.8 * near[0] / near[2]);
  // Direct signal only (B_inf = 0): the ratio far/near is exp(-beta 4.5) per channel.
  WaterModel no_veil = w.water;
  no_veil.B_inf.setZero();
  r.set_water(no_veil);
  const Eigen::Vector3d n2 = mean_rgb(r.render(body_at({0, 0, 2.5}), "down"), 48, 36, 2);
  const Eigen::Vector3d f2 = mean_rgb(r.render(body_at({0, 0, -2.0}), "down"), 48, 36, 2);
  const double tr_red = f2[0] / n2[0], tr_blue = f2[2] / n2[2];
  EXPECT_LT(tr_red, tr_blue);
  // 3 %: quantisation of the dimmer far red value (~0.16) is 1.2 %, of the near one < 0.5 %.
  EXPECT_NEAR(tr_red, std::exp(-0.223 * 4.5), 0.03 * std::exp(-0.223 * 4.5));
  EXPECT_NEAR(tr_blue, std::exp(-0.062 * 4.5), 0.03 * std::exp(-0.062 * 4.5));
}

TEST(Render, SegmentationIdsMatchGeometry) {
  World w = empty_world();
  w.seabed.enabled = true;
  w.seabed.depth_m = 10.0;
  w.seabed.size_m = {40, 40};
  w.seabed.resolution_m = 2.0;
  w.seabed.far_extent_m = 0.0;
  Pipeline p;
  p.name = "p";
  p.radius_m = 0.25;
  p.points_W = {{-10, 0, 9.8}, {10, 0, 9.8}};
  p.centerline_W = bent_centerline(p.points_W, 1.0);
  p.arc_length_m.assign(p.centerline_W.size(), 0.0);
  w.pipelines.push_back(p);
  Rock rock;
  rock.p_W = {3.0, 1.6, 9.85};
  rock.radii_m = {0.35, 0.35, 0.3};
  w.rocks.push_back(rock);
  Object box;
  box.name = "box";
  box.shape = "box";
  box.size_m = {0.5, 0.5, 0.5};
  box.X_WO = pose_from_xyz_rpy({3.0, -1.6, 9.75}, {0, 0, 0});
  box.seg_class = SegClass::kOther;
  w.objects.push_back(box);
  CameraModel down = down_camera(160, 120, 90.0);
  CameraModel front = front_camera(80, 60, 60, 60, 39.5, 29.5);
  front.X_BC.linear() = rotation_from_rpy(0, 0.2, 0) * R_camera_body_to_optical();  // tilted up 11.5 deg
  Renderer r(w, {down, front}, exact_options());
  const Frame f = r.render(body_at({3.0, 0.0, 7.0}), "down");
  EXPECT_EQ(seg_at(f, project(f, {3.0, 0.0, 9.55})), 2);  // pipe top
  EXPECT_EQ(seg_at(f, project(f, {2.0, 0.0, 9.55})), 2);
  EXPECT_EQ(seg_at(f, project(f, {3.0, 1.6, 9.6})), 3);   // rock top
  EXPECT_EQ(seg_at(f, project(f, {3.0, -1.6, 9.5})), 4);  // box top
  EXPECT_EQ(seg_at(f, project(f, {4.5, 0.9, 10.0})), 1);  // sand
  EXPECT_EQ(seg_at(f, project(f, {1.5, -0.8, 10.0})), 1);
  const Frame g = r.render(body_at({3.0, 0.0, 7.0}), "front");
  for (int u = 0; u < g.width; ++u) EXPECT_EQ(g.seg[u], 0) << u;  // top row: open water
  EXPECT_EQ(g.seg[(g.height - 1) * g.width + g.width / 2], 1);    // bottom row: seabed ahead
}

TEST(Render, AsyncReadbackReturnsFramesInOrderAndMatchesSync) {
  World w = empty_world();
  w.objects.push_back(plane({0, 0, 10.0}, {0, 0, 0}, 20.0, SegClass::kSeabed));
  RenderOptions o = exact_options();
  o.readback_slots = 2;
  Renderer r(w, {down_camera()}, o);
  const Frame sync = r.render(body_at({0, 0, 8.0}), "down", 0.5);
  for (int i = 0; i < 3; ++i) r.submit(body_at({0, 0, 8.0 - i}), "down", 1.0 + i);
  for (int i = 0; i < 3; ++i) {
    auto f = r.collect();
    ASSERT_TRUE(f.has_value());
    EXPECT_DOUBLE_EQ(f->stamp_s, 1.0 + i);
    EXPECT_NEAR(f->depth[0 + 36 * 96 + 48], 2.0 + i, 1e-3);
    if (i == 0) {
      EXPECT_EQ(f->rgb, sync.rgb);
    }
  }
  EXPECT_FALSE(r.collect().has_value());
}

// Frames handed back (recycle()) lend their buffers to later ones: the same pixels as fresh
// buffers, also when a frame's buffers are larger or smaller than the next camera's, and the
// memory is reused (the buffer a frame returned is the one the next fills).
TEST(Render, RecycledBuffersFillLaterFramesExactly) {
  World w = empty_world();
  w.objects.push_back(plane({0, 0, 10.0}, {0, 0, 0}, 20.0, SegClass::kSeabed));
  w.objects.push_back(plane({0.5, 0, 9.0}, {0, 0, 0}, 0.6, SegClass::kRock));
  CameraModel big = down_camera();
  big.name = "big";
  big.width *= 2;
  big.height *= 2;
  big.fx *= 2;
  big.fy *= 2;
  big.cx = big.width / 2.0;
  big.cy = big.height / 2.0;
  const std::vector<CameraModel> cams = {down_camera(), big};
  Renderer fresh(w, cams, exact_options());
  Renderer reused(w, cams, exact_options());
  const char* order[] = {"down", "down", "big", "down", "big", "big"};
  const std::uint8_t* handed_back = nullptr;
  for (int i = 0; i < 6; ++i) {
    const Pose X_WB = body_at({0.1 * i, 0, 8.0 - 0.2 * i});
    const Frame a = fresh.render(X_WB, order[i], 1.0 + i);
    Frame b = reused.render(X_WB, order[i], 1.0 + i);
    ASSERT_EQ(b.rgb.size(), a.rgb.size()) << i;
    ASSERT_EQ(b.seg.size(), a.seg.size()) << i;
    ASSERT_EQ(b.depth.size(), a.depth.size()) << i;
    EXPECT_EQ(b.rgb, a.rgb) << i;
    EXPECT_EQ(b.seg, a.seg) << i;
    EXPECT_EQ(b.depth, a.depth) << i;
    if (i == 1) {
      EXPECT_EQ(b.rgb.data(), handed_back) << "the buffer frame 0 handed back, reused in place";
    }
    handed_back = b.rgb.data();
    reused.recycle(std::move(b));
  }
}

// RenderOptions::gpu_timers: the GPU's time for each pass of the frame last collected, from GL
// timestamps taken inside the call: each finite and >= 0, their sum within the call's wall time;
// all zero when off.
TEST(Render, GpuTimersSplitTheFrameIntoItsPasses) {
  World w = empty_world();
  w.objects.push_back(plane({0, 0, 10.0}, {0, 0, 0}, 20.0, SegClass::kSeabed));
  RenderOptions o = exact_options();
  Renderer r(w, {down_camera()}, o);
  r.render(body_at({0, 0, 8.0}), "down", 0.5);
  const RenderTimings off = r.last_timings();
  EXPECT_EQ(off.gpu_shadow_ms + off.gpu_scene_ms + off.gpu_snow_ms + off.gpu_inscatter_ms + off.gpu_post_ms +
                off.gpu_readback_ms,
            0.0);
  o.gpu_timers = true;
  r.set_options(o);
  for (int i = 0; i < 3; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    r.render(body_at({0, 0, 8.0 - 0.1 * i}), "down", 1.0 + i);
    const double wall_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    const RenderTimings t = r.last_timings();
    const double parts[6] = {t.gpu_shadow_ms,    t.gpu_scene_ms, t.gpu_snow_ms,
                             t.gpu_inscatter_ms, t.gpu_post_ms,  t.gpu_readback_ms};
    double sum = 0.0;
    for (double p : parts) {
      EXPECT_TRUE(std::isfinite(p));
      EXPECT_GE(p, 0.0);
      sum += p;
    }
    EXPECT_GT(t.gpu_scene_ms + t.gpu_post_ms, 0.0);  // a frame was drawn
    EXPECT_LE(sum, wall_ms) << "timestamps taken inside render()";
  }
}

TEST(RenderErrors, CausesAreNamed) {
  World w = empty_world();
  EXPECT_THROW(
      {
        try {
          RenderOptions o = exact_options();
          o.egl.device_index = 99;
          Renderer r(w, {down_camera()}, o);
        } catch (const EglError& e) {
          EXPECT_NE(std::string(e.what()).find("99"), std::string::npos) << e.what();
          throw;
        }
      },
      EglError);
  CameraModel bad = down_camera();
  bad.fx = 0.0;
  EXPECT_THROW(Renderer(w, {bad}, exact_options()), ConfigError);
  Object o;
  o.name = "ghost";
  o.mesh_file = "/nonexistent/ghost.fbx";
  w.objects.push_back(o);
  try {
    Renderer r(w, {down_camera()}, exact_options());
    ADD_FAILURE() << "no error";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/ghost.fbx"), std::string::npos) << e.what();
  }
  w.objects.clear();
  Renderer r(w, {down_camera()}, exact_options());
  EXPECT_THROW(r.render(Pose::Identity(), "rear"), std::invalid_argument);
}

TEST(Readback, SplitRgbaMatchesTheByteLoop) {
  // Four pixels per step as words, then the tail: every length from 0 to 13 and a VGA frame + 3.
  std::uint32_t state = 12345u;
  for (std::size_t px : {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 640 * 480 + 3}) {
    std::vector<std::uint8_t> rgba(4 * px), rgb(3 * px, 0), alpha(px, 0);
    for (auto& b : rgba) b = static_cast<std::uint8_t>((state = state * 1664525u + 1013904223u) >> 24);
    unav::renderer::detail::split_rgba(rgba.data(), px, rgb.data(), alpha.data());
    for (std::size_t i = 0; i < px; ++i) {
      ASSERT_EQ(rgb[3 * i], rgba[4 * i]) << px << " " << i;
      ASSERT_EQ(rgb[3 * i + 1], rgba[4 * i + 1]) << px << " " << i;
      ASSERT_EQ(rgb[3 * i + 2], rgba[4 * i + 2]) << px << " " << i;
      ASSERT_EQ(alpha[i], rgba[4 * i + 3]) << px << " " << i;
    }
  }
}
