// Writes synchronized camera frames and ground truth in the TUM RGB-D dataset layout:
//   <root>/rgb/<stamp>.png          rgb8 images (PNG, stored BGR as OpenCV writes it)
//   <root>/depth/<stamp>.png        16-bit depth, value = metres * 5000 (TUM), 0 = no return
//   <root>/segmentation/<stamp>.png 8-bit class ids (0 water, 1 seabed, 2 pipeline, 3 rock, 4 other)
//   <root>/rgb.txt, depth.txt, segmentation.txt   "timestamp filename" lines
//   <root>/groundtruth.txt          "timestamp tx ty tz qx qy qz qw" (camera optical frame in world_ned)
//   <root>/groundtruth_body.txt     the same for base_link_frd
//   <root>/imu.txt                  "timestamp wx wy wz ax ay az" (body FRD, rad/s and m/s^2)
//   <root>/camera.yaml              intrinsics and distortion (written once)
// Every line is flushed as it is written: a run stopped with Ctrl-C loses nothing.
#pragma once

#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace unav_datagen {

class DatasetError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CameraIntrinsics {
  int width = 0, height = 0;
  double fx = 0, fy = 0, cx = 0, cy = 0;
  std::vector<double> distortion;  ///< plumb_bob k1 k2 p1 p2 k3
};

/// TUM's depth scale: 5000 units per metre (0.2 mm); 65535 is 13.1 m, the farthest storable.
constexpr double kDepthScale = 5000.0;
/// Metres to TUM 16-bit depth: 0 for non-finite, non-positive or too-far values.
std::uint16_t encode_depth(float metres);

class DatasetWriter {
 public:
  /// Creates the folders. Throws DatasetError naming the path when it cannot.
  explicit DatasetWriter(const std::string& root);
  ~DatasetWriter();

  void write_camera(const CameraIntrinsics& k);
  /// Each image is written once per stamp; `rgb` is width*height*3 bytes in RGB order.
  void write_rgb(double stamp, int width, int height, const std::uint8_t* rgb);
  void write_depth(double stamp, int width, int height, const float* depth_m);
  void write_segmentation(double stamp, int width, int height, const std::uint8_t* ids);
  void write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB);
  void write_imu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel);
  /// Flushes and closes every file (also done by the destructor).
  void close();
  std::size_t frames() const { return frames_; }
  const std::string& root() const { return root_; }

 private:
  static std::string stamp_name(double stamp);
  std::string root_;
  std::ofstream rgb_txt_, depth_txt_, seg_txt_, gt_txt_, gt_body_txt_, imu_txt_;
  std::size_t frames_ = 0;
};

}  // namespace unav_datagen
