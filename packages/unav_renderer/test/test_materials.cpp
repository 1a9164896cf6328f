// Physically based materials (RenderOptions::materials): GGX highlights, bump-mapped relief and
// settled sediment, each against what geometry predicts (llvmpipe).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;
using unav::renderer::test::exact_options;

namespace {

RenderOptions with_materials(bool lamps) {
  RenderOptions o = exact_options();
  o.materials = true;
  o.lamps = lamps;
  o.shadows = false;
  o.lamp_scatter_samples = 0;
  return o;
}

CameraModel down_camera(int size = 160) {
  CameraModel c = CameraModel::from_hfov("down", size, size, 100.0 * M_PI / 180.0);
  c.X_BC.linear() = rotation_from_rpy(0, -M_PI / 2, 0) * R_camera_body_to_optical();
  return c;
}

// Clear water (Jerlov I), a lamp 1.5 m to starboard of the camera pointing down with a wide beam
// (83 deg half angle) of the given intensity; a floor at 10 m of the given material. No sunlight:
// the lamp is the only light.
World lamp_over_floor(const Material& m, double intensity, const Eigen::Vector3d& lamp_B = {0.0, 1.5, 0.0}) {
  World w = unav::renderer::test::empty_world();
  w.water = jerlov_preset("I");
  w.sun.surface_irradiance = {0.0, 0.0, 0.0};
  Object floor = unav::renderer::test::floor_object(10.0, 30.0);
  floor.seg_class = SegClass::kOther;
  floor.material = m;
  w.objects.push_back(floor);
  Lamp l;
  l.name = "lamp";
  l.X_BL = pose_from_xyz_rpy(lamp_B, {0.0, -M_PI / 2, 0.0});
  l.cone_half_angle_rad = 1.45;
  l.intensity = {intensity, intensity, intensity};
  w.lamps.push_back(l);
  return w;
}

const Pose kBody = pose_from_xyz_rpy({0.0, 0.0, 6.0}, {0.0, 0.0, 0.0});

int green(const Frame& f, int u, int v) {
  return f.rgb[3 * (static_cast<std::size_t>(v) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(u)) + 1];
}

}  // namespace

TEST(Materials, MetalHighlightLiesWhereTheLampIsMirroredByTheFloor) {
  // A smooth metal floor (roughness 0.15): its highlight is the lamp's mirror image, where the
  // line from the camera to the lamp mirrored below the floor (z = 14 m) crosses it: (0, 0.75, 10),
  // i.e. on the image's centre column, 0.75 / 4 x fx right of the centre. A rougher metal spreads
  // the same light: a lower, wider peak. The lamp is dim (0.06) so that the sharp peak (~460 x a
  // Lambertian floor's radiance) stays below white.
  Material metal{"none", {0.9, 0.9, 0.9}, 1.0};
  metal.metallic = 1.0;
  metal.roughness = 0.15;
  const CameraModel cam = down_camera();
  const Frame f = Renderer(lamp_over_floor(metal, 0.06), {cam}, with_materials(true)).render(kBody, "down");
  int best = -1, bu = 0, bv = 0;
  for (int v = 0; v < f.height; ++v)
    for (int u = 0; u < f.width; ++u)
      if (green(f, u, v) > best) best = green(f, u, v), bu = u, bv = v;
  // Predicted pixel of the mirror point (the camera's optical frame: x = body y (starboard) for a
  // down camera whose image x points to starboard).
  const Eigen::Vector3d p = f.X_WC.inverse() * Eigen::Vector3d(0.0, 0.75, 10.0);
  const double pu = f.K(0, 0) * p.x() / p.z() + f.K(0, 2), pv = f.K(1, 1) * p.y() / p.z() + f.K(1, 2);
  metal.roughness = 0.5;
  const Frame rough = Renderer(lamp_over_floor(metal, 0.06), {cam}, with_materials(true)).render(kBody, "down");
  int rough_best = 0;
  for (std::size_t i = 1; i < rough.rgb.size(); i += 3) rough_best = std::max(rough_best, int{rough.rgb[i]});
  std::printf("highlight at (%d, %d), level %d; mirror point predicted at (%.1f, %.1f); roughness 0.5 peak %d\n", bu,
              bv, best, pu, pv, rough_best);
  // 1.5 px: the lobe (alpha 0.0225) is sharp, the 1/d^2 and beam falloff shift its maximum by
  // less than a pixel at this geometry (1 px = 6 cm on the floor), plus rounding to the pixel.
  EXPECT_NEAR(bu, pu, 1.5);
  EXPECT_NEAR(bv, pv, 1.5);
  EXPECT_GT(best, 100);
  EXPECT_LT(best, 255);
  EXPECT_LT(rough_best, best - 20);
  // Without materials the same floor is Lambertian: no peak away from the lamp's own footprint.
  const Frame flat = Renderer(lamp_over_floor(metal, 0.06), {cam},
                              [] {
                                RenderOptions o = with_materials(true);
                                o.materials = false;
                                return o;
                              }())
                         .render(kBody, "down");
  EXPECT_LT(green(flat, bu, bv), best - 20);
}

