// KITTI odometry layout (read by ORB-SLAM's KITTI examples, pykitti's image/time/pose loaders and
// evo's `kitti` reader):
//   <root>/sequences/<seq>/image_0/<index:06d>.png   8-bit grey images (KITTI's cam0 is grey)
//   <root>/sequences/<seq>/times.txt                 seconds since the first image, one per image
//   <root>/sequences/<seq>/calib.txt                 "P0: fx 0 cx 0 0 fy cy 0 0 0 1 0" (3x4, row-major)
//   <root>/poses/<seq>.txt                           per image, the 12 numbers of the 3x4 [R | t] of
//                                                    the camera in the FIRST camera's frame
// and, as an extension named like image_0 (file i = image i):
//   <root>/sequences/<seq>/depth_0/<index:06d>.png   uint16 depth along the optical axis, 1000 per metre
//   <root>/sequences/<seq>/seg_0/<index:06d>.png     8-bit segmentation class ids
// (a depth or segmentation image that arrives before its colour image waits for its index).
// The camera frame is the optical frame (x right, y down, z forward), as KITTI's. KITTI images
// are rectified: distortion coefficients are not stored, so record an undistorted camera (the
// down camera) for this layout; a distorted camera is reported by warnings(). Line i of the poses
// belongs to image i: the writer checks the pairing and reports images left without a pose.
#pragma once

#include <fstream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "unav_datagen/dataset_writer.hpp"

namespace unav::datagen {

class KittiWriter final : public SequenceWriter {
 public:
  /// Creates the folders of sequence `sequence` (e.g. "00"). Throws DatasetError naming the path.
  explicit KittiWriter(const std::string& root, const std::string& sequence = "00");
  ~KittiWriter() override;

  void write_camera(const CameraIntrinsics& k) override;
  void write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) override;
  void write_depth(double stamp, int width, int height, const float* depth_m) override;
  void write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) override;
  void write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB) override;
  void close() override;
  std::string format() const override { return "kitti"; }
  double depth_units_per_metre() const override { return kDepthUnitsPerMetre; }
  std::vector<std::string> layout_entries() const override { return {"sequences", "poses"}; }
  static constexpr double kDepthUnitsPerMetre = 1000.0;
  std::vector<std::string> warnings() const override;

 private:
  /// A depth (true) or label PNG, encoded, for the image of a stamp.
  using Png = std::pair<bool, std::vector<unsigned char>>;
  /// Writes it as depth_0/seg_0 file `index`.
  void write_per_pixel(std::size_t index, const Png& png);
  /// Writes it now if its colour image has an index, else keeps it until write_rgb gives one.
  void put(double stamp, Png png);
  std::string seq_dir_;
  std::ofstream times_, poses_;
  std::multimap<double, Png> pending_;
  std::vector<double> image_stamps_;
  std::size_t unpaired_poses_ = 0;
  bool have_first_ = false, distorted_ = false, closed_ = false;
  Eigen::Isometry3d X_C0W_ = Eigen::Isometry3d::Identity();  ///< inverse of the first camera pose
};

}  // namespace unav::datagen
