// Lamp shadows (shadow maps with PCF) on surfaces and in the lamp in-scattering (llvmpipe).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;

namespace {

// The exact optics of the image tests with the lamps, shadows and in-scattering chosen.
RenderOptions exact(bool lamps, bool shadows, int scatter_samples) {
  RenderOptions o = unav::renderer::test::exact_options();
  o.lamps = lamps;
  o.shadows = shadows;
  o.lamp_scatter_samples = scatter_samples;
  return o;
}

// Floor 4 m below the vehicle, a lamp 1.5 m to starboard pointing down, and a 0.4 m tile 2 m
// under the lamp: its shadow is a 0.8 m square on the floor centred under the lamp. The
// down-looking camera at the body origin sees the floor there (and the tile elsewhere).
World scene(bool floor, bool tile, double tile_size = 0.4, double tile_depth = 8.0) {
  World w;
  w.name = "shadows";
  w.file = "<test world>";
  w.seabed.enabled = false;
  if (floor) w.objects.push_back(unav::renderer::test::floor_object(10.0, 30.0));
  if (tile)
    w.objects.push_back(unav::renderer::test::shape_object("tile", "box", {tile_size, tile_size, 0.05},
                                                           {0.0, 1.5, tile_depth}, SegClass::kOther));
  Lamp l;
  l.name = "lamp";
  l.X_BL = pose_from_xyz_rpy({0.0, 1.5, 0.0}, {0.0, -M_PI / 2, 0.0});  // beam axis (x) down
  l.cone_half_angle_rad = 0.6;
  l.intensity = {6.0, 6.0, 6.0};
  w.lamps.push_back(l);
  return w;
}

CameraModel down_camera() {
  CameraModel c = CameraModel::from_hfov("down", 160, 160, 100.0 * M_PI / 180.0);
  c.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  return c;
}

const Pose kBody = pose_from_xyz_rpy({0.0, 0.0, 6.0}, {0.0, 0.0, 0.0});

// Green level (0..255) at the pixel where world point p_W is imaged.
int green_at(const Frame& f, const Eigen::Vector3d& p_W) {
  const Eigen::Vector3d p = f.X_WC.inverse() * p_W;
  const int u = static_cast<int>(std::lround(f.K(0, 0) * p.x() / p.z() + f.K(0, 2)));
  const int v = static_cast<int>(std::lround(f.K(1, 1) * p.y() / p.z() + f.K(1, 2)));
  return f.rgb[3 * (static_cast<std::size_t>(v) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(u)) + 1];
}

}  // namespace

TEST(Shadows, ShadowedPatchReceivesOnlyTheAmbientLight) {
  // In-scattering off (0 samples): the floor under the tile gets exactly what it gets with the
  // lamps off (the sun's light, itself shadowed by the tile: ambient only), within one level; a floor point in the beam
  // but outside the shadow gets the full lamp light (the same as without shadows).
  const World w = scene(true, true);
  Renderer with(w, {down_camera()}, exact(true, true, 0));
  Renderer without(w, {down_camera()}, exact(true, false, 0));
  Renderer dark(w, {down_camera()}, exact(false, true, 0));  // the sun's shadow as in `with`
  const Frame a = with.render(kBody, "down"), c = without.render(kBody, "down"), b = dark.render(kBody, "down");
  const Eigen::Vector3d shadowed(0.0, 1.5, 10.0), lit(1.2, 1.5, 10.0);
  std::printf("floor under the tile: %d (lamps off %d, no shadows %d); lit floor: %d (no shadows %d, lamps off %d)\n",
              green_at(a, shadowed), green_at(b, shadowed), green_at(c, shadowed), green_at(a, lit), green_at(c, lit),
              green_at(b, lit));
  EXPECT_NEAR(green_at(a, shadowed), green_at(b, shadowed), 1);
  EXPECT_GT(green_at(c, shadowed), green_at(b, shadowed) + 20);  // the lamp does light it without the tile's shadow
  EXPECT_NEAR(green_at(a, lit), green_at(c, lit), 1);
  EXPECT_GT(green_at(a, lit), green_at(b, lit) + 20);
}

