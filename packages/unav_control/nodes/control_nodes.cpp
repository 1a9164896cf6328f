#include "control_nodes.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>

#include "unav_common/resources.hpp"
#include "unav_control/config.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_runtime/conversions.hpp"
#include "unav_scene/scenario.hpp"
#include "unav_scene/world.hpp"

namespace unav::control {
namespace {

std::string config_root() { return unav::common::resource_or_empty("config"); }
// Relative vehicle paths: against the installed config/, or without it the file's config root.
std::string config_root_for(const std::string& file) {
  const std::string installed = config_root();
  return !installed.empty() ? installed : std::filesystem::absolute(file).parent_path().parent_path().string();
}

double stamp_of(const std_msgs::msg::Header& h) { return unav::seconds(h); }

physics::RigidBodyState state_of(const nav_msgs::msg::Odometry& m) {
  // The quaternion is passed as sent: the MPC rejects a non-unit one with a status.
  physics::RigidBodyState x;
  x.p_WB_W = unav::from_msg(m.pose().pose().position());
  x.q_WB = unav::from_msg(m.pose().pose().orientation());
  x.v_WB_B = unav::from_msg(m.twist().twist().linear());
  x.w_WB_B = unav::from_msg(m.twist().twist().angular());
  return x;
}

template <typename F>
auto wrap_config(F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const physics::ConfigError& e) {
    throw unav::ConfigError(e.what());
  }
}

}  // namespace

ControlAllocatorNode::ControlAllocatorNode(const unav::NodeOptions& options)
    : Node("control_allocator", options, "rov") {
  ControllerFileParam fp;
  fp.config_file = unav::common::resource_or_empty("config/controllers/allocator.yaml");
  declare_params(&fp);
  unav::scene::ScenarioParam scenario;
  declare_params(&scenario);
  if (scenario.given()) fp.config_file = scenario.load().control.allocator;  // as the in-process Episode
  const std::string& file = fp.config_file;
  AllocatorParams params = load_allocator_params(file);
  declare_params(&params);  // params files and -p name:=value, checked by the schema
  const AllocatorConfig cfg =
      make_allocator_config(params, config_root_for(file), "node '" + name() + "' (config_file " + file + ")");
  allocator_ = wrap_config([&] { return std::make_unique<Allocator>(make_allocator(cfg)); });
  for (const auto& t : cfg.vehicle.thrusters) names_.push_back(t.name);
  failed_sub_ =
      create_subscription<std_msgs::msg::String>("thrusters/set_failed", unav::QoS::reliable(),
                                                 [this](const std_msgs::msg::String& m) { on_set_failed(m.data()); });
  pub_ = create_publisher<unav_msgs::msg::ThrusterCommand>("thrusters/command", unav::QoS::reliable());
  achieved_pub_ = create_publisher<geometry_msgs::msg::WrenchStamped>("control/wrench_achieved", unav::QoS::reliable());
  sub_ = create_subscription<geometry_msgs::msg::WrenchStamped>(
      "control/wrench_command", unav::QoS::reliable(), [this](const geometry_msgs::msg::WrenchStamped& w) {
        Vector6d tau;
        tau << w.wrench().force().x(), w.wrench().force().y(), w.wrench().force().z(), w.wrench().torque().x(),
            w.wrench().torque().y(), w.wrench().torque().z();
        ThrusterVector u;
        const AllocationSummary s = allocator_->Allocate(tau, &u);
        if (s.status == AllocationStatus::kInvalidInput) {
          logger()->warn("wrench command with NaN/Inf rejected: all thrusters to zero");
        } else if ((s.status == AllocationStatus::kScaled || s.status == AllocationStatus::kInfeasible) &&
                   ++saturated_ % 100 == 1) {
          logger()->warn("wrench saturates the thrusters (scale {:.2f}); {} saturated commands so far", s.scale,
                         saturated_);
        }
        geometry_msgs::msg::WrenchStamped achieved;
        achieved.header() = w.header();
        achieved.wrench() = unav::to_wrench_msg(s.achieved);
        achieved_pub_->publish(achieved);  // before the command: the MPC has it when the next state comes
        unav_msgs::msg::ThrusterCommand cmd;
        cmd.header() = w.header();
        cmd.u().assign(u.data(), u.data() + u.size());
        pub_->publish(cmd);
      });
  logger()->info("{} thrusters, config {}", allocator_->thruster_matrix().cols(), file);
}

