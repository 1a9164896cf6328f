#include "scenario_mission_node.hpp"

#include <cmath>
#include <filesystem>

#include "unav_runtime/conversions.hpp"
#include "unav_sim/scenario_run.hpp"

namespace unav::sim {

ScenarioMissionNode::ScenarioMissionNode(const unav::NodeOptions& options) : Node("scenario_mission", options, "rov") {
  ScenarioMissionParams p;
  declare_params(&p);
  if (p.scenario.empty()) throw unav::ParameterError("node '" + name() + "': parameter 'scenario' is required");
  scenario_ = unav::scene::load_scenario_param(p.scenario, p.scenario_seed);
  if (!p.ground_truth_file.empty()) {
    const std::filesystem::path parent = std::filesystem::path(p.ground_truth_file).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    ground_truth_.open(p.ground_truth_file);
    if (!ground_truth_)
      throw unav::ParameterError("node '" + name() + "': cannot write ground_truth_file '" + p.ground_truth_file + "'");
    ground_truth_.precision(9);
  }
  pub_ = create_publisher<geometry_msgs::msg::PoseStamped>("control/pose_setpoint", unav::QoS::reliable());
  sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(100),
                                                      [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  logger()->info("mission of {} ({} waypoints, {:.1f} s)", p.scenario, scenario_.mission.waypoints.size(),
                 scenario_.mission.duration_s);
}

void ScenarioMissionNode::on_odom(const nav_msgs::msg::Odometry& m) {
  const double t = unav::seconds(m.header());
  const unav::control::PoseSetpoint sp = mission_setpoint(scenario_, t);
  geometry_msgs::msg::PoseStamped out;
  out.header() = m.header();
  out.pose() = unav::to_msg(sp.p_W, sp.q_WB);
  pub_->publish(out);
  // The state of each control instant, once (a held barrier's state is published again).
  const double periods = t / scenario_.control.period;
  if (ground_truth_.is_open() && std::abs(periods - std::round(periods)) < 1e-6 && t > last_written_ + 1e-9) {
    last_written_ = t;
    const auto& p = m.pose().pose().position();
    const auto& q = m.pose().pose().orientation();
    ground_truth_ << std::fixed << t << " " << p.x() << " " << p.y() << " " << p.z() << " " << q.x() << " " << q.y()
                  << " " << q.z() << " " << q.w() << "\n";
    ground_truth_.flush();
  }
}

}  // namespace unav::sim
