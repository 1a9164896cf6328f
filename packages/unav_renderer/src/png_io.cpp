// PNG files of frames (OpenCV).
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_renderer/errors.hpp"
#include "unav_renderer/renderer.hpp"

namespace unav::renderer {

void write_png_rgb(const Frame& frame, const std::string& path) {
  cv::Mat rgb(frame.height, frame.width, CV_8UC3, const_cast<std::uint8_t*>(frame.rgb.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path, bgr, {cv::IMWRITE_PNG_COMPRESSION, 9})) throw ConfigError(path + ": cannot write PNG");
}

std::vector<std::uint8_t> read_png_rgb(const std::string& path, int* width, int* height) {
  cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
  if (bgr.empty()) throw ConfigError(path + ": cannot read PNG");
  cv::Mat rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  *width = rgb.cols;
  *height = rgb.rows;
  return std::vector<std::uint8_t>(rgb.data, rgb.data + rgb.total() * 3);
}

}  // namespace unav::renderer
