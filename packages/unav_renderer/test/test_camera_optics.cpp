// The camera behind its housing: flat and dome ports, vignetting, shot noise (llvmpipe).
#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

using namespace unav::renderer;
using namespace unav::renderer::test;  // NOLINT(google-build-using-namespace): the shared test scenes

namespace {

// A small square marker (plane facing the camera) at body-frame position p (x forward).
Object marker(const Eigen::Vector3d& p, double size) {
  Object o;
  o.name = "marker";
  o.shape = "plane";
  o.size_m = {size, size, 1.0};
  o.X_WO = pose_from_xyz_rpy(p, {0.0, M_PI / 2, 0.0});  // normal -z turned to -x: faces the camera
  o.seg_class = SegClass::kOther;
  return o;
}

// Centroid of the marker's segmentation pixels.
Eigen::Vector2d centroid(const Frame& f) {
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  int n = 0;
  for (int v = 0; v < f.height; ++v)
    for (int u = 0; u < f.width; ++u)
      if (f.seg[static_cast<std::size_t>(v) * static_cast<std::size_t>(f.width) + static_cast<std::size_t>(u)] ==
          static_cast<std::uint8_t>(SegClass::kOther)) {
        s += Eigen::Vector2d(u, v);
        ++n;
      }
  EXPECT_GT(n, 0);
  return s / std::max(n, 1);
}

// The same frame of water without and with sensor noise (the camera's noise settings).
std::pair<Frame, Frame> clean_and_noisy(const CameraModel& cam) {
  RenderOptions noisy = exact_options();
  noisy.noise = true;
  Renderer clean_r(empty_world(), {cam}, exact_options());
  Renderer noisy_r(empty_world(), {cam}, noisy);
  return {clean_r.render(body_at({0, 0, 5.0}), "cam"), noisy_r.render(body_at({0, 0, 5.0}), "cam")};
}

}  // namespace

TEST(CameraOptics, FlatPortMagnifiesByTheRefractiveIndexRatio) {
  // A marker 0.25 m beside the axis at 5 m: 2.86 deg off axis in water. A flat port turns
  // that into asin(1.34 sin 2.86 deg) in air; at such a small angle the image offset grows by
  // n_water / n_air = 1.34 within 0.1% (third-order terms). A long lens (f = 1000 px) makes the
  // offset 50 px and the marker 40 px wide, so its centroid is good to ~0.1 px: tolerance 0.01.
  const Eigen::Vector3d p(5.0, 0.25, 0.0);
  World w = empty_world();
  w.objects.push_back(marker(p, 0.2));
  CameraModel air = forward_camera(400, 240, 1000.0);
  CameraModel flat = air;
  flat.port.type = CameraPort::Type::kFlat;
  flat.port.glass_thickness_m = 0.01;
  Renderer r(w, {air}, exact_options());
  const double du_air = centroid(r.render(Pose::Identity(), "cam")).x() - air.cx;
  Renderer rp(w, {flat}, exact_options());
  const Frame fp = rp.render(Pose::Identity(), "cam");
  const double du_port = centroid(fp).x() - flat.cx;
  std::printf("image offset in air %.3f px, behind a flat port %.3f px: ratio %.4f (n_water / n_air = 1.34)\n", du_air,
              du_port, du_port / du_air);
  EXPECT_NEAR(du_air, 1000.0 * 0.25 / 5.0, 0.2);
  EXPECT_NEAR(du_port / du_air, 1.34, 0.01);
  // The frame reports the water-side model: focal length x 1.34, pincushion (k1 > 0).
  EXPECT_NEAR(fp.K(0, 0), 1.34 * 1000.0, 1e-6 * 1000.0);
  EXPECT_GT(fp.D[0], 0.0);
}

