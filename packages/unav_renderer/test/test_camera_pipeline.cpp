// The camera after the water (llvmpipe): depth of field, lateral colour, white balance, JPEG.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "../src/pixel_ops.hpp"
#include "render_test_util.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;
using namespace unav::renderer::test;  // NOLINT(google-build-using-namespace): the shared test scenes

namespace {

// A plane facing the camera (body x forward) at body-frame position p, `size` metres square.
Object facing_plane(const std::string& name, const Eigen::Vector3d& p, double size, double albedo) {
  Object o;
  o.name = name;
  o.shape = "plane";
  o.size_m = {size, size, 1.0};
  o.X_WO = pose_from_xyz_rpy(p, {0.0, M_PI / 2, 0.0});  // normal -z turned to -x: faces the camera
  o.material.albedo = {albedo, albedo, albedo};
  o.seg_class = SegClass::kOther;
  return o;
}

// Channel ch (0 r, 1 g, 2 b) of a frame as doubles.
std::vector<double> channel(const Frame& f, int ch) {
  std::vector<double> out(static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height));
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = f.rgb[3 * i + static_cast<std::size_t>(ch)];
  return out;
}

double mean(const std::vector<double>& v) {
  double s = 0.0;
  for (double x : v) s += x;
  return s / static_cast<double>(v.size());
}

// Width [px] from 10 % to 90 % of the step between lo and hi along row `row` (width w), walking
// left from column `from` (inside the dark square) to the bright wall.
int edge_width_10_90(const std::vector<double>& g, int w, int row, int from, double lo, double hi) {
  int a = -1, b = -1;
  for (int u = from; u >= 0; --u) {
    const double x =
        (g[static_cast<std::size_t>(row) * static_cast<std::size_t>(w) + static_cast<std::size_t>(u)] - lo) / (hi - lo);
    if (b < 0 && x >= 0.1) b = u;
    if (a < 0 && x >= 0.9) a = u;
  }
  return b - a;
}

// The 10-90 % width of the edge spread of a uniform disc of diameter d: the share of the disc left
// of x, integrated numerically.
double disc_edge_width_10_90(double d) {
  const double r = 0.5 * d;
  auto share = [&](double x) {  // area of the disc with u < x, over the disc's
    const int n = 4000;
    double s = 0.0;
    for (int i = 0; i < n; ++i) {
      const double u = -r + (i + 0.5) * (2.0 * r / n);
      if (u < x) s += 2.0 * std::sqrt(std::max(0.0, r * r - u * u)) * (2.0 * r / n);
    }
    return s / (M_PI * r * r);
  };
  double x10 = -r, x90 = -r;
  for (double x = -r; x <= r; x += 1e-3 * r) {
    if (share(x) < 0.1) x10 = x;
    if (share(x) < 0.9) x90 = x;
  }
  return x90 - x10;
}

}  // namespace

TEST(CameraLens, BlurDiameterIsTheThinLensCircleOfConfusion) {
  // Against the lens equation directly: a point at z focuses at v = 1 / (1/f - 1/z) behind the
  // lens; the sensor sits at v_f (focused at z_f), so the point's cone of aperture A cuts it in a
  // disc of A |v - v_f| / v, over a pixel pitch of v_f / fx.
  CameraLens lens;
  lens.f_number = 2.0;
  lens.focal_length_mm = 8.0;
  lens.focus_distance_m = 1.0;
  const double f = 0.008, A = f / 2.0, fx = 800.0;
  const double vf = 1.0 / (1.0 / f - 1.0 / lens.focus_distance_m);
  for (double z : {0.3, 0.7, 1.0, 2.0, 10.0}) {
    const double v = 1.0 / (1.0 / f - 1.0 / z);
    const double expected = A * std::abs(v - vf) / v / (vf / fx);
    EXPECT_NEAR(lens.blur_diameter_px(z, fx), expected, 1e-9 * fx) << "z " << z;
  }
  EXPECT_EQ(lens.blur_diameter_px(1.0, fx), 0.0);
  lens.f_number = 0.0;  // a pinhole
  EXPECT_EQ(lens.blur_diameter_px(10.0, fx), 0.0);
}

