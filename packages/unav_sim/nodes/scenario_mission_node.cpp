#include "scenario_mission_node.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>

#include "unav_runtime/conversions.hpp"
#include "unav_sim/scenario_run.hpp"

namespace unav::sim {

ScenarioMissionNode::ScenarioMissionNode(const unav::NodeOptions& options) : Node("scenario_mission", options, "rov") {
  ScenarioMissionParams p;
  declare_params(&p);
  if (!p.scenario.given()) throw unav::ParameterError("node '" + name() + "': parameter 'scenario' is required");
  scenario_ = p.scenario.load();
  if (!p.ground_truth_file.empty()) {
    const std::filesystem::path parent = std::filesystem::path(p.ground_truth_file).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
    ground_truth_.open(p.ground_truth_file);
    if (!ground_truth_)
      throw unav::ParameterError("node '" + name() + "': cannot write ground_truth_file '" + p.ground_truth_file + "'");
  }
  if (p.lockstep.enabled) acker_ = std::make_unique<unav::lockstep::Acker>(*this, p.lockstep.name);
  pub_ = create_publisher<geometry_msgs::msg::PoseStamped>("control/pose_setpoint", unav::QoS::reliable());
  images_dir_ = p.images_dir;
  if (!images_dir_.empty()) {
    frame_lead_ns_ = std::llround((1.0 / scenario_.cameras.rate_hz - 1e-3) * 1e9);
    cameras_.reserve(scenario_.cameras.names.size());  // the subscriptions hold references into it
    for (const auto& c : scenario_.cameras.names) {
      std::filesystem::create_directories(std::filesystem::path(images_dir_) / c);
      Camera& cam = cameras_.emplace_back();
      cam.name = c;
      cam.sub = create_subscription<sensor_msgs::msg::Image>(
          "camera/" + c + "/image_raw", unav::QoS::reliable(10),
          [this, &cam](const sensor_msgs::msg::Image& m) { on_image(cam, m); });
    }
  }
  sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(100),
                                                      [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  logger()->info("mission of {} ({} waypoints, {:.1f} s){}", p.scenario.file, scenario_.mission.waypoints.size(),
                 scenario_.mission.duration_s, images_dir_.empty() ? "" : ", frames to " + images_dir_);
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
    write_tum_pose(ground_truth_, t, unav::from_msg(m.pose().pose().position()),
                   unav::from_msg(m.pose().pose().orientation()));
    ground_truth_.flush();
  }
  latest_odom_ns_ = std::max(latest_odom_ns_, unav::nanoseconds(m.header()));
  ack();
}

void ScenarioMissionNode::on_image(Camera& cam, const sensor_msgs::msg::Image& m) {
  const std::int64_t t_ns = unav::nanoseconds(m.header());
  if (t_ns <= cam.last_frame_ns) return ack();  // a frame sent again for a held barrier
  if (m.encoding() != "rgb8" || m.data().size() != static_cast<std::size_t>(m.width()) * m.height() * 3) {
    logger()->warn("camera/{}/image_raw at t = {} ns: not rgb8 of its size ({}, {}x{}): skipped", cam.name, t_ns,
                   m.encoding(), m.width(), m.height());
    return;
  }
  write_frame_png(frame_png_path(images_dir_, cam.name, t_ns), m.data().data(), static_cast<int>(m.width()),
                  static_cast<int>(m.height()));
  cam.last_frame_ns = t_ns;
  ack();
}

// Acks the latest state, capped just under the first frame instant some camera has not delivered
// (no ack before every camera's first frame): the physics never outruns the frames written.
void ScenarioMissionNode::ack() {
  if (!acker_ || latest_odom_ns_ == kNone) return;
  std::int64_t upto = latest_odom_ns_;
  for (const Camera& c : cameras_) {
    if (c.last_frame_ns == kNone) return;
    upto = std::min(upto, c.last_frame_ns + frame_lead_ns_);
  }
  acker_->ack(upto);
}

}  // namespace unav::sim