TEST(CameraOptics, WaterEquivalentModelPredictsFarOffAxisPixels) {
  // Markers up to ~25 deg off axis (in water) behind a flat port: where the reported K and
  // plumb_bob D (water_equivalent, fitted) put them, within 1 px (centroids of 0.1 m squares).
  CameraModel cam = forward_camera(320, 240, 200.0);
  cam.port.type = CameraPort::Type::kFlat;
  for (const Eigen::Vector3d& p :
       {Eigen::Vector3d(4.0, 1.5, 0.0), Eigen::Vector3d(4.0, -1.2, 0.9), Eigen::Vector3d(4.0, 0.6, -0.7)}) {
    World w = empty_world();
    w.objects.push_back(marker(p, 0.1));
    Renderer r(w, {cam}, exact_options());
    const Frame f = r.render(Pose::Identity(), "cam");
    const Eigen::Vector3d pc = cam.X_BC.inverse() * p;
    std::vector<cv::Point3d> obj = {{pc.x(), pc.y(), pc.z()}};
    std::vector<cv::Point2d> img;
    cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) K.at<double>(i, j) = f.K(i, j);
    for (int k = 0; k < 5; ++k) D.at<double>(0, k) = f.D[k];
    cv::projectPoints(obj, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), K, D, img);
    const Eigen::Vector2d c = centroid(f);
    EXPECT_NEAR(c.x(), img[0].x, 1.0) << p.transpose();
    EXPECT_NEAR(c.y(), img[0].y, 1.0) << p.transpose();
  }
}

TEST(CameraOptics, FlatPortRendersACroppedFieldAndKeepsItsBorder) {
  // Behind a flat port the field narrows (80 -> ~57 deg here), so the scene is rendered at the
  // water-side focal length over the output frame cropped to the rays its pixels see
  // (RenderTimings::internal_width/height). The crop must not cut what the border sees: a marker
  // placed where the reported model (K, D) puts a corner or edge-middle pixel covers that pixel
  // (the edge middles reach farthest out: the port's pincushion pulls the corners in).
  CameraModel cam = forward_camera(320, 240, 200.0);
  cam.port.type = CameraPort::Type::kFlat;
  Frame model;
  {
    Renderer r(empty_world(), {cam}, exact_options());
    model = r.render(Pose::Identity(), "cam");
    const RenderTimings t = r.last_timings();
    std::printf("flat port 320x240: internal image %dx%d\n", t.internal_width, t.internal_height);
    EXPECT_LT(t.internal_width, cam.width);
    EXPECT_LE(t.internal_height, cam.height);
  }
  cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) K.at<double>(i, j) = model.K(i, j);
  for (int k = 0; k < 5; ++k) D.at<double>(0, k) = model.D[k];
  for (const cv::Point2f px :
       {cv::Point2f(1, 1), cv::Point2f(318, 1), cv::Point2f(1, 238), cv::Point2f(318, 238), cv::Point2f(1, 120),
        cv::Point2f(318, 120), cv::Point2f(160, 1), cv::Point2f(160, 238)}) {
    std::vector<cv::Point2f> in = {px}, ray;
    cv::undistortPoints(in, ray, K, D);
    // Camera optical (x right, y down, z forward) -> body (x forward, y right, z down): 4 m ahead.
    const Eigen::Vector3d p_body = cam.X_BC * (4.0 * Eigen::Vector3d(ray[0].x, ray[0].y, 1.0));
    World w = empty_world();
    w.objects.push_back(marker(p_body, 0.25));  // ~17 px wide: the model's ~1 px error is far inside
    Renderer r(w, {cam}, exact_options());
    const Frame f = r.render(Pose::Identity(), "cam");
    const auto u = static_cast<std::size_t>(px.x), v = static_cast<std::size_t>(px.y);
    EXPECT_EQ(f.seg[v * 320 + u], static_cast<std::uint8_t>(SegClass::kOther)) << "border pixel " << px;
  }
}

namespace {
// Green levels (linear 8-bit) of a grey wall 10 m ahead with a dark 2 m square on it, direct signal
// only, forward scattering at `per_m` with a blur of `rad_px` pixels at 10 m.
std::vector<double> wall_levels(double range, double per_m, double rad_px, int* square_px) {
  World w = empty_world();
  w.water.B_inf.setZero();
  w.water.beta_D.setConstant(0.01);  // nearly clear: the wall's brightness nearly uniform
  w.water.K_d.setConstant(0.01);
  w.water.forward_scatter_per_m = per_m;
  CameraModel cam = forward_camera(160, 120, 120.0);
  cam.exposure = 12.0;
  w.water.forward_blur_rad_per_m = rad_px / (cam.fx * 10.0);
  Object wall = marker({range, 0.0, 5.0}, 40.0);  // on the axis of the camera at 5 m depth
  Object square = marker({range - 0.05, 0.0, 5.0}, 2.0 * range / 10.0);
  square.material.albedo = {0.02, 0.02, 0.02};
  w.objects = {wall, square};
  RenderOptions o = exact_options();
  o.forward_scatter = true;
  Renderer r(w, {cam}, o);
  const Frame f = r.render(body_at({0.0, 0.0, 5.0}), "cam");
  std::vector<double> g;
  for (std::size_t i = 1; i < f.rgb.size(); i += 3) g.push_back(f.rgb[i]);
  if (square_px) *square_px = static_cast<int>(std::lround(cam.fx * 2.0 / 10.0));
  return g;
}
}  // namespace

