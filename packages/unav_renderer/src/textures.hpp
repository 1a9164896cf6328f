// Procedural, tileable textures with their relief. Deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace unav::renderer::detail {

/// A procedural texture and the slope of its relief.
struct ProceduralTexture {
  /// size x size x 4: sRGB8 albedo, relief height in alpha (linear).
  std::vector<std::uint8_t> rgba;
  /// size x size x 2: the relief height's gradient (d/du, d/dv) per unit of texture coordinate (a
  /// tile is 1), periodic central differences before 8-bit rounding. Bump mapping reads it: a
  /// smooth slope per pixel, where screen-space derivatives of the height are constant over 2x2
  /// pixels (blocky, and grid-locked as the camera moves: VO and SLAM lost track on it).
  std::vector<float> gradient;
};

/// name: none (white, flat, 1 x 1), sand, rock, pipe_coating, checker. Throws ConfigError for
/// others.
ProceduralTexture make_texture(const std::string& name, int size);

}  // namespace unav::renderer::detail