TEST(Materials, SetOptionsSwitchesThemAtRunTime) {
  // Renderer::set_options(materials = false) draws what a Renderer made without materials draws,
  // bit for bit, and switching them back on restores the first image (the features are chosen
  // per frame, not when the scene is uploaded).
  Material metal{"sand", {0.9, 0.9, 0.9}, 1.0};
  metal.metallic = 1.0;
  metal.roughness = 0.3;
  const CameraModel cam = down_camera();
  RenderOptions on = with_materials(true), off = on;
  off.materials = false;
  Renderer r(lamp_over_floor(metal, 0.06), {cam}, on);
  const Frame a = r.render(kBody, "down");
  r.set_options(off);
  const Frame b = r.render(kBody, "down");
  const Frame fresh = Renderer(lamp_over_floor(metal, 0.06), {cam}, off).render(kBody, "down");
  r.set_options(on);
  const Frame c = r.render(kBody, "down");
  EXPECT_EQ(b.rgb, fresh.rgb);
  EXPECT_NE(a.rgb, b.rgb);  // a smooth metal's highlight and the sand's relief are gone
  EXPECT_EQ(a.rgb, c.rgb);
}

TEST(Materials, ReliefShadesOnlyWhereTheHeightVaries) {
  // A constant height field (the checker texture's) has no slope: any relief leaves the image
  // unchanged, bit for bit. Sand seen from 0.7 m (14 px per ripple) under the grazing light (65 deg
  // from the vertical) of a lamp 1.5 m ahead, across the ripples' crests (which run east-west):
  // their faces turned to the lamp brighten, the others darken: more contrast, about the same mean.
  const Pose low = pose_from_xyz_rpy({0.0, 0.0, 9.3}, {0.0, 0.0, 0.0});
  Material checker{"checker", {1.0, 1.0, 1.0}, 1.0};
  checker.roughness = 0.9;
  checker.sediment = 0.0;
  const CameraModel cam = down_camera();
  checker.relief_m = 0.0;
  const Frame a = Renderer(lamp_over_floor(checker, 2.0), {cam}, with_materials(true)).render(low, "down");
  checker.relief_m = 0.2;
  const Frame b = Renderer(lamp_over_floor(checker, 2.0), {cam}, with_materials(true)).render(low, "down");
  EXPECT_EQ(a.rgb, b.rgb);

  Material sand{"sand", {1.0, 1.0, 1.0}, 2.0};
  sand.relief_m = 0.0;
  // Mean and local contrast (mean absolute difference of vertically adjacent pixels: across the
  // crests, which an image row of this camera runs along), over the lit middle of the image.
  const auto stats = [&](const Material& m) {
    const Frame f = Renderer(lamp_over_floor(m, 6.0, {1.5, 0.0, 0.0}), {cam}, with_materials(true)).render(low, "down");
    double sum = 0, contrast = 0;
    int n = 0;
    for (int v = 40; v < 120; ++v)
      for (int u = 40; u < 120; ++u) {
        sum += green(f, u, v);
        contrast += std::abs(green(f, u, v + 1) - green(f, u, v));
        ++n;
      }
    return std::make_pair(sum / n, contrast / n);
  };
  const auto [flat_mean, flat_contrast] = stats(sand);
  sand.relief_m = 0.03;
  const auto [bump_mean, bump_contrast] = stats(sand);
  std::printf("sand under the lamp: mean %.1f -> %.1f, local contrast %.2f -> %.2f levels\n", flat_mean, bump_mean,
              flat_contrast, bump_contrast);
  EXPECT_NEAR(bump_mean, flat_mean, 0.1 * flat_mean);
  EXPECT_GT(bump_contrast, 1.5 * flat_contrast);
}