TEST(CameraOptics, ForwardScatterSpreadsTheDirectSignalAndKeepsIt) {
  // A share 1 - exp(-f z) of the direct signal spreads over a disc growing with range. A grey wall
  // at 10 m with a dark 24 px square on it, f = 0.1 / m (63 % scattered), 8 px radius there:
  //  - the mean over the image is kept (box means of a wall that fills the view; measured 0.1 %): 1 %;
  //  - the square's edge, a 1 px step without scattering, spreads: the row through its centre
  //    takes >= 4 px from 10 % to 90 % of the step;
  //  - the wall far from the square is unchanged (+-1 level; nearly clear water keeps it nearly
  //    uniform, as a blur of a curved profile would not be): > 32 px away (the 16 x 16 means are
  //    read bilinearly: a block's mean reaches 16 px beyond it) and 16 px inside the image (its
  //    edges clamp);
  //  - at 1 m the disc is under a pixel: the same image as without scattering (+-1 level).
  int sq = 0;
  const auto sharp = wall_levels(10.0, 0.0, 8.0, &sq);
  const auto blurred = wall_levels(10.0, 0.1, 8.0, nullptr);
  double m0 = 0.0, m1 = 0.0;
  for (std::size_t i = 0; i < sharp.size(); ++i) {
    m0 += sharp[i];
    m1 += blurred[i];
  }
  const std::size_t row = std::size_t{60} * 160;
  const double lo = sharp[row + 80], hi = sharp[row + 10];
  ASSERT_GT(hi, 80.0) << "the wall is too dark to measure: " << hi;
  ASSERT_LT(hi, 230.0) << "the wall is too bright: " << hi;
  ASSERT_LT(lo, 0.2 * hi);
  auto width_10_90 = [&](const std::vector<double>& g) {  // left edge of the square, along the row
    int a = -1, b = -1;
    for (int u = 80; u >= 0; --u) {
      const double x = (g[row + static_cast<std::size_t>(u)] - lo) / (hi - lo);
      if (b < 0 && x >= 0.1) b = u;
      if (a < 0 && x >= 0.9) a = u;
    }
    return b - a;
  };
  const int w_sharp = width_10_90(sharp), w_blur = width_10_90(blurred);
  double far_worst = 0.0;
  for (int v = 16; v < 120 - 16; ++v)
    for (int u = 16; u < 160 - 16; ++u)
      if (std::abs(u - 80) > sq / 2 + 32 || std::abs(v - 60) > sq / 2 + 32) {
        const std::size_t i = static_cast<std::size_t>(v) * 160 + static_cast<std::size_t>(u);
        far_worst = std::max(far_worst, std::abs(blurred[i] - sharp[i]));
      }
  const auto near_sharp = wall_levels(1.0, 0.0, 8.0, nullptr), near_blur = wall_levels(1.0, 0.1, 8.0, nullptr);
  double near_worst = 0.0;
  for (std::size_t i = 0; i < near_sharp.size(); ++i)
    near_worst = std::max(near_worst, std::abs(near_blur[i] - near_sharp[i]));
  std::printf(
      "forward scatter: mean %.2f -> %.2f, edge 10-90 %% %d px -> %d px, far wall worst %.0f, at 1 m worst %.0f\n",
      m0 / sharp.size(), m1 / sharp.size(), w_sharp, w_blur, far_worst, near_worst);
  EXPECT_NEAR(m1 / m0, 1.0, 0.01);
  EXPECT_LE(w_sharp, 2);
  EXPECT_GE(w_blur, 4);
  EXPECT_LE(far_worst, 1.0);
  EXPECT_LE(near_worst, 1.0);
}