TEST(Shadows, LampShaftsAreCutByObjectsAndNothingElseChanges) {
  // Seen from the side in turbid water (Jerlov 5C): a bright lamp (300, so the in-scattered light
  // is well above 8-bit rounding) 3 m ahead of a forward camera shines
  // down; a 1.6 m tile 1 m under it covers its whole cone (radius tan 0.6 = 0.68 m there). With
  // shadows, the water under the tile scatters no lamp light: pixels looking past the tile into
  // that water get darker, none gets brighter (beyond rounding), and the surfaces are unchanged.
  // With no occluder the images with and without shadows are identical.
  auto side_scene = [](bool tile) {
    World w = scene(false, tile, 1.6, 7.0);
    w.water = jerlov_preset("5C");
    w.lamps[0].X_BL = pose_from_xyz_rpy({3.0, 0.0, 0.0}, {0.0, -M_PI / 2, 0.0});
    w.lamps[0].intensity = {300.0, 300.0, 300.0};
    if (tile) w.objects[0].X_WO = pose_from_xyz_rpy({3.0, 0.0, 7.0}, {0.0, 0.0, 0.0});
    return w;
  };
  CameraModel fwd = CameraModel::from_hfov("fwd", 160, 120, 90.0 * M_PI / 180.0);
  fwd.X_BC.linear() = R_camera_body_to_optical();
  const World w = side_scene(true);
  const Frame with = Renderer(w, {fwd}, exact(true, true, 16)).render(kBody, "fwd");
  const Frame without = Renderer(w, {fwd}, exact(true, false, 16)).render(kBody, "fwd");
  int darker = 0, brighter = 0, worst = 0;
  for (std::size_t i = 1; i < with.rgb.size(); i += 3) {
    const int d = static_cast<int>(without.rgb[i]) - static_cast<int>(with.rgb[i]);
    darker += d >= 3 ? 1 : 0;
    brighter += d < -1 ? 1 : 0;
    worst = std::max(worst, d);
  }
  std::printf("shaft under the tile: %d pixels darker by >= 3 levels (most %d), %d brighter\n", darker, worst,
              brighter);
  EXPECT_GT(darker, 100);
  EXPECT_EQ(brighter, 0);
  const World open = side_scene(false);
  EXPECT_EQ(Renderer(open, {fwd}, exact(true, true, 16)).render(kBody, "fwd").rgb,
            Renderer(open, {fwd}, exact(true, false, 16)).render(kBody, "fwd").rgb);
}

TEST(Shadows, SunShadowLeavesTheAmbientShareOnly) {
  // Water with no attenuation or backscatter, the sun straight down (E0 = 1, ambient share
  // 0.35): a floor patch facing up receives E0 (0.35 + 0.65) in the open and E0 0.35 under a
  // tile. Camera straight above, the two points symmetric about it (same range): the ratio
  // of their levels is 0.35 (8-bit rounding of ~128: +-0.01). Lamps off.
  World w = scene(true, true);
  w.lamps.clear();
  w.water.beta_D.setZero();
  w.water.beta_B.setZero();
  w.water.K_d.setZero();
  w.water.B_inf.setZero();
  w.water.b_scatter.setZero();
  w.sun.direction_W = {0.0, 0.0, 1.0};
  w.sun.ambient_fraction = 0.35;
  Renderer r(w, {down_camera()}, exact(false, true, 0));
  const Frame f = r.render(kBody, "down");
  const int shadowed = green_at(f, {0.0, 1.5, 10.0}), lit = green_at(f, {0.0, -1.5, 10.0});
  std::printf("sun: floor under the tile %d, in the open %d: ratio %.3f (ambient share 0.35)\n", shadowed, lit,
              static_cast<double>(shadowed) / lit);
  EXPECT_NEAR(static_cast<double>(shadowed) / lit, 0.35, 0.01);
  // Without shadows both get the full light.
  Renderer r0(w, {down_camera()}, exact(false, false, 0));
  const Frame f0 = r0.render(kBody, "down");
  EXPECT_NEAR(green_at(f0, {0.0, 1.5, 10.0}), lit, 1);
}

