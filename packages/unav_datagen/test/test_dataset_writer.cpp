#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include <opencv2/imgcodecs.hpp>

#include "unav_datagen/dataset_writer.hpp"

using namespace unav_datagen;

TEST(DatasetWriter, DepthEncodingFollowsTum) {
  EXPECT_EQ(encode_depth(1.0f), 5000);
  EXPECT_EQ(encode_depth(0.0002f), 1);  // 0.2 mm resolution
  EXPECT_EQ(encode_depth(13.0f), 65000);
  EXPECT_EQ(encode_depth(14.0f), 0);  // beyond 13.1 m: not storable, marked missing
  EXPECT_EQ(encode_depth(std::numeric_limits<float>::infinity()), 0);
  EXPECT_EQ(encode_depth(std::nanf("")), 0);
  EXPECT_EQ(encode_depth(-1.0f), 0);
}

TEST(DatasetWriter, WritesTumLayoutThatReadsBack) {
  const std::string root = ::testing::TempDir() + "dataset_test";
  std::filesystem::remove_all(root);
  {
    DatasetWriter w(root);
    w.write_camera({4, 2, 100, 100, 2, 1, {0.1, 0, 0, 0, 0}});
    const std::uint8_t rgb[4 * 2 * 3] = {255, 0, 0, 0, 255, 0, 0, 0, 255, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15};
    const float depth[8] = {1.0f, 2.5f, 0.0f, 3.0f, 1.0f, 1.0f, 1.0f, 13.0f};
    const std::uint8_t seg[8] = {0, 1, 2, 3, 4, 1, 1, 1};
    Eigen::Isometry3d X = Eigen::Isometry3d::Identity();
    X.translation() = Eigen::Vector3d(1, 2, 10);
    w.write_rgb(12.5, 4, 2, rgb);
    w.write_depth(12.5, 4, 2, depth);
    w.write_segmentation(12.5, 4, 2, seg);
    w.write_pose(12.5, X, X);
    w.write_imu(12.501, Eigen::Vector3d(0, 0, 0.1), Eigen::Vector3d(0, 0, -9.81));
    EXPECT_EQ(w.frames(), 1u);
  }
  const cv::Mat rgb = cv::imread(root + "/rgb/12.500000.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(rgb.empty());
  EXPECT_EQ(rgb.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 0, 255));  // red pixel, stored BGR
  const cv::Mat d = cv::imread(root + "/depth/12.500000.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(d.type(), CV_16UC1);
  EXPECT_EQ(d.at<std::uint16_t>(0, 1), 12500);  // 2.5 m * 5000
  EXPECT_EQ(d.at<std::uint16_t>(0, 2), 0);
  const cv::Mat s = cv::imread(root + "/segmentation/12.500000.png", cv::IMREAD_UNCHANGED);
  EXPECT_EQ(s.at<std::uint8_t>(0, 3), 3);
  std::ifstream gt(root + "/groundtruth.txt");
  std::string header, line;
  std::getline(gt, header);
  std::getline(gt, line);
  EXPECT_EQ(line, "12.500000000 1.000000000 2.000000000 10.000000000 0.000000000 0.000000000 0.000000000 1.000000000");
  std::ifstream rgb_txt(root + "/rgb.txt");
  std::getline(rgb_txt, header);
  std::getline(rgb_txt, line);
  EXPECT_EQ(line, "12.500000000 rgb/12.500000.png");
}

TEST(DatasetWriter, UnwritableRootIsAnError) {
  try {
    DatasetWriter w("/proc/unav_cannot_write_here");
    FAIL();
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("/proc/unav_cannot_write_here"), std::string::npos);
  }
}