TEST(Materials, SedimentSettlesOnTopsNotOnWalls) {
  // A black box (albedo 0, so it returns nothing of its own) 1 m on a side, 2 m above the empty
  // sea: with sediment 1 its top turns towards the sand colour (at least the 0.3 share of the
  // patchy cover), its walls stay black. Sunlight only (down from the zenith, ambient 0.35).
  World w = unav::renderer::test::empty_world();
  w.water = jerlov_preset("I");
  Object box;
  box.name = "box";
  box.shape = "box";
  box.size_m = {1.0, 1.0, 1.0};
  box.X_WO = pose_from_xyz_rpy({0.0, 0.0, 8.0}, {0.0, 0.0, 0.3});
  box.material = Material{"none", {0.0, 0.0, 0.0}, 1.0};
  box.material.roughness = 0.9;  // no highlight
  box.material.sediment = 1.0;
  w.objects.push_back(box);
  const CameraModel cam = down_camera();
  // Seen from 1.5 m above the top, 0.8 m to the side: the top and one wall.
  const Pose X_WB = pose_from_xyz_rpy({-0.8, 0.0, 6.0}, {0.0, 0.0, 0.0});
  const Frame with = Renderer(w, {cam}, with_materials(false)).render(X_WB, "down");
  w.objects[0].material.sediment = 0.0;
  const Frame without = Renderer(w, {cam}, with_materials(false)).render(X_WB, "down");
  const auto level_at = [&](const Frame& f, const Eigen::Vector3d& p_W) {
    const Eigen::Vector3d p = f.X_WC.inverse() * p_W;
    return green(f, static_cast<int>(std::lround(f.K(0, 0) * p.x() / p.z() + f.K(0, 2))),
                 static_cast<int>(std::lround(f.K(1, 1) * p.y() / p.z() + f.K(1, 2))));
  };
  const Eigen::Vector3d top(0.0, 0.0, 7.5), wall(-0.5 * std::cos(0.3), -0.5 * std::sin(0.3), 8.2);
  const Eigen::Vector3d p = with.X_WC.inverse() * top;
  const std::size_t i = 3 * (static_cast<std::size_t>(std::lround(with.K(1, 1) * p.y() / p.z() + with.K(1, 2))) *
                                 static_cast<std::size_t>(with.width) +
                             static_cast<std::size_t>(std::lround(with.K(0, 0) * p.x() / p.z() + with.K(0, 2))));
  std::printf("top: %d (clean %d), rgb (%d, %d, %d) under 7.5 m of water; wall: %d (clean %d)\n", level_at(with, top),
              level_at(without, top), with.rgb[i], with.rgb[i + 1], with.rgb[i + 2], level_at(with, wall),
              level_at(without, wall));
  EXPECT_GT(level_at(with, top), level_at(without, top) + 8);
  EXPECT_NEAR(level_at(with, wall), level_at(without, wall), 1);
}

namespace {

// A 2 m square quad at the origin of its frame (normal along z) with UVs u = (x + 1) / 2,
// v = (y + 1) / 2, its material's diffuse map `texture` (OBJ + MTL, as exporters write them).
std::string write_textured_quad(const std::filesystem::path& dir, const std::string& texture) {
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "quad.mtl") << "newmtl painted\nKd 1 1 1\nmap_Kd " << texture << "\n";
  std::ofstream(dir / "quad.obj") << "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n"
                                     "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 -1\nusemtl painted\n"
                                     "f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 4/4/1\n";
  return (dir / "quad.obj").string();
}

}  // namespace

