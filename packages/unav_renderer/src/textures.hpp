// Procedural, tileable textures (sRGB8, size x size x 3). Deterministic.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace unav::renderer::detail {

/// name: none (white), sand, rock, pipe_coating, checker. Throws ConfigError for others.
std::vector<std::uint8_t> make_texture(const std::string& name, int size);

}  // namespace unav::renderer::detail
