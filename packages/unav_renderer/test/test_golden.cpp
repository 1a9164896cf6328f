// Golden images of worlds/pipe_inspection: front and down cameras, two water types.
// Regenerate with UNAV_UPDATE_GOLDEN=1 (writes into the source tree's test/golden/).
// Tolerance chosen to survive llvmpipe-versus-GPU differences (texture LOD selection,
// transcendental precision, point rasterisation): mean absolute difference <= 3 levels of
// 255 and at most 2 % of pixels off by more than 24 levels (edges, snow particles).
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>

#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;

namespace {

struct Case {
  const char* name;
  const char* camera;
  const char* water;
};

void check_golden(Renderer& r, const Case& c, const Pose& X_WB) {
  r.set_water(jerlov_preset(c.water));
  const Frame f = r.render(X_WB, c.camera, 1.0);
  const std::string path = std::string(UNAV_GOLDEN_DIR) + "/" + c.name + ".png";
  if (const char* u = std::getenv("UNAV_UPDATE_GOLDEN"); u && std::string(u) == "1") {
    write_png_rgb(f, path);
    GTEST_SKIP() << "golden written: " << path;
  }
  ASSERT_TRUE(std::filesystem::exists(path)) << path << " missing (UNAV_UPDATE_GOLDEN=1 writes it)";
  int w = 0, h = 0;
  const auto ref = read_png_rgb(path, &w, &h);
  ASSERT_EQ(w, f.width);
  ASSERT_EQ(h, f.height);
  double sum = 0;
  std::size_t outliers = 0;
  for (std::size_t i = 0; i < ref.size(); i += 3) {
    int worst = 0;
    for (int k = 0; k < 3; ++k) {
      const int d = std::abs(static_cast<int>(ref[i + k]) - static_cast<int>(f.rgb[i + k]));
      sum += d;
      worst = std::max(worst, d);
    }
    outliers += worst > 24;
  }
  const double mad = sum / ref.size();
  const std::size_t pixels = ref.size() / 3;  // 3 bytes a pixel
  const double frac = static_cast<double>(outliers) / static_cast<double>(pixels);
  EXPECT_LE(mad, 3.0) << c.name;
  EXPECT_LE(frac, 0.02) << c.name;
  if (mad > 3.0 || frac > 0.02) write_png_rgb(f, std::string(::testing::TempDir()) + c.name + "_actual.png");
}

}  // namespace

TEST(Golden, PipeInspectionFrontAndDownInTwoWaters) {
  World world = load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml");
  CameraModel front = CameraModel::from_hfov("front", 160, 120, 80.0 * M_PI / 180.0);
  front.X_BC = pose_from_xyz_rpy({0.21, 0, 0.05}, {0, 0, 0});
  front.X_BC.linear() = front.X_BC.linear() * R_camera_body_to_optical();
  CameraModel down = CameraModel::from_hfov("down", 160, 90, 90.0 * M_PI / 180.0);
  down.X_BC = pose_from_xyz_rpy({0.1, 0, 0.12}, {0, -M_PI / 2, 0});
  down.X_BC.linear() = down.X_BC.linear() * R_camera_body_to_optical();
  RenderOptions o;
  o.noise = false;
  o.texture_size = 256;
  Renderer r(world, {front, down}, o);
  // Above the first leg, 2 m over the seabed, looking along the pipe towards the turns.
  const Pose X_WB = pose_from_xyz_rpy({3.0, 0.2, 8.0}, {0, 0, 0.1});
  for (const Case& c :
       {Case{"pipe_front_jerlov_IB", "front", "jerlov_IB"}, Case{"pipe_down_jerlov_IB", "down", "jerlov_IB"},
        Case{"pipe_front_jerlov_5C", "front", "jerlov_5C"}, Case{"pipe_down_jerlov_5C", "down", "jerlov_5C"}})
    check_golden(r, c, X_WB);
}
