// scenario_mission: a scenario's mission over DDS, the setpoints `unav run --in-process` flies
// (unav::sim::mission_setpoint), so the same scenario runs as processes (physics_server,
// mpc_controller with setpoint_sync, control_allocator, this node; launch_scripts/
// scenario.launch.yaml).
//
// Ports (relative to the node namespace, default /rov):
//   sub  ground_truth/odom       nav_msgs/Odometry          reliable
//   pub  control/pose_setpoint   geometry_msgs/PoseStamped  reliable  one per state, stamped with
//                                the state's time (the MPC's setpoint_sync solves once it has it)
// With ground_truth_file set, the state at every multiple of control.period is written as TUM
// (t x y z qx qy qz qw), as `unav run --in-process` writes ground_truth.tum: the two compare line
// for line. Every line is flushed as written.
#pragma once

#include <fstream>
#include <memory>
#include <string>

#include "geometry_msgs/msg/pose_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "unav_common/config.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::sim {

struct ScenarioMissionParams {
  std::string scenario;
  int64_t scenario_seed = -1;
  std::string ground_truth_file;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("scenario", &scenario).Doc("scenario YAML whose mission is flown"));
    a->Visit(
        Field("scenario_seed", &scenario_seed).Min(-1.0).Doc("draw of the scenario's distributions; -1 = its seed"));
    a->Visit(
        Field("ground_truth_file", &ground_truth_file).Doc("TUM file of the state every control period; empty = none"));
  }
};

class ScenarioMissionNode : public unav::Node {
 public:
  explicit ScenarioMissionNode(const unav::NodeOptions& options);

 private:
  void on_odom(const nav_msgs::msg::Odometry& m);
  unav::scene::Scenario scenario_;
  std::ofstream ground_truth_;
  double last_written_ = -1.0;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PoseStamped>> pub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> sub_;
};

}  // namespace unav::sim