TEST(Shadows, LargeFloorDoesNotShadowItself) {
  // A 30 m floor of two triangles, nothing above it, seen at a slant out to its far edge: the sun's
  // map holds the floor itself (clipped to the map's 24 m), and every floor pixel must compare as
  // lit, so the image equals the one without shadows (8-bit rounding: <= 1 level). Before the
  // receiver's depth bias along the sunlight, acne streaks 8-12 m away darkened 789 values, by up
  // to 99 levels (the sun's direct share).
  World w = unav::renderer::test::empty_world();  // the sun straight down, no lamps
  w.objects.push_back(unav::renderer::test::floor_object(3.0, 30.0));
  w.objects[0].X_WO.translation().x() = 14.0;  // from 1 m behind the camera to 29 m ahead
  CameraModel cam = unav::renderer::test::forward_camera(160, 120, 90.0);
  cam.exposure = 1.5;
  const Pose X_WB = pose_from_xyz_rpy({0.0, 0.0, 1.0}, {0.0, -0.35, 0.0});  // pitched down 20 deg
  Renderer r(w, {cam}, exact(false, true, 0)), r0(w, {cam}, exact(false, false, 0));
  const Frame a = r.render(X_WB, "cam"), b = r0.render(X_WB, "cam");
  std::size_t floor_px = 0, off = 0;
  int worst = 0;
  for (std::size_t i = 0; i < a.seg.size(); ++i) {
    if (a.seg[i] == 0) continue;
    ++floor_px;
    for (int ch = 0; ch < 3; ++ch) {
      const int d = std::abs(static_cast<int>(a.rgb[3 * i + ch]) - static_cast<int>(b.rgb[3 * i + ch]));
      worst = std::max(worst, d);
      off += d > 1;
    }
  }
  std::printf("large floor: %zu floor pixels, %zu values off by more than 1 level, worst %d\n", floor_px, off, worst);
  EXPECT_GT(floor_px, 10000u);
  EXPECT_EQ(off, 0u);
}

namespace {
// The renderer refuses options `o` with a ConfigError naming `key`; `what` describes the value.
void expect_rejected(const RenderOptions& o, const std::string& key, const std::string& what) {
  try {
    Renderer r(scene(true, true), {down_camera()}, o);
    ADD_FAILURE() << key << " " << what << " accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << e.what();
  }
}
}  // namespace

TEST(Shadows, ShadowMapSizeIsValidated) {
  RenderOptions o = exact(true, true, 0);
  o.shadow_map_size = 0;
  expect_rejected(o, "shadow_map_size", "0");
  for (double bias : {-1.0, std::nan("")}) {
    o = exact(true, true, 0);
    o.shadow_bias = bias;
    expect_rejected(o, "shadow_bias", std::to_string(bias));
  }
  for (int samples : {-1, 257}) {  // the in-scatter march: a compile-time count
    o = exact(true, true, 0);
    o.lamp_scatter_samples = samples;
    expect_rejected(o, "lamp_scatter_samples", std::to_string(samples));
  }
}