TEST(Materials, MeshFileTextureIsDrawnByItsUvsTheRightWayUp) {
  // The quad's map is 2 x 2 texels: top row red, green; bottom row blue, white. By the UVs
  // (v = 0 is the image's bottom, as OBJ, glTF and FBX mean it), the quad's south-west quarter
  // (u, v < 0.5) is blue, south-east (x > 0: u > 0.5) white, north-west red, north-east green.
  // Seen from 1 m above in clear water at 2 m depth, each quarter's own colour dominates.
  const auto dir = std::filesystem::temp_directory_path() / ("unav_mesh_texture_" + std::to_string(::getpid()));
  cv::Mat tex(2, 2, CV_8UC3);
  tex.at<cv::Vec3b>(0, 0) = {0, 0, 255};      // BGR: red
  tex.at<cv::Vec3b>(0, 1) = {0, 255, 0};      // green
  tex.at<cv::Vec3b>(1, 0) = {255, 0, 0};      // blue
  tex.at<cv::Vec3b>(1, 1) = {255, 255, 255};  // white
  std::filesystem::create_directories(dir);
  ASSERT_TRUE(cv::imwrite((dir / "paint.png").string(), tex));
  World w = unav::renderer::test::empty_world();
  w.water = jerlov_preset("I");
  Object quad;
  quad.name = "painted_quad";
  quad.mesh_file = write_textured_quad(dir, "paint.png");
  quad.X_WO = pose_from_xyz_rpy({0.0, 0.0, 2.0}, {0.0, 0.0, 0.0});
  quad.material = Material{"none", {1.0, 1.0, 1.0}, 1.0};
  w.objects.push_back(quad);
  RenderOptions o = exact_options();
  o.texture_size = 64;
  const Frame f = Renderer(w, {down_camera()}, o).render(pose_from_xyz_rpy({0, 0, 1.0}, {0, 0, 0}), "down");
  const auto rgb_at = [&](double x, double y) {
    const Eigen::Vector3d p = f.X_WC.inverse() * Eigen::Vector3d(x, y, 2.0);
    const std::size_t i = 3 * (static_cast<std::size_t>(std::lround(f.K(1, 1) * p.y() / p.z() + f.K(1, 2))) * f.width +
                               static_cast<std::size_t>(std::lround(f.K(0, 0) * p.x() / p.z() + f.K(0, 2))));
    return Eigen::Vector3i(f.rgb[i], f.rgb[i + 1], f.rgb[i + 2]);
  };
  const Eigen::Vector3i sw = rgb_at(-0.5, -0.5), se = rgb_at(0.5, -0.5), nw = rgb_at(-0.5, 0.5), ne = rgb_at(0.5, 0.5);
  std::printf(
      "quad quarters: south-west (%d %d %d), south-east (%d %d %d), north-west (%d %d %d), north-east (%d %d %d)\n",
      sw.x(), sw.y(), sw.z(), se.x(), se.y(), se.z(), nw.x(), nw.y(), nw.z(), ne.x(), ne.y(), ne.z());
  EXPECT_GT(sw.z(), 3 * std::max(sw.x(), sw.y()) + 10);                                   // blue
  EXPECT_GT(nw.x(), 3 * std::max(nw.y(), nw.z()) + 10);                                   // red
  EXPECT_GT(ne.y(), 3 * std::max(ne.x(), ne.z()) + 10);                                   // green
  EXPECT_GT(std::min({se.x(), se.y(), se.z()}), 2 * std::max({sw.x(), nw.y(), ne.z()}));  // white

  // A map that is not there: the error names the world object, the mesh file and the texture.
  World bad = w;
  bad.objects[0].mesh_file = write_textured_quad(dir / "bad", "missing.png");
  try {
    Renderer r(bad, {down_camera()}, o);
    ADD_FAILURE() << "a mesh with a missing texture was accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("painted_quad"), std::string::npos) << m;
    EXPECT_NE(m.find("quad.obj"), std::string::npos) << m;
    EXPECT_NE(m.find("missing.png"), std::string::npos) << m;
  }
  std::filesystem::remove_all(dir);
}