void ControlAllocatorNode::on_set_failed(const std::string& request) {
  const size_t colon = request.find(':');
  const std::string name = request.substr(0, colon);
  const std::string flag = colon == std::string::npos ? "true" : request.substr(colon + 1);
  const auto it = std::find(names_.begin(), names_.end(), name);
  if (it == names_.end() || (flag != "true" && flag != "false")) {
    logger()->warn(
        "thrusters/set_failed '{}' ignored: expected '<thruster>' or '<thruster>:false' with a thruster "
        "of this vehicle",
        request);
    return;
  }
  const int index = static_cast<int>(it - names_.begin());
  if (!allocator_->SetThrusterFailed(index, flag == "true"))
    logger()->warn("thruster {} could not be marked {}", name, flag == "true" ? "failed" : "working");
  else
    logger()->warn("thruster {} marked {}: allocation recomputed", name, flag == "true" ? "FAILED" : "working");
}

MpcControllerNode::MpcControllerNode(const unav::NodeOptions& options) : Node("mpc_controller", options, "rov") {
  ControllerFileParam fp;
  fp.config_file = unav::common::resource_or_empty("config/controllers/mpc.yaml");
  declare_params(&fp);
  unav::scene::ScenarioParam scenario;
  declare_params(&scenario);
  physics::EnvironmentParams environment;
  if (scenario.given()) {  // the MPC the in-process Episode builds from the same scenario
    const unav::scene::Scenario sc = scenario.load();
    fp.config_file = sc.control.mpc;
    environment = physics::scenario_simulator_options(sc, 0.0).environment;
  }
  const std::string& file = fp.config_file;
  // One parameter system: the schema's defaults, then the config file, then this node's params
  // files and `-p name:=value` (e.g. -p horizon_steps:=30), each checked by the schema.
  MpcParams params = load_mpc_params(file);
  declare_params(&params);
  MpcConfig cfg = make_mpc_config(params, config_root_for(file), "node '" + name() + "' (config_file " + file + ")");
  dt_ = cfg.options.dt;
  MpcNodeParams np;
  declare_params(&np);
  setpoint_sync_ = np.setpoint_sync;
  achieved_sync_ = np.achieved_sync;
  if (setpoint_sync_ && cfg.options.max_solve_time_ms > 0.0) {
    // Lockstep promises identical runs: a wall-clock budget would make the plan depend on load.
    logger()->info("lockstep (setpoint_sync): max_solve_time_ms {} ignored, solves bounded by {} iterations",
                   cfg.options.max_solve_time_ms, cfg.options.max_iterations);
    cfg.options.max_solve_time_ms = 0.0;
  }
  mpc_ = wrap_config([&] { return std::make_unique<Mpc>(cfg.model, cfg.options, environment); });
  pub_ = create_publisher<geometry_msgs::msg::WrenchStamped>("control/wrench_command", unav::QoS::reliable());
  sp_sub_ = create_subscription<geometry_msgs::msg::PoseStamped>(
      "control/pose_setpoint", unav::QoS::reliable(), [this](const geometry_msgs::msg::PoseStamped& m) {
        // Pass non-unit or NaN setpoints through: the MPC rejects them with a status (tested).
        setpoint_.p_W = unav::from_msg(m.pose().position());
        setpoint_.q_WB = unav::from_msg(m.pose().orientation());
        have_setpoint_ = true;
        setpoint_t_ = std::max(setpoint_t_, stamp_of(m.header()));
        solve_pending();
      });
  achieved_sub_ = create_subscription<geometry_msgs::msg::WrenchStamped>(
      "control/wrench_achieved", unav::QoS::reliable(),
      [this](const geometry_msgs::msg::WrenchStamped& m) { on_achieved(m); });
  odom_sub_ = create_subscription<nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(),
                                                           [this](const nav_msgs::msg::Odometry& m) { on_odom(m); });
  logger()->info("MPC: horizon {} x {:.3f} s, model {}", cfg.options.horizon_steps, dt_, cfg.model_vehicle_path);
}

void MpcControllerNode::on_odom(const nav_msgs::msg::Odometry& m) {
  if (const std::string why = unav::odometry_problem(m); !why.empty()) {
    rejections_.reject(odom_sub_->topic_name(), why);
    return;
  }
  const double t = stamp_of(m.header());
  if (have_output_ && std::abs(t - last_output_t_) < 1e-9) {
    // The same state again: the physics re-publishes a held lockstep barrier when an answer was
    // lost (e.g. published before the allocator matched). Answer it again, or the loop stalls.
    pub_->publish(last_output_);
    return;
  }
  if (next_t_ >= 0.0 && t + 1e-6 < next_t_) return;
  if (!ready(t)) {
    pending_ = m;  // solved when the setpoint for this instant (and the last achieved wrench) arrive
    return;
  }
  solve(m);
}

