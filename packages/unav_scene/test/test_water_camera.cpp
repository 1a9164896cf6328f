// Water presets and camera configuration (no OpenGL).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "unav_scene/camera.hpp"
#include "unav_scene/errors.hpp"
#include "unav_scene/water.hpp"

using namespace unav::scene;
namespace fs = std::filesystem;

namespace {
const std::string kRoot = UNAV_REPO_ROOT;
}

TEST(Water, ConfigFilesMatchBuiltInPresets) {
  const auto names = jerlov_preset_names();
  ASSERT_EQ(names.size(), 10u);
  for (const auto& n : names) {
    const WaterModel a = jerlov_preset(n);
    const WaterModel b = load_water_file(kRoot + "/config/water/" + n + ".yaml");
    EXPECT_EQ(a.name, b.name);
    // Files print 4 significant digits.
    EXPECT_TRUE(a.beta_D.isApprox(b.beta_D, 1e-3)) << n;
    EXPECT_TRUE(a.beta_B.isApprox(b.beta_B, 1e-3)) << n;
    EXPECT_TRUE(a.K_d.isApprox(b.K_d, 1e-3)) << n;
    EXPECT_TRUE(a.B_inf.isApprox(b.B_inf, 1e-3)) << n;
    EXPECT_TRUE(a.b_scatter.isApprox(b.b_scatter, 1e-3)) << n;
    EXPECT_NEAR(a.forward_scatter_per_m, b.forward_scatter_per_m, 1e-9) << n;
  }
}

TEST(Water, ReferenceTableValuesAndVeilingLight) {
  const WaterModel ii = jerlov_preset("II");
  EXPECT_NEAR(ii.beta_D[0], 0.223, 1e-12);
  EXPECT_NEAR(ii.beta_D[2], 0.062, 1e-12);
  EXPECT_EQ(jerlov_preset("jerlov_9C").name, "jerlov_9C");
  // Veiling light decays with depth like the downwelling light: B_inf exp(-K_d d).
  const Eigen::Vector3d v = ii.veiling_light_at(10.0);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(v[c], ii.B_inf[c] * std::exp(-ii.K_d[c] * 10.0), 1e-12);
  // Schlick k for g = 0.92: 1.55 g - 0.55 g^3.
  EXPECT_NEAR(ii.schlick_k(), 1.55 * 0.92 - 0.55 * 0.92 * 0.92 * 0.92, 1e-12);
  EXPECT_THROW(jerlov_preset("IV"), ConfigError);
}

