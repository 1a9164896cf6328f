// Offline inputs of the estimators: a camera file and a folder of images.
#pragma once

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

/// Reads a camera YAML: our dataset format (width, height, fx, fy, cx, cy, distortion: [...]) or
/// a ROS camera_info YAML (image_width, image_height, camera_matrix.data, distortion_coefficients.data).
/// Throws InputError naming the file and key for missing keys, NaN/Inf, non-positive sizes.
CameraFile LoadCameraFile(const std::string& path);

struct SequenceImage {
  double stamp;
  std::string path;
};

/// The images of a folder, in time order: a TUM RGB-D dataset folder (rgb.txt: "stamp path"
/// lines) or a folder of .png/.jpg files, stamped by their file name when it is a number
/// (e.g. 12.300000.png) and else by their order at `fps`. Throws InputError for a missing or
/// empty folder, a malformed rgb.txt line (file:line) or non-increasing stamps.
std::vector<SequenceImage> ListImages(const std::string& dir, double fps = 10.0);

}  // namespace unav::localization