namespace {
// Green levels of a flat untextured floor filling the view, 2 m under the camera.
std::vector<double> floor_levels(double floor_depth, const char* water, bool caustics, double stamp, double exposure) {
  World w;
  w.name = "caustics";
  w.file = "<test world>";
  w.seabed.enabled = false;
  w.water = jerlov_preset(water);
  w.water.B_inf.setZero();  // the direct signal only
  w.sun.direction_W = {0.0, 0.0, 1.0};
  w.objects.push_back(unav::renderer::test::floor_object(floor_depth, 40.0));
  RenderOptions o = exact(false, false, 0);
  o.caustics = caustics;
  CameraModel cam = down_camera();
  cam.exposure = exposure;
  Renderer r(w, {cam}, o);
  const Frame fr = r.render(pose_from_xyz_rpy({0.0, 0.0, floor_depth - 2.0}, {0.0, 0.0, 0.0}), "down", stamp);
  std::vector<double> g;
  for (std::size_t i = 1; i < fr.rgb.size(); i += 3) g.push_back(fr.rgb[i]);
  return g;
}

// Relative modulation of the caustics: RMS of (with - without) over the mean without.
double modulation(double floor_depth, const char* water, double exposure, double* mean_ratio) {
  const auto on = floor_levels(floor_depth, water, true, 0.0, exposure);
  const auto off = floor_levels(floor_depth, water, false, 0.0, exposure);
  double d2 = 0.0, m_on = 0.0, m_off = 0.0;
  for (std::size_t i = 0; i < on.size(); ++i) {
    d2 += (on[i] - off[i]) * (on[i] - off[i]);
    m_on += on[i];
    m_off += off[i];
  }
  if (mean_ratio) *mean_ratio = m_on / m_off;
  return std::sqrt(d2 / static_cast<double>(on.size())) / (m_off / static_cast<double>(on.size()));
}
}  // namespace

TEST(Caustics, FadeWithDepthAndTurbidityKeepTheMeanAndMove) {
  // The same flat, untextured floor 2 m under the camera; modulation = RMS(with - without
  // caustics) / mean. Clear water (Jerlov I) at 3 m: strong; at 15 m weak (A falls as
  // exp(-d (2 K_d + 1/15)): 0.64 -> 0.11 of the strength); coastal 9C at 3 m (2 K_d = 1.55 / m):
  // nearly none (exposure raised so the floor sits mid-scale there too). Caustics redistribute
  // light: the mean changes by < 3 %. And they move: two stamps 1 s apart differ.
  double ratio = 0.0;
  const double shallow = modulation(3.0, "I", 1.0, &ratio);
  const double deep = modulation(15.0, "I", 1.6, nullptr);
  const double turbid = modulation(3.0, "9C", 8.0, nullptr);
  std::printf("caustic modulation: clear 3 m %.3f, clear 15 m %.3f, 9C 3 m %.3f; mean with/without %.4f\n", shallow,
              deep, turbid, ratio);
  EXPECT_GT(shallow, 0.08);
  EXPECT_LT(deep, shallow / 3.0);
  EXPECT_LT(turbid, shallow / 5.0);
  EXPECT_NEAR(ratio, 1.0, 0.03);
  EXPECT_NE(floor_levels(3.0, "I", true, 1.0, 1.0), floor_levels(3.0, "I", true, 0.0, 1.0));
}

TEST(Determinism, SamePoseStampAndSeedGiveIdenticalImagesWhateverCameBefore) {
  // Every effect on (noise, snow, caustics, lamp and sun shadows; the sun's map is cached
  // between frames): a frame rendered again after others, and by a fresh renderer, is
  // byte-identical.
  World w = scene(true, true);
  w.sun.direction_W = Eigen::Vector3d(-0.9, 0.5, 1.0).normalized();
  RenderOptions o;  // defaults: all effects
  o.texture_size = 64;
  const Pose P = pose_from_xyz_rpy({0.3, 0.2, 6.0}, {0.0, 0.0, 0.4});
  Renderer r(w, {down_camera()}, o);
  r.set_next_sequence(7);
  const Frame a = r.render(P, "down", 2.5);
  for (int i = 0; i < 3; ++i) r.render(pose_from_xyz_rpy({3.0 * i, -2.0, 5.0}, {0.0, 0.0, 0.0}), "down", 9.0 + i);
  r.set_next_sequence(7);
  const Frame b = r.render(P, "down", 2.5);
  Renderer fresh(w, {down_camera()}, o);
  fresh.set_next_sequence(7);
  const Frame c = fresh.render(P, "down", 2.5);
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.rgb, c.rgb);
  EXPECT_EQ(a.depth, c.depth);
}