TEST(CameraPipeline, DefocusBlursByTheCircleOfConfusionAndKeepsTheLight) {
  // A grey wall 4 m ahead with a dark 0.8 m square on it (60 px), clear water, no scattering.
  //  - focused on the wall: the pinhole's image (+-1 level: the taps all read the pixel itself);
  //  - focused at 0.3 m, f = 26 mm at f/2 (A = 13 mm): the blur disc at 4 m is
  //    fx A |1/0.3 - 1/4| = 12.0 px across; the square's edge spreads as a uniform disc's
  //    (10-90 % over ~5.4 px) within 30 % (16 taps are a coarse quadrature of the disc, and the
  //    bilinear taps add ~1 px);
  //  - the mean over the image is kept within 1.5 % (a blur of a wall that fills the view; the
  //    taps clamp at the image's edges).
  World w = empty_world();
  w.water.B_inf.setZero();
  w.water.beta_D.setConstant(0.01);
  w.water.K_d.setConstant(0.01);
  w.objects = {facing_plane("wall", {4.0, 0.0, 5.0}, 40.0, 0.5), facing_plane("square", {3.95, 0.0, 5.0}, 0.8, 0.02)};
  CameraModel cam = forward_camera(240, 180, 300.0);
  auto render = [&](double f_number, double focus_m) {
    CameraModel c = cam;
    c.lens.f_number = f_number;
    c.lens.focal_length_mm = 26.0;
    c.lens.focus_distance_m = focus_m;
    Renderer r(w, {c}, exact_options());
    return r.render(body_at({0.0, 0.0, 5.0}), "cam");
  };
  const Frame probe = render(0.0, 1.0);
  cam.exposure = 150.0 / std::max(1.0, static_cast<double>(probe.rgb[(90 * 240 + 20) * 3 + 1]));  // wall at ~150
  const Frame sharp = render(0.0, 1.0), focused = render(2.0, 4.0), blurred = render(2.0, 0.3);
  const auto gs = channel(sharp, 1), gf = channel(focused, 1), gb = channel(blurred, 1);
  double focused_worst = 0.0;
  for (std::size_t i = 0; i < gs.size(); ++i) focused_worst = std::max(focused_worst, std::abs(gf[i] - gs[i]));
  const int row = 90;
  const double lo = gs[static_cast<std::size_t>(row) * 240 + 120], hi = gs[static_cast<std::size_t>(row) * 240 + 20];
  ASSERT_GT(hi, 60.0) << "the wall is too dark to measure";
  ASSERT_LT(hi, 200.0) << "the wall is too bright (shoulder)";
  ASSERT_LT(lo, 0.2 * hi);
  CameraLens lens;
  lens.f_number = 2.0;
  lens.focal_length_mm = 26.0;
  lens.focus_distance_m = 0.3;
  const double d = lens.blur_diameter_px(3.95, 300.0), expected = disc_edge_width_10_90(d);
  const int w_sharp = edge_width_10_90(gs, 240, row, 120, lo, hi), w_blur = edge_width_10_90(gb, 240, row, 120, lo, hi);
  std::printf(
      "defocus: blur disc %.2f px, edge 10-90 %% %d px sharp, %d px blurred (uniform disc %.2f px); "
      "in focus worst %.0f levels; mean %.2f -> %.2f\n",
      d, w_sharp, w_blur, expected, focused_worst, mean(gs), mean(gb));
  EXPECT_LE(focused_worst, 1.0);
  EXPECT_LE(w_sharp, 2);
  EXPECT_NEAR(w_blur, expected, 0.3 * expected);
  EXPECT_NEAR(mean(gb) / mean(gs), 1.0, 0.015);
  EXPECT_EQ(blurred.seg, sharp.seg);  // labels and depth stay those of the sharp frame
  EXPECT_EQ(blurred.depth, sharp.depth);
}

