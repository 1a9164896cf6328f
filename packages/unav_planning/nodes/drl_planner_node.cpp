#include "drl_planner_node.hpp"

#include <chrono>
#include <cmath>

#include "unav_common/resources.hpp"
#include "unav_runtime/conversions.hpp"

namespace unav::planning {
namespace {

double yaw_of(const Eigen::Quaterniond& q) {
  const Eigen::Vector3d f = q * Eigen::Vector3d::UnitX();
  return std::atan2(f.y(), f.x());
}

}  // namespace

DrlPlannerNode::DrlPlannerNode(const unav::NodeOptions& options) : Node("drl_planner", options, "rov") {
  declare_params(&p_);
  check_undeclared_parameters();
  if (p_.policy == "drl") {
    std::string path = p_.model;
    if (!path.empty() && path.front() != '/') {
      const auto found = unav::common::try_find_resource(path);
      if (!found)
        throw unav::ParameterError("node '" + name() + "': model '" + p_.model +
                                   "' not found under the resource roots (give an absolute path)");
      path = *found;
    }
    try {
      policy_ = std::make_unique<OnnxPipePolicy>(path);
    } catch (const std::exception& e) {
      throw unav::ParameterError("node '" + name() + "': " + e.what());
    }
  } else {
    ClassicalFollowerParams c;
    c.hfov_deg = p_.camera_hfov_deg;
    c.height_m = p_.height_above_pipe;
    c.max_step_angle_deg = p_.action.max_step_angle_deg;
    c.max_turn_deg = p_.action.max_turn_deg;
    policy_ = std::make_unique<ClassicalPipeFollower>(c);
  }
  hold_depth_ = p_.hold_depth;
  pub_ = create_publisher<geometry_msgs::msg::PoseStamped>("control/pose_setpoint", unav::QoS::reliable());
  image_sub_ = create_subscription<sensor_msgs::msg::Image>("camera/" + p_.camera + "/image_raw",
                                                            unav::QoS::reliable(5).with_data_sharing(),
                                                            [this](const sensor_msgs::msg::Image& m) { on_image(m); });
  odom_sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(),
                                                           [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  logger()->info("policy {}, a waypoint every {:.2f} s from camera/{}/image_raw{}", policy_->name(), p_.step_period,
                 p_.camera, p_.sync_images ? " (image-synchronised)" : "");
}

DrlPlannerNode::~DrlPlannerNode() {
  if (decisions_ > 0)
    logger()->info("{} decisions, policy inference {:.2f} ms on average", decisions_,
                   inference_ms_ / static_cast<double>(decisions_));
}

void DrlPlannerNode::on_image(const sensor_msgs::msg::Image& m) {
  if (m.encoding() != "rgb8" || m.data().size() != static_cast<std::size_t>(m.height()) * m.step() ||
      m.step() < m.width() * 3) {
    logger()->warn("image with encoding '{}' {}x{} step {} ignored (rgb8 expected)", m.encoding(), m.width(),
                   m.height(), m.step());
    return;
  }
  image_ = m;
  if (pending_ && unav::nanoseconds(m.header()) >= next_decision_ns_ - 1000000) {
    const nav_msgs::msg::Odometry o = *pending_;
    pending_.reset();
    decide(o);
    answer(o);
  }
}

void DrlPlannerNode::on_odom(const nav_msgs::msg::Odometry& m) {
  if (const std::string why = unav::odometry_problem(m); !why.empty()) {
    rejections_.reject(odom_sub_->topic_name(), why);
    return;
  }
  const std::int64_t t = unav::nanoseconds(m.header());
  if (hold_depth_ < 0.0) hold_depth_ = m.pose().pose().position().z();
  if (next_decision_ns_ < 0) next_decision_ns_ = t;
  if (!have_setpoint_) {  // until the first decision: hold the first pose
    setpoint_ = unav::control::PoseSetpoint::FromPositionYaw(unav::from_msg(m.pose().pose().position()),
                                                             yaw_of(unav::from_msg(m.pose().pose().orientation())));
    setpoint_.p_W.z() = hold_depth_;
  }
  if (t >= next_decision_ns_) {
    // 1 ms slack: stamps are rounded to nanoseconds on the way.
    const bool image_ready = image_ && unav::nanoseconds(image_->header()) >= next_decision_ns_ - 1000000;
    if (p_.sync_images && !image_ready) {
      pending_ = m;  // answered when its image arrives
      return;
    }
    if (image_) decide(m);
  }
  answer(m);
}

void DrlPlannerNode::decide(const nav_msgs::msg::Odometry& m) {
  const auto& img = *image_;
  const cv::Mat rgb(static_cast<int>(img.height()), static_cast<int>(img.width()), CV_8UC3,
                    const_cast<std::uint8_t*>(img.data().data()), img.step());
  const auto t0 = std::chrono::steady_clock::now();
  const std::array<double, 2> a = policy_->act(rgb);
  inference_ms_ += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const Eigen::Vector3d p = unav::from_msg(m.pose().pose().position());
  const double yaw = yaw_of(unav::from_msg(m.pose().pose().orientation()));
  setpoint_ = unav::control::waypoint_from_action(p, yaw, a, p_.action, hold_depth_);
  have_setpoint_ = true;
  ++decisions_;
  const auto period_ns = static_cast<std::int64_t>(std::llround(p_.step_period * 1e9));
  const std::int64_t t = unav::nanoseconds(m.header());
  while (next_decision_ns_ <= t) next_decision_ns_ += period_ns;
  logger()->debug("t {:.2f} s: a = ({:+.3f}, {:+.3f}) -> waypoint ({:.2f}, {:.2f}, {:.2f})", unav::seconds(m.header()),
                  a[0], a[1], setpoint_.p_W.x(), setpoint_.p_W.y(), setpoint_.p_W.z());
}

void DrlPlannerNode::answer(const nav_msgs::msg::Odometry& m) {
  geometry_msgs::msg::PoseStamped out;
  out.header().stamp() = m.header().stamp();
  out.header().frame_id("world_ned");
  out.pose() = unav::to_msg(setpoint_.p_W, setpoint_.q_WB);
  pub_->publish(out);
}

}  // namespace unav::planning
