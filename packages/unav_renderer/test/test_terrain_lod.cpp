// Terrain level of detail (RenderOptions::terrain_lod_px) on worlds/pipe_inspection's seabed
// patch (65 x 65 points, 1 m apart, 0.15 m relief): the coarse tiles stay within their pixel
// budget of the full mesh, the skirts leave no seam open, and the image hardly changes. Its rocks'
// levels keep their outlines within the same budget.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;

namespace {

World pipe_world() { return load_world(std::string(UNAV_REPO_ROOT) + "/worlds/pipe_inspection/world.yaml"); }

// 320x240, 60 deg: fx = 277 px. Level 1 (2 m cells, 2.5-6 cm from the full mesh) starts ~5 m
// away at 2 px, so the view holds every level.
CameraModel front_camera() {
  CameraModel c = CameraModel::from_hfov("front", 320, 240, 60.0 * M_PI / 180.0);
  c.X_BC.linear() = c.X_BC.linear() * R_camera_body_to_optical();
  return c;
}

// 2 m over the seabed looking north along the patch (the renderer bench's pose), and the same
// pitched 20 deg down (steeper rays: the seams between levels cross more of the image).
const Pose kLevel = pose_from_xyz_rpy({-1.0, 0.3, 8.0}, {0.0, 0.0, 0.05});
const Pose kPitched = pose_from_xyz_rpy({-1.0, 0.3, 8.0}, {0.0, -20.0 * M_PI / 180.0, 0.4});

RenderOptions options(double lod_px) {
  RenderOptions o;
  o.noise = false;
  o.marine_snow = false;
  o.texture_size = 128;
  o.terrain_lod_px = lod_px;
  return o;
}

struct Shot {
  Frame frame;
  RenderTimings timings;
};

Shot shoot(double lod_px, const Pose& X_WB, bool seabed = true) {
  World w = pipe_world();
  w.seabed.enabled = seabed;
  Renderer r(w, {front_camera()}, options(lod_px));
  Shot s;
  s.frame = r.render(X_WB, "front", 0.0);
  s.timings = r.last_timings();
  return s;
}

constexpr auto kSeabed = static_cast<std::uint8_t>(SegClass::kSeabed);

// Pixels the full mesh shows as seabed and the level-of-detail image as open water: a seam.
std::size_t seams(const Frame& full, const Frame& lod) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < full.seg.size(); ++i) n += full.seg[i] == kSeabed && lod.seg[i] == 0;
  return n;
}

}  // namespace

TEST(TerrainLod, CoarseTilesStayWithinTheirPixelBudget) {
  for (const Pose& X_WB : {kLevel, kPitched}) {
    const Shot full = shoot(0.0, X_WB), lod = shoot(2.0, X_WB);
    // Off: every tile in view at full detail; on: the far ones coarser.
    EXPECT_GT(full.timings.terrain_tiles[0], 0u);
    EXPECT_EQ(full.timings.terrain_tiles[1] + full.timings.terrain_tiles[2], 0u);
    EXPECT_GT(lod.timings.terrain_tiles[1] + lod.timings.terrain_tiles[2], 0u);
    EXPECT_GT(lod.timings.terrain_tiles[0], 0u);  // the tiles under the camera stay whole

    const Frame &a = full.frame, &b = lod.frame;
    ASSERT_EQ(a.seg.size(), b.seg.size());
    EXPECT_EQ(seams(a, b), 0u);

    // Each surface point seen lies within the budget of the full mesh, vertically: 2 px at its
    // range r, 2 r / fx. The full mesh: depth_at() on the patch's grid, two triangles a cell as
    // make_seabed_mesh() lays them (the full image's points lie on it to float rounding: slack).
    const World w = pipe_world();
    const Eigen::Vector2d size = w.seabed.size_m, o = w.seabed.center_ne - 0.5 * size;
    const Eigen::Vector2d cells(std::ceil(size.x() / w.seabed.resolution_m),
                                std::ceil(size.y() / w.seabed.resolution_m));
    const Eigen::Vector2d step = size.cwiseQuotient(cells);
    const auto mesh_depth = [&](double n, double e) {
      const double gi = (n - o.x()) / step.x(), gj = (e - o.y()) / step.y();
      const double i = std::min(std::floor(gi), cells.x() - 1), j = std::min(std::floor(gj), cells.y() - 1);
      const double u = gi - i, v = gj - j;
      const auto z = [&](double ri, double rj) {
        return w.seabed.depth_at(o.x() + ri * step.x(), o.y() + rj * step.y());
      };
      return u + v <= 1.0 ? z(i, j) + v * (z(i, j + 1) - z(i, j)) + u * (z(i + 1, j) - z(i, j))
                          : z(i + 1, j + 1) + (1.0 - v) * (z(i + 1, j) - z(i + 1, j + 1)) +
                                (1.0 - u) * (z(i, j + 1) - z(i + 1, j + 1));
    };
    const auto stray = [&](const Frame& f, std::size_t* n) {
      std::vector<std::pair<double, double>> out;  // (|D - full mesh's D|, range)
      const double fx = f.K(0, 0), fy = f.K(1, 1), cx = f.K(0, 2), cy = f.K(1, 2);
      const Eigen::Vector2d c = w.seabed.center_ne, half = 0.5 * size - Eigen::Vector2d::Constant(0.5);
      for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
          const std::size_t i =
              static_cast<std::size_t>(y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(x);
          if (f.seg[i] != kSeabed) continue;
          const double z = f.depth[i];
          const Eigen::Vector3d p_C(z * (x - cx) / fx, z * (y - cy) / fy, z);  // K: pixel centres at integers
          const Eigen::Vector3d p = f.X_WC * p_C;
          if (std::abs(p.x() - c.x()) > half.x() || std::abs(p.y() - c.y()) > half.y()) continue;  // the far seabed
          out.emplace_back(std::abs(p.z() - mesh_depth(p.x(), p.y())), p_C.norm());
        }
      *n = out.size();
      return out;
    };
    std::size_t na = 0, nb = 0;
    double slack = 0.0;
    for (const auto& [d, r] : stray(a, &na)) slack = std::max(slack, d);
    EXPECT_LT(slack, 0.01);  // depth as float: ~1e-6 of 20 m, and the pixel's ray through its centre
    std::size_t off = 0;
    const double fx = b.K(0, 0);
    double worst = 0.0;
    for (const auto& [d, r] : stray(b, &nb)) {
      off += d > 2.0 * r / fx + slack + 0.002;
      worst = std::max(worst, d);
    }
    EXPECT_GT(nb, 10000u);
    EXPECT_EQ(off, 0u) << "of " << nb << " seabed pixels; full mesh within " << slack << " m, coarse within " << worst;

    // The image: far seabed a pixel or two away; measured mean 0.02-0.04 of 255 a channel at
    // 640x480 (a few hundred pixels where a rock's foot meets the sand).
    double sum = 0.0;
    for (std::size_t k = 0; k < a.rgb.size(); ++k) sum += std::abs(int{a.rgb[k]} - int{b.rgb[k]});
    EXPECT_LT(sum / static_cast<double>(a.rgb.size()), 0.25);
  }
}

