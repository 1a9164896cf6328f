// EuRoC/ASL MAV dataset layout (the format of the EuRoC MAV sequences, read by ORB-SLAM3's EuRoC
// examples, OpenVINS, Kalibr, evo's `euroc` reader):
//   <root>/mav0/cam0/data/<t_ns>.png                     8-bit grey images (EuRoC's cameras are mono)
//   <root>/mav0/cam0/data.csv                            "#timestamp [ns],filename"
//   <root>/mav0/cam0/sensor.yaml                         T_BS (camera in the body), rate_hz, resolution,
//                                                        pinhole intrinsics [fu, fv, cu, cv],
//                                                        radial-tangential [k1, k2, p1, p2]
//   <root>/mav0/imu0/data.csv                            "#timestamp [ns],w_RS_S_x [rad s^-1],...,a_RS_S_z [m s^-2]"
//   <root>/mav0/imu0/sensor.yaml                         T_BS = identity (the IMU is the body frame), rate_hz
//   <root>/mav0/state_groundtruth_estimate0/data.csv     "#timestamp, p_RS_R_x [m], ..., q_RS_w [], q_RS_x [], ..."
// and, as an extension in the same shape (cam0's stamps and mount):
//   <root>/mav0/depth0/data/<t_ns>.png, data.csv         uint16 depth along the optical axis, 1000 per
//                                                        metre (mm; 0 = no return or beyond 65.5 m)
//   <root>/mav0/seg0/data/<t_ns>.png, data.csv           8-bit segmentation class ids (manifest.json
//                                                        "labels")
// Frames: R = world_ned, S = B = base_link_frd (the IMU and ground truth are the body's), camera =
// the optical frame (x right, y down, z forward). Ground truth has the pose columns only (evo and
// the EuRoC tools read columns 0-7); simulated velocity and bias columns are not invented.
// Time stamps are integer nanoseconds of simulated time. rate_hz in sensor.yaml is measured from
// the stamps when the writer closes.
#pragma once

#include <fstream>
#include <string>
#include <vector>

#include "unav_datagen/dataset_writer.hpp"

namespace unav::datagen {

class EurocWriter final : public SequenceWriter {
 public:
  /// Creates the folders. Throws DatasetError naming the path when it cannot.
  explicit EurocWriter(const std::string& root);
  ~EurocWriter() override;

  void write_camera(const CameraIntrinsics& k) override;
  void set_camera_mount(const Eigen::Isometry3d& X_BC) override;
  void write_rgb(double stamp, int width, int height, const std::uint8_t* rgb) override;
  void write_depth(double stamp, int width, int height, const float* depth_m) override;
  void write_segmentation(double stamp, int width, int height, const std::uint8_t* ids) override;
  void write_pose(double stamp, const Eigen::Isometry3d& X_WC, const Eigen::Isometry3d& X_WB) override;
  void write_imu(double stamp, const Eigen::Vector3d& gyro, const Eigen::Vector3d& accel) override;
  void close() override;
  std::string format() const override { return "euroc"; }
  double depth_units_per_metre() const override { return kDepthUnitsPerMetre; }
  std::vector<std::string> layout_entries() const override { return {"mav0"}; }
  static constexpr double kDepthUnitsPerMetre = 1000.0;
  std::vector<std::string> warnings() const override;

  /// Seconds to EuRoC's integer nanoseconds (rounded).
  static long long to_ns(double stamp);

 private:
  /// First and last stamp of a stream: its rate in sensor.yaml, with the stream's count.
  struct Span {
    long long first_ns = -1, last_ns = -1;
    void add(long long ns) {
      if (first_ns < 0) first_ns = ns;
      last_ns = ns;
    }
  };
  void write_sensor_yamls();
  std::string mav_;
  std::ofstream cam_csv_, imu_csv_, gt_csv_, depth_csv_, seg_csv_;
  CameraIntrinsics k_;
  bool have_k_ = false, have_mount_ = false, closed_ = false;
  Eigen::Isometry3d X_BC_ = Eigen::Isometry3d::Identity();
  Span images_, imu_;
};

}  // namespace unav::datagen
