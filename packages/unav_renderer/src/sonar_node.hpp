// sonar: pings the vehicle's sonars (forward-looking, side-scan, profiling) at the poses the physics
// server publishes, on the renderer's GL scene.
//
// Ports (relative to the node namespace, default /rov; <s> = sonar name from sonars_config, all
// of them or those named in the `sonars` parameter):
//   sub  ground_truth/odom              nav_msgs/Odometry                       reliable
//   FLS:
//   pub  sonar/<s>/image                marine_acoustic_msgs/ProjectedSonarImage  reliable, depth 5
//   pub  sonar/<s>/image_fan            sensor_msgs/Image (mono8, Cartesian fan, forward up)
//   profiling: the FLS topics and
//   pub  sonar/<s>/points               sensor_msgs/PointCloud2 (x, y, z, intensity float32 in <s>_link:
//                                       each beam's strongest echo, detection_db above its median)
//   side-scan:
//   pub  sonar/<s>/raw                  marine_acoustic_msgs/RawSonarImage (2 beams: port, starboard)
//   pub  sonar/<s>/waterfall            sensor_msgs/Image (mono8, newest ping on top)
//   pub  /lockstep/ack                  unav_msgs/LockstepAck   (lockstep: true)
//   pub  /tf_static                     every sonar mount, <body_frame> -> <s>_link (z forward, x up)
// A ping is made for the first odometry at or after each multiple of 1 / ping_rate_hz (the
// sonar's config), stamped with the simulated time of the pose; in lockstep the ping instants
// must be physics barriers, and every odometry message is acked once the pings due at its time
// are published.
// Side-scan uses RawSonarImage: its samples are per beam in time order (sample_rate = c / (2 bin
// width)), which is what a side-scan records; ProjectedSonarImage would claim a fan geometry.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet_bodies_node.hpp"
#include "marine_acoustic_msgs/msg/projected_sonar_image.hpp"
#include "marine_acoustic_msgs/msg/raw_sonar_image.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "sensor_msgs/msg/point_cloud2.hpp"
#include "sensor_msgs/msg/point_field.hpp"
#include "tf2_msgs/msg/tf_message.hpp"
#include "unav_common/config.hpp"
#include "unav_renderer/sonar_renderer.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::renderer {

/// The sonar node's parameters (params file or `-p name:=value`; `--help` lists them).
struct SonarNodeParams {
  /// scenario, world, water, body_frame, fleet: the scenario's world, water and sonars (config,
  /// names) replace world, water, sonars_config and sonars
  SensorSceneParams scene;
  std::string sonars_config;  ///< default: the installed config/sensors/bluerov2_sonars.yaml
  std::vector<std::string> sonars;
  unav::lockstep::ParticipantParams lockstep{"sonar"};
  bool noise = true;          ///< speckle and background noise
  int64_t seed = 1;           ///< noise seed
  int fan_width = 512;        ///< FLS fan image width [px]; 0 = none
  int waterfall_lines = 400;  ///< side-scan waterfall height; 0 = none

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scene.Serialize(a);
    a->Visit(Field("sonars_config", &sonars_config).Doc("sonar YAML path"));
    a->Visit(Field("sonars", &sonars).Doc("sonars of sonars_config to ping; [] = all"));
    lockstep.Serialize(a);
    a->Visit(Field("noise", &noise).Doc("speckle and background noise"));
    a->Visit(Field("seed", &seed).Min(0.0).Doc("noise seed"));
    a->Visit(Field("fan_width", &fan_width).Range(0, 4096).Unit("px").Doc("FLS fan image width; 0 = no fan image"));
    a->Visit(Field("waterfall_lines", &waterfall_lines).Range(0, 10000).Doc("side-scan waterfall height; 0 = none"));
  }
};

class SonarNode : public unav::Node {
 public:
  explicit SonarNode(const unav::NodeOptions& options);
  ~SonarNode() override;
  std::uint64_t pings_published() const { return pings_; }
  /// Other vehicles' states taken (fleet_bodies).
  std::uint64_t fleet_states() const { return fleet_ ? fleet_->states() : 0; }

 private:
  struct Ports {
    std::string name;
    bool side_scan = false;
    double period = 0.1;
    double next_t = 0.0;
    std::shared_ptr<unav::Publisher<marine_acoustic_msgs::msg::ProjectedSonarImage>> image;
    std::shared_ptr<unav::Publisher<marine_acoustic_msgs::msg::RawSonarImage>> raw;
    std::shared_ptr<unav::Publisher<sensor_msgs::msg::Image>> view;          // fan or waterfall
    std::shared_ptr<unav::Publisher<sensor_msgs::msg::PointCloud2>> points;  // profiling
    std::unique_ptr<Waterfall> waterfall;
  };
  void on_odom(const nav_msgs::msg::Odometry& odom);
  /// The pings due at this state, published, then the state acked.
  void ping_state(const scene::Pose& X_WB, const std_msgs::msg::Header& header);
  void publish_ping(Ports& p, const SonarPing& ping, const std_msgs::msg::Header& header);
  void publish_profile(Ports& p, const SonarPing& ping, double detection_db, const std_msgs::msg::Header& h);

  std::unique_ptr<SonarRenderer> sonar_;
  std::vector<Ports> ports_;
  int fan_width_ = 512;
  std::uint64_t pings_ = 0;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::unique_ptr<unav::lockstep::Acker> acker_;
  unav::RejectionCounter rejections_{logger()};  // ground_truth/odom with NaN/Inf or a non-rotation
  std::shared_ptr<unav::Publisher<tf2_msgs::msg::TFMessage>> tf_static_pub_;
  std::unique_ptr<FleetPoses> fleet_;  // the other vehicles drawn
  bool lockstep_ = false;
};

}  // namespace unav::renderer