// Rocks at levels of detail (320 / 80 / 20 triangles, the same bound): the far ones coarser, their
// outlines within the budget of the finest mesh's, fewer triangles in the lamps' maps.
TEST(TerrainLod, RocksStayWithinTheirPixelBudget) {
  constexpr auto kRock = static_cast<std::uint8_t>(SegClass::kRock);
  std::size_t coarse = 0;
  for (const Pose& X_WB : {kLevel, kPitched}) {
    // Without the seabed: its own levels would hide or bare the rocks' feet.
    const Shot full = shoot(0.0, X_WB, false), lod = shoot(2.0, X_WB, false);
    const std::size_t* f = full.timings.object_parts;
    const std::size_t* l = lod.timings.object_parts;
    EXPECT_GT(f[0], 0u);
    EXPECT_EQ(f[1] + f[2], 0u);
    EXPECT_EQ(l[0] + l[1] + l[2], f[0]);  // the same rocks in view
    coarse += l[1] + l[2];
    EXPECT_LT(lod.timings.lamp_map_triangles, full.timings.lamp_map_triangles);
    // A pixel that is rock in one image and not in the other lies within 2 px (the budget) + 1 px
    // (the pixel grid: an outline moved by 2 px covers or bares a pixel up to 3 px off) of a rock
    // pixel of the other (or of the border: the rest of its outline may lie beyond the frame).
    const Frame &a = full.frame, &b = lod.frame;
    const auto rock_near = [](const Frame& im, int x, int y) {
      for (int dy = -3; dy <= 3; ++dy)
        for (int dx = -3; dx <= 3; ++dx) {
          const int u = x + dx, v = y + dy;
          if (dx * dx + dy * dy > 9) continue;
          if (u < 0 || v < 0 || u >= im.width || v >= im.height) return true;
          if (im.seg[static_cast<std::size_t>(v) * static_cast<std::size_t>(im.width) + static_cast<std::size_t>(u)] ==
              kRock)
            return true;
        }
      return false;
    };
    std::size_t changed = 0, stray = 0;
    for (int y = 0; y < a.height; ++y)
      for (int x = 0; x < a.width; ++x) {
        const std::size_t i =
            static_cast<std::size_t>(y) * static_cast<std::size_t>(a.width) + static_cast<std::size_t>(x);
        if ((a.seg[i] == kRock) == (b.seg[i] == kRock)) continue;
        ++changed;
        stray += !rock_near(a.seg[i] == kRock ? b : a, x, y);
      }
    EXPECT_EQ(stray, 0u) << "of " << changed << " pixels whose rock cover changed";
  }
  EXPECT_GT(coarse, 0u);
}

TEST(TerrainLod, SkirtsCloseTheSeamsAtAnyLevel) {
  // Low over the seabed (0.7 m) with budgets of 5 to 40 px: the seams between levels run 1-4 m
  // from the camera, where an open one (a 2-8 cm slit between a coarse edge and the full mesh's
  // points along it) would be pixels wide. Without the skirts: 45 water pixels (measured).
  const Pose low[] = {pose_from_xyz_rpy({2.0, 3.5, 9.3}, {0.0, 0.0, 0.3}),
                      pose_from_xyz_rpy({2.0, 3.5, 9.3}, {0.0, -15.0 * M_PI / 180.0, 2.0})};
  std::size_t coarse_tiles = 0;
  for (const Pose& X_WB : low) {
    const Shot full = shoot(0.0, X_WB);
    for (double px : {5.0, 10.0, 40.0}) {
      const Shot lod = shoot(px, X_WB);
      coarse_tiles += lod.timings.terrain_tiles[1] + lod.timings.terrain_tiles[2];
      EXPECT_EQ(seams(full.frame, lod.frame), 0u) << "budget " << px << " px";
    }
  }
  EXPECT_GT(coarse_tiles, 20u);
}

TEST(TerrainLod, BudgetIsValidated) {
  for (double px : {-1.0, std::nan(""), std::numeric_limits<double>::infinity()}) {
    RenderOptions o = options(px);
    try {
      Renderer r(pipe_world(), {front_camera()}, o);
      ADD_FAILURE() << "terrain_lod_px " << px << " accepted";
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("terrain_lod_px"), std::string::npos) << e.what();
    }
  }
}