namespace {

// The same 2 m quad as write_textured_quad() (u = (x + 1) / 2, v = (y + 1) / 2 after assimp's
// glTF v flip) as glTF 2.0 with external buffer and maps: normalTexture normal.png,
// metallicRoughnessTexture and occlusionTexture orm.png (glTF's packing: r occlusion, g
// roughness, b metallic).
std::string write_gltf_quad(const std::filesystem::path& dir) {
  std::filesystem::create_directories(dir);
  const float pos[12] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0};
  const float nrm[12] = {0, 0, -1, 0, 0, -1, 0, 0, -1, 0, 0, -1};
  const float uv[8] = {0, 1, 1, 1, 1, 0, 0, 0};  // glTF: v = 0 at the image's top
  const std::uint16_t idx[6] = {0, 1, 2, 0, 2, 3};
  std::ofstream bin(dir / "quad.bin", std::ios::binary);
  bin.write(reinterpret_cast<const char*>(pos), sizeof pos);
  bin.write(reinterpret_cast<const char*>(nrm), sizeof nrm);
  bin.write(reinterpret_cast<const char*>(uv), sizeof uv);
  bin.write(reinterpret_cast<const char*>(idx), sizeof idx);
  bin.close();
  std::ofstream(dir / "quad.gltf") << R"({
  "asset": {"version": "2.0"},
  "scenes": [{"nodes": [0]}], "scene": 0,
  "nodes": [{"mesh": 0}],
  "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 0}]}],
  "materials": [{"pbrMetallicRoughness": {"metallicRoughnessTexture": {"index": 1}, "metallicFactor": 1.0, "roughnessFactor": 1.0},
                 "normalTexture": {"index": 0}, "occlusionTexture": {"index": 1}}],
  "textures": [{"source": 0}, {"source": 1}],
  "images": [{"uri": "normal.png"}, {"uri": "orm.png"}],
  "buffers": [{"uri": "quad.bin", "byteLength": 140}],
  "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
                  {"buffer": 0, "byteOffset": 96, "byteLength": 32}, {"buffer": 0, "byteOffset": 128, "byteLength": 12}],
  "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]},
                {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
                {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}]
})";
  return (dir / "quad.gltf").string();
}

// Writes a 2 x 2 map whose west column (u < 0.5) is `west` and east column `east` (RGB); with
// rows, its south row (v < 0.5: the image's bottom) `west` and its north row `east`.
void write_columns(const std::filesystem::path& file, const cv::Vec3b& west, const cv::Vec3b& east, bool rows = false) {
  cv::Mat m(2, 2, CV_8UC3);
  for (int r = 0; r < 2; ++r)
    for (int c = 0; c < 2; ++c) {
      const cv::Vec3b& px = (rows ? r == 0 : c == 1) ? east : west;
      m.at<cv::Vec3b>(r, c) = {px[2], px[1], px[0]};  // BGR
    }
  ASSERT_TRUE(cv::imwrite(file.string(), m));
}

}  // namespace

