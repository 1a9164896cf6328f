// CPU pixel operations of the readback (exposed for unit tests).
#pragma once

#include <cstddef>
#include <cstdint>

namespace unav::renderer::detail {

/// rgba8 (px pixels) -> rgb8 and the alpha plane (the segmentation ids).
void split_rgba(const std::uint8_t* rgba, std::size_t px, std::uint8_t* rgb, std::uint8_t* alpha);

/// The rgb8 image (width x height, in place) compressed as a JPEG of `quality` (1..100: libjpeg's
/// baseline through OpenCV, 4:2:0 chroma) and decoded again: the artefacts a camera streaming MJPEG
/// or a dataset of JPEGs carries.
void jpeg_roundtrip(std::uint8_t* rgb, int width, int height, int quality);

}  // namespace unav::renderer::detail