TEST(CameraOptics, VignettingFollowsCosFourOfTheFieldAngle) {
  // Water only (veiling light everywhere, no noise, linear 8-bit): the image with full
  // vignetting over the one without is cos^4 of each pixel's field angle. 8-bit quantisation
  // of levels ~0.5: +-0.01 on the ratio.
  CameraModel cam = forward_camera(160, 120, 80.0);  // 90 x 73 deg
  cam.exposure = 2.0;
  CameraModel vig = cam;
  vig.vignetting = 1.0;
  Renderer r(empty_world(), {cam}, exact_options());
  Renderer rv(empty_world(), {vig}, exact_options());
  const Frame a = r.render(body_at({0, 0, 5.0}), "cam");
  const Frame b = rv.render(body_at({0, 0, 5.0}), "cam");
  double worst = 0.0;
  for (int v = 0; v < cam.height; v += 7)
    for (int u = 0; u < cam.width; u += 7) {
      const std::size_t i = 3 * (static_cast<std::size_t>(v) * 160 + static_cast<std::size_t>(u)) + 1;  // green
      ASSERT_GT(a.rgb[i], 40) << "too dark to measure";
      const double x = (u - cam.cx) / cam.fx, y = (v - cam.cy) / cam.fy;
      const double cos4 = 1.0 / ((1.0 + x * x + y * y) * (1.0 + x * x + y * y));
      const double ratio = static_cast<double>(b.rgb[i]) / a.rgb[i];
      worst = std::max(worst, std::abs(ratio - cos4));
      EXPECT_NEAR(ratio, cos4, 0.012) << u << "," << v;
    }
  std::printf("vignetting: worst |ratio - cos^4| %.4f (corner cos^4 = %.3f)\n", worst,
              1.0 / std::pow(1.0 + std::pow(79.5 / 80, 2) + std::pow(59.5 / 80, 2), 2));
}

TEST(CameraOptics, ShotNoiseStdGrowsAsTheSquareRootOfTheSignal) {
  // Shot noise only (read noise 0): the noisy minus the clean image has standard deviation
  // sqrt(shot I) at linear level I. Two exposures: the std ratio is sqrt of the level ratio.
  // ~19000 samples each: the std is known to ~1%; quantisation adds 1/255/sqrt(12): 5% bound.
  for (const double exposure : {0.8, 2.4}) {
    CameraModel cam = forward_camera(160, 120, 120.0);
    cam.exposure = exposure;
    cam.shot_noise = 0.004;
    const auto [c, n] = clean_and_noisy(cam);
    double s2 = 0.0, level = 0.0;
    std::size_t count = 0;
    for (std::size_t i = 1; i < c.rgb.size(); i += 3) {  // green
      const double d = (static_cast<double>(n.rgb[i]) - c.rgb[i]) / 255.0;
      s2 += d * d;
      level += c.rgb[i] / 255.0;
      ++count;
    }
    const double std_meas = std::sqrt(s2 / count), mean_level = level / count;
    const double expected = std::sqrt(0.004 * mean_level);
    std::printf("shot noise at level %.3f: std %.4f, sqrt(shot I) %.4f\n", mean_level, std_meas, expected);
    ASSERT_LT(mean_level + 3 * expected, 0.8);  // below the encoder's shoulder: linear
    EXPECT_NEAR(std_meas / expected, 1.0, 0.05);
  }
}

