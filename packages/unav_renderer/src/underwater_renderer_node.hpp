// underwater_renderer: renders the vehicle's cameras at the poses the physics server publishes.
//
// Ports (relative to the node namespace, default /rov; <cam> = camera name from cameras_config,
// all of them or those named in the `cameras` parameter):
//   sub  ground_truth/odom                      nav_msgs/Odometry       reliable
//   pub  camera/<cam>/image_raw                 sensor_msgs/Image       reliable, depth 5 (rgb8)
//   pub  camera/<cam>/camera_info               sensor_msgs/CameraInfo  reliable, depth 5
//   pub  camera/<cam>/depth/image_raw           sensor_msgs/Image       32FC1, metres along z
//   pub  camera/<cam>/segmentation/image_raw    sensor_msgs/Image       mono8 class ids
//   pub  /lockstep/ack                          unav_msgs/LockstepAck   (lockstep: true)
//   pub  /tf_static                             tf2_msgs/TFMessage      static (latched): every camera
//                                               mount, <body_frame> -> <cam>_optical, once
// Images are stamped with the simulated time of the pose they show; frame_id <cam>_optical.
// A frame is rendered for the first odometry at or after each multiple of 1/rate. In lockstep,
// frame instants must be physics barriers (1/rate a multiple of the server's lockstep_period),
// and every odometry message is acked after the frame due at its time has been published. A
// state repeated by the physics server (it resends a held barrier's state every second) for the
// instant of the last frame gets that frame published again, unchanged: a reader that matched
// after it was sent (16 processes starting at once), or lost it, gets it then and the barrier
// opens. Frame consumers therefore skip (and ack again) a frame stamp they already have.
// Free-running (lockstep false), frames are published as they finish rendering, in order, and a
// frame falling due while earlier ones still render starts at once on another worker: up to
// render_workers / cameras frames of each camera in flight (at least 1), so one camera with two
// workers renders two frames at once. A frame due while that many are in flight waits for the
// oldest (no frame is dropped). Shutting down publishes the frames still rendering.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fleet_bodies_node.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/camera_info.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/config.hpp"
#include "unav_renderer/renderer.hpp"
#include "unav_renderer/renderer_pool.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::renderer {

/// The underwater_renderer's parameters (params file or `-p name:=value`; `--help` lists them).
struct UnderwaterRendererParams {
  /// scenario, world, water, body_frame, fleet: the scenario's world, water, cameras (config,
  /// names, size, rate), render switches and seed replace world, water, cameras_config, cameras,
  /// rate, render and seed (the noise seed is then MixSeed(scenario seed), as the in-process
  /// Episode's)
  SensorSceneParams scene;
  std::string cameras_config;  ///< default: the installed config/sensors/bluerov2_cameras.yaml
  std::vector<std::string> cameras;
  double rate = 10.0;
  unav::lockstep::ParticipantParams lockstep{"renderer"};
  bool publish_depth = true;
  bool publish_segmentation = true;
  scene::RenderSettings render;
  int64_t seed = 1;
  int64_t render_workers = 2;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scene.Serialize(a);
    a->Visit(Field("cameras_config", &cameras_config).Doc("camera YAML path"));
    a->Visit(Field("cameras", &cameras).Doc("cameras of cameras_config to render; [] = all"));
    a->Visit(Field("rate", &rate).Range(0.01, 1000.0).Unit("Hz").Doc("frame rate per camera"));
    lockstep.Serialize(a);
    a->Visit(Field("publish_depth", &publish_depth).Doc("publish depth images"));
    a->Visit(Field("publish_segmentation", &publish_segmentation).Doc("publish segmentation images"));
    a->Visit(Field("render", &render).Doc("realism switches (render.noise, render.shadows, ...)"));
    a->Visit(Field("seed", &seed).Min(0.0).Doc("noise seed"));
    a->Visit(Field("render_workers", &render_workers)
                 .Range(1, 8)
                 .Doc("renderers at once, one EGL context and thread each (RendererPool): a frame's cameras "
                      "render in parallel; free-running, successive frames too (lockstep: at most one per "
                      "camera)"));
  }
};

class UnderwaterRendererNode : public unav::Node {
 public:
  explicit UnderwaterRendererNode(const unav::NodeOptions& options);
  ~UnderwaterRendererNode() override;
  std::uint64_t frames_published() const { return frames_; }
  /// Frames published again for a repeated state (see above).
  std::uint64_t frames_republished() const { return republished_; }
  /// Frame instants (all cameras) rendering at once at most: 1 in lockstep, free-running
  /// render_workers / cameras (at least 1).
  std::size_t max_frames_in_flight() const { return max_in_flight_; }
  /// Other vehicles' states taken (fleet_bodies).
  std::uint64_t fleet_states() const { return fleet_ ? fleet_->states() : 0; }
  /// The most frame instants that were in flight at once so far.
  std::size_t peak_frames_in_flight() const { return peak_in_flight_; }

 private:
  struct CameraPorts {
    std::string name;
    std::shared_ptr<unav::Publisher<sensor_msgs::msg::Image>> image, depth, seg;
    std::shared_ptr<unav::Publisher<sensor_msgs::msg::CameraInfo>> info;
    sensor_msgs::msg::Image image_msg, depth_msg, seg_msg;
    sensor_msgs::msg::CameraInfo info_msg;
  };
  /// A frame instant in flight: its header, and how many of its cameras were published.
  struct Instant {
    std_msgs::msg::dds_::Header_ header;
    std::size_t published = 0;
  };
  void on_odom(const nav_msgs::msg::Odometry& odom);
  /// Renders the frame instant of this state (lockstep: published), then acks it.
  void render_state(const Pose& X_WB, const BodyVelocity& velocity, const std_msgs::msg::dds_::Header_& header);
  void submit(const Pose& X_WB, const BodyVelocity& velocity, const std_msgs::msg::dds_::Header_& header);
  /// Publishes the rendered frames in order: those done (wait false) or all in flight (true).
  void publish_rendered(bool wait);
  /// Publishes the next frame of the oldest instant in flight, waiting for it.
  void publish_next();
  void publish_frame(CameraPorts& c, Frame& f, const std_msgs::msg::dds_::Header_& header);
  void republish_last_frame();

  std::unique_ptr<RendererPool> renderer_;  // the cameras of a frame in parallel, in order
  std::vector<CameraPorts> cameras_;
  std::deque<Instant> in_flight_;  // submitted to renderer_, oldest first
  std::size_t max_in_flight_ = 1, peak_in_flight_ = 0;
  std::shared_ptr<unav::Timer> poll_timer_;  // free-running: publishes frames as they finish
  double period_ = 0.1;
  double next_frame_t_ = -1.0;  // set by the first odometry
  bool lockstep_ = false;
  bool publish_depth_ = true, publish_seg_ = true;
  std::string ack_name_;
  std::uint64_t frames_ = 0, republished_ = 0;
  std::int64_t repeated_ns_ = INT64_MIN;  ///< the instant republish_last_frame() last answered
  int repeats_ = 0;                       ///< how many times in a row
  std::int64_t last_state_ns_ = INT64_MIN, last_frame_ns_ = INT64_MIN;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  unav::RejectionCounter rejections_{logger()};  // ground_truth/odom with NaN/Inf or a non-rotation
  std::shared_ptr<unav::Publisher<tf2_msgs::msg::TFMessage>> tf_static_pub_;
  std::unique_ptr<FleetPoses> fleet_;  // the other vehicles drawn
};

}  // namespace unav::renderer
