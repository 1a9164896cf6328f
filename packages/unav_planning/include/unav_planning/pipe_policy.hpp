// Pipe-following planners behind one interface: an image from the down camera in, the paper's
// action a = (a1, a2) in [-1, 1]^2 out (see unav_control/pipe_action.hpp for its meaning).
//   OnnxPipePolicy         the trained DRL policy (PPO CnnPolicy exported to ONNX by
//                          scripts/train_pipe_follower.py), run by OpenCV's DNN module
//   ClassicalPipeFollower  a classical vision baseline: the pipe as the low-texture band of the
//                          image, its axis from image moments, a proportional steering law
// No DDS: the drl_planner node (nodes/) adapts these to topics.
#pragma once

#include <array>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

namespace unav::planning {

class PipePolicy {
 public:
  virtual ~PipePolicy() = default;
  /// rgb: CV_8UC3, RGB order (sensor_msgs rgb8), any size (resized to what the policy needs).
  virtual std::array<double, 2> act(const cv::Mat& rgb) = 0;
  virtual std::string name() const = 0;
};

/// The ONNX model: input "image" float32 NHWC 0..255 of the trained size, output "action" (1, 2).
/// The trained size comes from <model>.json (obs_shape [h, w, 3]) written beside it at export.
class OnnxPipePolicy : public PipePolicy {
 public:
  /// Throws std::runtime_error with a one-line message: missing file, unreadable model, missing
  /// or malformed metadata, or an output that is not 2 numbers.
  explicit OnnxPipePolicy(const std::string& model_path);
  std::array<double, 2> act(const cv::Mat& rgb) override;
  std::string name() const override { return "drl(" + path_ + ")"; }
  int input_width() const { return width_; }
  int input_height() const { return height_; }

 private:
  struct Impl;
  std::shared_ptr<Impl> impl_;
  std::string path_;
  int width_ = 0, height_ = 0;
};

struct ClassicalFollowerParams {
  double hfov_deg = 90.0;          ///< down camera horizontal field of view
  double height_m = 1.5;           ///< flight height above the pipe (pixel -> metre scale)
  double lookahead_m = 3.0;        ///< steer to the pipe axis this far ahead
  double turn_gain = 0.5;          ///< heading change per step = gain x the pipe's angle (damped)
  double max_step_angle_deg = 60;  ///< the action scaling of the task
  double max_turn_deg = 30;
  double min_area_fraction = 0.03;  ///< smaller pipe blobs count as "pipe not seen"
};

/// The baseline. When no pipe is seen it keeps going straight (a = 0).
class ClassicalPipeFollower : public PipePolicy {
 public:
  explicit ClassicalPipeFollower(ClassicalFollowerParams params = {}) : p_(params) {}
  std::array<double, 2> act(const cv::Mat& rgb) override;
  std::string name() const override { return "classical"; }
  /// Last estimate: lateral offset of the pipe axis (m, > 0 right of the vehicle), its angle to
  /// the heading (rad, > 0 turning right), whether it was seen.
  double lateral_m() const { return lateral_m_; }
  double angle_rad() const { return angle_rad_; }
  bool seen() const { return seen_; }

 private:
  ClassicalFollowerParams p_;
  double lateral_m_ = 0, angle_rad_ = 0;
  bool seen_ = false;
};

}  // namespace unav::planning
