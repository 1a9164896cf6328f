// Control nodes (thin DDS adapters over unav_control):
//
// control_allocator
//   sub  control/wrench_command   geometry_msgs/WrenchStamped  body FRD [N, N m]
//   pub  thrusters/command        unav_msgs/ThrusterCommand    u_i in [-1, 1], stamped as the wrench
//   pub  control/wrench_achieved  geometry_msgs/WrenchStamped  B T(u) of that command (what the
//                                 thrusters really give, e.g. scaled when saturated), stamped alike
//   sub  thrusters/set_failed     std_msgs/String  "T3" marks thruster T3 failed, "T3:false" repairs
//                                 it; the allocation is recomputed at once
//   params: config_file (allocator YAML; default <unav_resources>/config/controllers/allocator.yaml),
//           scenario (its control.allocator replaces config_file)
//
// mpc_controller
//   sub  ground_truth/odom (remap to any odometry)  nav_msgs/Odometry  world_ned / base_link_frd;
//        NaN/Inf or a non-unit quaternion is rejected and counted (no solve, no answer)
//   sub  control/pose_setpoint    geometry_msgs/PoseStamped (world_ned)
//   sub  control/wrench_achieved  geometry_msgs/WrenchStamped: the allocator's achieved wrench for
//        the last command, given to the MPC's estimator (Mpc::SetAppliedWrench) before the next
//        solve, as the in-process Episode does
//   pub  control/wrench_command   geometry_msgs/WrenchStamped, stamped with the state's time
//   Solves once per odometry whose stamp reached the next multiple of the MPC dt (lockstep: the
//   physics barrier period should equal it). No setpoint yet: holds the first received pose.
//   A failed solve publishes the MPC's safe wrench and a warning; never NaN. With setpoint_sync,
//   a state is solved only once a setpoint stamped at or after it arrived (the waypoint follower
//   answers every odometry), which makes lockstep runs repeatable; with achieved_sync, also only
//   once the achieved wrench of its previous command arrived (the same in process and over DDS).
//   params: config_file (mpc YAML; default <unav_resources>/config/controllers/mpc.yaml),
//           scenario (its control.mpc replaces config_file; its environment is the model's)
//
// waypoint_follower
//   sub  ground_truth/odom        nav_msgs/Odometry
//   sub  control/path             nav_msgs/Path (world_ned); replaces the current path
//   sub  sim/reset                geometry_msgs/Pose: a new episode (physics_server): the path
//                                 starts again from its first waypoint
//   pub  control/pose_setpoint    geometry_msgs/PoseStamped, on every odometry
//   params: waypoints (flat [x, y, z, ...] NED, m; given, they win), pipeline_world (world.yaml:
//           follow its first pipeline), scenario (its world is the pipeline_world),
//           height_above_pipe (m), acceptance_radius (m)
//
// station_keeper
//   sub  <leader_fix_topic>       unav_msgs/UsblFix: the leader's fixes (position_world; invalid
//                                 ones and outliers beyond gate_m skipped)
//   sub  ground_truth/odom        nav_msgs/Odometry: this vehicle's state, the setpoint's clock
//   pub  control/pose_setpoint    geometry_msgs/PoseStamped, on every odometry: distance_m behind
//                                 the leader along its course (StationKeeper), at its depth +
//                                 depth_offset_m; before the first fix, the first pose received
//   A fix is applied at the first odometry fix_delay_s (0.1 s: two lockstep barriers, two
//   controller round trips) after its stamp, so a lockstep run repeats exactly; the setpoint
//   predicts the leader to the odometry's time.
//   params: leader_fix_topic, fix_delay_s, distance_m, depth_offset_m, alpha, beta, gate_m
#pragma once

#include <memory>
#include <optional>

#include "geometry_msgs/msg/pose.hpp"
#include "geometry_msgs/msg/pose_stamped.hpp"
#include "geometry_msgs/msg/wrench_stamped.hpp"
#include "nav_msgs/msg/odometry.hpp"
#include "nav_msgs/msg/path.hpp"
#include "std_msgs/msg/string.hpp"
#include "unav_common/config.hpp"
#include "unav_control/allocator.hpp"
#include "unav_control/mpc.hpp"
#include "unav_control/station_keeping.hpp"
#include "unav_control/waypoint_follower.hpp"
#include "unav_msgs/msg/thruster_command.hpp"
#include "unav_msgs/msg/usbl_fix.hpp"
#include "unav_runtime/runtime.hpp"
#include "unav_runtime/validation.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::control {

/// The YAML that control_allocator and mpc_controller start from (their schema's values are
/// then overridden by params files and `-p`).
struct ControllerFileParam {
  std::string config_file;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(unav::common::Field("config_file", &config_file).Doc("controller YAML read before the overrides"));
  }
};

/// mpc_controller's node-level parameter (the MPC's own are MpcParams).
struct MpcNodeParams {
  bool setpoint_sync = false;
  bool achieved_sync = false;
  template <class Archive>
  void Serialize(Archive* a) {
    a->Visit(
        unav::common::Field("setpoint_sync", &setpoint_sync)
            .Doc("solve for a state only once a setpoint stamped at or after it arrived (deterministic lockstep)"));
    a->Visit(unav::common::Field("achieved_sync", &achieved_sync)
                 .Doc("solve only once the allocator's achieved wrench for the previous command arrived "
                      "(control/wrench_achieved; deterministic lockstep with an allocator)"));
  }
};