namespace {

// Cameras and poses of the culling tests in the pipe world: a front (200x150, 80 deg) and a down
// (160x120, 90 deg) camera; over the pipe along it, low with the boulder ahead, at the skid and
// the pipe.
std::vector<CameraModel> front_and_down() {
  CameraModel front = CameraModel::from_hfov("front", 200, 150, 80.0 * M_PI / 180.0);
  front.X_BC.linear() = R_camera_body_to_optical();
  CameraModel down = CameraModel::from_hfov("down", 160, 120, 90.0 * M_PI / 180.0);
  down.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  return {front, down};
}
// How many rgb values of two same-size frames differ, and by how much at most (printed).
std::pair<std::size_t, int> rgb_difference(const Frame& a, const Frame& b, const char* cam) {
  int worst = 0;
  std::size_t off = 0;
  for (std::size_t i = 0; i < a.rgb.size(); ++i) {
    const int d = std::abs(static_cast<int>(a.rgb[i]) - static_cast<int>(b.rgb[i]));
    worst = std::max(worst, d);
    off += d > 0;
  }
  std::printf("%s: %zu of %zu values differ, by <= %d\n", cam, off, a.rgb.size(), worst);
  return {off, worst};
}
const Pose kOverPipe = pose_from_xyz_rpy({3.0, 0.2, 8.0}, {0, 0, 0.1});
const Pose kBoulderAhead = pose_from_xyz_rpy({9.0, 1.2, 9.0}, {0, 0.3, 1.2});
const Pose kSkidAndPipe = pose_from_xyz_rpy({16.0, -1.0, 8.5}, {0, 0.2, -1.6});

}  // namespace

// Shadow receiver culling skips the shadow lookups on terrain chunks that nothing can shadow;
// they would have read "lit", so the image must not change. Pipe world (pipe, rocks, a boulder
// and a skid casting on the seabed), sun and both lamps, front and down cameras, poses close to
// casters and far from them; and the culling must actually skip something there.
TEST(Shadows, ReceiverCullingChangesNoPixel) {
  World base = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  // And a rough seabed (slopes up to ~45 deg: it shadows itself) under a low sun (35 deg).
  World rough = base;
  rough.seabed.relief_amplitude_m = 0.8;
  rough.seabed.relief_wavelength_m = 3.0;
  rough.sun.direction_W = Eigen::Vector3d(std::cos(0.61), 0.0, std::sin(0.61));
  for (const World& world : {base, rough}) {
    RenderOptions o = unav::renderer::test::exact_options();
    o.lamps = true;
    o.materials = true;
    o.caustics = true;
    // Enough depth bias that the shadow maps show no acne on the rough seabed's 45-degree slopes:
    // culling removes acne (a lookup it skips reads "lit"), which is not what this test is about.
    o.shadow_bias = 4.0;
    o.shadow_culling_on_gpu = true;  // the culls under test, on a hardware GPU too
    RenderOptions no_cull = o;
    no_cull.shadow_receiver_culling = false;
    Renderer culled(world, front_and_down(), o);
    Renderer full(world, front_and_down(), no_cull);
    std::size_t skipped = 0, drawn = 0;
    for (const Pose& X_WB : {kOverPipe, kBoulderAhead, kSkidAndPipe,
                             pose_from_xyz_rpy({-4.0, 8.0, 7.0}, {0, 0.1, 2.5})}) {  // the open seabed
      for (const char* cam : {"front", "down"}) {
        const Frame a = culled.render(X_WB, cam, 1.0);
        skipped += culled.last_timings().shadow_lookups_skipped;
        drawn += culled.last_timings().shadow_lookups_drawn;
        const Frame b = full.render(X_WB, cam, 1.0);
        ASSERT_EQ(a.rgb.size(), b.rgb.size());
        const auto [off, worst] = rgb_difference(a, b, cam);
        // A skipped lookup would have returned 1 (lit): identical images (measured: 0 values
        // differ). One level allowed for float rounding across shader variants. With the default
        // bias, culling also removes acne: 26 values off by 1 here, up to 4 levels on the rough
        // seabed (gone with this bias, so acne and not a missed shadow).
        EXPECT_LE(worst, 1) << cam;
        EXPECT_LE(off, a.rgb.size() / 1000) << cam;
        EXPECT_EQ(a.depth, b.depth);
        EXPECT_EQ(a.seg, b.seg);
      }
    }
    std::printf("terrain chunk draws without shadow lookups: %zu of %zu\n", skipped, skipped + drawn);
    if (&world == &base) {
      EXPECT_GT(skipped, drawn / 4);
    }
  }
}