TEST(CameraPipeline, LateralColourMagnifiesRedAndShrinksBlue) {
  // A white square 100 px right of the principal point on black water: with lateral colour k, the
  // red image is magnified by 1 + k and the blue by 1 - k about the principal point, so their
  // centroids sit k x 100 px outside and inside the green's (1 px at k = 0.01). Bilinear resampling
  // keeps a centroid (its weights are linear in the shift): 0.1 px, 8-bit rounding included.
  World w = empty_world();
  w.water.B_inf.setZero();
  w.water.beta_D.setConstant(0.01);
  w.water.K_d.setConstant(0.01);
  w.objects = {facing_plane("target", {5.0, 5.0 * 100.0 / 400.0, 5.0}, 0.4, 0.9)};
  CameraModel cam = forward_camera(320, 240, 400.0);
  cam.exposure = 6.0;
  cam.lens.lateral_chromatic = 0.01;
  Renderer r(w, {cam}, exact_options());
  const Frame f = r.render(body_at({0.0, 0.0, 5.0}), "cam");
  double cx[3] = {0, 0, 0};
  for (int ch = 0; ch < 3; ++ch) {
    const auto v = channel(f, ch);
    double s = 0.0, su = 0.0;
    for (int y = 0; y < f.height; ++y)
      for (int u = 0; u < f.width; ++u) {
        const double x =
            v[static_cast<std::size_t>(y) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(u)];
        s += x;
        su += x * u;
      }
    ASSERT_GT(s, 0.0);
    cx[ch] = su / s - cam.cx;
  }
  std::printf("lateral colour: centroid offsets r %.3f g %.3f b %.3f px (k = 0.01)\n", cx[0], cx[1], cx[2]);
  EXPECT_NEAR(cx[1], 100.0, 1.0);
  EXPECT_NEAR(cx[0] - cx[1], 0.01 * cx[1], 0.1);
  EXPECT_NEAR(cx[2] - cx[1], -0.01 * cx[1], 0.1);
}

TEST(CameraPipeline, WhiteBalanceScalesTheLinearChannels) {
  // Water only (the veiling light fills the view; linear 8-bit, no noise): every pixel has the same
  // value, so the ratio of a channel with and without white balance is its gain, to 8-bit rounding
  // (+-1 level of ~64: 3 %). manual: the gains as given; auto at 3 m depth with
  // K_d = (0.4, 0.08, 0.05) / m: exp((K_c - K_g) 3 m) = 2.61 for red, 0.914 for blue. The veiling
  // light (B_inf E0 exp(-K_d d)) is made grey at 3 m, so no balanced channel reaches the shoulder.
  World w = empty_world();
  w.water.K_d = Eigen::Vector3d(0.4, 0.08, 0.05);
  w.water.B_inf = 0.25 * (w.water.K_d * 3.0).array().exp().matrix();
  auto level = [&](const CameraModel& c) {
    Renderer r(w, {c}, exact_options());
    const Frame f = r.render(body_at({0.0, 0.0, 3.0}), "cam");
    return Eigen::Vector3d(mean(channel(f, 0)), mean(channel(f, 1)), mean(channel(f, 2)));
  };
  const CameraModel off = forward_camera(64, 48, 60.0);
  const Eigen::Vector3d base = level(off);
  ASSERT_GT(base.minCoeff(), 50.0) << base.transpose();
  ASSERT_LT(base.maxCoeff() * 2.7, 204.0) << "the balanced channels would reach the shoulder: " << base.transpose();
  CameraModel manual = off, automatic = off;
  manual.white_balance.mode = "manual";
  manual.white_balance.gains = Eigen::Vector3d(1.6, 1.0, 0.8);
  automatic.white_balance.mode = "auto";
  const Eigen::Vector3d m = level(manual).cwiseQuotient(base), a = level(automatic).cwiseQuotient(base);
  const Eigen::Vector3d expected_auto((0.4 - 0.08) * 3.0, 0.0, (0.05 - 0.08) * 3.0);
  std::printf("white balance: levels %.1f %.1f %.1f; manual ratios %.3f %.3f %.3f; auto %.3f %.3f %.3f\n", base[0],
              base[1], base[2], m[0], m[1], m[2], a[0], a[1], a[2]);
  for (int i = 0; i < 3; ++i) {
    EXPECT_NEAR(m[i], manual.white_balance.gains[i], 0.03 * manual.white_balance.gains[i]) << i;
    EXPECT_NEAR(a[i], std::exp(expected_auto[i]), 0.03 * std::exp(expected_auto[i])) << i;
  }
  // Auto's gains are bounded: at 30 m red would need exp(0.32 x 30) = 15000.
  CameraWhiteBalance wb;
  wb.mode = "auto";
  const Eigen::Vector3d deep = wb.gains_for((-w.water.K_d * 30.0).array().exp().matrix());
  EXPECT_DOUBLE_EQ(deep[0], wb.max_gain);
  EXPECT_DOUBLE_EQ(deep[1], 1.0);
}