TEST(Camera, DefaultVehicleCamerasFromConfig) {
  const auto cams = load_cameras(kRoot + "/config/sensors/bluerov2_cameras.yaml");
  ASSERT_EQ(cams.size(), 2u);
  const CameraModel& front = cams[0];
  const CameraModel& down = cams[1];
  EXPECT_EQ(front.name, "front");
  EXPECT_EQ(down.name, "down");
  EXPECT_EQ(down.width, 320);  // the paper's policy input: 180 x 320 (h x w)
  EXPECT_EQ(down.height, 180);
  // Optical z (column 2 of R_BC) is body x for the front camera, body z for the down camera.
  EXPECT_TRUE(front.X_BC.linear().col(2).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  EXPECT_TRUE(down.X_BC.linear().col(2).isApprox(Eigen::Vector3d::UnitZ(), 1e-12));
  // Down camera: image right = body right, image up (-y optical) = body forward.
  EXPECT_TRUE(down.X_BC.linear().col(0).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  EXPECT_TRUE((-down.X_BC.linear().col(1)).isApprox(Eigen::Vector3d::UnitX(), 1e-12));
  // fx from the horizontal FOV: (w / 2) / tan(hfov / 2) = 160 for 90 deg.
  EXPECT_NEAR(down.fx, 160.0, 1e-9);
  EXPECT_NEAR(down.cx, 159.5, 1e-12);
  EXPECT_TRUE(front.has_distortion());
}

TEST(Camera, OneCameraByNameOrAnErrorListingTheCameras) {
  const std::string file = kRoot + "/config/sensors/bluerov2_cameras.yaml";
  EXPECT_EQ(load_camera(file, "down").width, 320);
  try {
    load_camera(file, "rear");
    ADD_FAILURE() << "no error for a missing camera";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.file(), file);
    EXPECT_EQ(e.value(), "rear");
    EXPECT_EQ(e.rule(), "no camera of that name (cameras: front, down)");
  }
}

TEST(Camera, BadFieldOfViewNamesFileAndKey) {
  const fs::path d = fs::temp_directory_path() / ("unav_cam_" + std::to_string(::getpid()));
  fs::create_directories(d);
  const std::string f = (d / "cams.yaml").string();
  std::ofstream(f) << "cameras:\n  - {name: c, width: 64, height: 48, hfov_deg: 0}\n";
  try {
    load_cameras(f);
    FAIL() << "no error";
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find(f), std::string::npos) << m;
    EXPECT_NE(m.find("cameras[0].hfov_deg"), std::string::npos) << m;
  }
  std::ofstream(f) << "cameras:\n  - {name: c, width: 64, height: 48, intrinsics: {fx: 50, fy: 51, cx: 30, cy: 20}}\n";
  const auto cams = load_cameras(f);
  EXPECT_NEAR(cams[0].K()(1, 1), 51.0, 1e-12);
  std::ofstream(f) << "cameras:\n  - {name: c, width: 64, height: 48, hfov_deg: 60, lens: fisheye}\n";
  EXPECT_THROW(load_cameras(f), ConfigError);
  EXPECT_THROW(CameraModel::from_hfov("x", 64, 48, -0.1), ConfigError);
}

