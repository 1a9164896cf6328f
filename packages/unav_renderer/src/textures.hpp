// Procedural, tileable textures (size x size x 4: sRGB8 albedo + linear relief height in alpha).
// Deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace unav::renderer::detail {

/// name: none (white), sand, rock, pipe_coating, checker. Throws ConfigError for others.
std::vector<std::uint8_t> make_texture(const std::string& name, int size);

/// The gradient of texture `name`'s relief height (its alpha, before 8-bit rounding) per unit of
/// texture coordinate (a tile is 1): size x size x 2 (d/du, d/dv), periodic central differences;
/// {0, 0} (1 x 1) for "none". Bump mapping reads it: a smooth slope per pixel, where screen-space
/// derivatives of the height are constant over 2x2 pixels (blocky, and grid-locked as the camera
/// moves: VO and SLAM lost track on it).
std::vector<float> make_relief_gradient(const std::string& name, int size);

}  // namespace unav::renderer::detail
