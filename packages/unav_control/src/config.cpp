// YAML loaders for the controller configs (see config.hpp).
#include "unav_control/config.hpp"

#include <filesystem>

#include <yaml-cpp/yaml.h>

namespace unav::control {

namespace {

namespace fs = std::filesystem;
using physics::ConfigError;

YAML::Node load_file(const std::string& path) {
  try {
    return YAML::LoadFile(path);
  } catch (const YAML::BadFile&) {
    throw ConfigError(path, "", "", "cannot open file");
  } catch (const YAML::Exception& e) {
    throw ConfigError(path, "", "", std::string("malformed YAML: ") + e.what());
  }
}

// Relative vehicle paths resolve against config_root, by default the parent of the file's
// folder (config/controllers/x.yaml -> config/).
std::string config_root_of(const std::string& yaml_path, const std::string& config_root) {
  return config_root.empty() ? fs::absolute(yaml_path).parent_path().parent_path().string() : config_root;
}

}  // namespace

AllocatorParams load_allocator_params(const std::string& yaml_path) {
  const YAML::Node root = load_file(yaml_path);
  const bool ros = root.IsMap() && root["control_allocator"] && root["control_allocator"].IsMap() &&
                   root["control_allocator"]["ros__parameters"];
  if (ros && root.size() != 1) throw ConfigError(yaml_path, "", "", "only 'control_allocator' expected at top level");
  AllocatorParams p;
  unav::common::LoadYaml(root, yaml_path, &p, ros ? "control_allocator.ros__parameters" : "");
  return p;
}

AllocatorConfig make_allocator_config(const AllocatorParams& p, const std::string& config_root, const std::string& where) {
  AllocatorConfig c;
  c.vehicle_path = fs::path(p.vehicle_config).is_absolute()
                       ? p.vehicle_config
                       : (fs::path(config_root) / p.vehicle_config).lexically_normal().string();
  if (!fs::exists(c.vehicle_path))
    throw ConfigError(where, "vehicle_config", c.vehicle_path, "names a file that does not exist");
  c.vehicle = physics::load_vehicle(c.vehicle_path);
  parse_allocation_mode(p.mode, &c.options.mode);  // the schema allowed only known modes
  c.options.thruster_weights = p.thruster_weights;
  const std::size_t n = c.vehicle.thrusters.size();
  if (!p.thruster_weights.empty() && p.thruster_weights.size() != n) {
    throw ConfigError(where, "thruster_weights", std::to_string(p.thruster_weights.size()) + " entries",
                      "must be empty or have one entry per thruster (" + std::to_string(n) + ")");
  }
  c.options.max_redistribution_iterations = p.max_redistribution_iterations;
  for (const std::string& name : p.failed_thrusters) {
    int found = -1;
    for (std::size_t i = 0; i < n; ++i) {
      if (c.vehicle.thrusters[i].name == name) found = static_cast<int>(i);
    }
    if (found < 0) throw ConfigError(where, "failed_thrusters", name, "names a thruster the vehicle does not have");
    c.failed_thrusters.push_back(found);
  }
  std::string msg;
  if (!c.options.IsValid(&msg)) throw ConfigError(where + ": " + msg);
  return c;
}

AllocatorConfig load_allocator_config(const std::string& yaml_path, const std::string& config_root) {
  return make_allocator_config(load_allocator_params(yaml_path), config_root_of(yaml_path, config_root), yaml_path);
}

Allocator make_allocator(const AllocatorConfig& config) {
  Allocator a(config.vehicle.thrusters, config.options);
  for (int i : config.failed_thrusters) a.SetThrusterFailed(i, true);
  return a;
}

MpcParams load_mpc_params(const std::string& yaml_path) {
  const YAML::Node root = load_file(yaml_path);
  // A ROS 2 params file (`mpc_controller: {ros__parameters: {...}}`) or the bare map.
  const bool ros = root.IsMap() && root["mpc_controller"] && root["mpc_controller"].IsMap() &&
                   root["mpc_controller"]["ros__parameters"];
  if (ros && root.size() != 1) throw ConfigError(yaml_path, "", "", "only 'mpc_controller' expected at top level");
  MpcParams p;
  unav::common::LoadYaml(root, yaml_path, &p, ros ? "mpc_controller.ros__parameters" : "");
  return p;
}

MpcConfig make_mpc_config(const MpcParams& p, const std::string& config_root, const std::string& where) {
  MpcConfig c;
  if (p.control_blocks > p.horizon_steps) {
    throw ConfigError(where, "control_blocks", std::to_string(p.control_blocks),
                      "must be <= horizon_steps (" + std::to_string(p.horizon_steps) + ")");
  }
  c.model_vehicle_path = fs::path(p.model_vehicle_config).is_absolute()
                             ? p.model_vehicle_config
                             : (fs::path(config_root) / p.model_vehicle_config).lexically_normal().string();
  // (config_root is the folder holding vehicles/, normally the installed config/.)
  if (!fs::exists(c.model_vehicle_path)) {
    throw ConfigError(where, "model_vehicle_config", c.model_vehicle_path, "names a file that does not exist");
  }
  c.model = physics::load_vehicle(c.model_vehicle_path);
  MpcOptions& o = c.options;
  o.horizon_steps = p.horizon_steps;
  o.dt = p.dt;
  o.control_blocks = p.control_blocks;
  o.state_weights << p.position_weights, p.attitude_weights, p.linear_velocity_weights, p.angular_velocity_weights;
  o.input_weights << p.force_weights, p.moment_weights;
  o.input_rate_weights << p.force_rate_weights, p.moment_rate_weights;
  o.terminal_weight_scale = p.terminal_weight_scale;
  c.bounds_margin = p.bounds_margin;
  o.actuator_time_constant = p.actuator_time_constant;
  o.disturbance_gain = p.disturbance_gain;
  o.disturbance_limit_fraction = p.disturbance_limit_fraction;
  o.max_iterations = p.max_iterations;
  o.max_solve_time_ms = p.max_solve_time_ms;
  o.function_tolerance = p.function_tolerance;
  c.waypoints.acceptance_radius = p.acceptance_radius;
  // Bounds: what the model vehicle's thrusters reach per axis (pseudo-inverse), with a margin.
  o.input_bounds = Allocator(c.model.thrusters).achievable_wrench_box().Scaled(c.bounds_margin);
  std::string msg;
  if (!o.IsValid(&msg)) throw ConfigError(where + ": " + msg);
  if (!c.waypoints.IsValid(&msg)) throw ConfigError(where + ": " + msg);
  return c;
}

MpcConfig load_mpc_config(const std::string& yaml_path, const std::string& config_root) {
  return make_mpc_config(load_mpc_params(yaml_path), config_root_of(yaml_path, config_root), yaml_path);
}

}  // namespace unav::control
