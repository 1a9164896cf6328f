#include "textures.hpp"

#include <algorithm>
#include <cmath>

#include "unav_renderer/errors.hpp"
#include "unav_scene/noise.hpp"

namespace unav::renderer::detail {
namespace {

using namespace unav::scene::noise;

struct C3 {
  double r, g, b;
};
C3 mix(const C3& a, const C3& b, double t) {
  return {a.r + (b.r - a.r) * t, a.g + (b.g - a.g) * t, a.b + (b.b - a.b) * t};
}
C3 mul(const C3& a, double s) { return {a.r * s, a.g * s, a.b * s}; }
// Non-negative here, so + 0.5 and truncation round to nearest; kept (not lround) so textures stay
// byte-identical.
std::uint8_t to8(double v) {
  return static_cast<std::uint8_t>(std::clamp(v, 0.0, 1.0) * 255.0 + 0.5);  // NOLINT(bugprone-incorrect-roundings)
}

// Albedo and relief height in [0, 1] (bump-mapped by the scene shader, scaled by the material's
// relief_m) of a texel.
struct Texel {
  C3 c;
  double h;
};

// u, v in [0, 1); all noise periodic over the tile.
Texel sand(double u, double v) {
  // Ripples: crests across u, wavelength = tile / 14, wobbling with a periodic fBm.
  const double wob = fbm2(u * 4, v * 4, 11, 3, 4);
  const double phase = 14.0 * u + 1.6 * (wob - 0.5) + 0.8 * std::sin(2 * M_PI * v);
  const double s = phase - std::floor(phase);
  // Asymmetric ripple: gentle stoss side lit, steep lee side in shade.
  const double shade = s < 0.72 ? 0.93 + 0.10 * (s / 0.72) : 0.80 + 0.15 * ((1.0 - s) / 0.28);
  // Its profile: rising over the stoss side, dropping over the lee side, crests rounded.
  const double rise = s < 0.72 ? s / 0.72 : (1.0 - s) / 0.28;
  double h = 0.5 - 0.5 * std::cos(M_PI * rise);
  const double grain = value_noise2(u * 256, v * 256, 5, 256);
  const double patch = fbm2(u * 8, v * 8, 23, 4, 8);
  C3 base = mix(C3{0.80, 0.74, 0.60}, C3{0.64, 0.58, 0.46}, patch);
  base = mul(base, shade * (0.90 + 0.20 * grain));
  h = 0.85 * h + 0.15 * grain;
  // Shell fragments and dark grains.
  const double speck = lattice(static_cast<int>(u * 512), static_cast<int>(v * 512), 3, 99);
  if (speck > 0.996)
    base = C3{0.95, 0.93, 0.88};
  else if (speck < 0.006)
    base = mul(base, 0.45);
  return {base, h};
}

Texel rock(double u, double v) {
  const double f = fbm2(u * 8, v * 8, 31, 5, 8);
  const double ridge = 1.0 - std::abs(2.0 * fbm2(u * 6, v * 6, 37, 3, 6) - 1.0);  // cracks
  C3 base = mix(C3{0.55, 0.52, 0.47}, C3{0.75, 0.71, 0.64}, f);
  base = mul(base, 0.65 + 0.35 * (1.0 - std::pow(ridge, 8.0)));
  const double algae = fbm2(u * 4 + 3, v * 4 + 7, 41, 4, 4);
  if (algae > 0.55) base = mix(base, C3{0.28, 0.36, 0.16}, std::min(1.0, (algae - 0.55) * 5.0));
  const double dots = value_noise2(u * 128, v * 128, 43, 128);
  // Knobbly surface cut by the cracks; the algae film adds nothing to the relief.
  return {mul(base, 0.85 + 0.3 * dots), 0.65 * f + 0.35 * (1.0 - std::pow(ridge, 8.0)) - 0.05 * (1.0 - dots)};
}

Texel pipe_coating(double u, double v) {
  // u: along the pipe (tile = one coating section), v: around it.
  const double f = fbm2(u * 8, v * 8, 51, 4, 8);
  C3 base = mix(C3{0.62, 0.56, 0.46}, C3{0.48, 0.44, 0.38}, f);
  // Marine growth: patchy green-brown film plus denser tufts.
  const double g = fbm2(u * 6 + 1, v * 6 + 5, 53, 5, 6);
  if (g > 0.45) base = mix(base, C3{0.36, 0.40, 0.20}, std::min(1.0, (g - 0.45) * 3.0));
  if (g > 0.62) base = mix(base, C3{0.22, 0.26, 0.12}, std::min(1.0, (g - 0.62) * 6.0));
  // Relief: the smooth coat at 0.3, growth standing out of it, barnacles highest.
  double h =
      0.3 + 0.05 * f + 0.35 * std::clamp((g - 0.45) * 3.0, 0.0, 1.0) + 0.2 * std::clamp((g - 0.62) * 6.0, 0.0, 1.0);
  // Barnacles / calcareous spots.
  const double b = lattice(static_cast<int>(u * 200), static_cast<int>(v * 200), 5, 57);
  if (b > 0.994) {
    base = C3{0.80, 0.79, 0.74};
    h = 1.0;
  }
  // Field joint band and a longitudinal weld stripe.
  if (u < 0.03 || u > 0.985) {  // the joint's bare band lies below the coat
    base = mul(C3{0.30, 0.30, 0.30}, 0.9 + 0.2 * f);
    h = 0.0;
  }
  if (std::abs(v - 0.5) < 0.006) base = mul(base, 0.7);
  return {mul(base, 0.9 + 0.2 * value_noise2(u * 128, v * 128, 59, 128)), h};
}

Texel checker(double u, double v) {
  const bool odd = (static_cast<int>(u * 8) + static_cast<int>(v * 8)) & 1;
  return {odd ? C3{0.9, 0.9, 0.9} : C3{0.1, 0.1, 0.1}, 0.5};
}

using TexelFn = Texel (*)(double, double);

TexelFn texel_function(const std::string& name) {
  TexelFn fn = nullptr;
  if (name == "sand")
    fn = sand;
  else if (name == "rock")
    fn = rock;
  else if (name == "pipe_coating")
    fn = pipe_coating;
  else if (name == "checker")
    fn = checker;
  else
    throw ConfigError("unknown procedural texture '" + name + "'");
  return fn;
}

}  // namespace

ProceduralTexture make_texture(const std::string& name, int size) {
  if (name == "none") return {{255, 255, 255, 128}, {0.0f, 0.0f}};
  const TexelFn fn = texel_function(name);
  ProceduralTexture out;
  out.rgba.resize(static_cast<std::size_t>(size) * size * 4);
  std::vector<double> h(static_cast<std::size_t>(size) * size);  // before 8-bit rounding
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const Texel t = fn((i + 0.5) / size, (j + 0.5) / size);
      const std::size_t k = static_cast<std::size_t>(j) * size + i;
      auto* p = &out.rgba[k * 4];
      p[0] = to8(t.c.r);
      p[1] = to8(t.c.g);
      p[2] = to8(t.c.b);
      p[3] = to8(t.h);
      h[k] = t.h;
    }
  // Central differences over the periodic tile, per unit of texture coordinate (one tile = 1).
  const auto at = [&](int i, int j) {
    return h[static_cast<std::size_t>((j + size) % size) * size + (i + size) % size];
  };
  out.gradient.resize(h.size() * 2);
  for (int j = 0; j < size; ++j)
    for (int i = 0; i < size; ++i) {
      const std::size_t k = (static_cast<std::size_t>(j) * size + i) * 2;
      out.gradient[k] = static_cast<float>((at(i + 1, j) - at(i - 1, j)) * 0.5 * size);
      out.gradient[k + 1] = static_cast<float>((at(i, j + 1) - at(i, j - 1)) * 0.5 * size);
    }
  return out;
}

}  // namespace unav::renderer::detail