TEST(CameraOptics, ReadNoiseIsGaussianAndIndependent) {
  // Read noise only (shot 0), linear 8-bit, water: green and blue levels 71..162, over 9 sigma
  // from black and white (red, near black, is clamped there and left out). The noisy minus the
  // clean image over 38400 samples has
  //  - standard deviation noise_stddev (estimate to 0.4 %; 8-bit rounding adds 1/12 level^2,
  //    +0.07 %): 2 % bound;
  //  - mean 0 (+-0.04 level expected): 0.15 level bound;
  //  - a normal shape: kurtosis 3 (its estimate +-0.025; a sum of 4 uniforms would give 2.7, a
  //    uniform 1.8) and the share beyond 3 sigma: differences are whole levels, so those beyond
  //    22.95 levels are the ones beyond 22.5 before rounding (2.94 sigma): 0.33 % (127 +-11
  //    samples): [0.22 %, 0.44 %];
  //  - no correlation between neighbouring pixels or between the two channels (|r| < 0.03; the
  //    estimate is +-0.005 for independent samples).
  CameraModel cam = forward_camera(160, 120, 120.0);
  cam.exposure = 2.5;
  cam.noise_stddev = 0.03;
  const auto [c, n] = clean_and_noisy(cam);
  const std::size_t npx = c.rgb.size() / 3;
  std::vector<double> d[2];  // green, blue
  double mean = 0.0;
  int lo = 255, hi = 0;
  for (std::size_t ch = 0; ch < 2; ++ch)
    for (std::size_t p = 0; p < npx; ++p) {
      const std::size_t i = 3 * p + 1 + ch;
      ASSERT_GT(c.rgb[i], 60) << "too dark: the clamp at black would cut the noise";
      ASSERT_LT(c.rgb[i], 200) << "too bright: the clamp at white would cut the noise";
      lo = std::min<int>(lo, c.rgb[i]);
      hi = std::max<int>(hi, c.rgb[i]);
      d[ch].push_back(static_cast<double>(n.rgb[i]) - c.rgb[i]);
      mean += d[ch].back();
    }
  mean /= 2.0 * static_cast<double>(npx);
  const double sigma = 0.03 * 255.0;  // levels
  double m2 = 0.0, m4 = 0.0;
  std::size_t tail = 0;
  for (const auto& dc : d)
    for (const double x : dc) {
      m2 += x * x;
      m4 += x * x * x * x;
      tail += std::abs(x) > 3.0 * sigma ? 1 : 0;
    }
  m2 /= 2.0 * static_cast<double>(npx);
  m4 /= 2.0 * static_cast<double>(npx);
  const double kurtosis = m4 / (m2 * m2), tail_share = static_cast<double>(tail) / (2.0 * static_cast<double>(npx));
  auto corr = [&](const std::vector<double>& a, const std::vector<double>& b, std::size_t step) {  // a[i], b[i + step]
    double sxy = 0.0;
    for (std::size_t i = 0; i + step < a.size(); ++i) sxy += a[i] * b[i + step];
    return sxy / static_cast<double>(a.size() - step) / m2;
  };
  const double r_channel = corr(d[0], d[1], 0), r_pixel = corr(d[0], d[0], 1), r_row = corr(d[1], d[1], 160);
  std::printf(
      "read noise: std %.3f levels (expected %.3f), mean %.3f, kurtosis %.3f, beyond 3 sigma %.3f %%, "
      "r channel %.4f pixel %.4f row %.4f; clean levels %d..%d\n",
      std::sqrt(m2), sigma, mean, kurtosis, 100.0 * tail_share, r_channel, r_pixel, r_row, lo, hi);
  EXPECT_NEAR(std::sqrt(m2) / sigma, 1.0, 0.02);
  EXPECT_NEAR(mean, 0.0, 0.15);
  EXPECT_NEAR(kurtosis, 3.0, 0.1);
  EXPECT_GT(tail_share, 0.0022);
  EXPECT_LT(tail_share, 0.0044);
  EXPECT_LT(std::abs(r_channel), 0.03);
  EXPECT_LT(std::abs(r_pixel), 0.03);
  EXPECT_LT(std::abs(r_row), 0.03);
}

TEST(CameraOptics, CentredDomeChangesNothingAndBadPortsAreErrors) {
  CameraModel cam = forward_camera(160, 120, 120.0);
  CameraModel dome = cam;
  dome.port.type = CameraPort::Type::kDome;
  dome.port.dome_radius_m = 0.05;
  const CameraModel eq = dome.water_equivalent();
  EXPECT_NEAR(eq.fx, cam.fx, 1e-6);
  EXPECT_LT(eq.distortion.cwiseAbs().maxCoeff(), 1e-6);
  CameraModel bad = cam;
  bad.port.type = CameraPort::Type::kFlat;
  bad.port.glass_thickness_m = -0.01;
  EXPECT_THROW(Renderer(empty_world(), {bad}, exact_options()), ConfigError);
}

namespace {

// A camera looking straight up (optical axis = -z of world_ned) on a level body.
CameraModel up_camera(int w, int h, double f) {
  CameraModel c = forward_camera(w, h, f);
  c.X_BC.linear() = rotation_from_rpy(0.0, M_PI / 2, 0.0) * R_camera_body_to_optical();
  return c;
}

// Zenith angle [rad] of pixel (u, v)'s ray for up_camera().
double zenith_angle(const CameraModel& c, double u, double v) {
  const double x = (u - c.cx) / c.fx, y = (v - c.cy) / c.fy;
  return std::atan(std::sqrt(x * x + y * y));
}

}  // namespace

