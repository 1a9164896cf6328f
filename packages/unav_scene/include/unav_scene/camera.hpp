// Camera models loaded from config/sensors/*.yaml.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "unav_scene/frames.hpp"

namespace unav::scene {

/// Pinhole camera with plumb_bob distortion, mounted on the vehicle body.
/// Pixel convention as OpenCV / ROS CameraInfo: the centre of the top-left pixel is (0, 0),
/// u = fx x/z + cx, v = fy y/z + cy in the optical frame.
struct CameraModel {
  std::string name = "camera";
  Pose X_BC = Pose::Identity();  ///< optical frame C in body frame base_link_frd
  int width = 320;
  int height = 180;
  double fx = 0, fy = 0, cx = 0, cy = 0;  ///< [px]
  /// plumb_bob coefficients k1, k2, p1, p2, k3 (OpenCV order); all zero = none.
  Eigen::Matrix<double, 5, 1> distortion = Eigen::Matrix<double, 5, 1>::Zero();
  double noise_stddev = 0.0;  ///< additive Gaussian noise, fraction of full scale (0..1)
  double exposure = 1.0;      ///< linear gain before sRGB encoding
  double near_m = 0.05, far_m = 200.0;

  Eigen::Matrix3d K() const;
  bool has_distortion() const { return distortion.cwiseAbs().maxCoeff() > 0.0; }
  /// Build from a horizontal field of view [rad]; fy = fx, principal point at the centre.
  static CameraModel from_hfov(const std::string& name, int width, int height, double hfov_rad);
  /// Throws ConfigError naming the camera and field (non-positive FOV/size, ...).
  void validate(const std::string& where) const;
};

/// Load all cameras of a sensor YAML file (layout: see config/sensors/bluerov2_cameras.yaml).
/// Errors name the file, the camera and the key.
std::vector<CameraModel> load_cameras(const std::string& path);

/// The camera called `name` in a sensor YAML file. Throws ConfigError naming the file, the camera
/// and the cameras the file has when there is none of that name.
CameraModel load_camera(const std::string& path, const std::string& name);

/// The paper's default vehicle: "front" (640x480, 80 deg) and "down" (320x180, 90 deg).
std::vector<CameraModel> default_cameras();

}  // namespace unav::scene
