// Sonar speckle and display coding (no GL): the marginals of Rayleigh and K speckle, the
// correlation the beam pattern and pulse length give, the codings' levels and saturation.
#include "unav_renderer/sonar_speckle.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numeric>
#include <stdexcept>
#include <vector>

using unav::renderer::DisplayCoding;
using unav::renderer::SpeckleParams;

namespace {

struct Moments {
  double mean = 0.0, contrast = 0.0, above3 = 0.0;
};

Moments moments(const std::vector<float>& v) {
  Moments m;
  double s = 0.0, s2 = 0.0;
  int above = 0;
  for (float x : v) {
    s += x;
    s2 += static_cast<double>(x) * x;
    above += x > 3.0f ? 1 : 0;
  }
  const double n = static_cast<double>(v.size());
  m.mean = s / n;
  m.contrast = std::sqrt(s2 / n - m.mean * m.mean) / m.mean;
  m.above3 = above / n;
  return m;
}

// Correlation coefficient of the field with itself shifted by (db bins, dc channels).
double correlation(const std::vector<float>& v, int bins, int channels, int db, int dc) {
  double sa = 0, sb = 0, sab = 0, saa = 0, sbb = 0;
  int n = 0;
  for (int y = 0; y + db < bins; ++y)
    for (int x = 0; x + dc < channels; ++x) {
      const double a = v[static_cast<std::size_t>(y) * channels + x];
      const double b = v[static_cast<std::size_t>(y + db) * channels + x + dc];
      sa += a, sb += b, sab += a * b, saa += a * a, sbb += b * b;
      ++n;
    }
  const double ca = saa / n - (sa / n) * (sa / n), cb = sbb / n - (sb / n) * (sb / n);
  return (sab / n - (sa / n) * (sb / n)) / std::sqrt(ca * cb);
}

double kernel_lag1(const std::vector<double>& w) {
  double c = 0.0;
  for (std::size_t i = 0; i + 1 < w.size(); ++i) c += w[i] * w[i + 1];
  return c;  // the kernel has a unit sum of squares
}

}  // namespace

// Fully developed speckle without texture: exponential intensity of unit mean (contrast 1,
// P(X > 3) = e^-3 = 0.0498), however correlated. 512 x 256 cells: the mean's standard error is
// under 0.5 % even with ~3 cells per grain; 3 % tolerances are over 5 of them.
TEST(SonarSpeckle, RayleighSpeckleIsExponentialWithUnitMean) {
  for (const double grain : {0.0, 1.7}) {
    SpeckleParams p;
    p.grain_beams = p.grain_bins = grain;
    unav::common::SplitMix64 rng{11};
    std::vector<float> f;
    unav::renderer::speckle_field(512, 256, p, &rng, &f);
    const Moments m = moments(f);
    EXPECT_NEAR(m.mean, 1.0, 0.03) << grain;
    EXPECT_NEAR(m.contrast, 1.0, 0.03) << grain;
    EXPECT_NEAR(m.above3, std::exp(-3.0), 0.005) << grain;
  }
}

// K-distributed (Gamma texture of shape nu times the exponential speckle): contrast
// sqrt(1 + 2 / nu): 1.225 at nu = 4, 1.732 at nu = 1 (heavier tails: a sparse seabed).
TEST(SonarSpeckle, KSpeckleHasTheContrastOfItsShape) {
  for (const double shape : {4.0, 1.0, 0.5}) {
    SpeckleParams p;
    p.shape = shape;
    unav::common::SplitMix64 rng{5};
    std::vector<float> f;
    unav::renderer::speckle_field(512, 256, p, &rng, &f);
    const Moments m = moments(f);
    EXPECT_NEAR(m.mean, 1.0, 0.03) << shape;
    EXPECT_NEAR(m.contrast / std::sqrt(1.0 + 2.0 / shape), 1.0, 0.05) << shape;
  }
}

// Correlated by the beam pattern and the pulse: the intensity correlation at one cell's lag is the
// squared amplitude correlation of the kernel (Siegert: |rho_A|^2) -- 0.37 at a 1.7-beam grain,
// 0.25 at 1.5 bins -- and vanishes beyond the kernel; grains of 1 cell or less are independent.
// (Lag-1 estimates over 131k cells: standard error < 0.01; 0.03 is over 3 of them.)
TEST(SonarSpeckle, GrainCorrelatesNeighboursAsThePatternAndPulseSay) {
  SpeckleParams p;
  p.grain_beams = 1.7;
  p.grain_bins = 1.5;
  unav::common::SplitMix64 rng{3};
  std::vector<float> f;
  unav::renderer::speckle_field(512, 256, p, &rng, &f);
  const double beams = std::pow(kernel_lag1(unav::renderer::speckle_kernel(1.7)), 2.0);
  const double bins = std::pow(kernel_lag1(unav::renderer::speckle_kernel(1.5)), 2.0);
  EXPECT_NEAR(correlation(f, 512, 256, 0, 1), beams, 0.03);
  EXPECT_NEAR(correlation(f, 512, 256, 1, 0), bins, 0.03);
  EXPECT_NEAR(correlation(f, 512, 256, 0, 6), 0.0, 0.03);
  // The kernel's own law: FWHM of exp(-d^2 / (2 s^2)) is the grain.
  EXPECT_NEAR(beams, std::exp(-0.5 * std::pow(2.0 * std::sqrt(2.0 * std::log(2.0)) / 1.7, 2.0)), 0.02);
  std::vector<float> g;
  unav::renderer::speckle_field(512, 256, SpeckleParams{}, &rng, &g);
  EXPECT_NEAR(correlation(g, 512, 256, 0, 1), 0.0, 0.03);
  EXPECT_EQ(unav::renderer::speckle_kernel(1.0).size(), 1u);
}