TEST(CameraOptics, SnellsWindowEndsAtTheCriticalAngle) {
  // Looking straight up from 5 m: water rays closer to the zenith than asin(1 / n) = 48.27 deg
  // (n = 1.34) see the sky through the surface, the others are totally reflected and show only
  // the veiling light, exactly as without the window. The transmittance falls to 0 at the
  // critical angle, so the edge is bracketed: brighter 2 deg inside it, identical 0.5 deg outside.
  World w = empty_world();
  w.sun.direction_W = Eigen::Vector3d(std::sin(0.5), 0.0, std::cos(0.5));  // no glint near the edge row
  const CameraModel cam = up_camera(321, 41, 80.0);                        // 127 deg across
  RenderOptions off = exact_options();
  off.snell_window = false;
  Renderer on_r(w, {cam}, exact_options());
  Renderer off_r(w, {cam}, off);
  const Frame a = on_r.render(body_at({0, 0, 5.0}), "cam");
  const Frame b = off_r.render(body_at({0, 0, 5.0}), "cam");
  const double critical = std::asin(1.0 / 1.34);
  int inside = 0, outside = 0;
  double edge_in = 0.0, edge_out = M_PI;
  for (int u = 0; u < cam.width; ++u) {
    const double theta = zenith_angle(cam, u, 20);
    const std::size_t i = 3 * (static_cast<std::size_t>(20) * cam.width + static_cast<std::size_t>(u)) + 1;  // green
    if (a.rgb[i] > b.rgb[i]) edge_in = std::max(edge_in, theta);
    if (a.rgb[i] == b.rgb[i]) edge_out = std::min(edge_out, theta);
    if (theta < critical - 2.0 * M_PI / 180) {
      EXPECT_GT(a.rgb[i], b.rgb[i] + 2) << "inside the window at " << theta * 180 / M_PI << " deg";
      ++inside;
    } else if (theta > critical + 0.5 * M_PI / 180) {
      EXPECT_EQ(a.rgb[i], b.rgb[i]) << "beyond the window at " << theta * 180 / M_PI << " deg";
      ++outside;
    }
  }
  EXPECT_GT(inside, 100);
  EXPECT_GT(outside, 40);
  std::printf("Snell's window: brighter up to %.2f deg, unchanged from %.2f deg (critical angle %.2f deg)\n",
              edge_in * 180 / M_PI, edge_out * 180 / M_PI, critical * 180 / M_PI);
}

TEST(CameraOptics, SnellsWindowCentreIsTheSkyAttenuatedOverTheDepth) {
  // No veiling light (B_inf = 0), linear output, gain 1: the zenith pixel is the sky radiance
  // through the window, n^2 x ambient x E0 (radiance n^2 law; Fresnel normalised at the zenith),
  // attenuated over the depth, exp(-beta_D d) per channel (Beer-Lambert). 8-bit: +-1 level.
  World w = empty_world();
  w.sun.direction_W = Eigen::Vector3d(std::sin(0.6), 0.0, std::cos(0.6));  // glint 34 deg away
  w.water.B_inf = Eigen::Vector3d::Zero();
  w.water.beta_D = Eigen::Vector3d(0.3, 0.1, 0.05);
  const CameraModel cam = up_camera(41, 41, 40.0);
  Renderer r(w, {cam}, exact_options());
  for (double depth : {2.0, 6.0}) {
    const Frame f = r.render(body_at({0, 0, depth}), "cam");
    const std::size_t i = 3 * (static_cast<std::size_t>(20) * cam.width + 20);
    for (int k = 0; k < 3; ++k) {
      const double expected = 1.34 * 1.34 * w.sun.ambient_fraction * std::exp(-w.water.beta_D[k] * depth);
      EXPECT_NEAR(f.rgb[i + k], std::min(255.0, 255.0 * expected), 1.0) << "channel " << k << " at " << depth << " m";
    }
    std::printf("zenith at %.0f m: rgb %d %d %d\n", depth, f.rgb[i], f.rgb[i + 1], f.rgb[i + 2]);
  }
}

