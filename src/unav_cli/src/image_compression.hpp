// sensor_msgs/Image -> sensor_msgs/CompressedImage the way ROS 2's compressed_image_transport does
// it (JPEG for 8-bit images, PNG for 16-bit ones; format "<encoding>; jpeg compressed bgr8"), so
// Foxglove and `ros2 run image_transport republish` read what we send. No DDS in it.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace unav::cli {

/// The parts of a sensor_msgs/Image the compressor reads (the pixels are not copied).
struct ImageView {
  std::string encoding;  ///< rgb8, bgr8, rgba8, bgra8, mono8, 8UC1, 8UC3, mono16, 16UC1
  std::uint32_t width = 0, height = 0, step = 0;
  bool big_endian = false;  ///< of 16-bit pixels
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};

struct CompressedImageData {
  std::string format;  ///< e.g. "rgb8; jpeg compressed bgr8", "mono16; png compressed mono16"
  std::vector<std::uint8_t> data;
};

/// Whether compress_image takes this encoding (float depth images are not: JPEG/PNG would lose it).
bool compressible(const std::string& encoding);

/// JPEG (quality 1-100) for 8-bit encodings, lossless PNG for 16-bit ones. Throws
/// std::invalid_argument naming the encoding or the size rule that does not hold.
CompressedImageData compress_image(const ImageView& image, int jpeg_quality);

}  // namespace unav::cli
