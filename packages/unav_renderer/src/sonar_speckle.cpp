#include "unav_renderer/sonar_speckle.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <utility>

#include <opencv2/core.hpp>

namespace unav::renderer {

namespace {

// A unit-variance Gaussian (the first of a Box-Muller pair).
double normal(unav::common::SplitMix64* rng) {
  const double u1 = 1.0 - rng->Uniform01(), u2 = rng->Uniform01();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

// Gamma(shape, 1 / shape): unit mean (Marsaglia and Tsang 2000; shape < 1 by the boost u^(1/a)).
double gamma_unit_mean(double shape, unav::common::SplitMix64* rng) {
  const double a = shape < 1.0 ? shape + 1.0 : shape;
  const double d = a - 1.0 / 3.0, c = 1.0 / std::sqrt(9.0 * d);
  double g = 0.0;
  for (;;) {
    double x, v;
    do {
      x = normal(rng);
      v = 1.0 + c * x;
    } while (v <= 0.0);
    v = v * v * v;
    const double u = rng->Uniform01();
    if (u < 1.0 - 0.0331 * x * x * x * x || std::log(u) < 0.5 * x * x + d * (1.0 - v + std::log(v))) {
      g = d * v;
      break;
    }
  }
  if (shape < 1.0) g *= std::pow(1.0 - rng->Uniform01(), 1.0 / shape);
  return g / shape;
}

}  // namespace

std::vector<double> speckle_kernel(double grain) {
  if (!(grain > 1.0)) return {1.0};
  // Intensity autocorrelation of a complex Gaussian field filtered by a Gaussian of std s:
  // exp(-d^2 / (2 s^2)), so its FWHM is 2 s sqrt(2 ln 2).
  const double s = grain / (2.0 * std::sqrt(2.0 * std::log(2.0)));
  const int half = static_cast<int>(std::ceil(3.0 * s));
  std::vector<double> w;
  double sum_sq = 0.0;
  for (int i = -half; i <= half; ++i) {
    w.push_back(std::exp(-0.5 * i * i / (s * s)));
    sum_sq += w.back() * w.back();
  }
  for (auto& x : w) x /= std::sqrt(sum_sq);
  return w;
}

namespace {

// 4096 complex Gaussian samples with E|z|^2 = 1 (exact Box-Muller from a fixed seed; 32 kB: in the
// L1 cache), drawn by random index: 12 bits of the stream per sample instead of a log, a root and a
// sine and cosine (the field is filtered and multiplied by the texture: the repeats do not show).
const std::vector<std::pair<float, float>>& complex_gaussians() {
  static const std::vector<std::pair<float, float>> table = [] {
    std::vector<std::pair<float, float>> t(1U << 12U);
    unav::common::SplitMix64 rng{0x5EC7E5EEDULL};
    for (auto& z : t) {
      const double r = std::sqrt(-std::log(1.0 - rng.Uniform01())), a = 2.0 * M_PI * rng.Uniform01();
      z = {static_cast<float>(r * std::cos(a)), static_cast<float>(r * std::sin(a))};
    }
    return t;
  }();
  return table;
}

}  // namespace

void speckle_field(int bins, int channels, const SpeckleParams& p, unav::common::SplitMix64* rng,
                   std::vector<float>* out) {
  const std::vector<double> kcd = speckle_kernel(p.grain_beams), kbd = speckle_kernel(p.grain_bins);
  const std::vector<float> kc(kcd.begin(), kcd.end()), kb(kbd.begin(), kbd.end());
  const int hc = static_cast<int>(kc.size() / 2), hb = static_cast<int>(kb.size() / 2);
  const int W = channels + 2 * hc, H = bins + 2 * hb;
  // White complex Gaussian with E|z|^2 = 1: five table draws per 64 bits of the stream.
  const auto& table = complex_gaussians();
  std::vector<float> re(static_cast<std::size_t>(W) * H), im(re.size());
  std::uint64_t bits = 0;
  int left = 0;
  for (std::size_t i = 0; i < re.size(); ++i) {
    if (left == 0) {
      bits = rng->Next();
      left = 5;
    }
    const auto& z = table[bits & 0xFFFU];
    bits >>= 12U;
    --left;
    re[i] = z.first;
    im[i] = z.second;
  }
  // Separable filter: across beams, then along range (each kernel has a unit sum of squares).
  std::vector<float> re1(static_cast<std::size_t>(channels) * H), im1(re1.size());
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < channels; ++x) {
      float a = 0.0f, b = 0.0f;
      const std::size_t row = static_cast<std::size_t>(y) * W + x;
      for (std::size_t k = 0; k < kc.size(); ++k) {
        a += kc[k] * re[row + k];
        b += kc[k] * im[row + k];
      }
      re1[static_cast<std::size_t>(y) * channels + x] = a;
      im1[static_cast<std::size_t>(y) * channels + x] = b;
    }
  // Along range, row by row: each output row a weighted sum of input rows (vectorizes).
  out->assign(static_cast<std::size_t>(bins) * channels, 0.0f);
  std::vector<float> a(static_cast<std::size_t>(channels)), b(a.size());
  for (int y = 0; y < bins; ++y) {
    std::fill(a.begin(), a.end(), 0.0f);
    std::fill(b.begin(), b.end(), 0.0f);
    for (std::size_t k = 0; k < kb.size(); ++k) {
      const float* r = re1.data() + (static_cast<std::size_t>(y) + k) * channels;
      const float* m = im1.data() + (static_cast<std::size_t>(y) + k) * channels;
      for (int x = 0; x < channels; ++x) {
        a[static_cast<std::size_t>(x)] += kb[k] * r[x];
        b[static_cast<std::size_t>(x)] += kb[k] * m[x];
      }
    }
    float* o = out->data() + static_cast<std::size_t>(y) * channels;
    for (int x = 0; x < channels; ++x)
      o[x] = a[static_cast<std::size_t>(x)] * a[static_cast<std::size_t>(x)] +
             b[static_cast<std::size_t>(x)] * b[static_cast<std::size_t>(x)];
  }
  if (!(p.shape > 0.0)) return;
  // The K texture: the scatterers' density, constant over patches a little larger than the grain
  // (it varies on larger scales than the speckle; the marginal stays K).
  const int tb = std::max(2, static_cast<int>(std::ceil(2.0 * p.grain_bins)));
  const int tc = std::max(2, static_cast<int>(std::ceil(2.0 * p.grain_beams)));
  const int nb = (bins + tb - 1) / tb, nc = (channels + tc - 1) / tc;
  std::vector<float> texture(static_cast<std::size_t>(nb) * nc);
  for (auto& t : texture) t = static_cast<float>(gamma_unit_mean(p.shape, rng));
  for (int y = 0; y < bins; ++y)
    for (int x = 0; x < channels; ++x)
      (*out)[static_cast<std::size_t>(y) * channels + x] *= texture[static_cast<std::size_t>(y / tb) * nc + x / tc];
}

std::vector<double> sidelobe_kernel(int channels, double sidelobe_db, double falloff_db_per_octave) {
  std::vector<double> k(static_cast<std::size_t>(std::max(channels, 1)), 0.0);
  const double first = 1.5, level = std::pow(10.0, sidelobe_db / 10.0);
  const double exponent = falloff_db_per_octave / (10.0 * std::log10(2.0));
  for (std::size_t d = 1; d < k.size(); ++d)
    if (static_cast<double>(d) >= first) k[d] = level * std::pow(first / static_cast<double>(d), exponent);
  return k;
}

void add_sidelobes(int bins, int channels, const std::vector<double>& kernel, std::vector<double>* field) {
  if (field->size() != static_cast<std::size_t>(bins) * static_cast<std::size_t>(channels) ||
      kernel.size() < static_cast<std::size_t>(channels))
    throw std::invalid_argument("add_sidelobes: field or kernel of the wrong size");
  if (channels < 2 || bins < 1) return;
  // Linear convolution of each row with the symmetric kernel: circular over n >= 2 channels - 1.
  const int n = cv::getOptimalDFTSize(2 * channels - 1);
  cv::Mat k_row = cv::Mat::zeros(1, n, CV_64F);
  for (int d = 1; d < channels; ++d) {
    k_row.at<double>(0, d) = kernel[static_cast<std::size_t>(d)];
    k_row.at<double>(0, n - d) = kernel[static_cast<std::size_t>(d)];
  }
  cv::Mat rows = cv::Mat::zeros(bins, n, CV_64F);
  for (int b = 0; b < bins; ++b)
    std::copy_n(field->data() + static_cast<std::size_t>(b) * channels, channels, rows.ptr<double>(b));
  cv::Mat k_spec, spec, leak;
  cv::dft(k_row, k_spec, cv::DFT_ROWS);
  cv::dft(rows, spec, cv::DFT_ROWS);
  for (int b = 0; b < bins; ++b) {  // every row by the one kernel spectrum (in place)
    cv::Mat row = spec.row(b);
    cv::mulSpectrums(row, k_spec, row, cv::DFT_ROWS);
  }
  cv::idft(spec, leak, cv::DFT_ROWS | cv::DFT_SCALE | cv::DFT_REAL_OUTPUT);
  for (int b = 0; b < bins; ++b) {
    const double* l = leak.ptr<double>(b);
    double* f = field->data() + static_cast<std::size_t>(b) * channels;
    // The DFT's rounding leaves ~1e-16 of the row's largest value where nothing leaks: not negative.
    for (int c = 0; c < channels; ++c) f[c] += std::max(l[c], 0.0);
  }
}

DisplayCoding::DisplayCoding(const std::string& coding, double gain_db, double dynamic_range_db, double gamma)
    : gamma_(coding == "gamma"),
      gain_db_(gain_db),
      dynamic_range_db_(dynamic_range_db),
      exponent_(0.5 * gamma),
      gain_(std::pow(10.0, gain_db / 10.0)) {}

std::uint8_t DisplayCoding::operator()(double v) const {
  if (!(v > 0.0)) return 0;
  const double level =
      gamma_ ? std::pow(v * gain_, exponent_) : 1.0 + (10.0 * std::log10(v) + gain_db_) / dynamic_range_db_;
  return static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(level, 0.0, 1.0)));
}

}  // namespace unav::renderer
