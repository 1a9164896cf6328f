// Sonar simulation on Mesa llvmpipe (headless EGL): analytic geometry and echo-level laws.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "render_test_util.hpp"
#include "unav_renderer/errors.hpp"
#include "unav_renderer/sonar_renderer.hpp"
#include "unav_renderer/sonar_speckle.hpp"
#include "unav_scene/scene_geometry.hpp"

using namespace unav::renderer;
using namespace unav::scene;  // NOLINT(google-build-using-namespace): World, SonarModel, Pose, ...

namespace {

constexpr double kDeg = M_PI / 180.0;

World flat_world(double seabed_depth_m) {
  World w;
  w.name = "sonar_test";
  w.file = "<test world>";
  w.seabed.enabled = seabed_depth_m > 0.0;
  w.seabed.depth_m = seabed_depth_m;
  w.seabed.size_m = {120.0, 120.0};
  w.seabed.resolution_m = 2.0;
  w.seabed.far_extent_m = 0.0;
  return w;
}

SonarModel fls(int beams, int bins, double h_deg, double v_deg, double r_min, double r_max) {
  SonarModel m;
  m.name = "fls";
  m.beams = beams;
  m.bins = bins;
  m.horizontal_aperture_rad = h_deg * kDeg;
  m.vertical_aperture_rad = v_deg * kDeg;
  m.min_range_m = r_min;
  m.max_range_m = r_max;
  m.ping_rate_hz = 1.0;
  return m;
}

SonarOptions exact() {
  SonarOptions o;
  o.noise = false;
  return o;
}

Pose body_at(const Eigen::Vector3d& p_W) {
  Pose X = Pose::Identity();
  X.translation() = p_W;
  return X;
}

// A large plane (two triangles) centred at p_W, facing -x (towards a sonar looking along +x),
// then yawed by yaw_rad about the vertical.
Object wall(const Eigen::Vector3d& p_W, double yaw_rad, double size_m) {
  Object o;
  o.name = "wall";
  o.shape = "plane";
  o.size_m = {size_m, size_m, 1.0};
  // The plane's normal is local -z; pitch +90 deg turns it to -x.
  o.X_WO = pose_from_xyz_rpy(p_W, {0.0, M_PI / 2, yaw_rad});
  o.seg_class = SegClass::kOther;
  return o;
}

double beam_energy(const SonarPing& p, int beam) {
  double e = 0.0;
  const double dr = p.ranges_m[1] - p.ranges_m[0];
  for (int b = 0; b < p.bins; ++b) e += p.at(b, beam) * dr;
  return e;
}

int first_bin_above(const SonarPing& p, int beam, double threshold) {
  for (int b = 0; b < p.bins; ++b)
    if (p.at(b, beam) > threshold) return b;
  return -1;
}

}  // namespace

TEST(Sonar, FlatSeabedFirstReturnAtGeometricRangeInEveryBeam) {
  // Sonar 2 m above a flat seabed, tilted 20 deg down. The first return of beam k comes from the
  // steepest ray of the beam: min over its azimuths and elevations of altitude / (ray's down
  // component). Rendered within one range bin of that in every beam.
  const double altitude = 2.0, tilt = 20.0 * kDeg;
  SonarModel m = fls(64, 256, 120.0, 20.0, 0.5, 15.0);
  m.X_BH = pose_from_xyz_rpy(Eigen::Vector3d::Zero(), {0.0, -tilt, 0.0});
  SonarRenderer sr(flat_world(10.0), {m}, exact());
  const Pose X_WB = body_at({0.0, 0.0, 10.0 - altitude});
  const SonarPing p = sr.ping(X_WB, "fls");
  ASSERT_EQ(p.channels, 64);
  ASSERT_EQ(p.bins, 256);
  const Eigen::Matrix3d R_WH = (X_WB * m.X_BH).linear();
  const double beam_w = m.horizontal_aperture_rad / m.beams;
  for (int k = 0; k < m.beams; ++k) {
    double r_first = 1e9;
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j <= 200; ++j) {
        const double az = m.beam_azimuth_rad(k) + (i / 40.0 - 0.5) * beam_w;
        const double el = (j / 200.0 - 0.5) * m.vertical_aperture_rad;
        const Eigen::Vector3d d_H(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el));
        const double down = (R_WH * d_H).z();
        if (down > 1e-6) r_first = std::min(r_first, altitude / down);
      }
    const int expected = static_cast<int>(std::floor((r_first - m.min_range_m) / m.bin_width_m()));
    double peak = 0.0;
    for (int b = 0; b < p.bins; ++b) peak = std::max(peak, static_cast<double>(p.at(b, k)));
    const int got = first_bin_above(p, k, 1e-3 * peak);
    EXPECT_NEAR(got, expected, 1) << "beam " << k << ", expected range " << r_first << " m";
  }
}