bool MpcControllerNode::ready(double t) const {
  if (setpoint_sync_ && setpoint_t_ < t - 1e-9) return false;
  return !(achieved_sync_ && have_output_ && achieved_t_ < last_output_t_ - 1e-9);
}

void MpcControllerNode::solve_pending() {
  if (!pending_ || !ready(stamp_of(pending_->header()))) return;
  const nav_msgs::msg::Odometry odom = *pending_;
  pending_.reset();
  solve(odom);
}

// The wrench the thrusters gave for our last command: the estimator's input until the next solve
// (the in-process Episode passes the allocator's achieved wrench the same way).
void MpcControllerNode::on_achieved(const geometry_msgs::msg::WrenchStamped& m) {
  const double t = stamp_of(m.header());
  if (!have_output_ || std::abs(t - last_output_t_) > 1e-9 || t <= achieved_t_) return;  // not for our last command
  Vector6d w;
  w << m.wrench().force().x(), m.wrench().force().y(), m.wrench().force().z(), m.wrench().torque().x(),
      m.wrench().torque().y(), m.wrench().torque().z();
  mpc_->SetAppliedWrench(w);
  achieved_t_ = t;
  solve_pending();
}

void MpcControllerNode::solve(const nav_msgs::msg::Odometry& m) {
  const double t = stamp_of(m.header());
  next_t_ = (std::floor((t + 1e-6) / dt_) + 1.0) * dt_;
  const physics::RigidBodyState x = state_of(m);
  if (!have_setpoint_) {  // hold where we are until told otherwise
    setpoint_ = PoseSetpoint::FromPositionYaw(x.p_WB_W, physics::roll_pitch_yaw(x.q_WB).z());
    have_setpoint_ = true;
  }
  Vector6d w;
  last_ = mpc_->Solve(x, setpoint_, t, &w);
  if (!last_.ok() && ++failures_ % 20 == 1)
    logger()->warn("MPC solve failed ({}): publishing the safe wrench; {} failures so far", last_.message, failures_);
  geometry_msgs::msg::WrenchStamped out;
  out.header().stamp() = m.header().stamp();
  out.header().frame_id(m.child_frame_id());
  out.wrench() = unav::to_wrench_msg(w);
  pub_->publish(out);
  last_output_ = out;
  last_output_t_ = t;
  have_output_ = true;
}

