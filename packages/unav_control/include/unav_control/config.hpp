// YAML loaders for config/controllers/{allocator,mpc}.yaml. Each file is a ROS 2 parameter file
// (`<node>: {ros__parameters: {...}}`, node = control_allocator / mpc_controller) or the bare
// parameter map. Vehicle paths are relative to the config root (default: the parent of the
// file's folder, i.e. config/) unless absolute. Unknown keys, wrong types, NaN and out-of-range
// values throw unav::ConfigError naming the file, the key, the value and the rule.
// The MPC's parameters are a schema (MpcParams, unav_common/config.hpp): each key is named once,
// with its type, default, range, unit and description; the mpc_controller node reads the same
// schema from its params file and `-p name:=value`.
#pragma once

#include <string>
#include <vector>

#include "unav_common/config.hpp"
#include "unav_control/allocator.hpp"
#include "unav_control/mpc.hpp"
#include "unav_control/waypoint_follower.hpp"

namespace unav::control {

/// The control_allocator's parameters, as written in config/controllers/allocator.yaml.
struct AllocatorParams {
  std::string vehicle_config = "vehicles/bluerov2_heavy.yaml";
  std::string mode = "redistributed";
  std::vector<double> thruster_weights;
  std::vector<std::string> failed_thrusters;
  int max_redistribution_iterations = 8;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("vehicle_config", &vehicle_config)
                 .Doc("thruster geometry: the physics server's vehicle YAML, relative to config/ or absolute"));
    a->Visit(Field("mode", &mode).OneOf({"pseudo_inverse", "redistributed"})
                 .Doc("saturation: uniform scaling, or saturated thrusters fixed and the rest reallocated"));
    a->Visit(Field("thruster_weights", &thruster_weights).Above(0.0)
                 .Doc("per thruster, larger = used less; [] = all 1"));
    a->Visit(Field("failed_thrusters", &failed_thrusters).Doc("thruster names marked failed at start, e.g. [T3]"));
    a->Visit(Field("max_redistribution_iterations", &max_redistribution_iterations).Range(1, 1000)
                 .Doc("redistribution passes"));
  }
};

struct AllocatorConfig {
  AllocatorOptions options;
  std::string vehicle_path;            ///< resolved path of the thruster/vehicle file
  physics::VehicleParams vehicle;      ///< loaded from vehicle_path (same file as the physics server's)
  std::vector<int> failed_thrusters;   ///< indices (resolved from names) to mark failed at start
};
AllocatorConfig load_allocator_config(const std::string& yaml_path, const std::string& config_root = "");
/// The parameters of an allocator file (ROS 2 params layout or bare map), validated by the schema.
AllocatorParams load_allocator_params(const std::string& yaml_path);
/// Builds the allocator configuration (loads the vehicle relative to `config_root`, resolves
/// failed thruster names); `where` names the source in errors.
AllocatorConfig make_allocator_config(const AllocatorParams& params, const std::string& config_root,
                                      const std::string& where);
/// The allocator of a config, with its failed thrusters applied.
Allocator make_allocator(const AllocatorConfig& config);

/// The mpc_controller's parameters, as written in config/controllers/mpc.yaml.
struct MpcParams {
  std::string model_vehicle_config = "vehicles/bluerov2_heavy.yaml";
  int horizon_steps = 20;
  double dt = 0.05;
  int control_blocks = 5;
  Eigen::Vector3d position_weights{200.0, 200.0, 200.0};
  Eigen::Vector3d attitude_weights{60.0, 60.0, 60.0};
  Eigen::Vector3d linear_velocity_weights{30.0, 30.0, 30.0};
  Eigen::Vector3d angular_velocity_weights{4.0, 4.0, 4.0};
  double terminal_weight_scale = 5.0;
  Eigen::Vector3d force_weights{2e-3, 2e-3, 2e-3};
  Eigen::Vector3d moment_weights{2e-2, 2e-2, 2e-2};
  Eigen::Vector3d force_rate_weights{1e-3, 1e-3, 1e-3};
  Eigen::Vector3d moment_rate_weights{1e-2, 1e-2, 1e-2};
  double bounds_margin = 0.9;
  double actuator_time_constant = 0.1;
  double disturbance_gain = 0.15;
  double disturbance_limit_fraction = 0.8;
  int max_iterations = 10;
  double max_solve_time_ms = 0.0;
  double function_tolerance = 1e-6;
  double acceptance_radius = 0.3;