// Shadow caster culling leaves out of the lamps' shadow maps the terrain chunks whose every lamp
// ray sinks faster than the terrain's steepest slope: what they hide from a lamp lies under the
// terrain, and the chunks whose shadow cannot reach the camera's view, so no pixel (surfaces,
// shafts in the water) may change. The pipe world and a rough seabed (slopes ~45 deg: only chunks
// right under a lamp pass the slope test), over the patch and from outside its footprint (where
// the slope test never applies: under the patch's edge is in view there).
TEST(Culling, ShadowCasterCullingChangesNoPixel) {
  World base = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  World rough = base;
  rough.seabed.relief_amplitude_m = 0.8;
  rough.seabed.relief_wavelength_m = 3.0;
  const Pose kOffPatch = pose_from_xyz_rpy({-30.0, -2.0, 9.5}, {0, 0.1, 0.0});
  for (const World* world : {&base, &rough}) {
    RenderOptions o = unav::renderer::test::exact_options();
    o.lamps = true;  // and their in-scattering, with its shadow lookups (shafts)
    o.materials = true;
    o.shadow_culling_on_gpu = true;  // the cull under test, on a hardware GPU too
    RenderOptions all = o;
    all.shadow_caster_culling = false;
    Renderer culled(*world, front_and_down(), o);
    Renderer full(*world, front_and_down(), all);
    std::size_t left_out = 0, drawn = 0;
    for (const Pose& X_WB : {kOverPipe, kBoulderAhead, kSkidAndPipe, kOffPatch}) {
      for (const char* cam : {"front", "down"}) {
        const Frame a = culled.render(X_WB, cam, 1.0);
        const RenderTimings t = culled.last_timings();
        const Frame b = full.render(X_WB, cam, 1.0);
        EXPECT_EQ(full.last_timings().lamp_map_culled, 0u);
        EXPECT_EQ(t.lamp_map_triangles + t.lamp_map_culled, full.last_timings().lamp_map_triangles);
        left_out += t.lamp_map_culled;
        drawn += t.lamp_map_triangles;
        ASSERT_EQ(a.rgb.size(), b.rgb.size());
        const auto [off, worst] = rgb_difference(a, b, cam);
        EXPECT_EQ(worst, 0) << cam;
        EXPECT_EQ(a.depth, b.depth);
        EXPECT_EQ(a.seg, b.seg);
      }
    }
    std::printf("lamp-map triangles: %zu drawn, %zu left out\n", drawn, left_out);
    EXPECT_GT(left_out, world == &base ? drawn / 5 : 0);  // measured: base 42 % of them
  }
}

