#include "image_compression.hpp"

#include <stdexcept>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

namespace unav::cli {
namespace {

struct Layout {
  int cv_type;  // of one pixel
  int to_bgr;   // cv::cvtColor code to the encoder's order, or -1
  bool sixteen_bit;
  const char* encoded;  // what the compressed pixels are, as compressed_image_transport names it
};

bool layout_of(const std::string& e, Layout* l) {
  if (e == "rgb8")
    *l = {CV_8UC3, cv::COLOR_RGB2BGR, false, "bgr8"};
  else if (e == "bgr8" || e == "8UC3")
    *l = {CV_8UC3, -1, false, "bgr8"};
  else if (e == "rgba8")
    *l = {CV_8UC4, cv::COLOR_RGBA2BGR, false, "bgr8"};
  else if (e == "bgra8")
    *l = {CV_8UC4, cv::COLOR_BGRA2BGR, false, "bgr8"};
  else if (e == "mono8" || e == "8UC1")
    *l = {CV_8UC1, -1, false, "mono8"};
  else if (e == "mono16" || e == "16UC1")
    *l = {CV_16UC1, -1, true, "mono16"};
  else
    return false;
  return true;
}

}  // namespace

bool compressible(const std::string& encoding) {
  Layout l{};
  return layout_of(encoding, &l);
}

CompressedImageData compress_image(const ImageView& image, int jpeg_quality) {
  Layout l{};
  if (!layout_of(image.encoding, &l))
    throw std::invalid_argument("image encoding '" + image.encoding +
                                "' cannot be compressed (rgb8, bgr8, rgba8, bgra8, mono8, mono16 can)");
  if (jpeg_quality < 1 || jpeg_quality > 100)
    throw std::invalid_argument("jpeg quality " + std::to_string(jpeg_quality) + ": must be in [1, 100]");
  const std::size_t row = static_cast<std::size_t>(image.width) * CV_ELEM_SIZE(l.cv_type);
  if (image.width == 0 || image.height == 0 || image.step < row ||
      image.size < static_cast<std::size_t>(image.step) * image.height)
    throw std::invalid_argument("image " + std::to_string(image.width) + "x" + std::to_string(image.height) + " " +
                                image.encoding + ": step " + std::to_string(image.step) + " and " +
                                std::to_string(image.size) + " bytes do not hold it (step >= " + std::to_string(row) +
                                ", bytes >= step * height)");
  // cv::Mat over the message's bytes: nothing is copied unless a conversion needs it.
  cv::Mat pixels(static_cast<int>(image.height), static_cast<int>(image.width), l.cv_type,
                 const_cast<std::uint8_t*>(image.data), image.step);
  cv::Mat converted;
  if (l.to_bgr >= 0) {
    cv::cvtColor(pixels, converted, l.to_bgr);
    pixels = converted;
  }
  if (l.sixteen_bit && image.big_endian) {
    pixels.copyTo(converted);
    for (int r = 0; r < converted.rows; ++r) {
      auto* p = converted.ptr<std::uint16_t>(r);
      for (int c = 0; c < converted.cols; ++c) p[c] = static_cast<std::uint16_t>((p[c] >> 8) | (p[c] << 8));
    }
    pixels = converted;
  }
  CompressedImageData out;
  const bool png = l.sixteen_bit;
  const std::vector<int> params =
      png ? std::vector<int>{cv::IMWRITE_PNG_COMPRESSION, 3} : std::vector<int>{cv::IMWRITE_JPEG_QUALITY, jpeg_quality};
  if (!cv::imencode(png ? ".png" : ".jpg", pixels, out.data, params))
    throw std::invalid_argument("image " + image.encoding + ": the encoder refused it");
  out.format = image.encoding + (png ? "; png compressed " : "; jpeg compressed ") + l.encoded;
  return out;
}

}  // namespace unav::cli