TEST(SonarSpeckle, DisplayCodingsLevelsAndSaturation) {
  const DisplayCoding db;  // 0 dB gain: full scale at v = 1, 60 dB below it 0
  EXPECT_EQ(db(1.0), 255);
  EXPECT_EQ(db(1e-3), 128);  // -30 dB: half way
  EXPECT_EQ(db(1e-7), 0);
  EXPECT_EQ(db(0.0), 0);
  const DisplayCoding gamma("gamma", 0.0, 60.0, 0.5);
  EXPECT_EQ(gamma(0.25), 180);                             // amplitude 0.5, to the power 0.5: 0.707
  EXPECT_EQ(gamma(4.0), 255);                              // above full scale: saturated
  const DisplayCoding gained("gamma", 6.0206, 60.0, 0.5);  // x4 in intensity: 0.25 becomes full scale
  EXPECT_EQ(gained(0.25), 255);
}

// The side-lobe envelope: nothing inside the first side lobe (1.5 beams), its level there, then
// the configured fall per octave (to rounding).
TEST(SonarSidelobes, KernelIsTheEnvelopeOfTheConfiguredLevelAndFall) {
  const auto k = unav::renderer::sidelobe_kernel(64, -20.0, 6.0);
  ASSERT_EQ(k.size(), 64u);
  EXPECT_EQ(k[0], 0.0);  // the main lobe: the beam's own cell
  EXPECT_EQ(k[1], 0.0);  // inside the first side lobe
  EXPECT_NEAR(10.0 * std::log10(k[2]), -20.0 + 6.0 * std::log2(1.5 / 2.0), 1e-9);
  for (std::size_t d : {3u, 5u, 12u, 31u}) EXPECT_NEAR(10.0 * std::log10(k[d] / k[2 * d]), 6.0, 1e-9) << d;
  const auto hann = unav::renderer::sidelobe_kernel(64, -31.5, 18.0);
  EXPECT_NEAR(10.0 * std::log10(hann[4] / hann[8]), 18.0, 1e-9);
}

// One strong cell: its range row gains k(|d|) times its intensity in every other beam (both
// sides, up to the fan's edges), no other row changes, the cell itself keeps its value; two
// cells leak the sum of what each leaks alone (linear).
TEST(SonarSidelobes, APointEchoLeaksTheKernelAcrossItsRangeRowOnly) {
  const int bins = 40, channels = 256;
  const auto k = unav::renderer::sidelobe_kernel(channels, -13.3, 6.0);
  auto point = [&](int b, int c, double v) {
    std::vector<double> f(static_cast<std::size_t>(bins) * channels, 0.0);
    f[static_cast<std::size_t>(b) * channels + c] = v;
    return f;
  };
  std::vector<double> f = point(17, 40, 2.0);
  unav::renderer::add_sidelobes(bins, channels, k, &f);
  double worst = 0.0;
  for (int b = 0; b < bins; ++b)
    for (int c = 0; c < channels; ++c) {
      const double got = f[static_cast<std::size_t>(b) * channels + c];
      const double want = b != 17 ? 0.0 : (c == 40 ? 2.0 : 2.0 * k[static_cast<std::size_t>(std::abs(c - 40))]);
      if (b != 17) {
        EXPECT_EQ(got, 0.0) << b << " " << c;  // a row of zeros transforms to zeros exactly
      } else {
        // DFT rounding: ~1e-16 of the row's largest value (2), far below the smallest leak (~1e-4).
        EXPECT_NEAR(got, want, 1e-12) << c;
        worst = std::max(worst, std::abs(got - want));
      }
    }
  std::printf("point echo: worst difference from the kernel %.2e (leak at 2 beams %.3e, at 215 beams %.3e)\n", worst,
              2.0 * k[2], 2.0 * k[215]);
  std::vector<double> a = point(5, 3, 1.0), b = point(5, 200, 0.5), ab(a.size());
  for (std::size_t i = 0; i < a.size(); ++i) ab[i] = a[i] + b[i];
  unav::renderer::add_sidelobes(bins, channels, k, &a);
  unav::renderer::add_sidelobes(bins, channels, k, &b);
  unav::renderer::add_sidelobes(bins, channels, k, &ab);
  for (std::size_t i = 0; i < ab.size(); ++i) EXPECT_NEAR(ab[i], a[i] + b[i], 1e-12) << i;
  std::vector<double> wrong(10);
  EXPECT_THROW(unav::renderer::add_sidelobes(bins, channels, k, &wrong), std::invalid_argument);
}
