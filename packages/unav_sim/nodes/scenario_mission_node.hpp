// scenario_mission: a scenario's mission over DDS, the setpoints `unav run --in-process` flies
// (unav::sim::mission_setpoint), so the same scenario runs as processes (physics_server,
// mpc_controller with setpoint_sync, control_allocator, this node; launch_scripts/
// scenario.launch.yaml).
//
// Ports (relative to the node namespace, default /rov):
//   sub  ground_truth/odom       nav_msgs/Odometry          reliable
//   pub  control/pose_setpoint   geometry_msgs/PoseStamped  reliable  one per state, stamped with
//                                the state's time (the MPC's setpoint_sync solves once it has it)
//   sub  camera/<cam>/image_raw  sensor_msgs/Image          reliable  (images_dir set; every camera
//                                of the scenario)
//   pub  /lockstep/ack           unav_msgs/LockstepAck      (lockstep: true)
// With ground_truth_file set, the state at every multiple of control.period is written as TUM
// (t x y z qx qy qz qw), as `unav run --in-process` writes ground_truth.tum: the two compare line
// for line. Every line is flushed as written. With images_dir set, every rgb8 frame is written
// as images_dir/<cam>/<t_ns>.png, as `unav run --in-process` writes them (write_frame_png): the
// two compare file for file. In lockstep it acks a state once its setpoint is out and, with
// images, never past the next frame instant some camera has not delivered (as dataset_recorder).
#pragma once

#include <cstdint>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "sensor_msgs/msg/image.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/lockstep_ack.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::sim {

struct ScenarioMissionParams {
  /// the scenario whose mission is flown (required)
  unav::scene::ScenarioParam scenario;
  std::string ground_truth_file;
  std::string images_dir;
  unav::lockstep::ParticipantParams lockstep{"scenario_mission"};

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(
        Field("ground_truth_file", &ground_truth_file).Doc("TUM file of the state every control period; empty = none"));
    a->Visit(
        Field("images_dir", &images_dir).Doc("folder of every camera's rgb frames (<cam>/<t_ns>.png); empty = none"));
    lockstep.Serialize(a);
  }
};

class ScenarioMissionNode : public unav::Node {
 public:
  explicit ScenarioMissionNode(const unav::NodeOptions& options);

 private:
  static constexpr std::int64_t kNone = std::numeric_limits<std::int64_t>::min();
  struct Camera {
    std::string name;
    std::int64_t last_frame_ns = kNone;
    std::shared_ptr<unav::Subscription<sensor_msgs::msg::Image>> sub;
  };
  void on_odom(const nav_msgs::msg::Odometry& m);
  void on_image(Camera& cam, const sensor_msgs::msg::Image& m);
  void ack();
  unav::scene::Scenario scenario_;
  std::ofstream ground_truth_;
  double last_written_ = -1.0;
  std::string images_dir_;
  std::vector<Camera> cameras_;
  std::int64_t latest_odom_ns_ = kNone;
  std::int64_t frame_lead_ns_ = 0;  ///< frame period - 1 ms: how far past a camera's last frame an ack may go
  std::unique_ptr<unav::lockstep::Acker> acker_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PoseStamped>> pub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> sub_;
};

}  // namespace unav::sim
