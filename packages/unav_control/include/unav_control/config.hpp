// YAML loaders for config/controllers/{allocator,mpc}.yaml. Each file is a ROS 2 parameter file
// (`<node>: {ros__parameters: {...}}`, node = control_allocator / mpc_controller) or the bare
// parameter map. Vehicle paths are relative to the config root (default: the parent of the
// file's folder, i.e. config/) unless absolute. Unknown keys, wrong types, NaN and out-of-range
// values throw physics::ConfigError naming the file, the key and the value.
#pragma once

#include <string>
#include <vector>

#include "unav_control/allocator.hpp"
#include "unav_control/mpc.hpp"
#include "unav_control/waypoint_follower.hpp"

namespace unav::control {

struct AllocatorConfig {
  AllocatorOptions options;
  std::string vehicle_path;            ///< resolved path of the thruster/vehicle file
  physics::VehicleParams vehicle;      ///< loaded from vehicle_path (same file as the physics server's)
  std::vector<int> failed_thrusters;   ///< indices (resolved from names) to mark failed at start
};
AllocatorConfig load_allocator_config(const std::string& yaml_path, const std::string& config_root = "");
/// The allocator of a config, with its failed thrusters applied.
Allocator make_allocator(const AllocatorConfig& config);

struct MpcConfig {
  MpcOptions options;                 ///< input_bounds = model's achievable wrench box x bounds_margin
  double bounds_margin = 0.9;         ///< in (0, 1]
  std::string model_vehicle_path;     ///< resolved path of the MPC's own model
  physics::VehicleParams model;       ///< loaded from model_vehicle_path
  WaypointFollowerOptions waypoints;  ///< acceptance radius etc. for the path follower
};
MpcConfig load_mpc_config(const std::string& yaml_path, const std::string& config_root = "");

}  // namespace unav::control