// A profiling sonar looking straight down, its 120 deg fan across track, 2 m above a flat seabed:
// beam k's return is at the slant range 2 / cos(az_k) (within the range its 1.9 deg beam spans
// over the flat bottom, and a bin), its point lies on the seabed in the world (same tolerance),
// and from 15 m up only the beams that reach the seabed within 20 m (|az| < 41.4 deg, give or take
// the half beam width at the edge) return.
TEST(Sonar, ProfilerRangesAFlatSeabedAcrossTrack) {
  SonarModel m = fls(64, 512, 120.0, 3.0, 0.3, 20.0);
  m.name = "profiler";
  m.type = SonarModel::Type::kProfiling;
  m.X_BH = pose_from_xyz_rpy(Eigen::Vector3d::Zero(), {0.0, -M_PI / 2, 0.0});
  SonarRenderer sr(flat_world(10.0), {m}, exact());
  const double half_beam = 0.5 * m.horizontal_aperture_rad / m.beams;
  for (const double altitude : {2.0, 15.0}) {
    const SonarPing p = sr.ping(body_at({0.0, 0.0, 10.0 - altitude}), "profiler");
    const auto points = detect_profile(p, m.detection_db);
    // Beams whose centre reaches the seabed within range return; so may those whose inner edge does.
    int centre = 0, edge = 0;
    for (int k = 0; k < m.beams; ++k) {
      const double az = std::abs(m.beam_azimuth_rad(k));
      centre += altitude / std::cos(az) < 19.9 ? 1 : 0;
      edge += altitude / std::cos(std::max(0.0, az - half_beam)) < 20.0 ? 1 : 0;
    }
    EXPECT_GE(static_cast<int>(points.size()), centre) << "altitude " << altitude;
    EXPECT_LE(static_cast<int>(points.size()), edge) << "altitude " << altitude;
    for (const auto& pt : points) {
      const double az = std::abs(p.azimuth_rad[static_cast<std::size_t>(pt.beam)]);
      const double spread = altitude * std::sin(az) / (std::cos(az) * std::cos(az)) * half_beam;  // d r / d az
      const double tol = spread + m.bin_width_m();
      EXPECT_NEAR(pt.range_m, altitude / std::cos(az), tol) << "beam " << pt.beam;
      const Eigen::Vector3d p_W = p.X_WS * pt.p_S;
      EXPECT_NEAR(p_W.z(), 10.0, tol) << "beam " << pt.beam;
      EXPECT_NEAR(p_W.x(), 0.0, 0.05 * altitude) << "beam " << pt.beam;  // the fan is across track
    }
  }
  SonarPing s;
  s.side_scan = true;
  EXPECT_THROW(detect_profile(s, 10.0), std::invalid_argument);
}

