// Offline inputs of the estimators: a camera file, a folder of images, and the aiding sensors'
// logs of a dataset (IMU, DVL, the camera's mount).
#pragma once

#include <Eigen/Geometry>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "unav_localization/slam_map.hpp"

namespace unav::localization {

/// An input file is unusable; what() names the file (and line or key) and the rule.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct CameraFile {
  PinholeCamera camera;
  std::vector<double> distortion;  ///< plumb_bob k1 k2 p1 p2 k3 (may be empty)
  double depth_scale = 0.0;        ///< depth PNG units per metre (`depth_scale`; 0: not given)
};

/// Reads a camera YAML: our dataset format (width, height, fx, fy, cx, cy, distortion: [...]), a
/// ROS camera_info YAML (image_width, image_height, camera_matrix.data, distortion_coefficients.data)
/// or a EuRoC cam0/sensor.yaml (resolution, intrinsics: fu fv cu cv, distortion_coefficients).
/// Throws InputError naming the file and key for missing keys, NaN/Inf, non-positive sizes.
CameraFile LoadCameraFile(const std::string& path);

struct SequenceImage {
  double stamp;
  std::string path;
};

/// The images of a folder, in time order: a TUM RGB-D dataset folder (rgb.txt: "stamp path"
/// lines) or a folder of .png/.jpg files, stamped by their file name when it is a number
/// (e.g. 12.300000.png; integer names of 16+ digits are nanoseconds, as EuRoC's
/// mav0/cam0/data/ has them) and else by their order at `fps`. Throws InputError for a missing or
/// empty folder, a malformed rgb.txt line (file:line) or non-increasing stamps.
std::vector<SequenceImage> ListImages(const std::string& dir, double fps = 10.0);

/// An IMU sample: angular rate [rad/s] and specific force [m/s^2] in the body frame at stamp [s].
struct ImuSample {
  double stamp = 0.0;
  Eigen::Vector3d gyro = Eigen::Vector3d::Zero(), accel = Eigen::Vector3d::Zero();
};
/// The IMU samples of a log, in time order: our datasets' imu.txt ("t wx wy wz ax ay az", '#'
/// comments) or EuRoC's mav0/imu0/data.csv ("t_ns,w_x,w_y,w_z,a_x,a_y,a_z", stamps in ns: any
/// line with commas). Throws InputError naming file:line for a malformed or non-finite line or a
/// stamp not after the one before.
std::vector<ImuSample> ReadImuSamples(const std::string& path);

/// A DVL reading: the bottom-relative velocity [m/s] of the DVL in its own axes, and whether it had
/// bottom lock (an unlocked reading's velocity is zero).
struct DvlSample {
  double stamp = 0.0;
  Eigen::Vector3d velocity = Eigen::Vector3d::Zero();
  bool valid = false;
};
/// The DVL readings of our datasets' nav/dvl.csv ("t,valid,vx_mps,vy_mps,vz_mps,..." after a '#'
/// header; NaN velocities where valid is 0), in time order. Throws InputError naming file:line.
std::vector<DvlSample> ReadDvlSamples(const std::string& path);

/// The camera's mount in the body frame (the optical frame's pose, metric) from a dataset's
/// manifest.json (camera.mount_xyz_m, camera.mount_quaternion_xyzw) or a EuRoC cam0/sensor.yaml
/// (T_BS: the camera in the IMU's body frame); nullopt when the file says it is not known or has
/// none. Throws InputError naming the file for an unreadable file or a malformed mount.
std::optional<Eigen::Isometry3d> ReadCameraMount(const std::string& manifest_path);

}  // namespace unav::localization
