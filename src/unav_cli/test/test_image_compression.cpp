// Images compressed as compressed_image_transport does: decoding the bytes gives the picture back
// (JPEG within its quantisation error, PNG exactly), in the right channel order, whatever the row
// padding; what cannot be compressed is refused naming the encoding or the size rule.
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "image_compression.hpp"

using unav::cli::compress_image;
using unav::cli::compressible;
using unav::cli::ImageView;

namespace {

// A smooth rgb8 gradient (JPEG's best case) with a red top-left quarter, rows padded to `step`.
std::vector<std::uint8_t> gradient_rgb8(int w, int h, int step) {
  std::vector<std::uint8_t> px(static_cast<std::size_t>(step) * h, 0xAB);  // padding bytes: junk
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      std::uint8_t* p = &px[static_cast<std::size_t>(y) * step + 3u * static_cast<std::size_t>(x)];
      const bool red = x < w / 2 && y < h / 2;
      p[0] = red ? 220 : static_cast<std::uint8_t>(x * 255 / w);
      p[1] = red ? 20 : static_cast<std::uint8_t>(y * 255 / h);
      p[2] = red ? 20 : 128;
    }
  return px;
}

}  // namespace

TEST(ImageCompression, JpegOfAnRgbImageDecodesToTheSameColours) {
  const int w = 64, h = 48, step = 3 * w + 8;
  const auto px = gradient_rgb8(w, h, step);
  const auto c = compress_image(ImageView{"rgb8", w, h, step, false, px.data(), px.size()}, 95);
  EXPECT_EQ(c.format, "rgb8; jpeg compressed bgr8");
  ASSERT_GT(c.data.size(), 2u);
  EXPECT_EQ(c.data[0], 0xFF);  // JPEG SOI marker
  EXPECT_EQ(c.data[1], 0xD8);
  EXPECT_LT(c.data.size(), px.size() / 3);  // a smooth image compresses well
  const cv::Mat bgr = cv::imdecode(c.data, cv::IMREAD_COLOR);
  ASSERT_EQ(bgr.cols, w);
  ASSERT_EQ(bgr.rows, h);
  // Quality 95 over a smooth field: a few levels of error on average (chroma subsampling costs
  // most at the red quarter's edges), never a channel swap (that would be 200 levels off).
  double sum = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      for (int ch = 0; ch < 3; ++ch)
        sum += std::abs(bgr.at<cv::Vec3b>(y, x)[2 - ch] -
                        px[static_cast<std::size_t>(y) * step + 3u * static_cast<std::size_t>(x) + ch]);
  EXPECT_LT(sum / (w * h * 3), 4.0);
  const cv::Vec3b red = bgr.at<cv::Vec3b>(h / 4, w / 4);  // deep inside the red quarter
  EXPECT_GT(red[2], 200);
  EXPECT_LT(red[0], 45);
}

TEST(ImageCompression, SixteenBitImagesArePngAndExact) {
  const int w = 20, h = 10;
  std::vector<std::uint16_t> depth(static_cast<std::size_t>(w) * h);
  for (int i = 0; i < w * h; ++i) depth[i] = static_cast<std::uint16_t>(1000 + 257 * i);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(depth.data());
  const auto c = compress_image(ImageView{"16UC1", w, h, 2 * w, false, bytes, depth.size() * 2}, 80);
  EXPECT_EQ(c.format, "16UC1; png compressed mono16");
  const cv::Mat back = cv::imdecode(c.data, cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_16UC1);
  for (int i = 0; i < w * h; ++i) ASSERT_EQ(back.at<std::uint16_t>(i / w, i % w), depth[i]) << i;

  // Big-endian pixels are swapped to the value they mean.
  std::vector<std::uint8_t> be(2u * static_cast<std::size_t>(w) * h);
  for (int i = 0; i < w * h; ++i) {
    be[2u * static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(depth[i] >> 8);
    be[2u * static_cast<std::size_t>(i) + 1] = static_cast<std::uint8_t>(depth[i] & 0xFF);
  }
  const auto cb = compress_image(ImageView{"mono16", w, h, 2 * w, true, be.data(), be.size()}, 80);
  const cv::Mat back_be = cv::imdecode(cb.data, cv::IMREAD_UNCHANGED);
  for (int i = 0; i < w * h; ++i) ASSERT_EQ(back_be.at<std::uint16_t>(i / w, i % w), depth[i]) << i;
}

TEST(ImageCompression, RefusesWhatItCannotCompress) {
  EXPECT_TRUE(compressible("rgb8"));
  EXPECT_TRUE(compressible("mono16"));
  EXPECT_FALSE(compressible("32FC1"));
  std::vector<std::uint8_t> px(100, 0);
  try {
    compress_image(ImageView{"32FC1", 5, 5, 20, false, px.data(), px.size()}, 90);
    ADD_FAILURE() << "32FC1 compressed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("'32FC1' cannot be compressed"), std::string::npos) << e.what();
  }
  try {  // 10x10 rgb8 needs step >= 30 and 300 bytes
    compress_image(ImageView{"rgb8", 10, 10, 30, false, px.data(), px.size()}, 90);
    ADD_FAILURE() << "a short buffer compressed";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("bytes >= step * height"), std::string::npos) << e.what();
  }
  EXPECT_THROW(compress_image(ImageView{"mono8", 10, 10, 10, false, px.data(), px.size()}, 0), std::invalid_argument);
}
