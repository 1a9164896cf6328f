// drl_planner: the paper's DRL planner on the wire (or the classical baseline behind the same
// interface). Every step_period seconds it reads the latest down-camera image, asks the policy
// for a = (a1, a2) and turns it into a 1 m waypoint (unav_control/pipe_action.hpp: the same
// rule as the training environment); it answers every odometry with the current waypoint, so
// the MPC's setpoint_sync and the lockstep barrier see one setpoint per state.
//   sub  camera/<camera>/image_raw   sensor_msgs/Image (rgb8)
//   sub  ground_truth/odom           nav_msgs/Odometry (world_ned / base_link_frd)
//   pub  control/pose_setpoint       geometry_msgs/PoseStamped (world_ned), stamped as the odometry
// With sync_images (lockstep), a decision at time t waits for the image stamped t (the renderer
// publishes it within the same barrier period), so runs repeat exactly; without, it uses the
// latest image. A missing or malformed model is a one-line error and a non-zero exit.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_common/config.hpp"
#include "unav_control/pipe_action.hpp"
#include "unav_planning/pipe_policy.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"

namespace unav::planning {

struct DrlPlannerParams {
  std::string policy = "drl";
  std::string model = "models/pipe_follower/policy.onnx";
  std::string camera = "down";
  double step_period = 1.5;
  unav::control::PipeActionParams action;  ///< as the training environment's (the same keys)
  double hold_depth = -1.0;
  bool sync_images = true;
  double camera_hfov_deg = 90.0;
  double height_above_pipe = 1.5;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(
        Field("policy", &policy).OneOf({"drl", "classical"}).Doc("the trained ONNX policy or the vision baseline"));
    a->Visit(Field("model", &model).Doc("ONNX file (+ .json beside it); relative: under the resource roots"));
    a->Visit(Field("camera", &camera).Doc("reads camera/<camera>/image_raw"));
    a->Visit(Field("step_period", &step_period)
                 .Above(0.0)
                 .Max(60.0)
                 .Unit("s")
                 .Doc("a new waypoint this often (training: step_duration_s)"));
    action.Serialize(a);
    a->Visit(
        Field("hold_depth", &hold_depth).Unit("m").Doc("waypoint depth (NED z); < 0: the depth at the first odometry"));
    a->Visit(
        Field("sync_images", &sync_images).Doc("decisions wait for the image stamped at the decision time (lockstep)"));
    a->Visit(Field("camera_hfov_deg", &camera_hfov_deg).Range(1.0, 179.0).Unit("deg").Doc("classical: field of view"));
    a->Visit(
        Field("height_above_pipe", &height_above_pipe).Above(0.0).Unit("m").Doc("classical: pixel -> metre scale"));
  }
};

class DrlPlannerNode : public unav::Node {
 public:
  explicit DrlPlannerNode(const unav::NodeOptions& options);
  ~DrlPlannerNode() override;
  std::uint64_t decisions() const { return decisions_; }

 private:
  void on_odom(const nav_msgs::msg::Odometry& m);
  void on_image(const sensor_msgs::msg::Image& m);
  void decide(const nav_msgs::msg::Odometry& m);
  void answer(const nav_msgs::msg::Odometry& m);

  DrlPlannerParams p_;
  std::unique_ptr<PipePolicy> policy_;
  std::optional<sensor_msgs::msg::Image> image_;
  std::optional<nav_msgs::msg::Odometry> pending_;  // waiting for its image (sync_images)
  std::int64_t next_decision_ns_ = -1;
  double hold_depth_ = -1.0;
  bool have_setpoint_ = false;
  unav::control::PoseSetpoint setpoint_;
  std::uint64_t decisions_ = 0;
  double inference_ms_ = 0.0;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  unav::RejectionCounter rejections_{logger()};  // odometry with NaN/Inf or a non-rotation
  std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> image_sub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PoseStamped>> pub_;
};

}  // namespace unav::planning
