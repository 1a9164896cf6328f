// PNG helpers shared by the sequence writers (internal to unav_datagen).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "unav_datagen/dataset_writer.hpp"

namespace unav::datagen::detail {

/// Writes <root>/<relative> with its digest logged (write_file_logged). Throws DatasetError naming
/// the path when OpenCV cannot encode it or the file cannot be written.
void write_png(const std::string& root, const std::string& relative, const cv::Mat& m);
/// A float depth image (metres) as uint16 units (encode_depth), row-major width x height.
cv::Mat depth_png(int width, int height, const float* depth_m, double units_per_metre);

}  // namespace unav::datagen::detail