TEST(Materials, MeshFileNormalAndOrmMapsShadeByTheirUvs) {
  // A white quad (roughness 1: no highlight; no sediment) 1 m under the down camera in clear
  // water, its own glTF maps. Levels are linear; the backscatter (same quad, albedo 0) is taken off.
  const auto dir = std::filesystem::temp_directory_path() / ("unav_mesh_maps_" + std::to_string(::getpid()));
  World w = unav::renderer::test::empty_world();
  w.water = jerlov_preset("I");
  Object quad;
  quad.name = "mapped_quad";
  quad.mesh_file = write_gltf_quad(dir);
  quad.X_WO = pose_from_xyz_rpy({0.0, 0.0, 2.0}, {0.0, 0.0, 0.0});
  quad.material = Material{"none", {1.0, 1.0, 1.0}, 1.0};
  quad.material.sediment = 0.0;
  w.objects.push_back(quad);
  const double amb = w.sun.ambient_fraction;
  const Pose X_WB = pose_from_xyz_rpy({0, 0, 1.0}, {0, 0, 0});
  // Green at the west and east quarter points (with north_south: the south and north ones).
  const auto levels = [&](const World& world, bool north_south = false) {
    const Frame f = Renderer(world, {down_camera()}, with_materials(false)).render(X_WB, "down");
    const auto at = [&](double x) {
      const Eigen::Vector3d p =
          f.X_WC.inverse() * (north_south ? Eigen::Vector3d(0.0, x, 2.0) : Eigen::Vector3d(x, 0.0, 2.0));
      return green(f, static_cast<int>(std::lround(f.K(0, 0) * p.x() / p.z() + f.K(0, 2))),
                   static_cast<int>(std::lround(f.K(1, 1) * p.y() / p.z() + f.K(1, 2))));
    };
    return std::pair<double, double>(at(-0.5), at(0.5));
  };
  World dark = w;
  dark.objects[0].material.albedo.setZero();

  // Normal map: west flat, east tilted 45 deg towards +u (+x); the sun comes from +x, 45 deg
  // off the zenith. Irradiance (ambient share a, skylight by (1 + up) / 2, direct by cos):
  // flat a + (1 - a) cos 45; tilted a (1 + cos 45) / 2 + (1 - a). Tilted the wrong way (-x) it
  // would get a (1 + cos 45) / 2 only.
  const double c45 = std::sqrt(0.5);
  write_columns(dir / "normal.png", {128, 128, 255}, {218, 128, 218});  // (n + 1) / 2: (0.707, 0, 0.707)
  write_columns(dir / "orm.png", {255, 255, 0}, {255, 255, 0});
  w.sun.direction_W = Eigen::Vector3d(-c45, 0.0, c45);
  dark.sun = w.sun;
  auto [fw, fe] = levels(w);
  auto [bw, be] = levels(dark);
  const double tilted = (fe - be) / (fw - bw);
  const double predicted = (amb * (1.0 + c45) / 2.0 + (1.0 - amb)) / (amb + (1.0 - amb) * c45);
  std::printf("normal map: west %.0f, east %.0f (backscatter %.0f %.0f): ratio %.3f, predicted %.3f\n", fw, fe, bw, be,
              tilted, predicted);
  // 8-bit levels near 100 (one level is 1 %) and the map's 8-bit normal: 3 %.
  EXPECT_NEAR(tilted, predicted, 0.03 * predicted);
  // The same along v: the north row tilted towards +v (+y, east in world_ned), the sun from +y.
  write_columns(dir / "normal.png", {128, 128, 255}, {128, 218, 218}, true);
  w.sun.direction_W = Eigen::Vector3d(0.0, -c45, c45);
  dark.sun = w.sun;
  std::tie(fw, fe) = levels(w, true);
  std::tie(bw, be) = levels(dark, true);
  std::printf("normal map along v: south %.0f, north %.0f: ratio %.3f, predicted %.3f\n", fw, fe, (fe - be) / (fw - bw),
              predicted);
  EXPECT_NEAR((fe - be) / (fw - bw), predicted, 0.03 * predicted);

  // ORM map, sun from the zenith, flat normals: east occlusion 0.5 halves the skylight only
  // (ratio a / 2 + 1 - a); a metallic east (b = 255) loses the diffuse direct light, which a
  // rough lobe seen 26 deg off the mirror direction does not give back.
  write_columns(dir / "normal.png", {128, 128, 255}, {128, 128, 255});
  write_columns(dir / "orm.png", {255, 255, 0}, {128, 255, 0});
  w.sun.direction_W = {0.0, 0.0, 1.0};
  dark.sun = w.sun;
  std::tie(fw, fe) = levels(w);
  std::tie(bw, be) = levels(dark);
  const double occluded = (fe - be) / (fw - bw);
  std::printf("occlusion 0.5: ratio %.3f, predicted %.3f\n", occluded, amb / 2.0 + 1.0 - amb);
  EXPECT_NEAR(occluded, amb / 2.0 + 1.0 - amb, 0.03);
  write_columns(dir / "orm.png", {255, 255, 0}, {255, 255, 255});
  std::tie(fw, fe) = levels(w);
  std::printf("metallic: west (dielectric) %.0f, east (metal) %.0f, backscatter %.0f\n", fw, fe, bw);
  EXPECT_LT(fe - be, 0.6 * (fw - bw));
  EXPECT_GT(fe - be, 0.9 * amb * (fw - bw));  // the skylight stays (albedo 1)

  // A normal map that is not there: the error names the object, the mesh file and the image.
  std::filesystem::remove(dir / "normal.png");
  try {
    Renderer r(w, {down_camera()}, with_materials(false));
    ADD_FAILURE() << "a mesh with a missing normal map was accepted";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("mapped_quad"), std::string::npos) << m;
    EXPECT_NE(m.find("normal.png"), std::string::npos) << m;
  }
  std::filesystem::remove_all(dir);
}