TEST(Sonar, NormalIncidenceReturnsMoreThanGrazing) {
  // Lambert's law: a surface returns mu cos^2(t) per unit area; the ensonified area of a solid
  // angle grows as 1 / cos(t), so a beam filled by a plane returns ~ cos(t). The same plane
  // yawed 70 deg about the beam's centre: ratio ~ 1 / cos(70 deg) = 2.92 (the incidence varies
  // by +-5 deg across this narrow beam: +-15% of the ratio at 70 deg; bounds 2.4..3.5).
  SonarModel m = fls(8, 400, 10.0, 10.0, 0.5, 12.0);
  World normal = flat_world(0.0), grazing = flat_world(0.0);
  normal.objects.push_back(wall({4.0, 0.0, 0.0}, 0.0, 40.0));
  grazing.objects.push_back(wall({4.0, 0.0, 0.0}, 70.0 * kDeg, 40.0));
  SonarRenderer sr(normal, {m}, exact());
  const double e_normal = beam_energy(sr.ping(Pose::Identity(), "fls"), 4);
  sr.set_world(grazing);
  const double e_grazing = beam_energy(sr.ping(Pose::Identity(), "fls"), 4);
  ASSERT_GT(e_grazing, 0.0);
  const double ratio = e_normal / e_grazing;
  std::printf("normal / grazing (70 deg) echo: %.3f (1 / cos 70 deg = 2.924)\n", ratio);
  EXPECT_GT(ratio, 2.4) << ratio;
  EXPECT_LT(ratio, 3.5) << ratio;
}

TEST(Sonar, EchoFallsWithRangeAsTheConfiguredSpreadingAndAbsorption) {
  // Without TVG, a plane at normal incidence filling the beam returns
  // E(R) ~ R^(2 - 2n) 10^(-alpha R / 5) (two-way spreading n, absorption alpha dB/m, area ~ R^2).
  // Across this 6 x 6 deg beam the ray ranges differ from R by < 0.3%: tolerance 2%.
  for (const double n : {2.0, 1.0}) {
    SonarModel m = fls(3, 600, 6.0, 6.0, 0.5, 10.0);
    m.tvg = false;
    m.spreading_exponent = n;
    m.frequency_hz = 1.2e6;  // ~0.4 dB/m: clearly measurable over 4 m
    World near_w = flat_world(0.0), far_w = flat_world(0.0);
    near_w.objects.push_back(wall({2.0, 0.0, 0.0}, 0.0, 20.0));
    far_w.objects.push_back(wall({6.0, 0.0, 0.0}, 0.0, 20.0));
    SonarRenderer sr(near_w, {m}, exact());
    const SonarPing p_near = sr.ping(Pose::Identity(), "fls");
    sr.set_world(far_w);
    const SonarPing p_far = sr.ping(Pose::Identity(), "fls");
    const double alpha = p_near.absorption_db_per_m;
    EXPECT_GT(alpha, 0.2);
    const double expected = std::pow(6.0 / 2.0, 2.0 - 2.0 * n) * std::pow(10.0, -alpha * (6.0 - 2.0) / 5.0);
    const double got = beam_energy(p_far, 1) / beam_energy(p_near, 1);
    std::printf("n = %.0f, alpha = %.3f dB/m: E(6 m) / E(2 m) = %.5f, law %.5f\n", n, alpha, got, expected);
    EXPECT_NEAR(got / expected, 1.0, 0.02) << "n = " << n << ": " << got << " vs " << expected;
  }
  // A 20 dB/decade TVG undoes this range law exactly (2 alpha r cancels the absorption): equal
  // echoes at both ranges. The default 30 dB/decade (seabed) makes the far plane 10 log10 3 =
  // 4.77 dB brighter.
  SonarModel m = fls(3, 600, 6.0, 6.0, 0.5, 10.0);
  m.tvg_db_per_decade = 20.0;
  World near_w = flat_world(0.0), far_w = flat_world(0.0);
  near_w.objects.push_back(wall({2.0, 0.0, 0.0}, 0.0, 20.0));
  far_w.objects.push_back(wall({6.0, 0.0, 0.0}, 0.0, 20.0));
  SonarRenderer sr(near_w, {m}, exact());
  const double e_near = beam_energy(sr.ping(Pose::Identity(), "fls"), 1);
  sr.set_world(far_w);
  EXPECT_NEAR(beam_energy(sr.ping(Pose::Identity(), "fls"), 1) / e_near, 1.0, 0.02);
  m.tvg_db_per_decade = 30.0;
  SonarRenderer sr30(near_w, {m}, exact());
  const double e30_near = beam_energy(sr30.ping(Pose::Identity(), "fls"), 1);
  sr30.set_world(far_w);
  EXPECT_NEAR(beam_energy(sr30.ping(Pose::Identity(), "fls"), 1) / e30_near, 3.0, 0.06);
}

