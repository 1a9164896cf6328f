#include "unav_sim/scenario_run.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "unav_common/time.hpp"
#include "unav_physics/scenario_builder.hpp"
#include "unav_scene/water.hpp"
#include "unav_sim/episode.hpp"

namespace fs = std::filesystem;

namespace unav::sim {

void write_concrete_scenario(const scene::Scenario& scenario, const std::string& out_dir) {
  fs::create_directories(out_dir);
  YAML::Emitter e;
  e.SetDoublePrecision(17);
  e << scene::scenario_yaml(scenario);
  const fs::path file = fs::path(out_dir) / "scenario.yaml";
  std::ofstream(file) << e.c_str() << "\n";
  if (!fs::exists(file)) throw std::runtime_error(file.string() + ": cannot be written");
}

void write_tum_pose(std::ostream& out, double t, const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  char line[256];
  std::snprintf(line, sizeof(line), "%.9f %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n", t, p.x(), p.y(), p.z(), q.x(),
                q.y(), q.z(), q.w());
  out << line;
}

std::string frame_png_path(const std::string& out_dir, const std::string& camera, std::int64_t t_ns) {
  char name[64];
  std::snprintf(name, sizeof(name), "%019lld.png", static_cast<long long>(t_ns));
  return (fs::path(out_dir) / camera / name).string();
}

void write_frame_png(const std::string& path, const std::uint8_t* rgb, int width, int height) {
  cv::Mat bgr;
  cv::cvtColor(cv::Mat(height, width, CV_8UC3, const_cast<std::uint8_t*>(rgb)), bgr, cv::COLOR_RGB2BGR);
  if (!cv::imwrite(path, bgr)) throw std::runtime_error(path + ": cannot be written");
}

control::PoseSetpoint mission_setpoint(const scene::Scenario& scenario, double t) {
  constexpr double kDeg = M_PI / 180.0;
  const auto& wps = scenario.mission.waypoints;
  if (wps.empty())
    return control::PoseSetpoint::FromPositionYaw(scenario.vehicle.initial_position,
                                                  scenario.vehicle.initial_rpy_deg.z() * kDeg);
  double begin = 0.0;
  Eigen::Vector3d from = scenario.vehicle.initial_position;
  for (const auto& w : wps) {
    if (t < begin + w.hold_s) {
      const Eigen::Vector3d leg = w.position - from;
      const double travelled = scenario.mission.speed_mps * (t - begin), length = leg.norm();
      const Eigen::Vector3d p = travelled >= length ? w.position : Eigen::Vector3d(from + leg * (travelled / length));
      return control::PoseSetpoint::FromPositionYaw(p, w.yaw_deg * kDeg);
    }
    begin += w.hold_s;
    from = w.position;
  }
  return control::PoseSetpoint::FromPositionYaw(wps.back().position, wps.back().yaw_deg * kDeg);
}

ScenarioRunResult run_scenario_in_process(const scene::Scenario& scenario, const std::string& out_dir,
                                          const ScenarioRunOptions& options) {
  const auto wall0 = std::chrono::steady_clock::now();
  EpisodeSetup setup = load_episode_setup(scenario);
  const scene::Scenario& sc = setup.scenario;
  const scene::World world = scene::scenario_world(sc);
  write_concrete_scenario(sc, out_dir);
  Episode ep(setup, world);
  ep.reset(static_cast<std::uint64_t>(sc.seed), physics::scenario_initial_state(sc));

  std::ofstream gt(fs::path(out_dir) / "ground_truth.tum");
  if (!gt) throw std::runtime_error(out_dir + "/ground_truth.tum: cannot be written");
  ScenarioRunResult r;
  auto write_pose = [&] {
    write_tum_pose(gt, ep.time(), ep.state().p_WB_W, ep.state().q_WB);
    ++r.poses;
  };
  const double frame_period = 1.0 / sc.cameras.rate_hz, period = sc.control.period;
  if (options.images)
    for (const auto& c : sc.cameras.names) fs::create_directories(fs::path(out_dir) / c);
  std::int64_t next_frame = 0;  // frames at k * frame_period, rendered at the first control instant at or after
  auto render_due = [&] {
    if (!options.images) return;
    while (static_cast<double>(next_frame) * frame_period <= ep.time() + 1e-9) {
      for (const auto& c : sc.cameras.names) {
        const Frame f = ep.render(c);
        write_frame_png(frame_png_path(out_dir, c, unav::Time::from_seconds(ep.time()).ns), f.rgb.data(), f.width,
                        f.height);
        ++r.frames;
      }
      ++next_frame;
    }
  };
  write_pose();
  render_due();
  const auto periods = static_cast<std::int64_t>(std::llround(sc.mission.duration_s / period));
  for (std::int64_t k = 0; k < periods; ++k) {
    if (options.stop != nullptr && options.stop->load()) {
      r.stopped = true;
      break;
    }
    ep.set_setpoint(mission_setpoint(sc, ep.time()));
    ep.advance(period);
    write_pose();
    render_due();
  }
  gt.flush();
  r.sim_s = ep.time();
  r.solver_failures = ep.solver_failures();
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return r;
}

}  // namespace unav::sim
