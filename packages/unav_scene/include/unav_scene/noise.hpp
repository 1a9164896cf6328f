// Deterministic hash-based value noise (no global RNG; same seed, same result).
#pragma once

#include <cmath>
#include <cstdint>

namespace unav::scene::noise {

inline std::uint32_t hash32(std::uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

/// Uniform in [0, 1) from integer lattice coordinates and a seed.
inline double lattice(int i, int j, int k, std::uint32_t seed) {
  std::uint32_t h = hash32(static_cast<std::uint32_t>(i) * 73856093U ^
                           static_cast<std::uint32_t>(j) * 19349663U ^
                           static_cast<std::uint32_t>(k) * 83492791U ^ hash32(seed));
  return (h & 0xFFFFFFU) / 16777216.0;
}

inline double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

/// 2D value noise in [0, 1), periodic with `period` cells when period > 0.
inline double value_noise2(double x, double y, std::uint32_t seed, int period = 0) {
  const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y));
  const double fx = smooth(x - xi), fy = smooth(y - yi);
  auto L = [&](int i, int j) {
    if (period > 0) {
      i = ((i % period) + period) % period;
      j = ((j % period) + period) % period;
    }
    return lattice(i, j, 0, seed);
  };
  const double a = L(xi, yi), b = L(xi + 1, yi), c = L(xi, yi + 1), d = L(xi + 1, yi + 1);
  return (a + (b - a) * fx) + ((c + (d - c) * fx) - (a + (b - a) * fx)) * fy;
}

/// fBm of value noise, result roughly in [0, 1).
inline double fbm2(double x, double y, std::uint32_t seed, int octaves, int period = 0) {
  double sum = 0, amp = 0.5, norm = 0;
  int p = period;
  for (int o = 0; o < octaves; ++o) {
    sum += amp * value_noise2(x, y, seed + 101U * o, p);
    norm += amp;
    x *= 2.0;
    y *= 2.0;
    p *= 2;
    amp *= 0.5;
  }
  return sum / norm;
}

/// 3D value noise in [0, 1).
inline double value_noise3(double x, double y, double z, std::uint32_t seed) {
  const int xi = static_cast<int>(std::floor(x)), yi = static_cast<int>(std::floor(y)),
            zi = static_cast<int>(std::floor(z));
  const double fx = smooth(x - xi), fy = smooth(y - yi), fz = smooth(z - zi);
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  double v[2];
  for (int k = 0; k < 2; ++k) {
    const double a = lattice(xi, yi, zi + k, seed), b = lattice(xi + 1, yi, zi + k, seed);
    const double c = lattice(xi, yi + 1, zi + k, seed), d = lattice(xi + 1, yi + 1, zi + k, seed);
    v[k] = lerp(lerp(a, b, fx), lerp(c, d, fx), fy);
  }
  return lerp(v[0], v[1], fz);
}

}  // namespace unav::scene::noise