TEST(Sonar, ObjectCastsAShadowOfTheRightAngularWidth) {
  // A level sonar 1.5 m above a flat seabed; a box 1 m wide and 4 m tall stands 6 m ahead
  // (front face at 5.8 m). Its vertical front edges are at azimuth +-atan(0.5 / 5.8) for every
  // elevation, so the seabed behind it (visible from 1.5 / sin(10 deg) = 8.6 m on) is dark over
  // 2 atan(0.5 / 5.8) = 9.86 deg. Beams are 0.47 deg wide; tolerance two beams (edge beams are
  // partly shadowed).
  SonarModel m = fls(128, 400, 60.0, 20.0, 0.5, 20.0);
  World w = flat_world(10.0);
  Object box;
  box.name = "box";
  box.shape = "box";
  box.size_m = {0.4, 1.0, 4.0};
  box.X_WO = pose_from_xyz_rpy({6.0, 0.0, 8.0}, {0.0, 0.0, 0.0});
  w.objects.push_back(box);
  SonarRenderer sr(w, {m}, exact());
  const SonarPing p = sr.ping(body_at({0.0, 0.0, 8.5}), "fls");
  std::vector<double> behind(static_cast<std::size_t>(m.beams), 0.0);
  for (int k = 0; k < m.beams; ++k)
    for (int b = 0; b < p.bins; ++b)
      if (p.ranges_m[static_cast<std::size_t>(b)] > 10.0 && p.ranges_m[static_cast<std::size_t>(b)] < 18.0)
        behind[static_cast<std::size_t>(k)] += p.at(b, k);
  std::vector<double> sorted = behind;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted[sorted.size() / 2];
  ASSERT_GT(median, 0.0);
  int dark = 0, first_dark = -1, last_dark = -1;
  for (int k = 0; k < m.beams; ++k)
    if (behind[static_cast<std::size_t>(k)] < 0.05 * median) {
      ++dark;
      if (first_dark < 0) first_dark = k;
      last_dark = k;
    }
  const double beam_w_deg = 60.0 / 128;
  std::printf("shadow: %d beams = %.2f deg (geometry %.2f deg), beams %d..%d\n", dark, dark * beam_w_deg,
              2.0 * std::atan(0.5 / 5.8) / kDeg, first_dark, last_dark);
  EXPECT_NEAR(dark * beam_w_deg, 2.0 * std::atan(0.5 / 5.8) / kDeg, 2.0 * beam_w_deg);
  EXPECT_EQ(last_dark - first_dark + 1, dark);             // one contiguous shadow ...
  EXPECT_NEAR(0.5 * (first_dark + last_dark), 63.5, 1.0);  // ... centred on the box
  // The box itself returns, in front of the shadow, in the central beams.
  const int front_bin = static_cast<int>((5.8 - m.min_range_m) / m.bin_width_m());
  EXPECT_GT(p.at(front_bin, 64) + p.at(front_bin + 1, 64), 0.0);
}