TEST(CameraPort, FlatPortSnellAndTheFittedWaterModel) {
  CameraModel c = CameraModel::from_hfov("front", 640, 480, 80.0 * M_PI / 180.0);
  c.port.type = CameraPort::Type::kFlat;
  // Snell: sin(theta_water) = sin(theta_air) / 1.34 for every ray.
  for (double a : {0.1, 0.4, 0.7}) {
    const Eigen::Vector3d w = c.port.to_water({std::sin(a), 0.0, std::cos(a)});
    EXPECT_NEAR(std::hypot(w.x(), w.y()), std::sin(a) / 1.34, 1e-12);
    EXPECT_NEAR(w.norm(), 1.0, 1e-12);
  }
  // The fitted plumb_bob model reproduces the exact refraction over the whole image: project
  // water rays of a grid of pixels with it and compare (max error < 0.3 px).
  const CameraModel e = c.water_equivalent();
  EXPECT_NEAR(e.fx, 1.34 * c.fx, 1e-6 * c.fx);
  EXPECT_EQ(e.port.type, CameraPort::Type::kNone);
  double worst = 0.0;
  for (int v = 0; v < 480; v += 20)
    for (int u = 0; u < 640; u += 20) {
      const Eigen::Vector3d w = c.port.to_water({(u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0});
      const double x = w.x() / w.z(), y = w.y() / w.z(), r2 = x * x + y * y;
      const double radial = 1.0 + e.distortion[0] * r2 + e.distortion[1] * r2 * r2 + e.distortion[4] * r2 * r2 * r2;
      worst = std::max(worst, std::hypot(e.fx * x * radial + e.cx - u, e.fy * y * radial + e.cy - v));
    }
  EXPECT_LT(worst, 0.3);
  // A dome centred on the pupil changes nothing; a pupil behind the centre magnifies less.
  CameraPort dome;
  dome.type = CameraPort::Type::kDome;
  EXPECT_TRUE(dome.to_water({0.3, 0.2, 1.0}).isApprox(Eigen::Vector3d(0.3, 0.2, 1.0).normalized(), 1e-12));
  c.port = dome;
  c.port.dome_offset_m = 0.02;  // pupil 2 cm ahead of the centre: rays leave the dome obliquely
  EXPECT_GT(std::abs(c.water_equivalent().fx / c.fx - 1.0), 0.01);
}

TEST(CameraPort, YamlKeysAndBadValues) {
  const fs::path p = fs::temp_directory_path() / "unav_port_cams.yaml";
  std::ofstream(p) << "cameras:\n  - name: front\n    width: 64\n    height: 48\n    hfov_deg: 60\n"
                      "    vignetting: 0.5\n    shot_noise: 0.002\n"
                      "    port: {type: flat, water_index: 1.33, glass_thickness_m: 0.012, air_gap_m: 0.005}\n";
  const CameraModel c = load_cameras(p.string())[0];
  EXPECT_EQ(c.port.type, CameraPort::Type::kFlat);
  EXPECT_DOUBLE_EQ(c.port.water_index, 1.33);
  EXPECT_DOUBLE_EQ(c.vignetting, 0.5);
  EXPECT_DOUBLE_EQ(c.shot_noise, 0.002);
  std::ofstream(p) << "cameras:\n  - name: front\n    width: 64\n    height: 48\n    hfov_deg: 60\n"
                      "    port: {type: flat, glass_thickness_m: -0.01}\n";
  try {
    load_cameras(p.string());
    FAIL() << "negative glass thickness accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("unav_port_cams.yaml"), std::string::npos) << what;
    EXPECT_NE(what.find("port.glass_thickness_m"), std::string::npos) << what;
    EXPECT_NE(what.find("-0.01"), std::string::npos) << what;
  }
  std::ofstream(p) << "cameras:\n  - name: front\n    width: 64\n    height: 48\n    hfov_deg: 60\n"
                      "    port: {type: porthole}\n";
  EXPECT_THROW(load_cameras(p.string()), ConfigError);
}

TEST(CameraPipeline, YamlKeysAndBadValues) {
  // The camera after the water: lens, white balance and JPEG keys read as written; a bad value
  // named by file, key path and value.
  const fs::path p = fs::temp_directory_path() / "unav_pipeline_cams.yaml";
  const std::string head = "cameras:\n  - name: front\n    width: 64\n    height: 48\n    hfov_deg: 60\n";
  std::ofstream(p) << head
                   << "    lens: {f_number: 2.8, focal_length_mm: 6, focus_distance_m: 1.5, lateral_chromatic: 0.002}\n"
                      "    white_balance: {mode: manual, gains: [1.8, 1.0, 0.7]}\n    jpeg_quality: 80\n";
  const CameraModel c = load_cameras(p.string())[0];
  EXPECT_DOUBLE_EQ(c.lens.f_number, 2.8);
  EXPECT_DOUBLE_EQ(c.lens.focal_length_mm, 6.0);
  EXPECT_DOUBLE_EQ(c.lens.focus_distance_m, 1.5);
  EXPECT_DOUBLE_EQ(c.lens.lateral_chromatic, 0.002);
  EXPECT_EQ(c.white_balance.mode, "manual");
  EXPECT_TRUE(c.white_balance.gains.isApprox(Eigen::Vector3d(1.8, 1.0, 0.7)));
  EXPECT_EQ(c.jpeg_quality, 80);
  EXPECT_TRUE(c.white_balance.gains_for(Eigen::Vector3d(0.1, 0.5, 0.6)).isApprox(c.white_balance.gains));
  const std::vector<std::pair<std::string, std::string>> bad = {
      {"    lens: {f_number: -1}\n", "lens.f_number"},
      {"    lens: {lateral_chromatic: 0.2}\n", "lens.lateral_chromatic"},
      {"    white_balance: {mode: daylight}\n", "white_balance.mode"},
      {"    white_balance: {gains: [1.0, .nan, 1.0]}\n", "white_balance.gains"},
      {"    jpeg_quality: 101\n", "jpeg_quality"},
  };
  for (const auto& [yaml, key] : bad) {
    std::ofstream(p) << head << yaml;
    try {
      load_cameras(p.string());
      ADD_FAILURE() << "accepted: " << yaml;
    } catch (const ConfigError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("unav_pipeline_cams.yaml"), std::string::npos) << what;
      EXPECT_NE(what.find(key), std::string::npos) << what;
    }
  }
}