/// waypoint_follower's parameters.
struct WaypointFollowerParams {
  unav::scene::ScenarioParam scenario;  ///< its world replaces pipeline_world
  double acceptance_radius = 0.3;
  std::vector<double> waypoints;
  std::string pipeline_world;
  double height_above_pipe = 1.5;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    scenario.Serialize(a);
    a->Visit(
        Field("acceptance_radius", &acceptance_radius).Range(1e-3, 100.0).Unit("m").Doc("waypoint reached within"));
    a->Visit(Field("waypoints", &waypoints).Unit("m").Doc("[x, y, z, ...] NED; given, they replace the pipeline"));
    a->Visit(Field("pipeline_world", &pipeline_world).Doc("world.yaml whose first pipeline to follow"));
    a->Visit(
        Field("height_above_pipe", &height_above_pipe).Range(0.0, 50.0).Unit("m").Doc("above the pipe's centre line"));
  }
};

/// station_keeper's parameters.
struct StationKeeperParams {
  std::string leader_fix_topic = "/rov/usbl/fix";
  double fix_delay_s = 0.1;
  StationKeepingOptions keeping;
  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("leader_fix_topic", &leader_fix_topic).Doc("the leader's USBL fixes (unav_msgs/UsblFix)"));
    a->Visit(Field("fix_delay_s", &fix_delay_s)
                 .Range(0.0, 10.0)
                 .Unit("s")
                 .Doc("a fix is used this long (simulated) after its stamp: lockstep runs repeat"));
    a->Visit(Field("distance_m", &keeping.distance_m).Above(0.0).Max(1000.0).Unit("m").Doc("behind the leader"));
    a->Visit(Field("depth_offset_m", &keeping.depth_offset_m).Range(-100.0, 100.0).Unit("m").Doc("below the leader"));
    a->Visit(Field("alpha", &keeping.alpha).Above(0.0).Max(1.0).Doc("tracker position gain"));
    a->Visit(Field("beta", &keeping.beta).Min(0.0).Below(2.0).Doc("tracker velocity gain"));
    a->Visit(Field("gate_m", &keeping.gate_m).Above(0.0).Max(1000.0).Unit("m").Doc("outlier gate"));
  }
};

class StationKeeperNode : public unav::Node {
 public:
  explicit StationKeeperNode(const unav::NodeOptions& options);
  const StationKeeper& keeper() const { return keeper_; }

 private:
  StationKeeper keeper_;
  std::vector<std::pair<double, Eigen::Vector3d>> pending_;  ///< fixes not applied yet (stamp, position)
  double fix_delay_s_ = 0.1;
  std::optional<PoseSetpoint> hold_;  ///< before the first fix: the first pose received
  unav::RejectionCounter rejections_{logger()};
  std::shared_ptr<unav::Subscription<unav_msgs::msg::UsblFix>> fix_sub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PoseStamped>> pub_;
};

class ControlAllocatorNode : public unav::Node {
 public:
  explicit ControlAllocatorNode(const unav::NodeOptions& options);

 private:
  void on_set_failed(const std::string& request);
  std::unique_ptr<Allocator> allocator_;
  std::vector<std::string> names_;
  std::uint64_t saturated_ = 0;
  std::shared_ptr<unav::Subscription<std_msgs::msg::String>> failed_sub_;
  std::shared_ptr<unav::Subscription<geometry_msgs::msg::WrenchStamped>> sub_;
  std::shared_ptr<unav::Publisher<unav_msgs::msg::ThrusterCommand>> pub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::WrenchStamped>> achieved_pub_;
};

class MpcControllerNode : public unav::Node {
 public:
  explicit MpcControllerNode(const unav::NodeOptions& options);
  const MpcSummary& last_summary() const { return last_; }
  /// Rejected odometry (NaN/Inf, not a rotation): never solved, never answered.
  const unav::RejectionCounter& rejections() const { return rejections_; }

 private:
  void on_odom(const nav_msgs::msg::Odometry& m);
  void solve(const nav_msgs::msg::Odometry& m);
  void on_achieved(const geometry_msgs::msg::WrenchStamped& m);
  /// Whether the state at t may be solved now (setpoint_sync, achieved_sync).
  bool ready(double t) const;
  void solve_pending();
  std::unique_ptr<Mpc> mpc_;
  bool setpoint_sync_ = false;
  bool achieved_sync_ = false;
  double achieved_t_ = -1.0;  ///< stamp of the last achieved wrench given to the MPC
  double setpoint_t_ = -1.0;
  std::optional<nav_msgs::msg::Odometry> pending_;
  double dt_ = 0.05;
  double next_t_ = -1.0;
  bool have_setpoint_ = false;
  PoseSetpoint setpoint_;
  MpcSummary last_;
  std::uint64_t failures_ = 0;
  geometry_msgs::msg::WrenchStamped last_output_;
  double last_output_t_ = -1.0;
  bool have_output_ = false;
  unav::RejectionCounter rejections_{logger()};
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<unav::Subscription<geometry_msgs::msg::PoseStamped>> sp_sub_;
  std::shared_ptr<unav::Subscription<geometry_msgs::msg::WrenchStamped>> achieved_sub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::WrenchStamped>> pub_;
};

class WaypointFollowerNode : public unav::Node {
 public:
  explicit WaypointFollowerNode(const unav::NodeOptions& options);
  const unav::RejectionCounter& rejections() const { return rejections_; }
  const WaypointFollower& follower() const { return follower_; }

 private:
  WaypointFollower follower_;
  bool finished_logged_ = false;
  unav::RejectionCounter rejections_{logger()};
  std::shared_ptr<unav::Subscription<geometry_msgs::msg::Pose>> reset_sub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Odometry>> odom_sub_;
  std::shared_ptr<unav::Subscription<nav_msgs::msg::Path>> path_sub_;
  std::shared_ptr<unav::Publisher<geometry_msgs::msg::PoseStamped>> pub_;
};

}  // namespace unav::control