TEST(Sonar, BeamAndBinGeometryMatchTheConfig) {
  SonarModel m = fls(100, 300, 90.0, 15.0, 1.0, 31.0);
  World w = flat_world(10.0);
  w.water.temperature_c = 15.0;
  SonarRenderer sr(w, {m}, SonarOptions{});
  const SonarPing p = sr.ping(body_at({0.0, 0.0, 4.0}), "fls", 12.5);
  EXPECT_EQ(p.channels, 100);
  EXPECT_EQ(p.bins, 300);
  ASSERT_EQ(p.ranges_m.size(), 300u);
  ASSERT_EQ(p.azimuth_rad.size(), 100u);
  EXPECT_NEAR(p.ranges_m[0], 1.05, 1e-6);
  EXPECT_NEAR(p.ranges_m[299], 30.95, 1e-5);
  EXPECT_NEAR(p.azimuth_rad[0], -45.0 * kDeg + 0.45 * kDeg, 1e-6);
  EXPECT_NEAR(p.azimuth_rad[99], 45.0 * kDeg - 0.45 * kDeg, 1e-6);
  EXPECT_EQ(p.intensity.size(), 30000u);
  EXPECT_EQ(p.image.size(), 30000u);
  EXPECT_DOUBLE_EQ(p.stamp_s, 12.5);
  EXPECT_NEAR(p.sound_speed_mps, sound_speed_mackenzie(15.0, 35.0, 4.0), 1e-9);
  // The acoustic frame: z forward along the boresight, x up.
  EXPECT_TRUE(p.X_WS.linear().col(2).isApprox(Eigen::Vector3d(1, 0, 0)));
  EXPECT_TRUE(p.X_WS.linear().col(0).isApprox(Eigen::Vector3d(0, 0, -1)));
  // Same seed and sequence, same noise; the next ping differs.
  sr.set_next_sequence(0);
  const SonarPing a = sr.ping(body_at({0.0, 0.0, 4.0}), "fls");
  const SonarPing b = sr.ping(body_at({0.0, 0.0, 4.0}), "fls");
  sr.set_next_sequence(0);
  const SonarPing c = sr.ping(body_at({0.0, 0.0, 4.0}), "fls");
  EXPECT_EQ(a.image, c.image);
  EXPECT_NE(a.image, b.image);
  EXPECT_THROW(sr.ping(Pose::Identity(), "nope"), std::invalid_argument);
}

TEST(Sonar, SideScanFirstReturnsAndPipeShadowWhereGeometrySays) {
  // Side-scan 3 m above a flat seabed, beams depressed 20 deg with a 50 deg fan: the steepest
  // ray (45 deg) meets the seabed at 3 / sin 45 = 4.24 m on both sides. A pipe (radius 0.25 m)
  // lies on the seabed parallel to the track 6 m to starboard: the ray grazing its top
  // (0.5 m above the seabed) reaches the seabed at 6 * 3 / 2.5 = 7.2 m across track, slant
  // 7.8 m; from just behind the pipe to there the starboard side is dark, the port side not.
  SonarModel m = sonar_preset("sidescan_900k");
  m.name = "ss";
  m.bins = 600;
  m.min_range_m = 0.5;
  m.max_range_m = 12.5;
  m.ping_rate_hz = 1.0;
  World w = flat_world(10.0);
  Pipeline pipe;
  pipe.name = "pipe";
  pipe.radius_m = 0.25;
  pipe.points_W = {{-30.0, 6.0, 9.75}, {30.0, 6.0, 9.75}};
  build_centerline(&pipe);
  w.pipelines.push_back(pipe);
  SonarRenderer sr(w, {m}, exact());
  const SonarPing p = sr.ping(body_at({0.0, 0.0, 7.0}), "ss");
  ASSERT_TRUE(p.side_scan);
  ASSERT_EQ(p.channels, 2);
  const double expected_first = 3.0 / std::sin(45.0 * kDeg);
  for (int side = 0; side < 2; ++side) {
    double peak = 0.0;
    for (int b = 0; b < p.bins; ++b) peak = std::max(peak, static_cast<double>(p.at(b, side)));
    const int got = first_bin_above(p, side, 1e-3 * peak);
    std::printf("side-scan side %d: first return in bin %d, geometry %.2f\n", side, got,
                (expected_first - m.min_range_m) / m.bin_width_m());
    EXPECT_NEAR(got, (expected_first - m.min_range_m) / m.bin_width_m(), 1.0) << "side " << side;
  }
  auto bin_of = [&](double r) { return static_cast<int>((r - m.min_range_m) / m.bin_width_m()); };
  // Pipe far side: its silhouette ends at slant ~ sqrt(6.25^2 + 2.75^2) = 6.83 m.
  double port = 0.0, stbd = 0.0;
  for (int b = bin_of(7.0); b <= bin_of(7.6); ++b) {
    port += p.at(b, 0);
    stbd += p.at(b, 1);
  }
  EXPECT_GT(port, 0.0);
  std::printf("side-scan 7.0..7.6 m: port %.4g, starboard (pipe shadow) %.4g\n", port, stbd);
  EXPECT_LT(stbd, 0.01 * port) << "no shadow behind the pipe";
  // Beyond the shadow's end the starboard seabed returns again.
  double stbd_after = 0.0, port_after = 0.0;
  for (int b = bin_of(8.2); b <= bin_of(9.0); ++b) {
    stbd_after += p.at(b, 1);
    port_after += p.at(b, 0);
  }
  EXPECT_GT(stbd_after, 0.3 * port_after);
  // The pipe returns strongly (coated steel, higher mu and near-normal incidence) before it.
  double pipe_echo = 0.0, port_same = 0.0;
  for (int b = bin_of(6.3); b <= bin_of(6.8); ++b) {
    pipe_echo += p.at(b, 1);
    port_same += p.at(b, 0);
  }
  EXPECT_GT(pipe_echo, 3.0 * port_same);
}