WaypointFollowerNode::WaypointFollowerNode(const unav::NodeOptions& options)
    : Node("waypoint_follower", options, "rov") {
  WaypointFollowerParams prm;
  declare_params(&prm);
  WaypointFollowerOptions wo;
  wo.acceptance_radius = prm.acceptance_radius;
  const std::vector<double>& flat = prm.waypoints;
  const std::string& world = prm.pipeline_world;
  const double height = prm.height_above_pipe;
  follower_ = WaypointFollower(wo);
  std::vector<PoseSetpoint> path;
  if ((!world.empty() || prm.scenario.given()) && flat.empty()) {
    // The scenario's world (generated when it says so), else pipeline_world.
    const unav::scene::World w = unav::scene::pipeline_world(prm.scenario, world);
    std::vector<Eigen::Vector3d> pts;
    const auto& c = w.pipelines.front().centerline_W;
    for (size_t i = 0; i < c.size(); i += 10) pts.push_back(c[i]);  // ~1 m spacing
    pts.push_back(c.back());
    path = path_above(pts, height);
  } else {
    if (flat.size() % 3 != 0)
      throw unav::ParameterError("node '" + name() + "': parameter 'waypoints' needs x, y, z triples, got " +
                                 std::to_string(flat.size()) + " numbers");
    std::vector<Eigen::Vector3d> pts;
    for (size_t i = 0; i + 2 < flat.size(); i += 3) pts.emplace_back(flat[i], flat[i + 1], flat[i + 2]);
    if (!pts.empty()) path = path_above(pts, 0.0);
  }
  std::string msg;
  if (!path.empty() && !follower_.SetPath(path, &msg)) throw unav::ParameterError("node '" + name() + "': " + msg);
  pub_ = create_publisher<geometry_msgs::msg::PoseStamped>("control/pose_setpoint", unav::QoS::reliable());
  path_sub_ = create_subscription<nav_msgs::msg::Path>("control/path", unav::QoS::reliable(),
                                                       [this](const nav_msgs::msg::Path& p) {
                                                         std::vector<PoseSetpoint> sp;
                                                         for (const auto& ps : p.poses()) {
                                                           PoseSetpoint s;
                                                           s.p_W = unav::from_msg(ps.pose().position());
                                                           s.q_WB = unav::from_msg(ps.pose().orientation());
                                                           sp.push_back(s);
                                                         }
                                                         std::string err;
                                                         if (!follower_.SetPath(sp, &err))
                                                           logger()->warn("path rejected: {}", err);
                                                         finished_logged_ = false;
                                                       });
  reset_sub_ = create_subscription<geometry_msgs::msg::Pose>("sim/reset", unav::QoS::reliable(),
                                                             [this](const geometry_msgs::msg::Pose& m) {
                                                               // As the physics server: a bad pose
                                                               // starts no episode.
                                                               if (!unav::pose_problem(m).empty()) return;
                                                               std::vector<PoseSetpoint> restart = follower_.path();
                                                               if (!restart.empty()) follower_.SetPath(restart);
                                                               finished_logged_ = false;
                                                             });
  odom_sub_ = create_subscription<nav_msgs::msg::Odometry>(
      "ground_truth/odom", unav::QoS::reliable(), [this](const nav_msgs::msg::Odometry& m) {
        if (const std::string why = unav::odometry_problem(m); !why.empty()) {
          rejections_.reject(odom_sub_->topic_name(), why);
          return;
        }
        // Without a path: a hold setpoint at the current position.
        const WaypointUpdate u = follower_.Update(unav::from_msg(m.pose().pose().position()));
        if (u.finished && !finished_logged_) {
          logger()->info("path finished at t = {:.2f} s", stamp_of(m.header()));
          finished_logged_ = true;
        }
        geometry_msgs::msg::PoseStamped out;
        out.header().stamp() = m.header().stamp();
        out.header().frame_id("world_ned");
        out.pose() = unav::to_msg(u.setpoint.p_W, u.setpoint.q_WB);
        pub_->publish(out);
      });
  logger()->info("{} waypoints", path.size());
}

StationKeeperNode::StationKeeperNode(const unav::NodeOptions& options) : Node("station_keeper", options) {
  StationKeeperParams prm;
  declare_params(&prm);
  keeper_ = wrap_config([&] { return StationKeeper(prm.keeping); });
  fix_delay_s_ = prm.fix_delay_s;
  pub_ = create_publisher<geometry_msgs::msg::PoseStamped>("control/pose_setpoint", unav::QoS::reliable());
  fix_sub_ = create_subscription<unav_msgs::msg::UsblFix>(
      prm.leader_fix_topic, unav::QoS::reliable(100), [this](const unav_msgs::msg::UsblFix& f) {
        if (!f.valid()) return;  // no reply: nothing to use
        pending_.emplace_back(stamp_of(f.header()), unav::from_msg(f.position_world()));
      });
  odom_sub_ = create_subscription<
      nav_msgs::msg::Odometry>("ground_truth/odom", unav::QoS::reliable(), [this](const nav_msgs::msg::Odometry& m) {
    if (const std::string why = unav::odometry_problem(m); !why.empty()) {
      rejections_.reject(odom_sub_->topic_name(), why);
      return;
    }
    const double t = stamp_of(m.header());
    // Fixes stamped fix_delay_s before this state: published that much simulated time before
    // it (in lockstep, two controller round trips ago), so every run has them by now and
    // applies the same ones at the same state. The prediction to `t` makes up the delay.
    std::stable_sort(pending_.begin(), pending_.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    size_t used = 0;
    while (used < pending_.size() && pending_[used].first <= t - fix_delay_s_) {
      keeper_.AddFix(pending_[used].first, pending_[used].second);
      ++used;
    }
    pending_.erase(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(used));
    if (!hold_) {
      hold_ = PoseSetpoint{unav::from_msg(m.pose().pose().position()), unav::from_msg(m.pose().pose().orientation())};
    }
    const PoseSetpoint sp = keeper_.Setpoint(t).value_or(*hold_);
    geometry_msgs::msg::PoseStamped out;
    out.header().stamp() = m.header().stamp();
    out.header().frame_id("world_ned");
    out.pose() = unav::to_msg(sp.p_W, sp.q_WB);
    pub_->publish(out);
  });
  logger()->info("station keeping {:.1f} m behind the leader of {}", prm.keeping.distance_m, prm.leader_fix_topic);
}

}  // namespace unav::control
