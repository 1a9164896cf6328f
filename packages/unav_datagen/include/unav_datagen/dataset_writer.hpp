// Sequence writers: one camera's frames with ground truth and IMU, in a dataset layout that
// existing tools read. SequenceWriter is the interface; make_sequence_writer() picks a layout:
//   tum    TUM RGB-D (DatasetWriter, below)
//   euroc  EuRoC/ASL MAV (EurocWriter, euroc_writer.hpp)
//   kitti  KITTI odometry (KittiWriter, kitti_writer.hpp)
//
// DatasetWriter writes synchronized camera frames and ground truth in the TUM RGB-D dataset layout:
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
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

namespace unav::datagen {

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
/// Metres to 16-bit depth units (TUM's 5000 per metre by default): 0 for non-finite,
/// non-positive or too-far values.
std::uint16_t encode_depth(float metres, double units_per_metre = kDepthScale);

/// One camera's sequence. Calls arrive in stamp order per stream; a layout ignores the streams
/// it has no place for (e.g. KITTI has no IMU file). Every writer flushes each record as it
/// writes it, so a run stopped with Ctrl-C keeps what it recorded; close() (also the destructor)
/// writes what needs the whole sequence (rates, summaries).
/// What a writer has written so far.
struct SequenceCounts {
  std::size_t images = 0, depth = 0, segmentation = 0, poses = 0, imu = 0;
};

class SequenceWriter {
 public:
  explicit SequenceWriter(std::string root) : root_(std::move(root)) {}
  virtual ~SequenceWriter() = default;
  /// The layout's name (tum, euroc, kitti).
  virtual std::string format() const = 0;
  /// What was written so far.
  const SequenceCounts& counts() const { return counts_; }
  /// Images written so far.
  std::size_t frames() const { return counts_.images; }
  const std::string& root() const { return root_; }
  /// Depth PNG units per metre (uint16; 0 = no return or beyond 65535 units).
  virtual double depth_units_per_metre() const = 0;
  /// The files and folders (relative to root()) this layout writes: what manifest.json covers.
  virtual std::vector<std::string> layout_entries() const = 0;
  virtual void write_camera(const CameraIntrinsics& k) = 0;
  /// The camera optical frame in the body frame (X_BC), once known; layouts that store extrinsics
  /// (EuRoC's T_BS) use it.
  virtual void set_camera_mount(const Eigen::Isometry3d& /*X_BC*/) {}
  /// Each image is written once per stamp; `rgb` is width*height*3 bytes in RGB order.
  virtual void write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) = 0;
  virtual void write_depth(double /*stamp*/, int /*width*/, int /*height*/, const float* /*depth_m*/) {}
  virtual void write_segmentation(double /*stamp*/, int /*width*/, int /*height*/, const std::uint8_t* /*ids*/) {}
  /// Ground truth of the image with this stamp: camera optical frame and body in world_ned.
  virtual void write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB) = 0;
  virtual void write_imu(double /*stamp*/, const Eigen::Vector3d& /*gyro*/, const Eigen::Vector3d& /*accel*/) {}
  virtual void close() = 0;
  /// Problems found while writing (e.g. an image without ground truth), one line each.
  virtual std::vector<std::string> warnings() const { return {}; }

 protected:
  std::string root_;
  SequenceCounts counts_;
};

/// The layouts make_sequence_writer() knows: "tum", "euroc", "kitti".
std::vector<std::string> sequence_formats();
/// Throws DatasetError naming the format (and the valid ones) or the path it cannot create.
std::unique_ptr<SequenceWriter> make_sequence_writer(const std::string& format, const std::string& root);

class DatasetWriter final : public SequenceWriter {
 public:
  /// Creates the folders. Throws DatasetError naming the path when it cannot.
  explicit DatasetWriter(const std::string& root);
  ~DatasetWriter() override;

  void write_camera(const CameraIntrinsics& k) override;
  void write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) override;
  void write_depth(double stamp, int width, int height, const float* depth_m) override;
  void write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) override;
  void write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB) override;
  void write_imu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) override;
  /// Flushes and closes every file (also done by the destructor).
  void close() override;
  std::string format() const override { return "tum"; }
  double depth_units_per_metre() const override { return kDepthScale; }
  std::vector<std::string> layout_entries() const override {
    return {"rgb",
            "depth",
            "segmentation",
            "rgb.txt",
            "depth.txt",
            "segmentation.txt",
            "groundtruth.txt",
            "groundtruth_body.txt",
            "imu.txt",
            "camera.yaml"};
  }

 private:
  static std::string stamp_name(double stamp);
  std::ofstream rgb_txt_, depth_txt_, seg_txt_, gt_txt_, gt_body_txt_, imu_txt_;
};

}  // namespace unav::datagen