TEST(Sonar, WaterfallAndFanImages) {
  SonarModel ss = sonar_preset("sidescan_900k");
  ss.name = "ss";
  ss.bins = 200;
  ss.max_range_m = 10.0;
  ss.ping_rate_hz = 1.0;
  SonarModel f = fls(64, 128, 120.0, 20.0, 0.5, 10.0);
  f.X_BH = pose_from_xyz_rpy(Eigen::Vector3d::Zero(), {0.0, -25.0 * kDeg, 0.0});
  SonarRenderer sr(flat_world(10.0), {f, ss}, SonarOptions{});
  Waterfall wf(200, 50);
  for (int i = 0; i < 5; ++i) wf.add(sr.ping(body_at({0.2 * i, 0.0, 7.0}), "ss"));
  EXPECT_EQ(wf.pings(), 5u);
  EXPECT_EQ(wf.width(), 400);
  // Rows below the 5 pings are still empty; the newest row has echoes on both halves.
  const auto& px = wf.pixels();
  EXPECT_EQ(*std::max_element(px.begin() + std::ptrdiff_t{400} * 6, px.end()), 0);
  EXPECT_GT(std::accumulate(px.begin(), px.begin() + 200, 0), 0);
  EXPECT_GT(std::accumulate(px.begin() + 200, px.begin() + 400, 0), 0);
  EXPECT_THROW(wf.add(sr.ping(Pose::Identity(), "fls")), std::invalid_argument);

  const FanImage fan = fan_image(sr.ping(body_at({0.0, 0.0, 7.0}), "fls"), 400);
  EXPECT_EQ(fan.width, 400);
  // 120 deg fan to 10 m: 2 * 10 sin 60 = 17.3 m wide, 10 m tall.
  EXPECT_NEAR(fan.metres_per_pixel, 2.0 * 10.0 * std::sin(60.0 * kDeg) / 400, 0.01);
  EXPECT_NEAR(fan.height, std::ceil(10.0 / fan.metres_per_pixel), 2);
  // Bottom corners are outside the fan; the centre column sees the seabed.
  EXPECT_EQ(fan.pixels[static_cast<std::size_t>(fan.height - 1) * 400], 0);
  int centre = 0;
  for (int v = 0; v < fan.height; ++v) centre += fan.pixels[static_cast<std::size_t>(v) * 400 + 200];
  EXPECT_GT(centre, 0);
}

TEST(Sonar, BadConfigIsAClearError) {
  SonarModel m = fls(0, 100, 60.0, 10.0, 0.5, 10.0);
  try {
    SonarRenderer sr(flat_world(10.0), {m}, exact());
    FAIL() << "zero beams accepted";
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("beams"), std::string::npos) << e.what();
  }
  m = fls(10, 100, 60.0, 10.0, 5.0, 5.0);
  EXPECT_THROW(SonarRenderer(flat_world(10.0), {m}, exact()), ConfigError);
  m = fls(10, 100, 200.0, 10.0, 0.5, 5.0);
  EXPECT_THROW(SonarRenderer(flat_world(10.0), {m}, exact()), ConfigError);
  m = fls(10, 100, 60.0, 10.0, 0.5, 5.0);
  EXPECT_THROW(SonarRenderer(flat_world(10.0), {m, m}, exact()), ConfigError);  // duplicate name
}