TEST(CameraPipeline, JpegQualityTradesErrorForBlockArtefacts) {
  // A smooth colour gradient with fine texture, compressed at qualities 10, 50 and 95: the error
  // falls as the quality rises (PSNR > 35 dB at 95: the +-6 level grain differs per channel, and
  // 4:2:0 chroma keeps a quarter of its colour), and at 10 the 8 x 8 blocks show: the mean
  // step across block boundaries exceeds the mean step inside blocks by > 30 % (the image itself
  // has the same steps everywhere: measured ratio ~1.0 before compression).
  const int w = 128, h = 96;
  std::vector<std::uint8_t> img(static_cast<std::size_t>(w) * h * 3);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> grain(-6, 6);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int c = 0; c < 3; ++c)
        img[(static_cast<std::size_t>(y) * w + x) * 3 + c] =
            static_cast<std::uint8_t>(std::clamp(40 + x + (c == 2 ? y : y / 2) + grain(rng), 0, 255));
  auto block_ratio = [&](const std::vector<std::uint8_t>& im) {
    double across = 0.0, inside = 0.0;
    int na = 0, ni = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x + 1 < w; ++x) {
        const std::size_t i = (static_cast<std::size_t>(y) * w + x) * 3 + 1;
        const double step = std::abs(static_cast<double>(im[i + 3]) - im[i]);
        if (x % 8 == 7) {
          across += step;
          ++na;
        } else {
          inside += step;
          ++ni;
        }
      }
    return (across / na) / (inside / ni);
  };
  auto psnr = [&](const std::vector<std::uint8_t>& a) {
    double se = 0.0;
    for (std::size_t i = 0; i < a.size(); ++i) se += std::pow(static_cast<double>(a[i]) - img[i], 2);
    return 10.0 * std::log10(255.0 * 255.0 / std::max(se / static_cast<double>(a.size()), 1e-12));
  };
  double last = 0.0, ratio10 = 0.0;
  for (int q : {10, 50, 95}) {
    std::vector<std::uint8_t> out = img;
    detail::jpeg_roundtrip(out.data(), w, h, q);
    const double p = psnr(out);
    std::printf("jpeg quality %d: PSNR %.1f dB, block step ratio %.2f\n", q, p, block_ratio(out));
    EXPECT_GT(p, last) << "quality " << q;
    last = p;
    if (q == 10) ratio10 = block_ratio(out);
  }
  std::printf("uncompressed block step ratio %.2f\n", block_ratio(img));
  EXPECT_GT(last, 35.0);
  EXPECT_GT(ratio10, 1.3 * block_ratio(img));

  // Through the renderer: the camera's frames carry it, labels and depth untouched.
  World world = empty_world();
  world.objects = {facing_plane("wall", {4.0, 0.0, 5.0}, 40.0, 0.5)};
  CameraModel cam = forward_camera(160, 120, 150.0);
  RenderOptions o = exact_options();
  o.noise = true;
  cam.noise_stddev = 0.02;
  Renderer plain(world, {cam}, o);
  cam.jpeg_quality = 20;
  Renderer jpeg(world, {cam}, o);
  const Frame a = plain.render(body_at({0, 0, 5}), "cam"), b = jpeg.render(body_at({0, 0, 5}), "cam");
  EXPECT_NE(a.rgb, b.rgb);
  EXPECT_EQ(a.seg, b.seg);
  EXPECT_EQ(a.depth, b.depth);
}