// The shadow culls run on a software rasterizer, and on a hardware GPU only when asked
// (RenderOptions::shadow_culling_on_gpu): there a frame is CPU-bound and they cost more than they save.
TEST(Culling, ShadowCullsRunOnHardwareGpusOnlyWhenAsked) {
  EXPECT_TRUE(EglContext::is_software_renderer("llvmpipe (LLVM 15.0.6, 256 bits)"));
  EXPECT_TRUE(EglContext::is_software_renderer("softpipe"));
  EXPECT_FALSE(EglContext::is_software_renderer("NVIDIA H100 80GB HBM3/PCIe/SSE2"));
  EXPECT_FALSE(EglContext::is_software_renderer("AMD Radeon RX 7900 XTX (radeonsi, navi31, LLVM 15.0.6)"));
  const World world = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  RenderOptions o = unav::renderer::test::exact_options();
  o.lamps = true;
  Renderer r(world, front_and_down(), o);
  const bool software = r.context().software();
  r.render(kOverPipe, "front", 1.0);
  const RenderTimings by_default = r.last_timings();
  o.shadow_culling_on_gpu = true;
  r.set_options(o);
  r.render(kOverPipe, "front", 1.0);
  const RenderTimings asked = r.last_timings();
  std::printf("%s: lamp-map triangles culled %zu by default, %zu when asked\n", r.context().gl_renderer().c_str(),
              by_default.lamp_map_culled, asked.lamp_map_culled);
  EXPECT_GT(asked.lamp_map_culled, 0u);
  EXPECT_GT(asked.shadow_lookups_skipped, 0u);
  EXPECT_EQ(by_default.lamp_map_culled > 0, software);
  EXPECT_EQ(by_default.shadow_lookups_skipped > 0, software);
}

TEST(Culling, OcclusionCullingChangesNoPixelAndShadesLess) {
  // Back faces of the solids (pipe, rocks, boulder, skid) and the far seabed under the patch are
  // not drawn: the same rgb, depth and segmentation bit for bit, from over the patch and from
  // outside its footprint (where the far seabed under it stays drawn), with fewer fragment shader
  // invocations where the driver counts them.
  const World world = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  RenderOptions o = unav::renderer::test::exact_options();
  o.lamps = true;
  o.materials = true;
  o.profile_passes = true;  // invocation counts
  RenderOptions all = o;
  all.occlusion_culling = false;
  Renderer culled(world, front_and_down(), o);
  Renderer full(world, front_and_down(), all);
  std::size_t inv_culled = 0, inv_full = 0;
  for (const Pose& X_WB : {kOverPipe, kBoulderAhead, kSkidAndPipe,
                           pose_from_xyz_rpy({-30.0, -2.0, 9.5}, {0, 0.1, 0.0})}) {  // off the patch, towards it
    for (const char* cam : {"front", "down"}) {
      const Frame a = culled.render(X_WB, cam, 1.0);
      inv_culled += culled.last_timings().scene_invocations;
      const Frame b = full.render(X_WB, cam, 1.0);
      inv_full += full.last_timings().scene_invocations;
      EXPECT_EQ(a.rgb, b.rgb) << cam;
      // Depth: where a solid's silhouette folds, its back face can lie at the front face's depth
      // to float rounding and won the depth test before (measured: 1 pixel of 8 frames, 1e-5 m).
      std::size_t dz = 0;
      float worst = 0.0f;
      for (std::size_t i = 0; i < a.depth.size(); ++i) {
        if (a.depth[i] == b.depth[i]) continue;
        ++dz;
        worst = std::max(worst, std::abs(a.depth[i] - b.depth[i]) / a.depth[i]);
      }
      EXPECT_LE(dz, 5u) << cam;
      EXPECT_LE(worst, 1e-5f) << cam;  // relative: a few float ulps of the distance
      EXPECT_EQ(a.seg, b.seg) << cam;
    }
  }
  std::printf("fragment shader invocations: %zu culled, %zu all\n", inv_culled, inv_full);
  if (inv_full > 0) {
    EXPECT_LT(inv_culled, inv_full);
  }
}
