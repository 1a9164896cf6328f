// A scenario run in process (`unav run SCENARIO.yaml --in-process`): the Episode built from the
// scenario by the one builder flies its mission (leg by leg: the setpoint travels to the waypoint
// at mission.speed_mps and holds it until the leg's hold_s is over; then the last waypoint until
// mission.duration_s), renders every camera at cameras.rate_hz and writes
//   OUT/scenario.yaml          the concrete scenario (seed drawn, paths resolved)
//   OUT/ground_truth.tum       base_link_frd in world_ned every control period (TUM: t x y z qx qy qz qw;
//                              t to the ns, the pose to 17 significant digits: bit for bit)
//   OUT/<camera>/<t_ns>.png    rgb8 frames, named by their simulated time in nanoseconds
// The scenario_mission node writes the same files over DDS (write_tum_pose, write_frame_png):
// the two paths compare byte for byte.
#pragma once

#include <atomic>
#include <cstdint>
#include <ostream>
#include <string>

#include <Eigen/Geometry>

#include "unav_control/mpc.hpp"
#include "unav_scene/scenario.hpp"

namespace unav::sim {

/// OUT/scenario.yaml: the concrete scenario (seed drawn, paths resolved); creates OUT.
void write_concrete_scenario(const scene::Scenario& scenario, const std::string& out_dir);

/// One TUM line: t (s, 9 decimals: the stamp's nanoseconds), position and quaternion x y z w to 17
/// significant digits (every bit of the double).
void write_tum_pose(std::ostream& out, double t, const Eigen::Vector3d& p, const Eigen::Quaterniond& q);
/// OUT/<camera>/<t_ns>.png for a frame of `camera` stamped t_ns (19 digits, zero-padded).
std::string frame_png_path(const std::string& out_dir, const std::string& camera, std::int64_t t_ns);
/// Writes an rgb8 image as PNG (OpenCV's default compression). Throws std::runtime_error.
void write_frame_png(const std::string& path, const std::uint8_t* rgb, int width, int height);

/// The setpoint the mission asks for at time `t` (s since the start).
control::PoseSetpoint mission_setpoint(const scene::Scenario& scenario, double t);

struct ScenarioRunOptions {
  bool images = true;                       ///< false: ground truth only
  const std::atomic<bool>* stop = nullptr;  ///< set (e.g. by SIGINT): stop after the current period
};

struct ScenarioRunResult {
  std::uint64_t poses = 0, frames = 0;
  double sim_s = 0.0, wall_s = 0.0;
  int solver_failures = 0;
  bool stopped = false;  ///< ended early by options.stop (every file written so far is complete)
};

/// Runs `scenario` into `out_dir` (created). Throws ConfigError / EglError / std::runtime_error.
ScenarioRunResult run_scenario_in_process(const scene::Scenario& scenario, const std::string& out_dir,
                                          const ScenarioRunOptions& options = {});

}  // namespace unav::sim
