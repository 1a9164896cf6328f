// CPU pixel operations of the readback (exposed for unit tests).
#pragma once

#include <cstddef>
#include <cstdint>

namespace unav::renderer::detail {

/// rgba8 (px pixels) -> rgb8 and the alpha plane (the segmentation ids).
void split_rgba(const std::uint8_t* rgba, std::size_t px, std::uint8_t* rgb, std::uint8_t* alpha);

}  // namespace unav::renderer::detail