TEST(Sonar, MovedObjectEchoesAsIfPlacedThere) {
  // Another vehicle (a movable box) moved into the fan gives the ping a world built with it there
  // gives (noise off: every bin the same), and its echo and shadow leave with it when it moves out.
  SonarModel m = fls(64, 200, 60.0, 20.0, 0.5, 15.0);
  auto world_with = [](const Pose& at, bool movable) {
    World w = flat_world(10.0);
    w.objects.push_back(unav::renderer::test::vehicle_box("rov2", at, movable));
    return w;
  };
  const Pose away = pose_from_xyz_rpy({-30.0, 0.0, 9.0}, {0.0, 0.0, 0.0});
  const Pose ahead = pose_from_xyz_rpy({5.0, 0.5, 9.0}, {0.0, 0.0, 0.4});
  SonarRenderer sr(world_with(away, true), {m}, exact());
  const SonarPing empty = sr.ping(body_at({0.0, 0.0, 8.5}), "fls");
  sr.set_object_pose("rov2", ahead);
  const SonarPing seen = sr.ping(body_at({0.0, 0.0, 8.5}), "fls");
  SonarRenderer placed(world_with(ahead, false), {m}, exact());
  EXPECT_EQ(seen.intensity, placed.ping(body_at({0.0, 0.0, 8.5}), "fls").intensity);
  EXPECT_NE(seen.intensity, empty.intensity);
  sr.set_object_pose("rov2", away);
  EXPECT_EQ(sr.ping(body_at({0.0, 0.0, 8.5}), "fls").intensity, empty.intensity);
  EXPECT_THROW(sr.set_object_pose("rov3", ahead), ConfigError);
}

// Side lobes in a ping: a wall 6 m ahead fills the middle beams; with the side lobes on, the beams
// that see only water at that range hear it (the arc across the fan), exactly the envelope applied
// to the ping without them (noise off: intensity = echo), and the wall's own beams change by less
// than the leakage's share. Off by default: every other test here is the ping without them.
TEST(Sonar, SidelobesDrawTheArcOfAStrongEchoAcrossTheFan) {
  SonarModel m = fls(128, 200, 120.0, 10.0, 0.5, 10.0);
  World w = flat_world(0.0);
  w.objects.push_back(wall({6.0, 0.0, 0.0}, 0.0, 1.0));
  SonarRenderer off(w, {m}, exact());
  const SonarPing p0 = off.ping(Pose::Identity(), "fls");
  m.sidelobes = true;
  m.sidelobe_db = -25.0;
  SonarRenderer on(w, {m}, exact());
  const SonarPing p1 = on.ping(Pose::Identity(), "fls");
  ASSERT_EQ(p0.intensity.size(), p1.intensity.size());
  std::vector<double> want(p0.intensity.begin(), p0.intensity.end());
  unav::renderer::add_sidelobes(m.bins, m.beams, unav::renderer::sidelobe_kernel(m.beams, -25.0, 6.0), &want);
  // Float samples (1e-6 relative); the DFT leaves ~1e-16 of a row's peak where nothing leaks.
  const double peak = *std::max_element(want.begin(), want.end());
  int lit_before = 0, lit_after = 0;
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_NEAR(p1.intensity[i], want[i], 1e-6 * want[i] + 1e-12 * peak) << i;
    lit_before += p0.intensity[i] > 0.0f ? 1 : 0;
    lit_after += p1.intensity[i] > 0.0f ? 1 : 0;
  }
  // The wall's range row in the edge beam (60 deg off, the wall spans +-5 deg): water before.
  int row = 0;
  for (int b = 0; b < m.bins; ++b)
    if (p0.at(b, 64) > p0.at(row, 64)) row = b;
  std::printf("sidelobes: %d lit cells -> %d; edge beam at the wall's range %.3g -> %.3g (wall beam %.3g)\n",
              lit_before, lit_after, p0.at(row, 0), p1.at(row, 0), p0.at(row, 64));
  EXPECT_EQ(p0.at(row, 0), 0.0f);
  EXPECT_GT(p1.at(row, 0), 0.0f);
  EXPECT_LT(p1.at(row, 0), 1e-3 * p0.at(row, 64));  // far down the envelope (-25 dB at 1.5 beams)
  EXPECT_GT(lit_after, lit_before);
}