  template <class Archive>
  void Serialize(Archive* a) {
    using unav::common::Field;
    a->Visit(Field("model_vehicle_config", &model_vehicle_config)
                 .Doc("the MPC's own model vehicle YAML, relative to config/ or absolute"));
    a->Visit(Field("horizon_steps", &horizon_steps).Range(1, 500).Doc("N, prediction steps"));
    a->Visit(Field("dt", &dt).Above(0.0).Max(10.0).Unit("s").Doc("model step (horizon = N dt)"));
    a->Visit(Field("control_blocks", &control_blocks).Range(1, 20).Doc("move blocking: free wrenches over the horizon, <= N"));
    a->Visit(Field("position_weights", &position_weights).Min(0.0).Unit("1/m^2").Doc("NED x y z"));
    a->Visit(Field("attitude_weights", &attitude_weights).Min(0.0).Unit("1/rad^2").Doc("rotation-vector error (body)"));
    a->Visit(Field("linear_velocity_weights", &linear_velocity_weights).Min(0.0).Unit("s^2/m^2").Doc("u v w"));
    a->Visit(Field("angular_velocity_weights", &angular_velocity_weights).Min(0.0).Unit("s^2/rad^2").Doc("p q r"));
    a->Visit(Field("terminal_weight_scale", &terminal_weight_scale).Min(0.0).Doc("x state weights at the last step"));
    a->Visit(Field("force_weights", &force_weights).Min(0.0).Unit("1/N^2").Doc("on F - F_hold"));
    a->Visit(Field("moment_weights", &moment_weights).Min(0.0).Unit("1/(N m)^2").Doc("on M - M_hold"));
    a->Visit(Field("force_rate_weights", &force_rate_weights).Min(0.0).Unit("1/N^2").Doc("between consecutive blocks"));
    a->Visit(Field("moment_rate_weights", &moment_rate_weights).Min(0.0).Unit("1/(N m)^2").Doc("between consecutive blocks"));
    a->Visit(Field("bounds_margin", &bounds_margin).Above(0.0).Max(1.0)
                 .Doc("MPC bounds = achievable wrench box of the model's thrusters x margin"));
    a->Visit(Field("actuator_time_constant", &actuator_time_constant).Min(0.0).Unit("s")
                 .Doc("thruster spin-up as a first-order lag; 0 = none"));
    a->Visit(Field("disturbance_gain", &disturbance_gain).Range(0.0, 1.0).Doc("disturbance estimator gain per solve"));
    a->Visit(Field("disturbance_limit_fraction", &disturbance_limit_fraction).Min(0.0)
                 .Doc("|d_hat| <= fraction x bounds (anti-windup)"));
    a->Visit(Field("max_iterations", &max_iterations).Range(1, 1000).Doc("Ceres iterations per solve"));
    a->Visit(Field("max_solve_time_ms", &max_solve_time_ms).Min(0.0).Unit("ms")
                 .Doc("wall-time budget; 0 = none (iterations only: runs repeat exactly; forced in lockstep)"));
    a->Visit(Field("function_tolerance", &function_tolerance).Above(0.0).Doc("Ceres relative cost change for convergence"));
    a->Visit(Field("acceptance_radius", &acceptance_radius).Above(0.0).Unit("m").Doc("waypoint reached within"));
  }
};

struct MpcConfig {
  MpcOptions options;                 ///< input_bounds = model's achievable wrench box x bounds_margin
  double bounds_margin = 0.9;         ///< in (0, 1]
  std::string model_vehicle_path;     ///< resolved path of the MPC's own model
  physics::VehicleParams model;       ///< loaded from model_vehicle_path
  WaypointFollowerOptions waypoints;  ///< acceptance radius etc. for the path follower
};
MpcConfig load_mpc_config(const std::string& yaml_path, const std::string& config_root = "");
/// The parameters of an MPC file (ROS 2 params layout or bare map), validated by the schema.
MpcParams load_mpc_params(const std::string& yaml_path);
/// Builds the MPC configuration from parameters: resolves and loads the model vehicle (relative
/// to `config_root`), checks the cross-field rules (control_blocks <= horizon_steps). `where`
/// names the source in errors (a file, or "node 'mpc_controller'").
MpcConfig make_mpc_config(const MpcParams& params, const std::string& config_root, const std::string& where);

}  // namespace unav::control