namespace {

// A floor (albedo 0.2) 10 m deep, with a bright tile (albedo 1) lying on it; sun overhead, no
// veiling light: the image is the direct signal only.
World floor_with_tile(bool tile) {
  World w = empty_world();
  w.water.B_inf.setZero();
  Object f = unav::renderer::test::floor_object(10.0, 40.0);
  f.material.albedo = {0.2, 0.2, 0.2};
  w.objects.push_back(f);
  if (tile) {
    Object t = f;
    t.name = "tile";
    t.shape = "box";
    t.size_m = {0.3, 0.3, 0.01};
    t.X_WO = pose_from_xyz_rpy({0.0, 0.0, 9.995}, {0.0, 0.0, 0.0});
    t.seg_class = SegClass::kOther;
    t.material.albedo = {1.0, 1.0, 1.0};
    w.objects.push_back(t);
  }
  return w;
}

// Sum and centroid of the tile's light: the green level above the floor-only image's.
struct Excess {
  double sum = 0.0;
  Eigen::Vector2d centroid = Eigen::Vector2d::Zero();
};
Excess excess_light(const Frame& f, const Frame& floor_only) {
  Excess e;
  for (int v = 0; v < f.height; ++v)
    for (int u = 0; u < f.width; ++u) {
      const std::size_t i = 3 * (static_cast<std::size_t>(v) * f.width + static_cast<std::size_t>(u)) + 1;
      const double x = static_cast<double>(f.rgb[i]) - static_cast<double>(floor_only.rgb[i]);
      e.sum += x;
      e.centroid += x * Eigen::Vector2d(u, v);
    }
  e.centroid /= std::max(e.sum, 1e-9);
  return e;
}

}  // namespace

TEST(CameraOptics, MotionBlurSmearsOverTheExposureAndKeepsTheLight) {
  // A down camera 2 m over a flat floor moving at 1 m/s forward and 0.4 m/s sideways, exposure
  // 0.2 s (the image moves fx 0.215 m / 2 m = 7.7 px): every point of the floor moves alike, so the blurred frame is
  // the sharp frame averaged over the exposure. Its light is conserved (sum within 1 %), its
  // centroid lies halfway between the sharp frames at the shutter's opening and at the stamp
  // (within 0.3 px), and the segmentation stays the stamp's. Without velocity nothing changes.
  CameraModel cam = CameraModel::from_hfov("down", 120, 120, 80.0 * M_PI / 180.0);
  cam.X_BC.linear() = rotation_from_rpy(0.0, -M_PI / 2, 0.0) * R_camera_body_to_optical();
  cam.exposure_time_s = 0.2;
  Renderer r(floor_with_tile(true), {cam}, exact_options());
  Renderer r0(floor_with_tile(false), {cam}, exact_options());
  const Eigen::Vector3d p_W(0.05, -0.03, 8.0);
  BodyVelocity vel;
  vel.linear = {1.0, 0.4, 0.0};
  const Pose at_stamp = body_at(p_W), at_opening = body_at(p_W - cam.exposure_time_s * vel.linear);
  const Frame sharp = r.render(at_stamp, "down");
  const Frame blurred = r.render(at_stamp, "down", 0.0, vel);
  const Excess s = excess_light(sharp, r0.render(at_stamp, "down"));
  const Excess o = excess_light(r.render(at_opening, "down"), r0.render(at_opening, "down"));
  const Excess b = excess_light(blurred, r0.render(at_stamp, "down", 0.0, vel));
  const Eigen::Vector2d halfway = 0.5 * (s.centroid + o.centroid);
  std::printf("motion blur: image moved %.2f px; blurred centroid %.2f px from halfway; light %.4f of the sharp\n",
              (s.centroid - o.centroid).norm(), (b.centroid - halfway).norm(), b.sum / s.sum);
  EXPECT_NEAR((s.centroid - o.centroid).norm(), 71.5 * 0.2 * std::sqrt(1.16) / 1.995, 0.3);
  EXPECT_LT((b.centroid - halfway).norm(), 0.3);
  EXPECT_NEAR(b.sum / s.sum, 1.0, 0.01);
  EXPECT_EQ(blurred.seg, sharp.seg);
  const Frame still = r.render(body_at(p_W), "down", 0.0, BodyVelocity{});
  EXPECT_EQ(still.rgb, sharp.rgb);
}

TEST(CameraOptics, DistortedImageIsThePinholeImageResampled) {
  // A lens with distortion images the same radiance as the ideal pinhole with its K: each output
  // pixel is the pinhole image at the undistorted point OpenCV gives for it (bilinear), its class
  // and depth those of the nearest pinhole pixel. A floor seen at a slant (a smooth gradient),
  // water above its edge and a marker give surfaces, water and silhouettes; the comparison skips
  // pixels whose 2 x 2 bilinear neighbourhood spans two classes (an edge is no smooth function to
  // interpolate). Both images are 8-bit linear (no shoulder below 0.8): a bilinear mean of rounded
  // levels is within 1 level of the rounded value, +1 for float rounding of the two renders.
  World w = empty_world();
  Object f = unav::renderer::test::floor_object(3.0, 30.0);
  f.X_WO.translation().x() = 14.0;  // its near edge 1 m ahead: water beyond its far edge, 29 m out
  w.objects.push_back(f);
  w.objects.push_back(marker({4.0, 0.4, 1.2}, 0.6));
  CameraModel pin = forward_camera(160, 120, 90.0);
  pin.exposure = 1.5;
  CameraModel dist = pin;
  dist.name = "dist";
  dist.distortion << -0.25, 0.06, 0.002, -0.001, 0.0;
  RenderOptions o = exact_options();
  o.shadows = false;  // (this 30 m two-triangle plane shows sun-shadow acne streaks far off at grazing view)
  Renderer r(w, {pin, dist}, o);
  const Pose X_WB = pose_from_xyz_rpy({0.0, 0.0, 1.0}, {0.0, -0.35, 0.0});  // pitched down 20 deg
  const Frame a = r.render(X_WB, "cam");
  const Frame b = r.render(X_WB, "dist");
  std::vector<cv::Point2f> px, q;
  for (int v = 0; v < dist.height; ++v)
    for (int u = 0; u < dist.width; ++u) px.emplace_back(static_cast<float>(u), static_cast<float>(v));
  cv::Mat K = (cv::Mat_<double>(3, 3) << dist.fx, 0, dist.cx, 0, dist.fy, dist.cy, 0, 0, 1);
  cv::Mat D(1, 5, CV_64F);
  for (int k = 0; k < 5; ++k) D.at<double>(0, k) = dist.distortion[k];
  cv::undistortPoints(px, q, K, D, cv::noArray(), K,
                      cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 30, 1e-6));
  const int W = pin.width, H = pin.height;
  const auto at = [W](int u, int v) { return static_cast<std::size_t>(v) * static_cast<std::size_t>(W) + u; };
  std::size_t n = 0, classes[5] = {0, 0, 0, 0, 0};
  double sum = 0.0, worst = 0.0;
  for (int v = 0; v < dist.height; ++v)
    for (int u = 0; u < dist.width; ++u) {
      const cv::Point2f& p = q[at(u, v)];
      const int x0 = static_cast<int>(std::floor(p.x)), y0 = static_cast<int>(std::floor(p.y));
      if (x0 < 0 || y0 < 0 || x0 + 1 >= W || y0 + 1 >= H) continue;  // the pinhole does not see it
      const std::uint8_t s = a.seg[at(x0, y0)];
      if (a.seg[at(x0 + 1, y0)] != s || a.seg[at(x0, y0 + 1)] != s || a.seg[at(x0 + 1, y0 + 1)] != s) continue;
      const std::size_t i = at(u, v);
      ASSERT_EQ(b.seg[i], s) << u << "," << v;
      const std::size_t nearest = at(static_cast<int>(std::lround(p.x)), static_cast<int>(std::lround(p.y)));
      if (s != 0)
        EXPECT_NEAR(b.depth[i], a.depth[nearest], 1e-5 * a.depth[nearest]) << u << "," << v;
      else
        EXPECT_TRUE(std::isinf(b.depth[i])) << u << "," << v;
      const double fx = p.x - x0, fy = p.y - y0;
      for (int ch = 0; ch < 3; ++ch) {
        const auto c = [&](int x, int y) { return static_cast<double>(a.rgb[3 * at(x, y) + ch]); };
        const double expect = (1 - fy) * ((1 - fx) * c(x0, y0) + fx * c(x0 + 1, y0)) +
                              fy * ((1 - fx) * c(x0, y0 + 1) + fx * c(x0 + 1, y0 + 1));
        const double d = std::abs(b.rgb[3 * i + ch] - expect);
        worst = std::max(worst, d);
        sum += d;
        EXPECT_LE(d, 2.0) << u << "," << v << " channel " << ch;
      }
      ++n;
      ++classes[s];
    }
  std::printf(
      "distorted vs resampled pinhole: %zu pixels (water %zu, floor %zu, marker %zu), mean |diff| %.3f, "
      "worst %.2f levels\n",
      n, classes[0], classes[1], classes[4], sum / (3.0 * static_cast<double>(std::max<std::size_t>(n, 1))), worst);
  // Every kind of pixel took part, and most of the frame did.
  EXPECT_GT(classes[0], 1000u);
  EXPECT_GT(classes[1], 1000u);
  EXPECT_GT(classes[4], 100u);
  EXPECT_GT(n, static_cast<std::size_t>(dist.width * dist.height) / 2);
  EXPECT_LT(sum / (3.0 * static_cast<double>(n)), 0.5);
}
